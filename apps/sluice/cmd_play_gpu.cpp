// `sluice play --headless --gpu FILE`: playback through the renderer without a
// window. The same path as the window player (runtime::Player -> FrameFeed ->
// Renderer::record), into an OffscreenTarget with two frames in flight, so
// uploads of the next frame overlap rendering of the current one. Reports,
// per new frame: the interval between new frames (wall), the GPU time of the
// frame's render and of its upload copy.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <thread>

#include "commands.h"
#include "frame_errors.h"
#include "human.h"
#include "play.h"
#include "reads_text.h"
#include "sluice/render/offscreen.h"
#include "sluice/stream/stream.h"
#include "view_options.h"

namespace sluice::app {
namespace {

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// What a GPU playback measured, per new frame after the first pass.
struct GpuPlayTally {
  std::vector<double> intervals, render_ms, upload_ms, decode_ms;
  uint64_t ticks = 0, new_frames = 0;
};

// The closing report of `play --headless --gpu`.
void report(const PlayOptions& o, bool gpu_decode, double elapsed, const runtime::PlaybackStats& s, const GpuPlayTally& t) {
  const double frame = median(t.intervals), draw = median(t.render_ms), copy = median(t.upload_ms), decode = median(t.decode_ms);
  std::printf("played %s through the renderer: %llu new frames in %s (%s frames/s), %llu refreshes; stalls %llu, "
              "drops %llu, errors %llu, frames served from memory %llu\n",
              o.file.c_str(), (unsigned long long)t.new_frames, human_duration(elapsed).c_str(),
              fixed(double(t.new_frames) / elapsed, 1).c_str(), (unsigned long long)t.ticks, (unsigned long long)s.stalls,
              (unsigned long long)s.drops, (unsigned long long)s.errors, (unsigned long long)s.pipeline.cache_hits);
  std::printf("  %s\n", reads_text(s.pipeline).c_str());
  if (gpu_decode) {
    std::printf("  frames relayed to device memory as read (the window in device memory): %llu of %llu read\n",
                (unsigned long long)s.pipeline.frames_relayed, (unsigned long long)s.pipeline.frames_read);
  }
  if (t.intervals.empty()) {
    std::printf("  (play more than one pass over the file, e.g. --loop --seconds 10, for per-frame medians)\n");
    return;
  }
  std::printf("  per new frame after the first pass (medians of %zu): interval %s ms, GPU render %s ms, GPU upload copy %s ms, "
              "GPU decode %s ms (%s)\n",
              t.intervals.size(), fixed(frame, 2).c_str(), fixed(draw, 2).c_str(), fixed(copy, 2).c_str(), fixed(decode, 2).c_str(),
              gpu_decode ? "frames decoded on the GPU" : "frames decoded on the CPU");
  std::printf("  interval / (render + upload) = %s; interval / max(render, upload) = %s (1.0: the copy is hidden "
              "behind rendering or the other way round)\n",
              fixed(frame / std::max(draw + copy, 1e-9), 2).c_str(), fixed(frame / std::max(std::max(draw, copy), 1e-9), 2).c_str());
}

}  // namespace

void run_play_gpu(const PlayOptions& o, const WindowPlayOptions& w) {
  const auto [width, height] = parse_size(w.size);
  const ViewSettings& v = w.view;
  render::Context context(v.context_options());
  constexpr uint32_t kInFlight = 2;
  stream::StreamOptions so = stream_options(o, v, false);
  so.renderer.frames_in_flight = kInFlight;
  so.motion = stream::ViewMotion::Fixed;  // the camera stays where it is: frames hold what it draws
  stream::Stream stream(context, o.file, so);
  const io::ContainerReader& reader = stream.reader();
  v.apply_environment(stream.renderer());
  stream.set_look(v.fluid_options(stream.scene()), v.lod_options());
  const render::Camera camera = v.camera(stream.scene(), float(width) / float(height));
  render::OffscreenOptions oo;
  oo.frames_in_flight = kInFlight;
  oo.read_back = false;
  render::OffscreenTarget target(context, width, height, oo);
  const render::View view = render::camera_view(camera, {0, 0, width, height});
  stream.set_views({&view, 1});
  runtime::Player& player = stream.player();
  const bool gpu_decode = stream.decodes_on_gpu();
  const double display_hz = o.display_hz > 0 ? o.display_hz : player.frame_rate() * std::max(std::abs(o.rate), 1e-3);
  if (!o.quiet) {
    std::fprintf(stderr,
                 "playing %s through the renderer on %s (%s) at %ux%u: %llu frames at %.4g fps, display %.4g Hz, %s; "
                 "frames decoded on the %s; particles as %s\n",
                 o.file.c_str(), context.device().name.c_str(), context.device().type.c_str(), width, height,
                 (unsigned long long)reader.frame_count(), player.frame_rate(), display_hz,
                 runtime::end_mode_name(so.player.end), gpu_decode ? "GPU" : "CPU",
                 particles_text(so.renderer, reader, 0).c_str());
  }

  using Steady = std::chrono::steady_clock;
  const auto period = std::chrono::duration_cast<Steady::duration>(std::chrono::duration<double>(1.0 / display_hz));
  const auto start = Steady::now();
  auto next_tick = start;
  std::optional<Steady::time_point> last_new;
  std::vector<double> intervals, render_ms, upload_ms, decode_ms;
  uint64_t last_stats_frame = UINT64_MAX, ticks = 0, new_frames = 0;
  FrameErrors errors;
  double next_stats = o.stats_every;
  player.play();
  while (true) {
    const stream::FeedUpdate fed = stream.update();
    errors.drain(player);
    const render::FrameStats stats = target.render(stream.renderer(), camera, stream.fluid(), stream.lod());
    ++ticks;
    const auto now = Steady::now();
    if (fed.changed) {
      ++new_frames;
      // The first loop over the file warms up (first decode, shader JIT).
      if (last_new && new_frames > reader.frame_count()) {
        intervals.push_back(std::chrono::duration<double, std::milli>(now - *last_new).count());
      }
      last_new = now;
    }
    // Figures come back frames_in_flight frames later: take each frame's once.
    if (stats.record_index != last_stats_frame && stats.particles > 0 && new_frames > reader.frame_count()) {
      render_ms.push_back(stats.gpu_ms);
      upload_ms.push_back(stats.upload_ms);
      decode_ms.push_back(stats.decode_ms);
      last_stats_frame = stats.record_index;
    }
    const double elapsed = std::chrono::duration<double>(now - start).count();
    if (o.stats && elapsed >= next_stats) {
      std::fprintf(stderr, "%7.1f s  frame %llu  new frames %llu  render %.2f ms  upload %.2f ms  decode %.2f ms (GPU); %s\n",
                   elapsed, (unsigned long long)fed.frame, (unsigned long long)new_frames, stats.gpu_ms, stats.upload_ms,
                   stats.decode_ms, reads_text(player.stats().pipeline).c_str());
      next_stats += o.stats_every;
    }
    const runtime::PlayerState state = player.state();
    if (state == runtime::PlayerState::Ended || state == runtime::PlayerState::Stopped) break;
    if (o.seconds > 0 && elapsed >= o.seconds) break;
    next_tick += period;
    if (next_tick < now - period) next_tick = now;
    std::this_thread::sleep_until(next_tick);
  }
  target.finish();
  errors.print_unshown();
  if (context.validation_active() && context.validation_errors() > 0) {
    std::fprintf(stderr, "sluice: %llu Vulkan validation errors\n", (unsigned long long)context.validation_errors());
    throw ExitCode{1};
  }
  report(o, gpu_decode, std::chrono::duration<double>(Steady::now() - start).count(), player.stats(),
         {std::move(intervals), std::move(render_ms), std::move(upload_ms), std::move(decode_ms), ticks, new_frames});
}

}  // namespace sluice::app
