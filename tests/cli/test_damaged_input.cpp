// `sluice convert` on damaged input, as a user meets it: legacy files cut
// short or with a count raised give an error naming the file and exit 1 (not
// a crash); a reader that crashes or hangs on one file of a series ends as an
// error naming that file, the output keeping the frames before it, or with
// --skip-bad as a listed skip. Crashes and hangs of VTK's reader are injected
// into the worker process (SLUICE_READER_FAULT), the only way to have them on
// purpose.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include "cli_run.h"

namespace {

namespace fs = std::filesystem;

using sluice::cli_test::Result;

Result sluice(const std::string& args, const std::string& env = "") { return sluice::cli_test::run_sluice(args, env); }

fs::path fresh_dir(const std::string& name) { return sluice::cli_test::fresh_dir("damaged_input", name); }

void put_be32(std::string& out, uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) out += static_cast<char>((v >> s) & 0xFF);
}
void put_float(std::string& out, float f) {
  uint32_t v;
  std::memcpy(&v, &f, 4);
  put_be32(out, v);
}

// A legacy binary POLYDATA file as DualSPHysics writes its particles
// (version 3.0 cell lists, float points, uint Idp, float Vel and Rhop).
std::string legacy_polydata(int n, int seed) {
  std::mt19937 rng(static_cast<uint32_t>(seed));
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::string s = "# vtk DataFile Version 3.0\nPartFluid\nBINARY\nDATASET POLYDATA\n";
  s += "POINTS " + std::to_string(n) + " float\n";
  for (int i = 0; i < 3 * n; ++i) put_float(s, u(rng));
  s += "\nVERTICES " + std::to_string(n) + " " + std::to_string(2 * n) + "\n";
  for (int i = 0; i < n; ++i) {
    put_be32(s, 1);
    put_be32(s, static_cast<uint32_t>(i));
  }
  s += "\nPOINT_DATA " + std::to_string(n) + "\nSCALARS Idp unsigned_int\nLOOKUP_TABLE default\n";
  for (int i = 0; i < n; ++i) put_be32(s, static_cast<uint32_t>((i * 7919) % n));
  s += "\nVECTORS Vel float\n";
  for (int i = 0; i < 3 * n; ++i) put_float(s, u(rng) - 0.5f);
  s += "\nSCALARS Rhop float\nLOOKUP_TABLE default\n";
  for (int i = 0; i < n; ++i) put_float(s, 1000.0f + u(rng));
  s += "\n";
  return s;
}

