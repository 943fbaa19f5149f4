// import::convert() and import::open_playable() as a library caller meets
// them: the observer hears the plan, every frame and the decisions; a bad
// frame stops with ConvertStopped after the output keeps the frames before
// it; the cache converts once, then reuses; a temporary conversion goes
// with its PlayableFile. The bundled sample goes through VTK's reader in
// the worker executable found by default (sluice-import-worker as built).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "../io/test_util.h"
#include "sluice/import/convert.h"
#include "sluice/io/maintenance.h"
#include "sluice/import/playable.h"
#include "sluice/io/reader.h"

namespace {

namespace fs = std::filesystem;
using sluice::import::ConvertObserver;
using sluice::import::ConvertOptions;
using sluice::import::Notice;

// A CSV frame: a block of particles on a floor at y = 0 that slumps along
// -y frame by frame (its top falls, its floor stays), so only the motion
// says that up is +y (a flat layer would say otherwise: the block is tall).
void write_csv_frame(const fs::path& path, int frame) {
  std::ofstream out(path);
  out << "x,y,z,id\n";
  const double squash = 1.0 - 0.1 * frame;
  int id = 0;
  for (int i = 0; i < 12; ++i) {
    for (int j = 0; j < 12; ++j) {
      for (int k = 0; k < 12; ++k) out << 0.1 * i << ',' << 0.1 * j * squash << ',' << 0.1 * k << ',' << id++ << '\n';
    }
  }
}

struct Heard {
  int plans = 0;
  uint64_t planned_frames = 0, last_done = 0;
  std::vector<uint64_t> done;
  std::vector<sluice::import::Note> notes;

