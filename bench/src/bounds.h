// The machine's own bounds for streaming a file: memory copy on several
// threads, sequential reads from storage (page cache bypassed) and from the
// page cache, and control over what of a file the page cache holds.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

namespace sluice::bench {

// memcpy of 64 MiB per thread on `threads` threads at once, GB/s in all.
double parallel_memcpy_gbps(int threads, double min_seconds);

// Writes back and drops bytes [offset, offset + bytes) of `path` from the page
// cache (posix_fadvise DONTNEED). Pages other processes map stay.
void drop_from_page_cache(const std::string& path, uint64_t offset, uint64_t bytes);
// Share of those bytes the page cache holds now, 0..1 (mincore).
double page_cache_share(const std::string& path, uint64_t offset, uint64_t bytes);

// Bytes this process has had storage deliver so far (read_bytes of
// /proc/self/io: page-cache misses it caused, readahead included, and
// O_DIRECT reads); 0 where the kernel does not say.
uint64_t process_read_bytes();

enum class ReadMode { PageCache, BufferedCold, Direct };

// pread of the range in 8 MiB pieces, in order, on `threads` threads taking
// the next piece in turn (as the pipeline's read threads do), GB/s.
// PageCache repeats until min_seconds; BufferedCold drops the range first and
// reads it once (kernel readahead on); Direct reads it once with O_DIRECT.
// nullopt: the mode is not available here (O_DIRECT refused).
std::optional<double> sequential_read_gbps(const std::string& path, uint64_t offset, uint64_t bytes, ReadMode mode,
                                           double min_seconds, int threads = 1);

// The page-cache range read through the pipeline's own source
// (runtime::FileRecordSource, mapped or pread) into a window of `window`
// areas of `frame_bytes`, as frames land in staging: 8 MiB pieces on
// `threads` threads, consecutive frames' pieces from one queue, GB/s. Unlike
// sequential_read_gbps (one hot 8 MiB buffer per thread), every destination
// line is cold, as it is for the pipeline.
double window_read_gbps(const std::string& path, uint64_t offset, uint64_t bytes, uint64_t frame_bytes, int threads,
                        bool mapped, double min_seconds, uint32_t window = 12);

}  // namespace sluice::bench
