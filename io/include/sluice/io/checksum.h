// sluice/io/checksum.h: the chunk checksum (XXH3-64 of a chunk's payload,
// the value ChunkDesc::checksum holds), for readers that check chunks
// themselves as they bring them in.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

namespace sluice::io {

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
