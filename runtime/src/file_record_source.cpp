#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "sluice/io/error.h"
#include "sluice/runtime/record_source.h"

namespace sluice::runtime {

FileRecordSource::FileRecordSource(std::string path, int buffered_fd, bool direct)
    : path_(std::move(path)), buffered_fd_(buffered_fd) {
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
}

void FileRecordSource::fall_back(const std::string& why) {
  if (falling_back_.exchange(true)) return;  // another read thread is doing it
  refused_ = why;  // written before the release below, read after an acquire of it
  direct_fd_.store(-1, std::memory_order_release);
}

size_t FileRecordSource::read_at(std::span<std::byte> dst, uint64_t offset) {
  while (true) {
    const int direct = direct_fd_.load(std::memory_order_relaxed);
    const int fd = direct >= 0 ? direct : buffered_fd_;
    const ssize_t n = ::pread(fd, dst.data(), dst.size(), static_cast<off_t>(offset));
    if (n >= 0) return static_cast<size_t>(n);
    if (errno == EINTR) continue;
    // Some filesystems accept O_DIRECT at open and refuse the reads.
    if (direct >= 0 && errno == EINVAL) {
      fall_back(std::string(std::strerror(EINVAL)) + " on read");
      continue;
    }
    throw io::Error({path_}, "read of " + std::to_string(dst.size()) + " bytes at offset " + std::to_string(offset) +
                                 " failed: " + std::strerror(errno));
  }
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
  if (!refused_.empty() || owned_fd_ >= 0) return "pread (O_DIRECT refused: " + refused_ + ")";
  return "pread";
}

}  // namespace sluice::runtime
