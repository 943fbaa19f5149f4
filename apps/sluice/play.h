// `sluice play`: the options both players share (the window player and the
// headless null sink) and how they become runtime::PlayerOptions.
#pragma once

#include <CLI/CLI.hpp>

#include <cstdint>
#include <memory>
#include <string>

#include "sluice/runtime/player.h"
#if SLUICE_WITH_RENDER
#include "sluice/stream/stream.h"
#include "view_options.h"
#endif

namespace sluice::app {

struct PlayOptions {
  std::string file;    // the .sluice file played
  std::string source;  // what the user named (shown in the title and the HUD); the file if empty
  bool headless = false, stats = false, loop = false, bounce = false, once = false, reverse = false, direct = false,
       quiet = false, paused = false, no_cache = false;
  double fps = 0, rate = 1, seconds = 0, display_hz = 0, stats_every = 1;
  std::string memory, policy = "hold", on_error = "skip";
  std::string layers = "surface";  // --layers: surface (narrow band + blobs) or all
  std::string decode = "auto";     // --decode: auto, cpu or gpu (decode_option.h)
  uint32_t window = 0;
  int threads = 0, read_threads = 0;
  uint64_t start = 0;
};

// The end mode: --bounce, --loop, --once; a window loops unless told otherwise,
// headless playback stops at the end (so that it terminates).
runtime::EndMode end_mode(const PlayOptions& o, bool window);
// Throws std::runtime_error on a --memory it cannot read.
runtime::PlayerOptions player_options(const PlayOptions& o, bool window);
#if SLUICE_WITH_RENDER
// What a player through the renderer streams: player_options(), --layers,
// --decode and --up. Throws std::runtime_error as those do.
stream::StreamOptions stream_options(const PlayOptions& o, const ViewSettings& v, bool window);
#endif

#if SLUICE_WITH_WINDOW
// The window player (cmd_play_window.cpp) and headless playback through the
// renderer (cmd_play_gpu.cpp), in builds with a window.
struct WindowPlayOptions {
  std::string size = "1280x720";
  bool no_hud = false, no_vsync = false;
  int exit_after = 0;  // presented frames showing data, 0: run until closed
  std::string screenshot;
  bool gpu = false;    // --headless --gpu: through the renderer into an offscreen image
  ViewSettings view;
};
std::shared_ptr<WindowPlayOptions> add_window_play_options(CLI::App& play);
void run_play_window(const PlayOptions& o, const WindowPlayOptions& w);
void run_play_gpu(const PlayOptions& o, const WindowPlayOptions& w);
#endif

}  // namespace sluice::app
