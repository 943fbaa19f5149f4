// What `sluice play` and `sluice render` open: a .sluice file as it is, or
// anything `convert` reads, converted once into a cache and reused while the
// input files are unchanged (their sizes and modification times).
//
// Cache: `.sluice-cache/NAME.sluice` next to the input when that folder is
// writable, else `$XDG_CACHE_HOME/sluice` (~/.cache/sluice). Each cached file
// has a `.key` beside it listing the input files, sizes, times and the
// conversion settings; a different key converts again.
#pragma once

#include <filesystem>
#include <string>

namespace sluice::app {

struct PlayableOptions {
  bool no_cache = false;  // convert into a temporary file, removed afterwards
  bool quiet = false;
};

// Owns a temporary conversion (--no-cache) and removes it when destroyed.
class PlayableFile {
 public:
  PlayableFile(std::string path, bool temporary) : path_(std::move(path)), temporary_(temporary) {}
  ~PlayableFile();
  PlayableFile(const PlayableFile&) = delete;
  PlayableFile& operator=(const PlayableFile&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  bool temporary_;
};

// True when `path` is a regular file that starts with the .sluice magic.
bool is_sluice_file(const std::filesystem::path& path);

// Returns `input` itself when it is a .sluice file; else converts it (or
// reuses the cache). Throws std::runtime_error / io::Error naming the input.
PlayableFile open_playable(const std::string& input, const PlayableOptions& options);

}  // namespace sluice::app
