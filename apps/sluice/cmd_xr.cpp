// `sluice xr FILE`: the sequence in a headset through OpenXR. A client of the
// public API like any host: xr::Session (the runtime's Vulkan device, its
// swapchains and frame loop), stream::Stream driven by the predicted display
// time drawing both eyes, and
// xr::Controls turning the controllers into playback and placement.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <thread>

#include "commands.h"
#include "frame_errors.h"
#include "human.h"
#include "decode_option.h"
#include "layers_option.h"
#include "reads_text.h"
#include "play.h"
#include "playable.h"
#include "sluice/stream/stream.h"
#include "sluice/xr/controls.h"
#include "sluice/xr/placement.h"
#include "sluice/xr/session.h"
#include "view_options.h"

namespace sluice::app {
namespace {

struct XrOptions {
  PlayOptions play;
  ViewSettings view;
  uint64_t frames = 0;  // exit after this many frames (0: until the runtime ends the session)
  bool no_depth = false, local = false;
  float size = 1.5f;    // metres the data spans at first
};

// Media time from the runtime's predicted display times: seconds since the
// first frame's, 0 before it (so playback starts where it should).
class DisplayClock final : public runtime::Clock {
 public:
  double now() const override { return now_; }
  void show(double display_seconds) {
    if (first_ < 0) first_ = display_seconds;
    now_ = std::max(now_, display_seconds - first_);
  }

 private:
  double first_ = -1, now_ = 0;
};

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

uint32_t state_bit(xr::State s) { return 1u << unsigned(s); }

std::string states_text(uint32_t seen) {
  std::string out;
  for (xr::State s : {xr::State::Idle, xr::State::Ready, xr::State::Synchronized, xr::State::Visible, xr::State::Focused,
                      xr::State::Stopping, xr::State::LossPending, xr::State::Exiting}) {
    if (!(seen & state_bit(s))) continue;
    if (!out.empty()) out += ", ";
    out += xr::to_string(s);
  }
  return out;
}

// What the controllers asked for this frame: play or pause, step, the LOD level.
void apply_commands(const xr::Commands& c, runtime::Player& player, render::LodOptions& lod) {
  if (c.toggle_play) player.state() == runtime::PlayerState::Playing ? player.pause() : player.play();
  if (c.step != 0) player.step(c.step);
  if (c.lod_delta != 0) {
    lod.level = std::clamp(lod.level + c.lod_delta, 0.02f, 1.0f);
    if (lod.mode == render::LodMode::Off && lod.level < 1) lod.mode = render::LodMode::DensityPreserving;
  }
}

// Both eyes recorded into the frame's command buffer: in one pass into an
// array swapchain, else one record() per eye.
render::FrameSync record_eyes(stream::Stream& stream, const xr::Frame& frame,
                              const std::array<render::View, 2>& views) {
  if (frame.stereo) return stream.record(frame.command_buffer, frame.stereo_target, views);
  render::FrameSync sync;
  for (size_t e = 0; e < 2; ++e) sync = stream.record(frame.command_buffer, frame.eyes[e].target, std::span(&views[e], 1));
  return sync;
}

void report_xr(uint64_t drawn, double elapsed, const xr::SessionCounters& n, const runtime::PlaybackStats& s,
               const std::vector<double>& gpu_ms, bool array_swapchain) {
  std::printf("xr: %llu frames drawn in %s (%s frames/s), %llu ended, %llu with a stereo projection layer, %llu with depth; "
              "states: %s\n",
              (unsigned long long)drawn, human_duration(elapsed).c_str(), fixed(double(drawn) / std::max(elapsed, 1e-9), 1).c_str(),
              (unsigned long long)n.frames, (unsigned long long)n.projection_layers, (unsigned long long)n.depth_layers,
              states_text(n.states_seen).c_str());
  std::printf("  %llu media frames shown; stalls %llu, drops %llu, errors %llu; GPU %s ms (median) per %s\n",
              (unsigned long long)s.frames_shown, (unsigned long long)s.stalls, (unsigned long long)s.drops,
              (unsigned long long)s.errors, fixed(median(gpu_ms), 2).c_str(),
              array_swapchain ? "frame (both eyes in one pass)" : "eye");
}

void run_xr(const XrOptions& o) {
  const PlayOptions& p = o.play;
  xr::SessionOptions so;
  so.validation = o.view.validation;
  so.quiet_validation = p.quiet;
  so.depth = !o.no_depth;
  so.floor = o.local ? xr::Floor::Local : xr::Floor::Stage;
  xr::Session session(so);
  const xr::SystemInfo& sys = session.system();
  if (!p.quiet) {
    std::fprintf(stderr, "xr: %s, %s; %ux%u per eye on %s; %s swapchain%s; %s space\n", sys.runtime.c_str(), sys.system.c_str(),
                 sys.eye_width[0], sys.eye_height[0], session.context().device().name.c_str(),
                 sys.array_swapchain ? "one array" : "per-eye", sys.depth_layer ? " with depth" : "",
                 sys.floor == xr::Floor::Stage ? "STAGE" : "LOCAL");
  }

  // The session submits without the context's queue lock: frames are
  // relayed only where the relay has a queue of its own.
  DisplayClock clock;
  stream::StreamOptions sopts = stream_options(p, o.view, true);
  sopts.renderer.frames_in_flight = xr::Session::kRecordsInFlight;  // one record() per eye
  sopts.queue_lock = stream::QueueLock::HostDoesNot;
  sopts.clock = &clock;
  stream::Stream stream(session.context(), p.file, sopts);
  const render::SceneInfo& scene = stream.scene();
  if (!p.quiet) {
    std::fprintf(stderr, "xr: particles as %s\n", particles_text(sopts.renderer, stream.reader(), 0).c_str());
  }
  o.view.apply_environment(stream.renderer());
  render::LodOptions lod = o.view.lod_options();
  stream.set_look(o.view.fluid_options(scene), lod);
  runtime::Player& player = stream.player();
  xr::PlacementOptions placement;
  placement.size = o.size;
  xr::Controls controls(xr::initial_placement(scene, sys.floor, placement));
  if (!p.paused) player.play();

  uint64_t drawn = 0, ended = 0;
  FrameErrors errors;
  bool exit_asked = false;
  double last_display = -1;
  std::vector<double> gpu_ms;
  uint64_t last_stats = UINT64_MAX;
  const auto start = std::chrono::steady_clock::now();
  while (session.poll()) {
    if (!session.running()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));  // IDLE: the runtime is not ready for frames
      continue;
    }
    xr::Frame frame = session.begin_frame();
    clock.show(frame.display_seconds);
    const double dt = last_display < 0 ? 0 : frame.display_seconds - last_display;
    last_display = frame.display_seconds;
    const xr::Commands c = controls.update(frame.actions, dt);
    apply_commands(c, player, lod);
    std::array<render::View, 2> views;
    if (frame.render) {
      for (size_t e = 0; e < 2; ++e) {
        const xr::Eye& eye = frame.eyes[e];
        views[e] = xr::eye_view(eye.pose, eye.fov, controls.placement(), so.near, so.far, eye.viewport);
      }
      // Both eyes' demand, with a margin for head motion until the frames
      // read now are shown.
      stream.set_views(views);
    }
    stream.set_look(stream.fluid(), lod);
    stream.update();
    errors.drain(player);
    session.end_frame(frame, frame.render ? record_eyes(stream, frame, views) : render::FrameSync{});
    if (frame.render) ++drawn;
    ++ended;
    const render::FrameStats stats = stream.renderer().last_stats();
    if (stats.record_index != last_stats && stats.particles > 0) {
      gpu_ms.push_back(stats.gpu_ms);
      last_stats = stats.record_index;
    }
    if (o.frames > 0 && ended >= o.frames && !exit_asked) {
      session.request_exit();
      exit_asked = true;
    }
    const auto state = player.state();
    if (!exit_asked && (state == runtime::PlayerState::Ended || state == runtime::PlayerState::Stopped)) {
      session.request_exit();
      exit_asked = true;
    }
  }
  errors.print_unshown();
  report_xr(drawn, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), session.counters(),
            player.stats(), gpu_ms, sys.array_swapchain);
  if (so.validation && session.validation_errors() > 0) {
    std::fprintf(stderr, "sluice: %llu Vulkan validation errors\n", (unsigned long long)session.validation_errors());
    throw ExitCode{1};
  }
}

}  // namespace

