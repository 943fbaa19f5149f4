// A bounded read buffer over a file: words, lines and raw byte runs.
#include "byte_stream.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "sluice/error.h"

namespace sluice::import::detail {

using namespace sluice::io;  // the container's types: frames, errors, shapes
using io::Error;  // (not sluice::Error, its base)
namespace {

constexpr size_t kBufferBytes = size_t(1) << 16;

bool is_space(char c) { return c == ' ' || c == '\n' || c == '\r' || c == '\t' || c == '\v' || c == '\f'; }

}  // namespace

ByteStream::ByteStream(const std::string& path)
    : path_(path), buffer_(new char[kBufferBytes]), capacity_(kBufferBytes) {
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) throw Error({path}, std::string("cannot open: ") + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd_, &st) != 0) {
    const int e = errno;
    ::close(fd_);
    throw Error({path}, std::string("cannot read its size: ") + std::strerror(e));
  }
  size_ = static_cast<uint64_t>(st.st_size);
}

ByteStream::~ByteStream() {
  if (fd_ >= 0) ::close(fd_);
}

size_t ByteStream::available(size_t want) {
  if (end_ - pos_ >= want) return end_ - pos_;
  // Keep the unread tail, refill behind it.
  std::memmove(buffer_.get(), buffer_.get() + pos_, end_ - pos_);
  base_ += pos_;
  end_ -= pos_;
  pos_ = 0;
  while (end_ < capacity_ && base_ + end_ < size_) {
    const ssize_t got = ::pread(fd_, buffer_.get() + end_, capacity_ - end_, static_cast<off_t>(base_ + end_));
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) throw Error({path_}, std::string("read error: ") + std::strerror(errno));
    if (got == 0) {
      size_ = base_ + end_;  // the file shrank while we read it
      break;
    }
    end_ += static_cast<size_t>(got);
    if (end_ - pos_ >= want) break;
  }
  return end_ - pos_;
}

std::string_view ByteStream::word() {
  for (;;) {
    if (pos_ == end_ && available(1) == 0) return {};
    const char c = buffer_[pos_];
    if (!is_space(c)) break;
    if (c == '\n') ++line_;
    ++pos_;
  }
  size_t n = 0;
  for (;;) {
    if (pos_ + n == end_ && available(n + 1) == n) break;
    if (is_space(buffer_[pos_ + n])) break;
    if (++n > kLongestWord) {
      throw Error({path_}, "a word of more than " + std::to_string(kLongestWord) + " characters at byte " +
                               std::to_string(offset()) + ": not a text section");
    }
  }
  const std::string_view out(buffer_.get() + pos_, n);
  pos_ += n;
  return out;
}

std::string_view ByteStream::line() {
  size_t n = 0;
  for (;;) {
    if (pos_ + n == end_ && available(n + 1) == n) break;
    if (buffer_[pos_ + n] == '\n') break;
    if (++n > kLongestWord) {
      throw Error({path_}, "a line of more than " + std::to_string(kLongestWord) + " characters at byte " +
                               std::to_string(offset()) + ": not a text line");
    }
  }
  std::string_view out(buffer_.get() + pos_, n);
  pos_ += n;
  if (pos_ < end_) {  // the newline
    ++pos_;
    ++line_;
  }
  if (!out.empty() && out.back() == '\r') out.remove_suffix(1);
  return out;
}

void ByteStream::read(void* into, uint64_t n) {
  if (n == 0) return;  // `into` may be the null data of an empty buffer
  if (n > remaining()) {
    throw Error({path_}, "needs " + std::to_string(n) + " bytes at byte " + std::to_string(offset()) + " but " +
                             std::to_string(remaining()) + " remain");
  }
  auto* out = static_cast<char*>(into);
  const size_t buffered = std::min<uint64_t>(n, end_ - pos_);
  std::memcpy(out, buffer_.get() + pos_, buffered);
  pos_ += buffered;
  uint64_t done = buffered;
  if (done == n) return;
  // Large runs bypass the buffer, which is empty now.
  base_ += pos_;
  pos_ = end_ = 0;
  while (done < n) {
    const ssize_t got = ::pread(fd_, out + done, n - done, static_cast<off_t>(offset()));
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) {
      throw Error({path_}, got < 0 ? std::string("read error: ") + std::strerror(errno)
                                   : "the file ended while it was read (another program shortened it)");
    }
    done += static_cast<uint64_t>(got);
    base_ += static_cast<uint64_t>(got);
  }
}

void ByteStream::skip(uint64_t n) {
  if (n > remaining()) {
    throw Error({path_}, "needs " + std::to_string(n) + " bytes at byte " + std::to_string(offset()) + " but " +
                             std::to_string(remaining()) + " remain");
  }
  const size_t buffered = std::min<uint64_t>(n, end_ - pos_);
  pos_ += buffered;
  if (buffered == n) return;
  base_ += pos_ + (n - buffered);
  pos_ = end_ = 0;
}

}  // namespace sluice::import::detail
