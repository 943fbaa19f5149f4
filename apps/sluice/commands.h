// Each subcommand registers its options on the CLI and runs when chosen.
#pragma once

#include <CLI/CLI.hpp>

namespace sluice::app {

void add_convert(CLI::App& app);
void add_info(CLI::App& app);
void add_verify(CLI::App& app);
void add_recover(CLI::App& app);
void add_bench(CLI::App& app);
void add_play(CLI::App& app);
void add_synth(CLI::App& app);
void add_export(CLI::App& app);
// Only in builds with SLUICE_WITH_RENDER:
void add_render(CLI::App& app);
void add_devices(CLI::App& app);
void add_bench_render(CLI::App& bench);
void add_bench_layers(CLI::App& bench);  // `sluice bench layers`  // `sluice bench render`, under the bench command
// Only in builds with SLUICE_WITH_XR:
void add_xr(CLI::App& app);

// Thrown by a subcommand that has already printed what went wrong, to set the
// process exit code without another message.
struct ExitCode {
  int code;
};

}  // namespace sluice::app