void add_xr(CLI::App& app) {
  auto o = std::make_shared<XrOptions>();
  CLI::App* cmd = app.add_subcommand("xr", "Show a sequence in a headset through OpenXR (stereo, controllers)");
  cmd->footer("Examples:\n"
              "  sluice xr run.sluice                          # loops; the data stands on the floor in front of you\n"
              "  sluice xr out/run.pvd --size 3                # anything `play` takes; 3 m across at first\n"
              "  XR_RUNTIME_JSON=/path/openxr_monado.json sluice xr run.sluice --frames 100   # a scripted run\n"
              "Controllers (Touch, Index, Vive, or the simple profile): squeeze (select) grabs: one hand moves and\n"
              "turns the fluid, two hands also scale it; A/X (menu) plays and pauses; the stick or trackpad\n"
              "scrubs left/right and changes the level of detail up/down. The OpenXR runtime picks the GPU and\n"
              "the views; the look options are `render`'s.");
  add_input_options(*cmd, "file", o->play.file, o->play.no_cache);
  cmd->add_option("--frames", o->frames, "End the session after this many frames (scripted runs)");
  cmd->add_option("--size", o->size, "Metres the data's largest extent spans at first")->capture_default_str();
  cmd->add_flag("--local", o->local, "Use the LOCAL space (seated) even where STAGE exists");
  cmd->add_flag("--no-depth", o->no_depth, "Do not submit depth to the compositor");
  cmd->add_option("--fps", o->play.fps, "Media frame rate (default: the file's, else 30)");
  cmd->add_option("--rate", o->play.rate, "Playback rate; negative plays in reverse")->capture_default_str();
  cmd->add_flag("--once", o->play.once, "Stop at the last frame and end the session (default: loop)");
  cmd->add_flag("--bounce", o->play.bounce, "Turn around at either end");
  cmd->add_flag("--paused", o->play.paused, "Start paused");
  cmd->add_option("--start", o->play.start, "First frame")->capture_default_str();
  add_layers_option(*cmd, o->play.layers);
  add_decode_option(*cmd, o->play.decode);
  cmd->add_option("--memory", o->play.memory, "Cap on the memory the prefetch window uses, e.g. 8G");
  cmd->add_flag("-q,--quiet", o->play.quiet, "Only the summary");
  add_view_options(*cmd, o->view);
  // The headset sets the views and the runtime picks the GPU.
  for (const char* name : {"--camera", "--fov", "--device"}) cmd->remove_option(cmd->get_option(name));
  cmd->callback([o] {
    const PlayableFile input = open_playable(o->play.file, {o->play.no_cache, o->play.quiet});
    XrOptions x = *o;
    x.play.source = o->play.file;
    x.play.file = input.path();
    run_xr(x);
  });
}

}  // namespace sluice::app
