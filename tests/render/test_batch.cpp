// The batch recipe (Stream::show, docs/embedding.md "Drawing each frame
// once"): frames 0..12 of the bundled sample stepped to and drawn one by
// one, each picture that frame's full read (load_frame), not the one
// before. Validation on.
#include <gtest/gtest.h>

#include <cmath>

#include "render_test_util.h"
#include "sample_file.h"
#include "sluice/error.h"
#include "sluice/render/image_io.h"
#include "sluice/render/load.h"
#include "sluice/render/offscreen.h"
#include "sluice/stream/stream.h"

namespace sluice::render {
using namespace sluice::stream;  // the stream module under test
namespace {

using testing::context;
using testing::ValidationGuard;
constexpr uint32_t kW = 160, kH = 120;

TEST(Batch, ShowDrawsEachFrameOfTheSampleAsAsked) {
#if !SLUICE_WITH_VTK
  GTEST_FAIL() << "needs the VTK importer to convert the sample";
#endif
  ValidationGuard guard;
  StreamOptions options;
  options.renderer.frames_in_flight = 1;
  options.motion = ViewMotion::Fixed;
  Stream stream(context(), testing::sample_file(), options);
  const SceneInfo& scene = stream.scene();
  const View view = camera_view(Camera::framing(scene.bounds, scene.up, float(kW) / float(kH)), {0, 0, kW, kH});
  stream.set_views({&view, 1});
  OffscreenTarget shown(context(), kW, kH);  // one frame in flight: render() waits
  testing::OffscreenRenderer full(context(), scene, kW, kH);

  const uint64_t frames = stream.reader().frame_count();
  ASSERT_EQ(frames, 13u) << "the bundled sample's frames";
  Image before{kW, kH, {}};
  uint64_t told_apart = 0;
  for (uint64_t f = 0; f < frames; ++f) {
    SCOPED_TRACE("frame " + std::to_string(f));
    const FeedUpdate u = stream.show(f);
    EXPECT_EQ(u.frame, f);
    shown.render(stream.renderer(), {&view, 1}, stream.fluid(), stream.lod());
    const Image got{kW, kH, shown.read_rgba8()};
    load_frame(full.renderer, stream.reader(), f, -1, io::LayerSet::surface());
    full.target.render(full.renderer, {&view, 1}, stream.fluid(), stream.lod());
    const Image want{kW, kH, full.target.read_rgba8()};
    const double same = psnr(got, want);
    EXPECT_TRUE(std::isinf(same) || same >= 50.0) << "PSNR " << same << " against frame " << f << "'s full read";
    if (f > 0 && want.rgba != before.rgba) {
      // Frames that look different: the picture is this one's, not the last.
      EXPECT_LT(psnr(got, before), same) << "closer to frame " << f - 1 << " than to frame " << f;
      ++told_apart;
    }
    before = want;
  }
  EXPECT_GE(told_apart, 10u) << "the sample's frames should mostly differ";
  EXPECT_THROW(stream.show(frames), Error);
}

}  // namespace
}  // namespace sluice::render
