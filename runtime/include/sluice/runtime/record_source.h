// sluice/runtime/record_source.h: where the reader thread gets its bytes.
//
// FileRecordSource reads the container out of the page cache, either by
// copying from a read-only mapping of the file with streaming stores (the
// default: no destination line is read before it is written) or with pread;
// gives the kernel readahead hints (posix_fadvise); and can bypass the page
// cache with O_DIRECT, falling back to buffered reads when the filesystem
// refuses it.
// The interface exists so tests can wrap the real source and inject faults.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

namespace sluice::runtime {

enum class AccessPattern : uint8_t { Sequential, Random };

// How a copy out of the page cache writes its destination. Streaming: past
// the CPU's caches (the destination is read much later: a window of frames
// in staging). Cached: plain stores that leave it in the cache (the GPU
// copies it soon after: a small ring, runtime/frame_allocator.h).
enum class Stores : uint8_t { Streaming, Cached };

// Threads: read_at() may be called from several of the pipeline's read
// threads at once (different ranges); the hints from the reader thread only;
// describe() from any thread.
class RecordSource {
 public:
  virtual ~RecordSource() = default;
  // Reads up to dst.size() bytes at `offset`; returns how many were read, 0
  // at end of file. May return fewer than asked (the caller loops). Throws
  // io::Error naming the file when the read fails.
  virtual size_t read_at(std::span<std::byte> dst, uint64_t offset) = 0;
  // Reads all of dst at `offset` (fewer bytes only where the file ends) and
  // sets `checksum` to io::chunk_checksum() of the bytes read: how a reader
  // checks a chunk as it brings it in. This default reads with read_at()
  // and then hashes dst; FileRecordSource hashes its mapping's bytes block
  // by block as it copies them, so that they come from memory once.
  // `stores` is a hint for copies out of a mapping. Threads and errors as
  // read_at().
  virtual size_t read_checked(std::span<std::byte> dst, uint64_t offset, uint64_t& checksum,
                              Stores stores = Stores::Streaming);
  // As read_at(), for a run of a view's demand (a part of a frame): the
  // device should move these bytes and no others. FileRecordSource reads
  // them with pread on a descriptor whose readahead is off (or O_DIRECT),
  // never through its mapping, whose page faults make the kernel read
  // around them. This default calls read_at().
  virtual size_t read_span(std::span<std::byte> dst, uint64_t offset) { return read_at(dst, offset); }
  // Offsets, sizes and buffer addresses of reads must be multiples of this
  // (O_DIRECT); 1 when there is no constraint. May change after a read (a
  // refused O_DIRECT falls back to buffered reads).
  virtual size_t alignment() const = 0;
  // Hints; they may do nothing.
  virtual void will_need(uint64_t /*offset*/, uint64_t /*bytes*/) {}
  virtual void set_access(AccessPattern /*pattern*/) {}
  // "mapped", "pread", "pread, O_DIRECT", "pread (O_DIRECT refused: ...)".
  virtual std::string describe() const = 0;
};

class FileRecordSource final : public RecordSource {
 public:
  // Reads `path` through `buffered_fd` (borrowed: the ContainerReader's
  // descriptor) or, with `direct`, through its own O_DIRECT descriptor.
  // With `mapped`, buffered reads copy out of a mapping of the file as it
  // was at construction (bytes past that end, if the file grows, come by
  // pread); a file cut shorter while mapped reads as ending at its new end,
  // as pread would (mapped_copy.h says how), never as a crash. Where the
  // file cannot be mapped, pread, and describe() says why.
  FileRecordSource(std::string path, int buffered_fd, bool direct, bool mapped = true);
  ~FileRecordSource() override;
  FileRecordSource(const FileRecordSource&) = delete;
  FileRecordSource& operator=(const FileRecordSource&) = delete;

  size_t read_at(std::span<std::byte> dst, uint64_t offset) override;
  size_t read_checked(std::span<std::byte> dst, uint64_t offset, uint64_t& checksum,
                      Stores stores = Stores::Streaming) override;
  size_t read_span(std::span<std::byte> dst, uint64_t offset) override;
  size_t alignment() const override;
  void will_need(uint64_t offset, uint64_t bytes) override;
  void set_access(AccessPattern pattern) override;
  std::string describe() const override;
  bool direct() const { return direct_fd_.load(std::memory_order_acquire) >= 0; }

  static constexpr size_t kDirectAlignment = 4096;

 private:
  void fall_back(const std::string& why);
  void map_file();
  size_t copy_mapped(std::span<std::byte> dst, uint64_t offset);
  bool reaches(uint64_t end) const;  // the file is at least `end` bytes long now
  size_t read_buffered(std::span<std::byte> dst, uint64_t offset);  // pread on buffered_fd_, EINTR retried

  std::string path_;
  int buffered_fd_;
  std::atomic<int> direct_fd_{-1};
  std::atomic<bool> falling_back_{false};  // the first thread to see a refusal records why
  int owned_fd_ = -1;
  int span_fd_ = -1;  // buffered, POSIX_FADV_RANDOM: read_span()'s (-1: buffered_fd_)
  std::string refused_;  // why O_DIRECT is not in use, once it was asked for
  const std::byte* map_ = nullptr;  // the whole file as it was at construction, read-only
  uint64_t map_bytes_ = 0;
  std::string unmapped_;  // why a mapping was asked for and not made
};

}  // namespace sluice::runtime
