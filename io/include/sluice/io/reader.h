// sluice/io/reader.h: random access to a `.sluice` file, and the chunk
// checksum for readers that check chunks themselves.
//
// Opening reads the header and the frame index (found through the footer), so
// seeking to any frame costs one read. Every size in the file is checked
// against the file's real size and the format's limits before it is used.
//
// Threads: after construction every const member may be called concurrently
// (reads use pread on a shared descriptor).
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "sluice/io/codec.h"
#include "sluice/io/format.h"

namespace sluice::io {

// Whether `path` is a regular file that starts as a .sluice file does (its
// magic): for tools that take simulation output or a .sluice file. False
// when it cannot be read.
bool is_container(const std::filesystem::path& path);

class ContainerReader {
 public:
  // Throws io::Error: not a .sluice file, unsupported version, corrupt
  // header, or no valid index (the message then says to run `sluice recover`).
  explicit ContainerReader(const std::filesystem::path& path);
  ~ContainerReader();
  ContainerReader(const ContainerReader&) = delete;
  ContainerReader& operator=(const ContainerReader&) = delete;

  const std::string& path() const { return path_; }
  const FileHeader& header() const { return header_; }
  const FrameIndex& index() const { return index_; }
  uint64_t frame_count() const { return index_.frames.size(); }
  uint64_t file_size() const { return file_size_; }
  int descriptor() const { return fd_; }  // for callers that manage their own reads

  // Reads frame `frame`'s record into `out`, which must hold exactly
  // index().frames[frame].bytes bytes.
  void read_record(uint64_t frame, std::span<std::byte> out) const;
  std::vector<std::byte> read_record(uint64_t frame) const;

  // Reads and checks frame `frame`'s header and chunk table alone (where its
  // layers' payloads lie, for tools that report or read parts of it).
  FrameHeader read_table(uint64_t frame) const;

  // Validates a record's header and chunk table (checksum, sizes) and that it
  // matches the index entry of `frame`.
  FrameHeader parse_record(uint64_t frame, std::span<const std::byte> record) const;
  // The same into `into`, reusing its memory, with errors at `where` (the
  // caller's, naming the file and `frame`): parsing allocates nothing once
  // `into` has held as many chunks. For the streaming pipeline's reader.
  void parse_record(uint64_t frame, std::span<const std::byte> record, FrameHeader& into,
                    const ErrorLocation& where) const;

  // The header and chunk table alone, from the first bytes of the record
  // (at least frame_table_bytes(index chunk count, attributes)): for readers
  // that then read only some layers' payloads (layers_end()). Checked as
  // parse_record checks them; payloads are checked when decoded.
  void parse_table(uint64_t frame, std::span<const std::byte> prefix, FrameHeader& into, const ErrorLocation& where) const;

  ErrorLocation location(uint64_t frame) const { return {path_, frame, {}}; }
  ErrorLocation location(uint64_t frame, uint64_t chunk) const { return {path_, frame, chunk}; }

 private:
  std::string path_;
  int fd_ = -1;
  uint64_t file_size_ = 0;
  FileHeader header_;
  FrameIndex index_;
};

// A frame decoded into host memory: convenient for tools and tests; the
// runtime decodes chunk by chunk into its own buffers instead.
struct DecodedFrame {
  FrameHeader header;
  std::vector<std::byte> particles;                // decoded_particle_bytes(coding) per particle
  std::vector<std::vector<uint16_t>> attributes;   // per attribute, per particle (chunk ranges apply)
  std::vector<uint64_t> chunk_first;               // first particle of each chunk
};

// Reads and decodes frame `frame`'s chunks of `layers`, in parallel (TBB).
// The default is every particle: blobs are left out.
DecodedFrame decode_frame(const ContainerReader& reader, uint64_t frame, LayerSet layers = LayerSet::particles());

// World-space x,y,z of every particle of a decoded frame.
std::vector<float> world_positions(const DecodedFrame& frame, PositionCoding coding);
// LOD value of every particle of a decoded frame.
std::vector<uint16_t> lod_values_of(const DecodedFrame& frame, PositionCoding coding);

// Checksums: the chunk checksum (XXH3-64 of a chunk's payload,
// the value ChunkDesc::checksum holds), for readers that check chunks
// themselves as they bring them in.

// XXH3-64 of `payload`, with the widest vectors the CPU has. Any thread.
uint64_t chunk_checksum(std::span<const std::byte> payload);

// Copies one block: `n` bytes from src to dst (the caller's copy: streaming
// stores, a copy that catches SIGBUS, ...).
using BlockCopy = void (*)(std::byte* dst, const std::byte* src, size_t n, void* context);

// chunk_checksum() of the n bytes at src, computed while they are copied to
// dst: `copy` is called for consecutive blocks of at most kChecksumBlock
// bytes, in order, and each block of src is hashed right after its copy,
// while the cache still holds it, so that the bytes come from memory once.
// The value is that of the bytes hashed (src as read after each block's
// copy). Any thread; no allocation. `copy` may leave by longjmp (nothing
// here needs unwinding).
inline constexpr size_t kChecksumBlock = 32 << 10;
uint64_t copy_and_checksum(std::byte* dst, const std::byte* src, size_t n, BlockCopy copy, void* context);

}  // namespace sluice::io
