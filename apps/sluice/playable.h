// What `sluice play`, `render` and `xr` open (import/playable.h), with the
// cache's and the conversion's messages on stderr.
#pragma once

#include <CLI/CLI.hpp>

#include <string>

#include "sluice/import/playable.h"

namespace sluice::app {

using import::PlayableFile;

struct PlayableOptions {
  bool no_cache = false;  // convert into a temporary file, removed afterwards
  bool quiet = false;
};

// The input argument (`name`: "file" or "input") and --no-cache, as play,
// render and xr take them, into `input` and `no_cache`.
void add_input_options(CLI::App& cmd, const char* name, std::string& input, bool& no_cache);

// import::open_playable, printing; a stopped conversion's error says what
// to pass next.
import::PlayableFile open_playable(const std::string& input, const PlayableOptions& options);

}  // namespace sluice::app
