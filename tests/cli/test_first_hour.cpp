// A new user's first hour, through the `sluice` command on small sequences
// written here as a solver would (CSV, no times): which way is up, what the
// time is, playing straight from what the solver wrote (the cache), and what
// progress looks like in a log.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include "cli_run.h"

namespace {

namespace fs = std::filesystem;

using sluice::cli_test::Result;

// Runs `sluice ARGS`; `both`: stderr joins stdout.
Result sluice(const std::string& args, bool both = true) { return sluice::cli_test::run_sluice(args, "", both); }

fs::path fresh_dir(const std::string& name) { return sluice::cli_test::fresh_dir("first_hour", name); }

// Where particle (along, across, height) goes for a solver whose up is
// `up` (0 x, 1 y, 2 z; negative: pointing down that axis).
std::array<double, 3> place(double along, double across, double height, int up_axis, bool negative) {
  std::array<double, 3> p{};
  p[up_axis] = negative ? -height : height;
  p[(up_axis + 1) % 3] = along;
  p[(up_axis + 2) % 3] = across;
  return p;
}

// A water column collapsing under gravity onto a floor, against a wall at
// along = 0: the top falls, the front runs out along the floor, the floor
// and the wall stay. With a hydrostatic pressure column `p` when asked.
void write_collapse(const fs::path& dir, int up_axis, bool negative, int frames, bool moving, bool pressure) {
  const double h = 0.02, width = 0.3, height = 0.5, depth = 0.2;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.1 * h, 0.1 * h);
  std::vector<std::array<double, 3>> base;
  for (double a = h / 2; a < width; a += h) {
    for (double c = h / 2; c < depth; c += h) {
      for (double z = h / 2; z < height; z += h) base.push_back({a + jitter(rng), c + jitter(rng), z + jitter(rng)});
    }
  }
  for (int f = 0; f < frames; ++f) {
    const double s = moving ? std::min(0.5, 0.008 * f * f) : 0.0;  // fraction of the height fallen
    std::ofstream out(dir / ("fluid_" + std::to_string(f) + ".csv"));
    out << "id,x,y,z" << (pressure ? ",p" : "") << "\n";
    for (size_t i = 0; i < base.size(); ++i) {
      const auto [a, c, z] = base[i];
      const double fallen = z * (1 - s), spread = a * (1 + 2 * s * (1 + z / height));
      const auto p = place(spread, c, fallen, up_axis, negative);
      out << i << ',' << p[0] << ',' << p[1] << ',' << p[2];
      if (pressure) out << ',' << 1000 * 9.81 * (height * (1 - s) - fallen);
      out << '\n';
    }
  }
}

std::string info_json(const fs::path& file) { return sluice("info --json \"" + file.string() + "\"", false).out; }

std::string convert(const fs::path& dir, const std::string& extra = "") {
  const fs::path out = dir / "out.sluice";
  const Result r = sluice("convert \"" + (dir / "fluid_*.csv").string() + "\" -o \"" + out.string() + "\" -f " + extra);
  EXPECT_EQ(r.status, 0) << r.out;
  return r.out;
}

void expect_up(const std::string& json, const std::string& up, const std::string& evidence) {
  EXPECT_NE(json.find("\"up\": \"" + up + "\""), std::string::npos) << json.substr(0, 900);
  EXPECT_NE(json.find("\"up_evidence\": \"" + evidence + "\""), std::string::npos) << json.substr(0, 900);
}

TEST(FirstHour, ZUpCollapseIsFoundFromTheFall) {
  const fs::path dir = fresh_dir("z_up");
  write_collapse(dir, 2, false, 8, true, false);
  const std::string log = convert(dir);
  EXPECT_NE(log.find("up: +z (motion)"), std::string::npos) << log;
  expect_up(info_json(dir / "out.sluice"), "+z", "motion");
}

TEST(FirstHour, YUpCollapseIsFoundFromTheFall) {
  const fs::path dir = fresh_dir("y_up");
  write_collapse(dir, 1, false, 8, true, false);
  convert(dir);
  expect_up(info_json(dir / "out.sluice"), "+y", "motion");
}

TEST(FirstHour, UpsideDownYIsFoundFromTheFall) {
  const fs::path dir = fresh_dir("minus_y");
  write_collapse(dir, 1, true, 8, true, false);
  convert(dir);
  expect_up(info_json(dir / "out.sluice"), "-y", "motion");
}

TEST(FirstHour, StillPoolIsFoundFromItsPressure) {
  const fs::path dir = fresh_dir("still_y");
  write_collapse(dir, 1, false, 3, false, true);  // a column at rest: not flat, so only the pressure tells
  convert(dir);
  expect_up(info_json(dir / "out.sluice"), "+y", "pressure");
}

TEST(FirstHour, StillLayerWithoutPressureIsFoundFromItsShape) {
  const fs::path dir = fresh_dir("still_layer");
  // A pool 1 x 0.8 wide and 0.1 deep, at rest, x-up.
  std::ofstream out(dir / "fluid_0.csv");
  out << "x,y,z\n";
  for (double a = 0; a < 0.1; a += 0.02) {
    for (double b = 0; b < 1.0; b += 0.02) {
      for (double c = 0; c < 0.8; c += 0.02) out << a << ',' << b << ',' << c << '\n';
    }
  }
  out.close();
  convert(dir);
  expect_up(info_json(dir / "out.sluice"), "+x", "shape");
}

TEST(FirstHour, GivenUpWins) {
  const fs::path dir = fresh_dir("given");
  write_collapse(dir, 2, false, 4, true, false);
  convert(dir, "--up -x");
  expect_up(info_json(dir / "out.sluice"), "-x", "given");
}

