#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "mapped_copy.h"
#include "sluice/io/reader.h"
#include "sluice/error.h"
#include "sluice/runtime/record_source.h"

namespace sluice::runtime {
namespace {

// Names the file, the range and errno.
io::Error read_failed(const std::string& path, size_t bytes, uint64_t offset, int error) {
  return io::Error({path}, "read of " + std::to_string(bytes) + " bytes at offset " + std::to_string(offset) +
                               " failed: " + std::strerror(error));
}

}  // namespace

FileRecordSource::FileRecordSource(std::string path, int buffered_fd, bool direct, bool mapped)
    : path_(std::move(path)), buffered_fd_(buffered_fd) {
  if (mapped) map_file();
  span_fd_ = ::open(path_.c_str(), O_RDONLY | O_CLOEXEC);
  if (span_fd_ >= 0) ::posix_fadvise(span_fd_, 0, 0, POSIX_FADV_RANDOM);  // exactly the bytes asked for
  if (!direct) return;
  owned_fd_ = ::open(path_.c_str(), O_RDONLY | O_DIRECT | O_CLOEXEC);
  if (owned_fd_ < 0) {
    refused_ = std::strerror(errno);  // tmpfs and some network filesystems say EINVAL
    return;
  }
  direct_fd_.store(owned_fd_, std::memory_order_release);
}

FileRecordSource::~FileRecordSource() {
  if (owned_fd_ >= 0) ::close(owned_fd_);
  if (span_fd_ >= 0) ::close(span_fd_);
  if (map_) ::munmap(const_cast<std::byte*>(map_), map_bytes_);
}

void FileRecordSource::map_file() {
  struct stat st {};
  if (::fstat(buffered_fd_, &st) != 0 || !S_ISREG(st.st_mode) || st.st_size <= 0) {
    unmapped_ = "not a regular file with bytes";
    return;
  }
  void* map = ::mmap(nullptr, static_cast<size_t>(st.st_size), PROT_READ, MAP_SHARED, buffered_fd_, 0);
  if (map == MAP_FAILED) {
    unmapped_ = std::strerror(errno);
    return;
  }
  map_ = static_cast<const std::byte*>(map);
  map_bytes_ = static_cast<uint64_t>(st.st_size);
}

size_t FileRecordSource::copy_mapped(std::span<std::byte> dst, uint64_t offset) {
  const size_t n = static_cast<size_t>(std::min<uint64_t>(dst.size(), map_bytes_ - offset));
  // The bytes count only if the file still reaches past them afterwards: a
  // mapped page the file was cut inside reads as zeros past the cut, and
  // pages wholly past it raise SIGBUS. Either way pread says where the file
  // ends now.
  if (detail::copy_from_mapping(dst.data(), map_ + offset, n) && reaches(offset + n)) return n;
  return read_buffered(dst.first(n), offset);
}

bool FileRecordSource::reaches(uint64_t end) const {
  struct stat st {};
  return ::fstat(buffered_fd_, &st) == 0 && static_cast<uint64_t>(st.st_size) >= end;
}

size_t FileRecordSource::read_buffered(std::span<std::byte> dst, uint64_t offset) {
  while (true) {
    const ssize_t n = ::pread(buffered_fd_, dst.data(), dst.size(), static_cast<off_t>(offset));
    if (n >= 0) return static_cast<size_t>(n);
    if (errno == EINTR) continue;
    throw read_failed(path_, dst.size(), offset, errno);
  }
}

void FileRecordSource::fall_back(const std::string& why) {
  if (falling_back_.exchange(true)) return;  // another read thread is doing it
  refused_ = why;  // written before the release below, read after an acquire of it
  direct_fd_.store(-1, std::memory_order_release);
}

size_t FileRecordSource::read_at(std::span<std::byte> dst, uint64_t offset) {
  while (true) {
    const int direct = direct_fd_.load(std::memory_order_relaxed);
    if (direct < 0) return offset < map_bytes_ ? copy_mapped(dst, offset) : read_buffered(dst, offset);
    const ssize_t n = ::pread(direct, dst.data(), dst.size(), static_cast<off_t>(offset));
    if (n >= 0) return static_cast<size_t>(n);
    if (errno == EINTR) continue;
    // Some filesystems accept O_DIRECT at open and refuse the reads.
    if (errno == EINVAL) {
      fall_back(std::string(std::strerror(EINVAL)) + " on read");
      continue;
    }
    throw read_failed(path_, dst.size(), offset, errno);
  }
}

size_t FileRecordSource::read_span(std::span<std::byte> dst, uint64_t offset) {
  if (direct_fd_.load(std::memory_order_relaxed) >= 0) return read_at(dst, offset);
  const int fd = span_fd_ >= 0 ? span_fd_ : buffered_fd_;
  while (true) {
    const ssize_t n = ::pread(fd, dst.data(), dst.size(), static_cast<off_t>(offset));
    if (n >= 0) return static_cast<size_t>(n);
    if (errno == EINTR) continue;
    throw read_failed(path_, dst.size(), offset, errno);
  }
}

size_t RecordSource::read_checked(std::span<std::byte> dst, uint64_t offset, uint64_t& checksum, Stores /*stores*/) {
  size_t got = 0;
  while (got < dst.size()) {
    const size_t n = read_at(dst.subspan(got), offset + got);
    if (n == 0) break;
    got += n;
  }
  checksum = io::chunk_checksum(dst.first(got));
  return got;
}

size_t FileRecordSource::read_checked(std::span<std::byte> dst, uint64_t offset, uint64_t& checksum, Stores stores) {
  const bool mapped = direct_fd_.load(std::memory_order_relaxed) < 0 && offset < map_bytes_ && dst.size() <= map_bytes_ - offset;
  if (mapped && detail::copy_from_mapping_checked(dst.data(), map_ + offset, dst.size(), checksum, stores == Stores::Streaming) && reaches(offset + dst.size())) {
    return dst.size();
  }
  return RecordSource::read_checked(dst, offset, checksum);  // pread: O_DIRECT, past the mapping, or a file cut under it
}

size_t FileRecordSource::alignment() const {
  return direct_fd_.load(std::memory_order_relaxed) >= 0 ? kDirectAlignment : 1;
}

void FileRecordSource::will_need(uint64_t offset, uint64_t bytes) {
  if (direct()) return;  // the page cache is not in the way
  ::posix_fadvise(buffered_fd_, static_cast<off_t>(offset), static_cast<off_t>(bytes), POSIX_FADV_WILLNEED);
}

void FileRecordSource::set_access(AccessPattern pattern) {
  // Sequential doubles the kernel's readahead; Random turns it off, which
  // suits reverse play and scrubbing (readahead only goes forward).
  ::posix_fadvise(buffered_fd_, 0, 0, pattern == AccessPattern::Sequential ? POSIX_FADV_SEQUENTIAL : POSIX_FADV_RANDOM);
}

std::string FileRecordSource::describe() const {
  if (direct_fd_.load(std::memory_order_acquire) >= 0) return "pread, O_DIRECT";
  const std::string buffered = map_ ? "mapped" : unmapped_.empty() ? "pread" : "pread (not mapped: " + unmapped_ + ")";
  if (!refused_.empty() || owned_fd_ >= 0) return buffered + " (O_DIRECT refused: " + refused_ + ")";
  return buffered;
}

}  // namespace sluice::runtime
