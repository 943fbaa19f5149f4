// Live frames (LiveSource): a moving ball of particles pushed from memory is
// drawn where it is, frame after frame, and the recording holds exactly the
// particles pushed (within the quantization error), their LOD values from the
// ids, and nothing of a frame that was refused.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>

#include "render_test_util.h"
#include "sluice/error.h"
#include "sluice/render/inspection.h"
#include "sluice/io/lod.h"
#include "sluice/io/reader.h"
#include "sluice/stream/live_source.h"
#include "sluice/render/offscreen.h"

namespace sluice::render {
using namespace sluice::stream;  // the stream module under test
namespace {

using testing::context;
using testing::ValidationGuard;
constexpr uint32_t kW = 160, kH = 120;

// About 4000 particles filling a ball of radius 0.3 on a jittered grid.
std::vector<float> ball(Vec3 centre, std::vector<float>* speed) {
  std::vector<float> xyz;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> jitter(-0.004f, 0.004f);
  const float h = 0.03f;
  for (int i = -10; i <= 10; ++i) {
    for (int j = -10; j <= 10; ++j) {
      for (int k = -10; k <= 10; ++k) {
        const Vec3 p{float(i) * h, float(j) * h, float(k) * h};
        if (length(p) > 0.3f) continue;
        xyz.insert(xyz.end(), {centre.x + p.x + jitter(rng), centre.y + p.y + jitter(rng), centre.z + p.z + jitter(rng)});
        speed->push_back(length(p) / 0.3f);
      }
    }
  }
  return xyz;
}

Camera front() { return testing::camera_looking_along_y(3); }

TEST(Live, AMovingBallIsDrawnWhereItIsAndRecorded) {
  ValidationGuard guard;
  const std::filesystem::path path = std::filesystem::temp_directory_path() / "sluice_live_test.sluice";
  std::filesystem::remove(path);
  LiveOptions lo;
  lo.particle_spacing = 0.03f;
  lo.frame_rate = 25;
  lo.attributes = {"speed"};
  lo.color_attribute = 0;
  lo.record = path;
  lo.encode.chunk_particles = 1024;  // several chunks, so culling and chunk order matter
  const Bounds bounds{{-1.2f, -0.5f, -0.5f}, {1.2f, 0.5f, 0.5f}};
  Renderer renderer(context(), live_scene(bounds, lo, {{0.0f, 1.0f}}));
  LiveSource live(renderer, lo);
  OffscreenTarget target(context(), kW, kH);
  FluidOptions fo;
  fo.ground = false;
  fo.particle_radius = 0.03f;

  std::vector<std::vector<float>> pushed;
  std::vector<uint64_t> ids;
  float last_column = -1;
  for (int f = 0; f < 5; ++f) {
    std::vector<float> speed;
    const Vec3 centre{-0.6f + 0.3f * float(f), 0, 0};
    pushed.push_back(ball(centre, &speed));
    const uint64_t n = pushed.back().size() / 3;
    ids.resize(n);
    for (uint64_t i = 0; i < n; ++i) ids[i] = 1000 + i;
    renderer.wait_upload(live.push({pushed.back(), ids, {speed}, 0.04 * f}));
    const FrameStats stats = target.render(renderer, front(), fo, {});
    EXPECT_EQ(stats.particles, n);
    // The fluid's pixels are centred where the ball's centre projects.
    const std::vector<float> depth = sluice::render::read_raw_depth(renderer);
    double sum = 0;
    size_t count = 0;
    for (uint32_t y = 0; y < kH; ++y) {
      for (uint32_t x = 0; x < kW; ++x) {
        if (depth[size_t(y) * kW + x] > 0) {
          sum += x + 0.5;
          ++count;
        }
      }
    }
    ASSERT_GT(count, 300u);
    const View view = camera_view(front(), {0, 0, kW, kH});
    const Vec4 clip = view.projection * (view.view * Vec4{centre.x, centre.y, centre.z, 1});
    const double expect = (clip.x / clip.w * 0.5 + 0.5) * kW;
    EXPECT_NEAR(sum / double(count), expect, 2.0) << "frame " << f;
    EXPECT_GT(sum / double(count), last_column);
    last_column = float(sum / double(count));
  }
  // A frame with a NaN is refused before anything is committed or recorded.
  std::vector<float> bad(pushed.back());
  bad[4] = std::nanf("");
  EXPECT_THROW(live.push({bad, {}, {}, 1.0}), sluice::render::Error);
  EXPECT_EQ(live.frames_pushed(), 5u);
  live.finish();

  const io::ContainerReader reader(path);
  ASSERT_EQ(reader.frame_count(), 5u);
  EXPECT_EQ(reader.header().attributes.size(), 1u);
  EXPECT_FLOAT_EQ(reader.header().frame_rate, 25.0f);
  std::vector<uint16_t> expect_lod = io::lod_values(ids, ids.size());
  std::sort(expect_lod.begin(), expect_lod.end());
  for (uint64_t f = 0; f < 5; ++f) {
    const io::DecodedFrame d = io::decode_frame(reader, f);
    const std::vector<float> got = io::world_positions(d, reader.header().position_coding);
    ASSERT_EQ(got.size(), pushed[f].size());
    // Every recorded particle lies within the quantization error of a pushed one.
    double worst = 0;
    for (size_t i = 0; i < got.size(); i += 3 * 7) {
      double best = 1e30;
      for (size_t j = 0; j < pushed[f].size(); j += 3) {
        const double dx = got[i] - pushed[f][j], dy = got[i + 1] - pushed[f][j + 1], dz = got[i + 2] - pushed[f][j + 2];
        best = std::min(best, dx * dx + dy * dy + dz * dz);
      }
      worst = std::max(worst, std::sqrt(best));
    }
    EXPECT_LT(worst, 0.03 * 1e-3) << "frame " << f << ": largest distance to a pushed particle";
    // LOD values are the ids' hashes (the same multiset every frame).
    std::vector<uint16_t> lod = io::lod_values_of(d, reader.header().position_coding);
    std::sort(lod.begin(), lod.end());
    EXPECT_EQ(lod, expect_lod) << "frame " << f;
  }
  std::filesystem::remove(path);
}

TEST(Live, RefusesInputThatDoesNotFitTheScene) {
  LiveOptions lo;
  lo.attributes = {"speed"};
  lo.ids = false;
  Renderer plain(context(), live_scene({{0, 0, 0}, {1, 1, 1}}, LiveOptions{}));
  EXPECT_THROW(LiveSource(plain, lo), sluice::render::Error);  // the scene has no attributes
  Renderer renderer(context(), live_scene({{0, 0, 0}, {1, 1, 1}}, lo));
  LiveSource live(renderer, lo);
  const std::vector<float> xyz{0.5f, 0.5f, 0.5f, 0.6f, 0.5f};
  EXPECT_THROW(live.push({xyz, {}, {}, 0}), sluice::render::Error);  // not triples
  const std::vector<float> one{0.5f, 0.5f, 0.5f};
  const std::vector<uint64_t> two_ids{1, 2};
  EXPECT_THROW(live.push({one, two_ids, {}, 0}), sluice::render::Error);  // ids on a source without them
  const std::vector<float> values{1, 2};
  EXPECT_THROW(live.push({one, {}, {values}, 0}), sluice::render::Error);
  EXPECT_NO_THROW(renderer.wait_upload(live.push({one, {}, {}, 0})));  // attributes left out: zero
  EXPECT_EQ(live.frames_pushed(), 1u);
}

}  // namespace
}  // namespace sluice::render