  ConvertObserver observer() {
    ConvertObserver o;
    o.planned = [this](const sluice::import::ConvertPlan& p) {
      ++plans;
      planned_frames = p.frames;
    };
    o.progressed = [this](const sluice::import::ConvertProgress& p) { done.push_back(p.frames_done); };
    o.noted = [this](const sluice::import::Note& n) { notes.push_back(n); };
    return o;
  }
  bool heard(Notice about) const {
    return std::any_of(notes.begin(), notes.end(), [&](const auto& n) { return n.about == about; });
  }
};

TEST(ImportConvert, TheObserverHearsThePlanEveryFrameAndTheUpAxis) {
  sluice::test::TempDir dir;
  for (int f = 0; f < 6; ++f) write_csv_frame(dir / ("frame_" + std::to_string(f) + ".csv"), f);
  ConvertOptions o;
  o.input = (dir / "frame_*.csv").string();
  o.dt = 0.01;
  Heard heard;
  const sluice::import::ConvertSummary s = sluice::import::convert(o, (dir / "out.sluice").string(), heard.observer());
  EXPECT_EQ(s.frames, 6u);
  EXPECT_EQ(s.particles, 6u * 1728u);
  EXPECT_EQ(heard.plans, 1);
  EXPECT_EQ(heard.planned_frames, 6u);
  EXPECT_EQ(heard.done, (std::vector<uint64_t>{1, 2, 3, 4, 5, 6})) << "one call per frame, in order";
  EXPECT_TRUE(heard.heard(Notice::Up));
  EXPECT_FALSE(heard.heard(Notice::NoTimes)) << "dt was given";
  EXPECT_FALSE(heard.heard(Notice::NoIds)) << "the id column is found";
  EXPECT_EQ(s.header.up, sluice::io::UpAxis::PosY) << "the block slumps along -y";
  EXPECT_EQ(s.header.up_evidence, sluice::io::UpEvidence::Motion);
  EXPECT_FALSE(fs::exists(dir / "out.sluice.partial"));
  const sluice::io::ContainerReader reader((dir / "out.sluice").string());
  EXPECT_EQ(reader.frame_count(), 6u);
  EXPECT_NEAR(reader.index().frames[5].time, 0.05, 1e-9);
}

TEST(ImportConvert, ABadFrameStopsAfterKeepingTheFramesBeforeIt) {
  sluice::test::TempDir dir;
  for (int f = 0; f < 5; ++f) write_csv_frame(dir / ("frame_" + std::to_string(f) + ".csv"), f);
  std::ofstream(dir / "frame_3.csv", std::ios::app) << "1,2,three,4\n";
  ConvertOptions o;
  o.input = (dir / "frame_*.csv").string();
  const std::string out = (dir / "out.sluice").string();
  try {
    sluice::import::convert(o, out);
    FAIL() << "frame 3 is bad";
  } catch (const sluice::import::ConvertStopped& e) {
    EXPECT_NE(std::string(e.what()).find("frame_3.csv"), std::string::npos) << e.what();
    EXPECT_EQ(e.frames_kept(), 3u);
    EXPECT_TRUE(e.output_complete());
    EXPECT_EQ(e.output(), out);
  }
  EXPECT_EQ(sluice::io::ContainerReader(out).frame_count(), 3u);

  o.skip_bad = true;
  Heard heard;
  const sluice::import::ConvertSummary s = sluice::import::convert(o, out, heard.observer());
  EXPECT_EQ(s.frames, 4u);
  ASSERT_EQ(s.skipped.size(), 1u);
  EXPECT_EQ(s.skipped[0].frame, 3u);
  EXPECT_TRUE(heard.heard(Notice::Skipped));
}

TEST(ImportConvert, ADamagedFirstFileIsFrameZerosErrorWhichSkipBadLeavesOut) {
  // The series' arrays come from the first file that reads, so a damaged
  // first file no longer stops the whole input before any frame is read.
  sluice::test::TempDir dir;
  for (const auto& entry : fs::directory_iterator(SLUICE_SAMPLE_DIR)) {
    if (entry.path().extension() == ".vtu") fs::copy_file(entry.path(), dir / entry.path().filename());
  }
  const fs::path first = dir / "dam_break_3d_fluid_00000.vtu";
  ASSERT_TRUE(fs::exists(first));
  fs::resize_file(first, 5000);  // cut inside its first array
  ConvertOptions o;
  o.input = (dir / "*.vtu").string();
  const std::string out = (dir / "out.sluice").string();
  try {
    sluice::import::convert(o, out);
    FAIL() << "frame 0 is damaged";
  } catch (const sluice::io::Error& e) {
    EXPECT_NE(std::string(e.what()).find("dam_break_3d_fluid_00000.vtu"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("frame 0"), std::string::npos) << e.what();
  }
  o.skip_bad = true;
  const sluice::import::ConvertSummary s = sluice::import::convert(o, out);
  EXPECT_EQ(s.frames, 12u);
  ASSERT_EQ(s.skipped.size(), 1u);
  EXPECT_EQ(s.skipped[0].frame, 0u);
  const sluice::io::ContainerReader reader(out);
  EXPECT_EQ(reader.frame_count(), 12u);
}

TEST(ImportConvert, ASpacingWhoseBoundUnderflowsIsNotStated) {
  // fuzz_vtk_import's frame (tests/data/fuzz/findings/vtk_import_bound_underflow):
  // particles 1e-45 apart beside others 1e31 away estimate a spacing of
  // 5.6e-45, whose position bound rounds to 0. The file then promised
  // exactness with 16-bit positions, and its own verify found it 4e26 off.
  sluice::test::TempDir dir;
  std::ofstream(dir / "frame.csv") << "x,y,z\n0,-0.5,1\n0,1e-45,0\n3e-45,0,4e-45\n0,6e-45,0\n7e-45,0,8e-45\n"
                                      "5.7742524e+31,0,0\n8192,-0.2299365,2.839981e+29\n";
  ConvertOptions o;
  o.input = (dir / "frame.csv").string();
  const std::string out = (dir / "out.sluice").string();
  const sluice::import::ConvertSummary s = sluice::import::convert(o, out);
  EXPECT_EQ(s.header.particle_spacing, 0.0f) << "no spacing stated rather than one with a bound of 0";
  const sluice::io::VerifyReport report = sluice::io::verify_container(out);
  EXPECT_TRUE(report.problems.empty()) << report.problems.front();

  o.spacing = 1e-44f;  // given, it is refused with what to do
  try {
    sluice::import::convert(o, (dir / "given.sluice").string());
    FAIL() << "a spacing whose bound underflows was accepted";
  } catch (const sluice::io::Error& e) {
    EXPECT_NE(std::string(e.what()).find("too small"), std::string::npos) << e.what();
  }
}

TEST(ImportConvert, TheBundledSampleThroughTheDefaultWorker) {
  sluice::test::TempDir dir;
  ConvertOptions o;
  o.input = std::string(SLUICE_SAMPLE_DIR) + "/dam_break_3d.pvd";
  o.isolation.mode = sluice::import::Isolation::WorkerProcesses;  // the worker found as built
  const sluice::import::ConvertSummary s = sluice::import::convert(o, (dir / "dam.sluice").string());
  EXPECT_EQ(s.frames, 13u);
  EXPECT_EQ(s.particles, 13u * 9360u);
  EXPECT_EQ(s.header.up, sluice::io::UpAxis::PosZ);
}

TEST(ImportPlayable, TheCacheConvertsOnceThenReuses) {
  sluice::test::TempDir dir;
  for (int f = 0; f < 3; ++f) write_csv_frame(dir / ("frame_" + std::to_string(f) + ".csv"), f);
  const std::string input = (dir / "frame_*.csv").string();
  std::vector<std::string> converted, reused;
  sluice::import::PlayableOptions o;
  o.events.converting = [&](const std::string& entry) { converted.push_back(entry); };
  o.events.reused = [&](const std::string& entry) { reused.push_back(entry); };
  std::string first;
  {
    const sluice::import::PlayableFile file = sluice::import::open_playable(input, o);
    first = file.path();
    EXPECT_TRUE(sluice::io::is_container(first));
  }
  EXPECT_TRUE(fs::exists(first)) << "a cache entry stays";
  const sluice::import::PlayableFile again = sluice::import::open_playable(input, o);
  EXPECT_EQ(again.path(), first);
  EXPECT_EQ(converted.size(), 1u);
  EXPECT_EQ(reused.size(), 1u);
  EXPECT_EQ(sluice::import::open_playable(first, o).path(), first) << "a .sluice file opens as it is";
}

TEST(ImportPlayable, ATemporaryConversionGoesWithItsFile) {
  sluice::test::TempDir dir;
  for (int f = 0; f < 2; ++f) write_csv_frame(dir / ("frame_" + std::to_string(f) + ".csv"), f);
  sluice::import::PlayableOptions o;
  o.use = sluice::import::CacheUse::Temporary;
  std::string path;
  {
    sluice::import::PlayableFile file = sluice::import::open_playable((dir / "frame_*.csv").string(), o);
    const sluice::import::PlayableFile moved = std::move(file);
    path = moved.path();
    EXPECT_TRUE(sluice::io::is_container(path));
  }
  EXPECT_FALSE(fs::exists(path)) << "removed once, by the file it moved into";
}

}  // namespace
