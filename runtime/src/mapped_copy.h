// Copying out of a file's read-only mapping: stores that bypass the cache,
// and a truncated file reported instead of a crash.
//
// Why stores that bypass the cache: a frame read from the page cache goes to
// a window of frame-sized areas that no cache holds, so ordinary stores (and
// pread's kernel copy) first read every destination line into the cache and
// then write it back. Streaming stores write the line once. Measured by
// bench/device/readpath.cpp (docs/measurements.md, "Reading out of the
// file's mapping").
//
// Why a truncated file needs care: touching a mapped page past the file's
// current end raises SIGBUS. copy_from_mapping() catches that on the calling
// thread only (a handler installed once per process, chained to whatever
// handler was there before, which still gets every SIGBUS not raised inside
// a copy) and returns false.
#pragma once

#include <cstddef>
#include <cstdint>

namespace sluice::runtime::detail {

// Copies n bytes from src (inside a read-only file mapping) to dst. Returns
// false when the mapping's pages vanished under the copy (the file was cut
// while it ran): dst then holds an unknown prefix. Any thread; no allocation.
bool copy_from_mapping(std::byte* dst, const std::byte* src, size_t n) noexcept;

// copy_from_mapping(), and sets `checksum` to io::chunk_checksum() of the
// bytes, each block hashed from the cache right after its copy
// (io::copy_and_checksum); with streaming stores, or plain ones that leave
// dst in the cache. False as above.
bool copy_from_mapping_checked(std::byte* dst, const std::byte* src, size_t n, uint64_t& checksum, bool streaming = true) noexcept;

// Copies n bytes with streaming stores where the CPU has them (x86-64:
// SSE2), plain memcpy elsewhere; dst and src may have any alignment.
void stream_copy(std::byte* dst, const std::byte* src, size_t n) noexcept;

}  // namespace sluice::runtime::detail
