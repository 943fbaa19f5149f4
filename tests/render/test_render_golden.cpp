// Golden images of the bundled PySPH dam break (converted at test time) from
// three viewpoints, 320x240, compared with committed PNGs: PSNR must reach
// kMinPsnr dB. Regenerate the references (after an intended change of the
// look) with SLUICE_UPDATE_GOLDEN=1 (the run then fails, so an update is
// never taken for a pass); the images of the last run are kept in the test
// temp folder as *_actual.png either way.
#include <gtest/gtest.h>

#include <cmath>

#include <filesystem>

#include "render_test_util.h"
#include "sample_file.h"
#include "sluice/io/reader.h"
#include "sluice/render/image_io.h"
#include "sluice/render/renderer.h"
#include "sluice/render/load.h"

namespace sluice::render {
namespace {

namespace fs = std::filesystem;
using testing::context;
using testing::ValidationGuard;

// Same lavapipe build: identical but for the order of additive thickness
// (atomic compaction); other CPUs or Mesa versions differ a little more.
constexpr double kMinPsnr = 38.0;

struct Golden {
  const char* name;
  uint64_t frame;
  const char* camera;  // empty: the default framing
  const char* display;
  bool color_by_rho;
};

const Golden kGoldens[] = {
    {"dam_default_f12", 12, "", "transparent", false},
    {"dam_low_f6", 6, "eye=2.6,-1.2,0.45;target=0.7,0,0.22;up=0,0,1;fov=45", "transparent", false},
    {"dam_top_rho_f12", 12, "eye=0.8,-0.25,2.6;target=0.8,0,0.2;up=0,1,0;fov=40", "opaque", true},
};

void PrintTo(const Golden& g, std::ostream* os) { *os << g.name; }

class GoldenImage : public ::testing::TestWithParam<Golden> {};

TEST_P(GoldenImage, MatchesReference) {
#if !SLUICE_WITH_VTK
  GTEST_SKIP() << "needs the VTK importer to convert the sample";
#endif
  ValidationGuard guard;
  const Golden& g = GetParam();
  const io::ContainerReader reader(testing::sample_file());
  const SceneInfo scene = scene_info(reader);
  testing::OffscreenRenderer r(context(), scene, 320, 240);
  FluidOptions o;
  o.display_mode = parse_display_mode(g.display);
  o.scalar_visibility = g.color_by_rho;
  o.colormap = Colormap::Turbo;
  sluice::render::load_frame(r, reader, g.frame, g.color_by_rho ? 0 : -1);
  Camera cam = Camera::framing(scene.bounds, Vec3{0, 0, 1}, 320.0f / 240.0f);
  if (*g.camera) cam.apply(g.camera);
  const FrameStats stats = r.render(cam, o, {});
  EXPECT_EQ(stats.particles, 9360u);
  EXPECT_GT(stats.drawn, 9000u);
  const Image actual{320, 240, r.read_rgba8()};
  // Beside the test's other temporary files, not in the working directory.
  const fs::path actual_path = fs::path(::testing::TempDir()) / (std::string(g.name) + "_actual.png");
  write_png(actual_path.string(), actual);
  const fs::path reference = fs::path(SLUICE_GOLDEN_DIR) / (std::string(g.name) + ".png");
  if (std::getenv("SLUICE_UPDATE_GOLDEN")) {
    // Updating is not testing: the run fails so that it is never taken for a pass.
    write_png(reference.string(), actual);
    FAIL() << "wrote " << reference << " (SLUICE_UPDATE_GOLDEN is set: run again without it to test)";
  }
  ASSERT_TRUE(fs::exists(reference)) << reference << " is missing; run with SLUICE_UPDATE_GOLDEN=1 to create it";
  const double db = psnr(read_png(reference.string()), actual);
  std::printf("%s: PSNR %.2f dB against %s\n", g.name, db, reference.c_str());
  EXPECT_GE(db, kMinPsnr) << "see " << actual_path;
}

INSTANTIATE_TEST_SUITE_P(PySPH, GoldenImage, ::testing::ValuesIn(kGoldens),
                         [](const ::testing::TestParamInfo<Golden>& p) { return std::string(p.param.name); });

}  // namespace
}  // namespace sluice::render
