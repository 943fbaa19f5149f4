// Reading by the view's demand, through the renderer: a frame read with
// only the tiers its views need draws exactly what the full read draws
// (same depth, same count drawn, same picture) for mono and stereo views,
// cLOD and density-preserving LOD, decoded on the CPU, decoded on the GPU
// and relayed into device memory; a paused player's refined frame equals
// the full read's picture. Validation on, every test.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "render_test_util.h"
#include "sluice/bench/synth.h"
#include "sluice/io/reader.h"
#include "sluice/stream/demand.h"
#include "sluice/render/inspection.h"
#include "sluice/stream/frame_feed.h"
#include "sluice/render/image_io.h"
#include "sluice/render/offscreen.h"
#include "sluice/render/staging_allocator.h"
#include "sluice/stream/stream.h"
#include "sluice/render/load.h"
#include "sluice/runtime/clock.h"
#include "sluice/runtime/player.h"

namespace sluice::render {
using namespace sluice::stream;  // the stream module under test
namespace {

namespace fs = std::filesystem;
using testing::context;
using testing::ValidationGuard;

constexpr uint32_t kW = 200, kH = 120;

// A sloshing pool of 200k particles in layers (surface, blobs, interior),
// tiered, GPU-decodable: what `sluice synth --gpu-decodable` writes.
// Written once per test program, removed when it exits.
struct PoolFile {
  fs::path path = fs::temp_directory_path() / ("sluice_demand_" + std::to_string(::getpid()) + ".sluice");
  PoolFile() {
    bench::SynthOptions o;
    o.particles = 200'000;
    o.frames = 2;
    o.output = path.string();
    o.planes = io::PlaneCoding::GpuDecodable;
    o.chunk_particles = 16384;
    bench::write_synthetic(o);
  }
  ~PoolFile() {
    std::error_code ignored;
    fs::remove(path, ignored);
  }
};

fs::path pool_file() {
  static const PoolFile file;
  return file.path;
}

struct Shot {
  std::vector<uint8_t> rgba;
  std::vector<float> depth;
  uint64_t drawn = 0;
};

struct Case {
  const char* name;
  std::vector<View> views;
  LodOptions lod;
};

std::vector<Case> cases(const SceneInfo& scene) {
  const Camera overview = Camera::framing(scene.bounds, scene.up, float(kW) / float(kH));
  Camera close = overview;
  close.target = scene.bounds.center() - Vec3{0.25f * (scene.bounds.max.x - scene.bounds.min.x), 0, 0};
  close.eye = close.target + (overview.eye - overview.target) * 0.25f;
  Camera side = overview;
  side.target = Vec3{scene.bounds.max.x, scene.bounds.center().y, scene.bounds.center().z};
  LodOptions clod, density, full;
  // Positions at full precision: these cases draw exactly what the full
  // read draws (precision by distance is PrecisionByDistance's, below).
  for (LodOptions* o : {&clod, &density, &full}) o->position_error_pixels = 0;
  clod.mode = LodMode::Clod;
  clod.level = 0.3f;
  density.mode = LodMode::DensityPreserving;
  density.level = 0.3f;
  full.mode = LodMode::Clod;
  full.level = 1.0f;
  const Viewport vp{0, 0, kW, kH};
  std::vector<View> eyes;
  for (float shift : {-0.02f, 0.02f}) {
    Camera c = overview;
    c.eye = c.eye + Vec3{shift, 0, 0};
    c.target = c.target + Vec3{shift, 0, 0};
    eyes.push_back(camera_view(c, vp));
  }
  return {{"overview, cLOD 0.3", {camera_view(overview, vp)}, clod},
          {"overview, density 0.3", {camera_view(overview, vp)}, density},
          {"close-up, cLOD 0.3", {camera_view(close, vp)}, clod},
          {"half outside, level 1", {camera_view(side, vp)}, full},
          {"stereo, cLOD 0.3", eyes, clod}};
}

Shot draw(Renderer& renderer, OffscreenTarget& target, const Case& c) {
  FluidOptions fluid;
  const FrameStats stats = target.render(renderer, c.views, fluid, c.lod);
  return {target.read_rgba8(), {}, stats.drawn};
}

// The full read: Renderer::load_frame of the surface and blobs.
Shot reference(const io::ContainerReader& reader, const SceneInfo& scene, uint64_t frame, const Case& c) {
  testing::OffscreenRenderer r(context(), scene, kW, kH);
  OffscreenTarget target(context(), kW, kH, {.layers = uint32_t(c.views.size())});
  sluice::render::load_frame(r.renderer, reader, frame, -1, io::LayerSet::surface());
  Shot s = draw(r.renderer, target, c);
  s.depth = sluice::render::read_raw_depth(r);
  return s;
}

enum class Path { Cpu, Gpu, Relayed };

// Frame `frame` through a pipeline reading by the case's demand.
Shot by_demand(const io::ContainerReader& reader, const SceneInfo& scene, uint64_t frame, const Case& c, Path path,
               runtime::PipelineStats& stats) {
  testing::OffscreenRenderer r(context(), scene, kW, kH);
  OffscreenTarget target(context(), kW, kH, {.layers = uint32_t(c.views.size())});
  StagingAllocator staging(context(), {.resident = path == Path::Relayed});
  runtime::PipelineOptions po;
  po.decode.threads = 2;
  po.layers = io::LayerSet::surface();
  po.decode.attributes = std::vector<uint32_t>{};
  po.decode.mode = (path != Path::Cpu) ? sluice::runtime::DecodeMode::KeepEncoded : sluice::runtime::DecodeMode::Cpu;
  po.demand = view_demand(c.views, scene, FluidOptions{}, c.lod, 0);
  runtime::Pipeline pipeline(reader, staging, po);
  pipeline.restart({reader.frame_count(), int64_t(frame), 1, 1, runtime::EndMode::Stop});
  EXPECT_FALSE(pipeline.wait_next().end);
  runtime::FrameHandle h = pipeline.take();
  EXPECT_FALSE(h.failed()) << (h.failed() ? h.error()->text() : "");
  if (h.failed()) return {};
  if (path == Path::Relayed) {
    EXPECT_TRUE(h.layout().resident);
    EXPECT_EQ(h.content(), runtime::FrameContent::Relayed);
  }
  r.commit(h, -1, &staging);
  Shot s = draw(r.renderer, target, c);
  s.depth = sluice::render::read_raw_depth(r);
  stats = pipeline.stats();
  return s;
}

void expect_same(const Shot& got, const Shot& want, const std::string& what) {
  EXPECT_EQ(got.drawn, want.drawn) << what << ": the cull kept other particles";
  EXPECT_EQ(got.depth, want.depth) << what << ": depth is a min over splats, bit-exact";
  const double db = psnr({kW, kH, got.rgba}, {kW, kH, want.rgba});
  EXPECT_TRUE(std::isinf(db) || db >= 60.0) << what << ": PSNR " << db;
}

TEST(DemandRender, ReadingByTheViewDrawsWhatTheFullReadDraws) {
  ValidationGuard guard;
  const io::ContainerReader reader(pool_file());
  const SceneInfo scene = scene_info(reader);
  uint64_t read = 0, whole = 0;
  for (const Case& c : cases(scene)) {
    const Shot want = reference(reader, scene, 1, c);
    EXPECT_GT(want.drawn, 1000u) << c.name;
    for (const Path path : {Path::Cpu, Path::Gpu, Path::Relayed}) {
      const std::string what = std::string(c.name) + (path == Path::Cpu ? ", CPU decode" : path == Path::Gpu ? ", GPU decode" : ", relayed");
      runtime::PipelineStats stats;
      expect_same(by_demand(reader, scene, 1, c, path, stats), want, what);
      read += stats.bytes_read;
      whole += stats.record_bytes;
      if (std::string(c.name) == "overview, cLOD 0.3") {
        EXPECT_LT(stats.bytes_read, stats.record_bytes / 4) << what << ": the overview reads a fraction";
      }
    }
  }
  EXPECT_LT(read, whole);
}

// Precision by distance (format 3.0): records far enough away are read
// without their fine parts, for fewer bytes, and at the renderer's default
// error the picture stays within 40 dB PSNR of the full read's; a coarser
// error (4x) shows what the rule trades (printed; at 200 x 120 the default
// leaves every record whole, its particles being a fraction of a pixel).
TEST(DemandRender, PrecisionByDistanceKeepsThePicture) {
  ValidationGuard guard;
  const io::ContainerReader reader(pool_file());
  const SceneInfo scene = scene_info(reader);
  const float stated = LodOptions{}.position_error_pixels;
  ASSERT_GT(stated, 0.f) << "on by default";
  for (Case c : cases(scene)) {
    const Shot want = reference(reader, scene, 1, c);
    runtime::PipelineStats exact_stats;
    by_demand(reader, scene, 1, c, Path::Gpu, exact_stats);
    for (const float error : {stated, 4 * stated}) {
      c.lod.position_error_pixels = error;
      for (const Path path : {Path::Cpu, Path::Relayed}) {
        runtime::PipelineStats stats;
        const Shot got = by_demand(reader, scene, 1, c, path, stats);
        const double db = psnr({kW, kH, got.rgba}, {kW, kH, want.rgba});
        std::printf("%s, %.2f px, %s: PSNR %.1f dB, %llu of %llu bytes (at full precision %llu), drawn %llu of %llu\n",
                    c.name, error, path == Path::Cpu ? "CPU decode" : "relayed", db, (unsigned long long)stats.bytes_read,
                    (unsigned long long)stats.record_bytes, (unsigned long long)exact_stats.bytes_read,
                    (unsigned long long)got.drawn, (unsigned long long)want.drawn);
        EXPECT_LE(stats.bytes_read, exact_stats.bytes_read) << c.name;
        if (error == stated) {
          EXPECT_TRUE(std::isinf(db) || db >= 40.0) << c.name << ": PSNR " << db;
        }
        // A coarser error reads the overview's far records coarse: fewer bytes, through the whole path.
        if (error > stated && std::string(c.name) == "overview, cLOD 0.3") {
          EXPECT_LT(stats.bytes_read, exact_stats.bytes_read);
        }
      }
    }
  }
}

// Paused on the overview at level 0.3, then level 1: the player reads the
// frame again with the tiers it lacks and the picture is the full read's.
TEST(DemandRender, APausedFrameConvergesToTheFullReadsPicture) {
  ValidationGuard guard;
  const io::ContainerReader reader(pool_file());
  const SceneInfo scene = scene_info(reader);
  const Case low = cases(scene)[0];
  Case high = low;
  high.lod.level = 1.0f;
  testing::OffscreenRenderer r(context(), scene, kW, kH);
  StagingAllocator staging(context(), FrameFeed::staging_options(context(), reader.header(), DecodeSite::Auto, true));
  runtime::PlayerOptions po;
  po.start_frame = 1;
  po.pipeline.decode.threads = 2;
  po.pipeline.layers = io::LayerSet::surface();
  FrameFeed::configure(po, staging, -1, reader.header(), DecodeSite::Auto);
  po.pipeline.demand = view_demand(low.views, scene, FluidOptions{}, low.lod, 0);
  runtime::VirtualClock clock;
  runtime::Player player(reader, staging, clock, po);
  FrameFeed feed(r.renderer, player, &staging, -1);
  const auto until = [&](auto done) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (std::chrono::steady_clock::now() < deadline) {
      player.wait_for_due();
      feed.update();
      if (done()) return true;
    }
    return false;
  };
  ASSERT_TRUE(until([&] { return player.shown() != nullptr; }));
  feed.set_views(high.views, FluidOptions{}, high.lod, 0);
  ASSERT_TRUE(until([&] { return !player.pipeline().short_of(*player.shown(), player.demand()); }));
  EXPECT_EQ(player.stats().refinements, 1u);
  r.renderer.wait_upload(feed.last().ticket);
  OffscreenTarget target(context(), kW, kH);
  Shot got = draw(r.renderer, target, high);
  got.depth = sluice::render::read_raw_depth(r);
  expect_same(got, reference(reader, scene, 1, high), "refined");
}

// stream::Stream reads for the views and look it is given: the overview at
// cLOD 0.3 reads a fraction of the records from its first frame on; the
// look alone raised to level 1 reads the paused frame again; LayerSet
// particles() reads whole.
TEST(DemandRender, AStreamReadsWhatItsViewsAndLookDraw) {
  ValidationGuard guard;
  const Case low = cases(scene_info(io::ContainerReader(pool_file())))[0];
  StreamOptions options;
  options.motion = ViewMotion::Fixed;
  options.player.pipeline.decode.threads = 2;
  Stream stream(context(), pool_file(), options);
  stream.set_look(FluidOptions{}, low.lod);
  ASSERT_TRUE(stream.reads_by_view()) << "a layered, tiered file with LOD on";
  stream.set_views(low.views);
  runtime::Player& player = stream.player();
  const auto until = [&](runtime::Player& p, Stream& s, auto done) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (std::chrono::steady_clock::now() < deadline) {
      p.wait_for_due();
      s.update();
      if (done()) return true;
    }
    return false;
  };
  ASSERT_TRUE(until(player, stream, [&] { return player.shown() != nullptr; }));
  const runtime::PipelineStats first = player.stats().pipeline;
  EXPECT_GT(first.frames_read, 0u);
  EXPECT_EQ(first.frames_by_demand, first.frames_read) << "every frame read by the view, the first too";
  EXPECT_LT(first.bytes_read, first.record_bytes / 4) << "the overview reads a fraction";
  LodOptions high = low.lod;
  high.level = 1.0f;
  stream.set_look(FluidOptions{}, high);  // the views stay: the look alone asks for more
  ASSERT_TRUE(until(player, stream, [&] { return !player.pipeline().short_of(*player.shown(), player.demand()); }));
  EXPECT_EQ(player.demand().level, 1.0f) << "the player took the new look";
  EXPECT_EQ(player.stats().refinements, 1u);

  options.layers = io::LayerSet::particles();
  Stream whole(context(), pool_file(), options);
  whole.set_look(FluidOptions{}, low.lod);
  EXPECT_FALSE(whole.reads_by_view());
  whole.set_views(low.views);
  runtime::Player& whole_player = whole.player();
  ASSERT_TRUE(until(whole_player, whole, [&] { return whole_player.shown() != nullptr; }));
  EXPECT_EQ(whole_player.stats().pipeline.frames_by_demand, 0u);
}

}  // namespace
}  // namespace sluice::render
