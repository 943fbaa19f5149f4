// sluice/import/playable.h: what a player opens: a .sluice file as it is,
// or anything convert() reads, converted once into a cache and reused while
// the input files are unchanged (their sizes and modification times). The
// `sluice play`, `render` and `xr` commands open their input this way.
//
// Cache: `.sluice-cache/NAME.sluice` next to the input when that folder is
// writable, else `$XDG_CACHE_HOME/sluice` (~/.cache/sluice). Each cached file
// has a `.key` beside it listing the input files, sizes, times and the
// conversion settings; a different key converts again. One process fills an
// entry; another opening the same input meanwhile waits for it
// (io/writer.h), then reuses it.
//
// Threads: one call per input at a time in a process. Errors: io::Error and
// ConvertStopped as convert() throws them, naming the input.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <utility>

#include "sluice/import/convert.h"

namespace sluice::import {

enum class CacheUse : uint8_t {
  Cache,      // convert into the cache, reuse it while the input is unchanged
  Temporary,  // convert into a temporary file, removed with the PlayableFile
};

// What the cache does, as it does it (all optional; on the calling thread).
struct CacheEvents {
  std::function<void(const std::string& entry)> reused;                    // the entry is up to date
  std::function<void(const std::string& entry)> converting;                // converting into it
  std::function<void(const std::string& folder, long pid)> waiting;        // another process fills it (pid or 0)
};

struct PlayableOptions {
  CacheUse use = CacheUse::Cache;
  // Where cached conversions go (created if missing); empty: .sluice-cache/
  // beside the input where that folder is writable, else the user cache.
  std::filesystem::path cache_folder;
  IsolationPolicy isolation;   // how the conversion reads third-party formats
  ConvertObserver observer;    // the conversion's plan, progress and notes
  CacheEvents events;
};

// Owns a temporary conversion (--no-cache) and removes it when destroyed.
class PlayableFile {
 public:
  PlayableFile(std::string path, bool temporary) : path_(std::move(path)), temporary_(temporary) {}
  ~PlayableFile();
  PlayableFile(PlayableFile&& other) noexcept
      : path_(std::move(other.path_)), temporary_(std::exchange(other.temporary_, false)) {}
  PlayableFile(const PlayableFile&) = delete;
  PlayableFile& operator=(const PlayableFile&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  bool temporary_;
};


// Returns `input` itself when it is a .sluice file; else converts it (every
// point array carried, the rest convert()'s defaults) or reuses the cache.
PlayableFile open_playable(const std::string& input, const PlayableOptions& options = {});

}  // namespace sluice::import
