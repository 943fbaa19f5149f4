#include "file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace sluice::io {

int open_or_throw(const std::string& path, int flags, int mode) {
  const int fd = ::open(path.c_str(), flags | O_CLOEXEC, mode);
  if (fd < 0) throw Error({path}, std::string("cannot open: ") + std::strerror(errno));
  return fd;
}

void write_all_or_throw(int fd, std::span<const std::byte> bytes, const std::string& path) {
  while (!bytes.empty()) {
    const ssize_t n = ::write(fd, bytes.data(), bytes.size());
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw Error({path}, std::string("write failed: ") + std::strerror(errno));
    bytes = bytes.subspan(static_cast<size_t>(n));
  }
}

void pread_all_or_throw(int fd, std::span<std::byte> bytes, uint64_t offset, const ErrorLocation& where) {
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::pread(fd, bytes.data() + done, bytes.size() - done, static_cast<off_t>(offset + done));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw Error(where, std::string("read failed: ") + std::strerror(errno));
    if (n == 0) {
      throw Error(where, "unexpected end of file at byte " + std::to_string(offset + done) + " (the file is truncated)");
    }
    done += static_cast<size_t>(n);
  }
}

uint64_t file_size_or_throw(int fd, const std::string& path) {
  struct stat st {};
  if (::fstat(fd, &st) != 0) throw Error({path}, std::string("cannot stat: ") + std::strerror(errno));
  return static_cast<uint64_t>(st.st_size);
}

}  // namespace sluice::io