TEST(FirstHour, TimesFromFpsOrDtOrSaidToBeMissing) {
  const fs::path dir = fresh_dir("times");
  write_collapse(dir, 2, false, 5, true, false);
  std::string log = convert(dir, "--fps 50");
  std::string json = info_json(dir / "out.sluice");
  EXPECT_NE(json.find("\"time_source\": \"step\""), std::string::npos) << json.substr(0, 900);
  EXPECT_NE(json.find("\"frame_rate\": 50"), std::string::npos);
  EXPECT_NE(json.find("\"frame\": 4, \"time\": 0.08,"), std::string::npos) << json;  // 4 / 50 s

  convert(dir, "--dt 0.5");
  json = info_json(dir / "out.sluice");
  EXPECT_NE(json.find("\"frame\": 4, \"time\": 2,"), std::string::npos) << json;
  EXPECT_NE(json.find("\"frame_rate\": 30"), std::string::npos);
  const std::string text = sluice("info \"" + (dir / "out.sluice").string() + "\"").out;
  EXPECT_NE(text.find("every 0.5 s; played at 30 frames/s = 15.000x simulation speed"), std::string::npos) << text;

  log = convert(dir);
  EXPECT_NE(log.find("states no simulation times"), std::string::npos) << log;
  json = info_json(dir / "out.sluice");
  EXPECT_NE(json.find("\"time_source\": \"frame number\""), std::string::npos);
  EXPECT_NE(sluice("info \"" + (dir / "out.sluice").string() + "\"").out.find("no simulation times"), std::string::npos);
}

// Frames a headless play showed, from its summary.
bool played_all(const Result& r, int frames) {
  return r.status == 0 && r.out.find(std::to_string(frames) + " frames shown") != std::string::npos;
}

TEST(FirstHour, PlayStraightFromAGlobThroughTheCache) {
  const fs::path dir = fresh_dir("cache_glob");
  write_collapse(dir, 2, false, 4, true, false);
  const std::string glob = "\"" + (dir / "fluid_*.csv").string() + "\"";
  const std::string play = "play --headless --once --fps 200 " + glob;
  Result r = sluice(play);
  EXPECT_TRUE(played_all(r, 4)) << r.out;
  EXPECT_NE(r.out.find("converting it once into"), std::string::npos) << r.out;
  const fs::path cached = dir / ".sluice-cache" / "cache_glob_fluid.sluice";
  ASSERT_TRUE(fs::exists(cached)) << r.out;
  ASSERT_TRUE(fs::exists(cached.string() + ".key"));
  const auto written = fs::last_write_time(cached);

  r = sluice(play);  // unchanged input: the cache as it is
  EXPECT_TRUE(played_all(r, 4)) << r.out;
  EXPECT_NE(r.out.find("using its conversion"), std::string::npos) << r.out;
  EXPECT_EQ(fs::last_write_time(cached), written);

  // A solver writes another frame: the cache is refreshed and plays 5.
  write_collapse(dir, 2, false, 5, true, false);
  r = sluice(play);
  EXPECT_TRUE(played_all(r, 5)) << r.out;
  EXPECT_NE(r.out.find("converting it once into"), std::string::npos) << r.out;

  // --no-cache converts into a temporary file and leaves the cache alone.
  const auto refreshed = fs::last_write_time(cached);
  r = sluice(play + " --no-cache");
  EXPECT_TRUE(played_all(r, 5)) << r.out;
  EXPECT_NE(r.out.find("temporary file"), std::string::npos) << r.out;
  EXPECT_EQ(fs::last_write_time(cached), refreshed);
}

TEST(FirstHour, ProgressInALogIsAFewLines) {
  const fs::path dir = fresh_dir("progress");
  write_collapse(dir, 2, false, 40, true, false);
  const Result r = sluice("convert \"" + (dir / "fluid_*.csv").string() + "\" -o \"" + (dir / "out.sluice").string() + "\" -f");
  ASSERT_EQ(r.status, 0) << r.out;
  int lines = 0;
  for (size_t at = r.out.find("] "); at != std::string::npos; at = r.out.find("] ", at + 1)) {
    if (r.out.find(" frames", at) < r.out.find('\n', at)) ++lines;
  }
  EXPECT_GE(lines, 1) << r.out;
  EXPECT_LE(lines, 11) << r.out;  // a tenth at a time at most, never one per frame (40)
  EXPECT_EQ(r.out.find('\r'), std::string::npos) << "no carriage returns in a log";
}

#if SLUICE_WITH_VTK
TEST(FirstHour, RenderStraightFromAPvd) {
  const fs::path dir = fresh_dir("cache_pvd");
  for (const auto& e : fs::directory_iterator(SLUICE_SAMPLE_DIR)) fs::copy(e.path(), dir / e.path().filename());
  const std::string render = "render \"" + (dir / "dam_break_3d.pvd").string() + "\" --frames 12 --size 96x64 --out \"" +
                             (dir / "shot.png").string() + "\"";
  Result r = sluice(render);
  ASSERT_EQ(r.status, 0) << r.out;
  EXPECT_TRUE(fs::exists(dir / "shot.png"));
  EXPECT_TRUE(fs::exists(dir / ".sluice-cache" / "dam_break_3d.sluice"));
  r = sluice(render + " --force");  // an image there: render asks before it overwrites
  EXPECT_EQ(r.status, 0) << r.out;
  EXPECT_NE(r.out.find("using its conversion"), std::string::npos) << r.out;
}
#endif

}  // namespace
