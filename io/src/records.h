// Serialization of the container's records (docs/format.md). Parsers check
// every field against the format's limits and the bytes actually present.
#pragma once

#include <span>
#include <vector>

#include "sluice/error.h"
#include "sluice/io/format.h"

namespace sluice::io {

inline constexpr std::array<uint8_t, 8> kFileMagic = {0x89, 'S', 'L', 'U', 'I', 'C', 'E', '\n'};
inline constexpr uint32_t kFrameMagic = 0x52464C53;  // "SLFR"
// Frame flags (frame header offset 36): bit 0, records ordered coarse to
// fine (format 2.0); bit 1, positions split into records and fine parts
// (format 3.0, only with bit 0). Other bits are rejected.
inline constexpr uint32_t kFrameCoarseToFine = 1;
inline constexpr uint32_t kFrameSplitPositions = 2;
// Chunk descriptor byte 18 (the tier), bit 7: the descriptor is a fine part
// (format 3.0), not a record.
inline constexpr uint8_t kFinePartFlag = 0x80;
inline constexpr uint32_t kIndexMagic = 0x58494C53;  // "SLIX"
inline constexpr uint32_t kHeaderCopyMagic = 0x43484C53;  // "SLHC": the header again, right after it (format 1.5)
inline constexpr std::array<uint8_t, 8> kFooterMagic = {'S', 'L', 'U', 'I', 'C', 'E', 'I', 'X'};
inline constexpr size_t kFileHeaderFixedBytes = 36;

std::vector<std::byte> serialize_file_header(const FileHeader& header);
// The copy of the header that follows it (format 1.5, what `recover`
// rebuilds a damaged header from): kHeaderCopyMagic, then `header`'s bytes.
std::vector<std::byte> serialize_header_copy(std::span<const std::byte> header);
// Reads header_bytes from the fixed part (first kFileHeaderFixedBytes bytes).
uint32_t peek_file_header_bytes(std::span<const std::byte> fixed, const ErrorLocation& where);
FileHeader parse_file_header(std::span<const std::byte> bytes, const ErrorLocation& where);

std::vector<std::byte> serialize_frame_table(const FrameHeader& frame, size_t attribute_count);
struct FramePrefix {
  uint32_t frame_number;
  uint64_t frame_bytes;
  uint32_t chunk_count;
};
// Checks the magic and the sizes of the fixed part of a frame record.
FramePrefix parse_frame_prefix(std::span<const std::byte> fixed, const ErrorLocation& where);
// Parses and validates header + chunk table; `record` holds at least the
// table (the payloads are checked against it when decoded).
FrameHeader parse_frame_table(std::span<const std::byte> record, size_t attribute_count, const ErrorLocation& where);
// The same into `into`, reusing its chunk table's memory (no allocation once
// it has held as many chunks).
void parse_frame_table(std::span<const std::byte> record, size_t attribute_count, const ErrorLocation& where,
                       FrameHeader& into);

std::vector<std::byte> serialize_index(const FrameIndex& index, size_t attribute_count);
FrameIndex parse_index(std::span<const std::byte> bytes, size_t attribute_count, uint64_t file_size,
                       const ErrorLocation& where);

struct Footer {
  uint64_t index_offset;
  uint64_t index_bytes;
};
std::vector<std::byte> serialize_footer(const Footer& footer);
// Returns false (no throw) when the bytes are not a footer: the file was cut short.
bool parse_footer(std::span<const std::byte> bytes, Footer& out);

FrameIndexEntry index_entry_for(const FrameHeader& frame, uint64_t offset);


}  // namespace sluice::io
