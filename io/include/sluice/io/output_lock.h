// sluice/io/output_lock.h: one writer per output.
//
// Two `sluice convert`s to one file, or two players filling one cache
// entry, would otherwise write the same `.partial` and rename each other's
// half-written bytes. A writer holds an OutputLock on its output for as
// long as it writes (until the rename): an exclusive flock(2) on
// `OUTPUT.lock`, which holds the holder's process id for the error message
// and is removed on release. The lock is advisory (other programs are not
// stopped) and dies with its process, so a crash never leaves it held.
#pragma once

#include <filesystem>
#include <functional>
#include <string>

namespace sluice::io {

class OutputLock {
 public:
  enum class Wait { No, Yes };
  // Takes the lock on `output`. Wait::No: throws io::Error naming `output`
  // and the holder's process id when another holds it. Wait::Yes: blocks
  // until the holder releases it, calling `on_wait(pid)` once first (pid 0
  // when unknown). Throws io::Error when the lock file cannot be created.
  explicit OutputLock(const std::filesystem::path& output, Wait wait = Wait::No,
                      const std::function<void(const std::filesystem::path& output, long pid)>& on_wait = {});
  ~OutputLock();  // removes the lock file and releases the lock
  OutputLock(const OutputLock&) = delete;
  OutputLock& operator=(const OutputLock&) = delete;

  const std::filesystem::path& path() const { return path_; }  // OUTPUT.lock

 private:
  std::filesystem::path path_;
  int fd_ = -1;
};

}  // namespace sluice::io
