// `--format 2.0|1.5` of convert and synth: which container layout to write.
#pragma once

#include <CLI/CLI.hpp>

#include <cstdint>

namespace sluice::app {

// Adds the option to `cmd`, writing the major version (2, or 1 for 1.5)
// into `major` (io::set_format_version takes it).
void add_format_option(CLI::App& cmd, uint16_t& major);

}  // namespace sluice::app
