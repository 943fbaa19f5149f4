// `sluice bench live` (see live_bench.h).
#include "sluice/bench/live_bench.h"

#include <algorithm>
#include <chrono>
#include <cstdio>

#include "machine.h"
#include "sluice/bench/synth.h"
#include "sluice/stream/live_source.h"
#include "sluice/render/offscreen.h"
#include "sluice/bench/table.h"

namespace sluice::bench {

void run_live_bench(const LiveBenchOptions& o) {
  render::ContextOptions co;
  co.device = o.device;
  render::Context context(co);
  Table table({"particles", "encode ms", "encode Mp/s", "decode ms", "upload ms (GPU)", "render ms (GPU)", "push to drawn ms",
               "frames/s"});
  for (const uint64_t n : o.sizes) {
    std::fprintf(stderr, "generating %d frames of %s particles...\n", o.frames, count_name(n).c_str());
    SynthOptions so;
    so.particles = n;
    so.frames = uint64_t(std::max(o.frames, 1));
    const std::unique_ptr<import::FrameSource> source = synthetic_source(so);
    std::vector<io::ParticleFrame> frames;
    for (uint64_t f = 0; f < so.frames; ++f) frames.push_back(source->read(f));
    render::Bounds bounds{{1e30f, 1e30f, 1e30f}, {-1e30f, -1e30f, -1e30f}};
    for (const io::ParticleFrame& f : frames) {
      for (size_t i = 0; i < f.positions.size(); i += 3) {
        for (int a = 0; a < 3; ++a) {
          bounds.min[a] = std::min(bounds.min[a], f.positions[i + size_t(a)]);
          bounds.max[a] = std::max(bounds.max[a], f.positions[i + size_t(a)]);
        }
      }
    }
    stream::LiveOptions lo;
    lo.particle_spacing = so.spacing;
    lo.frame_rate = so.frame_rate;
    lo.record = o.record;
    render::Renderer renderer(context, stream::live_scene(bounds, lo, {}, n));
    stream::LiveSource live(renderer, lo);
    render::OffscreenTarget target(context, o.width, o.height, {1, false, false});
    const render::Camera camera = render::Camera::framing(bounds, render::Vec3{0, 0, 1}, float(o.width) / float(o.height));
    render::FluidOptions fluid;
    std::vector<double> encode, decode, upload, draw, total;
    for (int pass = 0; pass < 4; ++pass) {  // the first pass warms up
      for (const io::ParticleFrame& f : frames) {
        const auto t0 = std::chrono::steady_clock::now();
        renderer.wait_upload(live.push({f.positions, f.ids, {}, f.time}));
        const double wall = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        const render::FrameStats stats = target.render(renderer, camera, fluid, {});
        if (pass == 0) continue;
        encode.push_back(live.last_encode_ms());
        decode.push_back(live.last_decode_ms());
        upload.push_back(stats.upload_ms);
        draw.push_back(stats.gpu_ms);
        total.push_back(wall);
      }
    }
    live.finish();
    const double e = median(encode), t = median(total);
    table.row({count_name(n), fixed(e, 1), fixed(double(n) / (e * 1e3), 1), fixed(median(decode), 1), fixed(median(upload), 2),
               fixed(median(draw), 2), fixed(t, 1), fixed(1e3 / t, 1)});
  }
  std::printf(
      "sluice bench live: frames pushed from memory through stream::LiveSource (encode on %u cores, decode into "
      "staging, copy), medians of %d pushes after a warm-up; %s\ndevice: %s (%s); host: %s\n\n",
      unsigned(core_count()), 3 * o.frames, o.record.empty() ? "not recorded" : ("recorded to " + o.record).c_str(),
      context.device().name.c_str(), context.device().driver.c_str(), cpu_model().c_str());
  table.print("Per pushed frame ('push to drawn' is the push() call plus waiting for its copy; 'render' is after it)");
}

}  // namespace sluice::bench
