#include "sluice/io/writer.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>

#include "sluice/error.h"

namespace sluice::io {
namespace {

long holder_of(int fd) {
  char text[32] = {};
  const ssize_t n = ::pread(fd, text, sizeof text - 1, 0);
  return n > 0 ? std::strtol(text, nullptr, 10) : 0;
}

// The lock file at `path` is still the one `fd` opened (a releasing holder
// removes it: a lock on the removed file would guard nothing).
bool still_linked(int fd, const std::filesystem::path& path) {
  struct stat held{}, named{};
  return ::fstat(fd, &held) == 0 && ::stat(path.c_str(), &named) == 0 && held.st_ino == named.st_ino &&
         held.st_dev == named.st_dev;
}

}  // namespace

OutputLock::OutputLock(const std::filesystem::path& output, Wait wait,
                       const std::function<void(const std::filesystem::path&, long)>& on_wait) {
  path_ = output;
  path_ += ".lock";
  bool told = false;
  while (true) {
    fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) throw Error({output.string()}, "cannot create the lock file " + path_.string() + ": " + std::strerror(errno));
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      if (errno != EWOULDBLOCK) {
        const std::string why = std::strerror(errno);
        ::close(fd_);
        throw Error({output.string()}, "cannot lock " + path_.string() + ": " + why);
      }
      const long pid = holder_of(fd_);
      if (wait == Wait::No) {
        ::close(fd_);
        throw Error({output.string()}, "another sluice" + (pid > 0 ? " (process " + std::to_string(pid) + ")" : std::string()) +
                                           " is writing this file; wait for it to finish or write to another name");
      }
      if (!told && on_wait) on_wait(output, pid);
      told = true;
      if (::flock(fd_, LOCK_EX) != 0) {
        const std::string why = std::strerror(errno);
        ::close(fd_);
        throw Error({output.string()}, "waiting for the lock " + path_.string() + " failed: " + why);
      }
    }
    if (still_linked(fd_, path_)) break;
    ::close(fd_);  // the holder removed it as we took it: take the new one
  }
  const std::string pid = std::to_string(::getpid()) + "\n";
  if (::ftruncate(fd_, 0) != 0 || ::pwrite(fd_, pid.data(), pid.size(), 0) != ssize_t(pid.size())) {
    // Only the message suffers: the lock itself is held.
  }
}

OutputLock::~OutputLock() {
  if (fd_ < 0) return;
  ::unlink(path_.c_str());  // before the release: a waiter then sees it gone and retries
  ::close(fd_);
}

}  // namespace sluice::io