void write(const fs::path& p, const std::string& bytes) {
  std::ofstream(p, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

bool has(const std::string& text, const std::string& word) { return text.find(word) != std::string::npos; }

// The four files of the reliability issue: cut at half, 200 bytes changed,
// POINTS raised, an unstructured grid cut inside its points.
TEST(DamagedInput, LegacyFilesGiveErrorsNotCrashes) {
  const fs::path dir = fresh_dir("legacy");
  const std::string good = legacy_polydata(20000, 1);
  write(dir / "cut.vtk", good.substr(0, good.size() / 2));
  std::string raised = good;
  raised.replace(raised.find("POINTS 20000"), 12, "POINTS 99999999");
  write(dir / "raised.vtk", raised);

  Result r = sluice("convert " + (dir / "cut.vtk").string() + " -o " + (dir / "o.sluice").string() + " -f -q");
  EXPECT_EQ(r.status, 1) << r.out;
  EXPECT_TRUE(has(r.out, "cut.vtk") && has(r.out, "cut short")) << r.out;

  r = sluice("convert " + (dir / "raised.vtk").string() + " -o " + (dir / "o.sluice").string() + " -f -q");
  EXPECT_EQ(r.status, 1) << r.out;
  EXPECT_TRUE(has(r.out, "raised.vtk") && has(r.out, "POINTS") && has(r.out, "99999999")) << r.out;

  std::mt19937 rng(5);
  for (int round = 0; round < 8; ++round) {
    std::string flipped = good;
    for (int k = 0; k < 200; ++k) flipped[rng() % flipped.size()] = static_cast<char>(rng());
    write(dir / "flipped.vtk", flipped);
    r = sluice("convert " + (dir / "flipped.vtk").string() + " -o " + (dir / "o.sluice").string() + " -f -q");
    EXPECT_EQ(r.signal, 0) << "round " << round << ": " << r.out;
    EXPECT_TRUE(r.status == 0 || (r.status == 1 && has(r.out, "flipped.vtk"))) << "round " << round << ": " << r.out;
  }
}

// A bad frame in the middle of a series: the output keeps the frames before
// it; with --skip-bad the others are converted and the bad one listed.
TEST(DamagedInput, BadFrameStopsCleanlyOrIsSkipped) {
  const fs::path dir = fresh_dir("series");
  for (int f = 0; f < 4; ++f) write(dir / ("fluid_" + std::to_string(f) + ".vtk"), legacy_polydata(3000, f));
  const std::string good = slurp(dir / "fluid_2.vtk");
  write(dir / "fluid_2.vtk", good.substr(0, good.size() * 3 / 4));
  const std::string input = "'" + (dir / "fluid_*.vtk").string() + "'";
  const std::string out = (dir / "o.sluice").string();

  Result r = sluice("convert " + input + " -o " + out + " -f -q");
  EXPECT_EQ(r.status, 1) << r.out;
  EXPECT_TRUE(has(r.out, "fluid_2.vtk") && has(r.out, "holds the 2 frames before it")) << r.out;
  EXPECT_TRUE(has(sluice("info " + out).out, "frames        2")) << sluice("info " + out).out;

  r = sluice("convert " + input + " -o " + out + " -f -q --skip-bad");
  EXPECT_EQ(r.status, 0) << r.out;
  EXPECT_TRUE(has(r.out, "skipped 1 frame") && has(r.out, "fluid_2.vtk")) << r.out;
  EXPECT_TRUE(has(sluice("info " + out).out, "frames        3")) << sluice("info " + out).out;
  EXPECT_EQ(sluice("verify " + out + " -q").status, 0);
}

// VTK's XML reader is the third-party code: it runs in worker processes,
// where a crash or a hang ends as an error naming the file.
class ReaderFaults : public ::testing::Test {
 protected:
  void SetUp() override {
    // One folder per test: ctest runs them in parallel processes.
    dir_ = fresh_dir(std::string("faults_") + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    for (const char* f : {"00000", "00050", "00100", "00150"}) {
      fs::copy_file(fs::path(SLUICE_SAMPLE_DIR) / ("dam_break_3d_fluid_" + std::string(f) + ".vtu"),
                    dir_ / ("dam_break_3d_fluid_" + std::string(f) + ".vtu"));
    }
    input_ = "'" + (dir_ / "*.vtu").string() + "'";
    out_ = (dir_ / "o.sluice").string();
  }
  fs::path dir_;
  std::string input_, out_;
};

TEST_F(ReaderFaults, CrashNamesTheFileAndKeepsTheFramesBefore) {
  const Result r = sluice("convert " + input_ + " -o " + out_ + " -f -q", "SLUICE_READER_FAULT=crash:00100");
  EXPECT_EQ(r.status, 1) << r.out;
  EXPECT_EQ(r.signal, 0) << r.out;
  EXPECT_TRUE(has(r.out, "dam_break_3d_fluid_00100.vtu") && has(r.out, "crashed") && has(r.out, "SIGSEGV")) << r.out;
  EXPECT_TRUE(has(sluice("info " + out_).out, "frames        2")) << sluice("info " + out_).out;
}

TEST_F(ReaderFaults, CrashIsSkippedWithSkipBad) {
  const Result r = sluice("convert " + input_ + " -o " + out_ + " -f -q --skip-bad", "SLUICE_READER_FAULT=crash:00050");
  EXPECT_EQ(r.status, 0) << r.out;
  EXPECT_TRUE(has(r.out, "skipped 1 frame") && has(r.out, "dam_break_3d_fluid_00050.vtu")) << r.out;
  EXPECT_TRUE(has(sluice("info " + out_).out, "frames        3")) << sluice("info " + out_).out;
}

TEST_F(ReaderFaults, HangEndsAtTheReadTimeout) {
  const Result r =
      sluice("convert " + input_ + " -o " + out_ + " -f -q --read-timeout 1", "SLUICE_READER_FAULT=hang:00000");
  EXPECT_EQ(r.status, 1) << r.out;
  EXPECT_TRUE(has(r.out, "dam_break_3d_fluid_00000.vtu") && has(r.out, "more than 1 s")) << r.out;
}

}  // namespace
