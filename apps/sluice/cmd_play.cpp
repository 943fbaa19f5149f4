// `sluice play FILE`: plays through the streaming pipeline, in a window
// (cmd_play_window.cpp) or, with --headless, into a null sink in real time,
// saying how it went (stats as it plays with --stats, a summary at the end).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <thread>

#include "commands.h"
#include "frame_errors.h"
#include "play.h"
#include "playable.h"
#include "human.h"
#if SLUICE_WITH_RENDER
#include "decode_option.h"
#endif
#include "layers_option.h"
#include "sluice/io/reader.h"
#include "sluice/runtime/player.h"

namespace sluice::app {
namespace {

std::string rate_text(double bytes, double seconds) { return human_bytes(seconds > 0 ? bytes / seconds : 0) + "/s"; }

// Average decode speed of a busy worker, and how busy they were.
std::pair<double, double> worker_figures(const runtime::PipelineRates& r) {
  double speed = 0, busy = 0;
  const double n = double(std::max<size_t>(1, r.worker_decode_mbps.size()));
  for (size_t w = 0; w < r.worker_decode_mbps.size(); ++w) {
    speed += r.worker_decode_mbps[w] / n;
    busy += r.worker_busy[w] / n;
  }
  return {speed * 1e6, busy};
}

void print_stats_line(const runtime::PlaybackStats& now, const runtime::PlaybackStats& before, uint64_t frames,
                      double elapsed) {
  const runtime::PipelineRates r = runtime::rates_between(before.pipeline, now.pipeline);
  const auto [speed, busy] = worker_figures(r);
  const double shown = r.seconds > 0 ? double(now.frames_shown - before.frames_shown) / r.seconds : 0;
  std::fprintf(stderr,
               "%7.1f s  frame %llu/%llu  %s  %5.1f fps  stalls %llu  drops %llu  errors %llu  window %u/%u  ready %u  "
               "read %s  decode %s (%zu workers %s, %.0f%% busy)\n",
               elapsed, (unsigned long long)now.frame + 1, (unsigned long long)frames, runtime::state_name(now.state), shown,
               (unsigned long long)now.stalls, (unsigned long long)now.drops, (unsigned long long)now.errors,
               now.pipeline.active_frames, now.pipeline.window_frames, now.pipeline.frames_ready, rate_text(r.read_mbps * 1e6, 1).c_str(),
               rate_text(r.decode_mbps * 1e6, 1).c_str(), r.worker_decode_mbps.size(), rate_text(speed, 1).c_str(),
               100 * busy);
}

void print_window_change(const runtime::WindowChange& c) {
  std::fprintf(stderr, "window: %u frames%s (limited by %s; host budget %s, %u record buffers)%s\n", c.plan.frames,
               c.previous_frames ? (" (was " + std::to_string(c.previous_frames) + ")").c_str() : "",
               c.plan.limited_by.c_str(), human_bytes(double(c.plan.host_budget)).c_str(), c.plan.record_buffers,
               c.plan.over_budget ? ": over budget, two frames do not fit" : "");
}

void run_play_headless(const PlayOptions& o) {
  const io::ContainerReader reader(o.file);
  if (reader.frame_count() == 0) throw std::runtime_error(o.file + ": no frames to play");
  const runtime::PlayerOptions po = player_options(o, false);
  runtime::HostFrameAllocator allocator;  // the null sink's frames live in host memory
  const runtime::SteadyClock clock;
  runtime::Player player(reader, allocator, clock, po);
  const double display_hz = o.display_hz > 0 ? o.display_hz : player.frame_rate() * std::max(std::abs(po.rate), 1e-3);
  if (!o.quiet) {
    std::fprintf(stderr, "playing %s: %llu frames at %.4g fps x %.3g, display %.4g Hz, %s, %s, %s\n", o.file.c_str(),
                 (unsigned long long)reader.frame_count(), player.frame_rate(), po.rate, display_hz,
                 runtime::end_mode_name(po.end), o.policy == "skip" ? "skip to the newest frame" : "hold the last frame",
                 player.pipeline().io_mode().c_str());
  }

  using Steady = std::chrono::steady_clock;
  const auto period = std::chrono::duration_cast<Steady::duration>(std::chrono::duration<double>(1.0 / display_hz));
  const auto start = Steady::now();
  auto next_tick = start;
  double next_stats = o.stats_every;
  runtime::PlaybackStats last = player.stats();
  FrameErrors errors;
  player.play();
  while (true) {
    player.update();  // the null sink: a new frame would be drawn here
    errors.drain(player);
    const double elapsed = std::chrono::duration<double>(Steady::now() - start).count();
    if (o.stats && elapsed >= next_stats) {
      const runtime::PlaybackStats now = player.stats();
      print_stats_line(now, last, reader.frame_count(), elapsed);
      last = now;
      next_stats += o.stats_every;
    }
    const runtime::PlayerState state = player.state();
    if (state == runtime::PlayerState::Ended || state == runtime::PlayerState::Stopped) break;
    if (o.seconds > 0 && elapsed >= o.seconds) break;
    next_tick += period;
    const auto now = Steady::now();
    if (next_tick < now - period) next_tick = now;  // far behind (a slow tick): do not burst to catch up
    std::this_thread::sleep_until(next_tick);       // pacing, like a display's vsync
  }

  errors.print_unshown();
  const double elapsed = std::chrono::duration<double>(Steady::now() - start).count();
  const runtime::PlaybackStats s = player.stats();
  runtime::PipelineStats zero;
  zero.workers.resize(s.pipeline.workers.size());
  runtime::PipelineStats at_end = s.pipeline;
  at_end.elapsed_seconds = elapsed;
  const runtime::PipelineRates r = runtime::rates_between(zero, at_end);
  const auto [speed, busy] = worker_figures(r);
  std::printf("played %s: %llu frames shown in %s (%s frames/s, media at %.4g fps x %.3g), %s\n", o.file.c_str(),
              (unsigned long long)s.frames_shown, human_duration(elapsed).c_str(),
              fixed(double(s.frames_shown) / elapsed, 1).c_str(), player.frame_rate(), po.rate, runtime::state_name(s.state));
  std::printf("  stalls %llu, drops %llu, errors %llu, frames served from memory %llu\n", (unsigned long long)s.stalls,
              (unsigned long long)s.drops, (unsigned long long)s.errors, (unsigned long long)s.pipeline.cache_hits);
  std::printf("  read %s at %s (%s), decoded %s at %s; %zu workers at %s each while busy, %.0f%% busy\n",
              human_bytes(double(s.pipeline.bytes_read)).c_str(), rate_text(double(s.pipeline.bytes_read), elapsed).c_str(),
              s.pipeline.io_mode.c_str(), human_bytes(double(s.pipeline.decoded_bytes)).c_str(),
              rate_text(double(s.pipeline.decoded_bytes), elapsed).c_str(), s.pipeline.workers.size(),
              rate_text(speed, 1).c_str(), 100 * busy);
  std::printf("  window %u of %u frames in use; peak memory: decoded buffers %s + compressed records %s\n",
              s.pipeline.active_frames, s.pipeline.window_frames,
              human_bytes(double(allocator.peak_held_bytes())).c_str(),
              human_bytes(double(s.pipeline.peak_record_bytes)).c_str());
  if (s.errors > 0 && s.state == runtime::PlayerState::Stopped) throw ExitCode{1};
}

}  // namespace

runtime::EndMode end_mode(const PlayOptions& o, bool window) {
  if (o.bounce) return runtime::EndMode::Bounce;
  if (o.loop) return runtime::EndMode::Loop;
  return window && !o.once ? runtime::EndMode::Loop : runtime::EndMode::Stop;
}

runtime::PlayerOptions player_options(const PlayOptions& o, bool window) {
  runtime::PlayerOptions po;
  po.frame_rate = o.fps;
  po.rate = o.reverse ? -std::abs(o.rate) : o.rate;
  po.start_frame = o.start;
  po.end = end_mode(o, window);
  po.policy = o.policy == "skip" ? runtime::RealTimePolicy::SkipToNewest : runtime::RealTimePolicy::HoldLastFrame;
  po.on_error = o.on_error == "stop" ? runtime::ErrorPolicy::Stop : runtime::ErrorPolicy::SkipFrame;
  po.pipeline.decode.threads = o.threads;
  po.pipeline.read.threads = o.read_threads;
  po.pipeline.read.direct_io = o.direct;
  po.pipeline.layers = layer_set(o.layers);
  po.pipeline.window.budget.max_frames = o.window;
  if (!o.memory.empty()) {
    const auto bytes = runtime::parse_byte_size(o.memory);
    if (!bytes) throw std::runtime_error("--memory: cannot read '" + o.memory + "' as a size (try 8G or 512M)");
    po.pipeline.window.budget.memory_cap = *bytes;
  }
  if (!o.quiet) po.pipeline.window.on_change = print_window_change;
  return po;
}

void add_play(CLI::App& app) {
  auto o = std::make_shared<PlayOptions>();
  CLI::App* cmd = app.add_subcommand("play", "Play a .sluice file as liquid in a window, or headless into a null sink");
  cmd->footer("Examples:\n"
              "  sluice play run.sluice                                   # a window; loops; H hides the HUD\n"
              "  sluice play out/run.pvd                                  # converted once into out/.sluice-cache/\n"
              "  sluice play --headless --stats run.sluice --loop --seconds 30\n"
              "Frames stream through the prefetch pipeline (read ahead, decoded on every core) at the file's frame\n"
              "rate; a late frame is held (--policy hold) or skipped (--policy skip). Headless playback feeds a null\n"
              "sink and reports stalls, drops and throughput.");
  add_input_options(*cmd, "file", o->file, o->no_cache);
  cmd->add_flag("--headless", o->headless, "No window: play into a null sink");
  cmd->add_flag("--stats", o->stats, "Print stream stats every second");
  cmd->add_option("--fps", o->fps, "Media frame rate (default: the file's, else 30)");
  cmd->add_option("--rate", o->rate, "Playback rate; negative plays in reverse")->capture_default_str();
  cmd->add_flag("--reverse", o->reverse, "Play backwards");
  cmd->add_flag("--loop", o->loop, "Loop at the end (the window's default)");
  cmd->add_flag("--once", o->once, "Stop at the last frame (the headless default)");
  cmd->add_flag("--paused", o->paused, "Window: start paused");
  cmd->add_flag("--bounce", o->bounce, "Turn around at either end");
  cmd->add_option("--start", o->start, "First frame")->capture_default_str();
  cmd->add_option("--seconds", o->seconds, "Stop after this long (default: at the end; forever with --loop)");
  cmd->add_option("--display-hz", o->display_hz, "Refreshes per second of the null display (default: one per frame)");
  cmd->add_option("--policy", o->policy, "When a frame is late: hold (the last frame) or skip (to the newest)")
      ->capture_default_str()
      ->check(CLI::IsMember({"hold", "skip"}));
  cmd->add_option("--on-error", o->on_error, "A frame that cannot be read: skip it, or stop")
      ->capture_default_str()
      ->check(CLI::IsMember({"skip", "stop"}));
  add_layers_option(*cmd, o->layers);
#if SLUICE_WITH_RENDER
  add_decode_option(*cmd, o->decode);
#endif
  cmd->add_option("--memory", o->memory, "Cap on the memory the prefetch window uses, e.g. 8G");
  cmd->add_option("--window", o->window, "Cap on the prefetch window, in frames");
  cmd->add_option("-t,--threads", o->threads, "Decode workers (default: all cores but one per 4 kept for reading)");
  cmd->add_option("-r,--read-threads", o->read_threads, "Threads reading a record (default: one per 4 cores, 1 to 4, or thirteen sixteenths of the cores, 1 to 13, when the GPU decodes; a quarter of --threads when that is given)");
  cmd->add_flag("--direct", o->direct, "Read with O_DIRECT (bypass the page cache) where the filesystem allows");
  cmd->add_option("--stats-every", o->stats_every, "Seconds between stats lines")->capture_default_str();
  cmd->add_flag("-q,--quiet", o->quiet, "Only the summary");
#if SLUICE_WITH_WINDOW
  std::shared_ptr<WindowPlayOptions> w = add_window_play_options(*cmd);
  cmd->callback([o, w] {
    const PlayableFile input = open_playable(o->file, {o->no_cache, o->quiet});
    PlayOptions p = *o;
    p.source = o->file;
    p.file = input.path();
    if (p.headless && w->gpu) run_play_gpu(p, *w);
    else if (p.headless) run_play_headless(p);
    else run_play_window(p, *w);
  });
#else
  cmd->callback([o] {
    if (!o->headless) {
      throw std::runtime_error("this sluice was built without a window (it needs libglfw3-dev, libimgui-dev and "
                               "Vulkan): pass --headless to play into a null sink");
    }
    const PlayableFile input = open_playable(o->file, {o->no_cache, o->quiet});
    PlayOptions p = *o;
    p.source = o->file;
    p.file = input.path();
    run_play_headless(p);
  });
#endif
}

#if SLUICE_WITH_RENDER
stream::StreamOptions stream_options(const PlayOptions& o, const ViewSettings& v, bool window) {
  stream::StreamOptions so;
  so.player = player_options(o, window);
  so.layers = layer_set(o.layers);
  so.decode = decode_site(o.decode);
  so.up = v.up_override();
  render::apply_particles(v.particles, so.renderer);
  return so;
}
#endif

}  // namespace sluice::app
