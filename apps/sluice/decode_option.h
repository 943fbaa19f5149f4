// `--decode auto|cpu|gpu` of play, render and xr: where frames are decoded.
#pragma once

#include <CLI/CLI.hpp>

#include <string>

#include "sluice/stream/frame_feed.h"

namespace sluice::app {

// Adds the option to `cmd`, writing "auto", "cpu" or "gpu" into `value`.
void add_decode_option(CLI::App& cmd, std::string& value);
stream::DecodeSite decode_site(const std::string& value);

}  // namespace sluice::app
