// What a user must be able to trust (issue: "a far particle never spoils a
// frame, no two writers share a file, every failure says so, recover saves
// every good frame"): each case as the user meets it, through the shell.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "cli_run.h"

namespace {

namespace fs = std::filesystem;
using sluice::cli_test::Result;

const std::string kSample = std::string(SLUICE_SAMPLE_DIR);
const std::string kBinary = SLUICE_BINARY;

// A bash script with $S the sluice binary and $D the sample folder.
Result shell(const std::string& script) {
  return sluice::cli_test::run_command("S='" + kBinary + "' D='" + kSample + "' bash -c '" + script + "' 2>&1");
}

Result sluice(const std::string& args) { return sluice::cli_test::run_sluice(args); }

fs::path fresh_dir(const std::string& name) { return sluice::cli_test::fresh_dir("trust", name); }

// A fresh folder holding the bundled sample converted to d.sluice.
fs::path with_sample(const std::string& name) {
  const fs::path dir = fresh_dir(name);
  const Result c = sluice("convert " + kSample + "/dam_break_3d.pvd -o " + (dir / "d.sluice").string() + " -q");
  EXPECT_EQ(c.status, 0) << c.out;
  return dir;
}

std::string text_of(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> leftovers(const fs::path& dir, const std::string& suffix) {
  std::vector<std::string> found;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    const std::string name = e.path().string();
    if (name.size() >= suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0) found.push_back(name);
  }
  return found;
}

// Two converts with different options into one file, 20 times: never a
// corrupt file, never a wrong status; the loser names the winner.
TEST(OneWriter, ConcurrentConvertsNeverShareAFile) {
  const fs::path dir = fresh_dir("converts");
  for (int i = 0; i < 20; ++i) {
    const Result r = shell("cd " + dir.string() + " && rm -f mix.sluice; "
                           "($S convert $D/dam_break_3d.pvd -o mix.sluice -a rho -q -f > a.txt 2>&1; echo $? > a.rc) & "
                           "($S convert $D/dam_break_3d.pvd -o mix.sluice --lossless -q -f > b.txt 2>&1; echo $? > b.rc) & "
                           "wait; cat a.rc b.rc");
    ASSERT_EQ(r.status, 0) << r.out;
    const int a = std::stoi(text_of(dir / "a.rc")), b = std::stoi(text_of(dir / "b.rc"));
    ASSERT_TRUE(a == 0 || b == 0) << text_of(dir / "a.txt") << text_of(dir / "b.txt");
    for (const auto& [rc, log] : {std::pair{a, dir / "a.txt"}, std::pair{b, dir / "b.txt"}}) {
      if (rc != 0) EXPECT_NE(text_of(log).find("another sluice"), std::string::npos) << text_of(log);
    }
    const Result v = sluice("verify -q " + (dir / "mix.sluice").string());
    ASSERT_EQ(v.status, 0) << "run " << i << ": " << v.out;
  }
}

// Two players of one fresh glob, 20 times: both play, the cache is whole.
TEST(OneWriter, ConcurrentPlaysShareTheCache) {
  const fs::path dir = fresh_dir("plays");
  for (int i = 0; i < 20; ++i) {
    fs::remove_all(dir / "in");
    fs::create_directories(dir / "in");
    for (const char* f : {"dam_break_3d_fluid_00000.vtu", "dam_break_3d_fluid_00050.vtu", "dam_break_3d_fluid_00100.vtu"}) {
      fs::copy_file(kSample + "/" + f, dir / "in" / f);
    }
    const Result r = shell("cd " + dir.string() + " || exit 1; "
                           "($S play \"in/*.vtu\" --headless -q > a.txt 2>&1; echo $? > a.rc) & "
                           "($S play \"in/*.vtu\" --headless -q > b.txt 2>&1; echo $? > b.rc) & wait");
    ASSERT_EQ(r.status, 0) << r.out;
    ASSERT_EQ(std::stoi(text_of(dir / "a.rc")), 0) << text_of(dir / "a.txt");
    ASSERT_EQ(std::stoi(text_of(dir / "b.rc")), 0) << text_of(dir / "b.txt");
    ASSERT_EQ(sluice("verify -q " + (dir / "in/.sluice-cache/in.sluice").string()).status, 0);
  }
}

// A full disk (a file-size limit, the signal ignored so writes fail with
// EFBIG as on ENOSPC): non-zero status, nothing under the real name.
TEST(EveryFailure, FullDiskFailsConvert) {
  const fs::path dir = fresh_dir("full_convert");
  const Result r = shell("cd " + dir.string() + " && trap \"\" XFSZ && ulimit -f 200 && "
                         "$S convert $D/dam_break_3d.pvd -o out.sluice -a rho -q");
  EXPECT_NE(r.status, 0) << r.out;
  EXPECT_FALSE(fs::exists(dir / "out.sluice")) << r.out;
  EXPECT_NE(r.out.find("sluice recover"), std::string::npos) << r.out;
}

TEST(EveryFailure, FullDiskFailsExport) {
  const fs::path dir = with_sample("full_export");
  const Result r = shell("cd " + dir.string() + " && trap \"\" XFSZ && ulimit -f 100 && $S export d.sluice -o out/x.vtp -q");
  EXPECT_NE(r.status, 0) << r.out;
  EXPECT_TRUE(leftovers(dir, ".partial").empty());
  EXPECT_FALSE(fs::exists(dir / "out/x.pvd")) << "the series index says the export is complete";
}

TEST(EveryFailure, FullDiskFailsRenderPng) {
  const fs::path dir = with_sample("full_png");
  const Result r = shell("cd " + dir.string() + " && trap \"\" XFSZ && ulimit -f 20 && "
                         "$S render d.sluice --frames 3 --size 640x360 -o shot.png -q");
  EXPECT_NE(r.status, 0) << r.out;
  EXPECT_FALSE(fs::exists(dir / "shot.png")) << r.out;
  EXPECT_TRUE(leftovers(dir, ".partial").empty());
}

TEST(EveryFailure, FullDiskFailsRenderMp4) {
  const fs::path dir = with_sample("full_mp4");
  const Result r = shell("cd " + dir.string() + " && trap \"\" XFSZ && ulimit -f 8 && "
                         "$S render d.sluice --size 640x360 -o movie.mp4 -q");
  EXPECT_NE(r.status, 0) << r.out;
  EXPECT_FALSE(fs::exists(dir / "movie.mp4")) << r.out;
  EXPECT_TRUE(leftovers(dir, ".partial").empty());
  // And with room, the video is written and reads back.
  const Result ok = shell("cd " + dir.string() + " && $S render d.sluice --size 320x180 -o movie.mp4 -q && "
                          "ffprobe -v error -count_packets -show_entries stream=nb_read_packets -of csv=p=0 movie.mp4");
  EXPECT_EQ(ok.status, 0) << ok.out;
  EXPECT_NE(ok.out.find("13"), std::string::npos) << ok.out;
}

TEST(EveryFailure, RenderRefusesToOverwrite) {
  const fs::path dir = with_sample("overwrite");
  const std::string render = "render " + (dir / "d.sluice").string() + " --frames 2 --size 160x90 -q -o " + (dir / "a.png").string();
  ASSERT_EQ(sluice(render).status, 0);
  const Result again = sluice(render);
  EXPECT_NE(again.status, 0);
  EXPECT_NE(again.out.find("--force"), std::string::npos) << again.out;
  EXPECT_EQ(sluice(render + " -f").status, 0);
}

// --frames takes a list: render and export write exactly the listed frames.
TEST(Friction, FrameLists) {
  const fs::path dir = with_sample("lists");
  const Result r = sluice("render " + (dir / "d.sluice").string() + " --frames 0,6,12 --size 96x64 -q -o " + (dir / "shots").string());
  ASSERT_EQ(r.status, 0) << r.out;
  for (const char* f : {"frame_00000.png", "frame_00006.png", "frame_00012.png"}) EXPECT_TRUE(fs::exists(dir / "shots" / f)) << f;
  EXPECT_FALSE(fs::exists(dir / "shots/frame_00001.png"));
  const Result e = sluice("export " + (dir / "d.sluice").string() + " --frames 3,9 -o " + (dir / "out/x.vtp").string());
  ASSERT_EQ(e.status, 0) << e.out;
  EXPECT_TRUE(fs::exists(dir / "out/x_00003.vtp"));
  EXPECT_TRUE(fs::exists(dir / "out/x_00009.vtp"));
  EXPECT_FALSE(fs::exists(dir / "out/x_00004.vtp"));
}

// `sluice devices` lists what --device takes: here lavapipe, usable, at
// index 0 (as text and JSON), and that index picks it.
TEST(Friction, DevicesNameWhatDeviceTakes) {
  const Result text = sluice("devices");
  ASSERT_EQ(text.status, 0) << text.out;
  EXPECT_NE(text.out.find("0: llvmpipe"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("sluice runs on it"), std::string::npos) << text.out;
  const Result json = sluice("devices --json");
  ASSERT_EQ(json.status, 0) << json.out;
  EXPECT_NE(json.out.find("\"usable\": true"), std::string::npos) << json.out;
  const fs::path dir = with_sample("devices");
  const Result r = sluice("render " + (dir / "d.sluice").string() + " --frames 0 --size 64x48 -q --device 0 -o " +
                          (dir / "d.png").string());
  EXPECT_EQ(r.status, 0) << r.out;
  EXPECT_TRUE(fs::exists(dir / "d.png"));
}

// `sluice info --records FRAME` lists a frame's records by layer and tier
// span; a frame past the end is an error naming the count.
TEST(Friction, InfoRecordsListsAFramesRecordsBySpan) {
  const fs::path dir = fresh_dir("records");
  const std::string file = (dir / "s.sluice").string();
  const Result synth = sluice("synth -n 200000 --frames 2 -q -o " + file);
  ASSERT_EQ(synth.status, 0) << synth.out;
  const Result r = sluice("info " + file + " --records 1");
  ASSERT_EQ(r.status, 0) << r.out;
  EXPECT_NE(r.out.find("frame 1:"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("coarse to fine"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("surface"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("blobs"), std::string::npos) << r.out;
  const Result past = sluice("info " + file + " --records 2");
  EXPECT_NE(past.status, 0);
  EXPECT_NE(past.out.find("no frame 2 (the file has 2)"), std::string::npos) << past.out;
}

// Recover keeps the frames after a damaged one, rebuilds a damaged header
// from its copy, and fails when there is nothing to save.
TEST(Recover, SavesEveryGoodFrame) {
  const fs::path dir = fresh_dir("recover");
  const fs::path file = dir / "d.sluice";
  ASSERT_EQ(sluice("convert " + kSample + "/dam_break_3d.pvd -o " + file.string() + " -a rho -q").status, 0);
  const Result info = sluice("info --json " + file.string());
  // Frame 6's offset, from the index as info prints it.
  size_t at = 0;
  for (int i = 0; i <= 6; ++i) at = info.out.find("\"offset\": ", at) + 10;
  const uint64_t frame6 = std::stoull(info.out.substr(at));
  std::string bytes = text_of(file);
  std::string damaged = bytes;
  damaged[frame6 + 3000] = char(damaged[frame6 + 3000] ^ 0x5a);
  std::ofstream(dir / "frame.sluice", std::ios::binary) << damaged;
  const Result r = sluice("recover " + (dir / "frame.sluice").string() + " -o " + (dir / "frame_r.sluice").string());
  ASSERT_EQ(r.status, 0) << r.out;
  EXPECT_NE(r.out.find("frame 6"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("recovered 12 frames"), std::string::npos) << r.out;
  EXPECT_EQ(sluice("verify -q " + (dir / "frame_r.sluice").string()).status, 0);

  std::string header = bytes;
  header[21] = char(header[21] ^ 0x40);  // the spacing
  std::ofstream(dir / "header.sluice.partial", std::ios::binary) << header;
  const Result h = sluice("recover " + (dir / "header.sluice.partial").string());
  ASSERT_EQ(h.status, 0) << h.out;
  EXPECT_NE(h.out.find("rebuilt from its copy"), std::string::npos) << h.out;
  EXPECT_NE(h.out.find("recovered 13 frames"), std::string::npos) << h.out;
  EXPECT_EQ(sluice("verify -q " + (dir / "header.sluice").string()).status, 0) << "the default name drops .partial";

  std::ofstream(dir / "junk.sluice", std::ios::binary) << std::string(100, 'x');
  EXPECT_EQ(sluice("recover " + (dir / "junk.sluice").string()).status, 1);
}

// The fall is written into the header once the first frames show it: a
// conversion cut short by a bad frame keeps a y-up run's up axis.
TEST(Recover, CutShortConversionKeepsTheUpAxis) {
  const fs::path dir = fresh_dir("up");
  fs::create_directories(dir / "in");
  for (int f = 0; f < 20; ++f) {
    char name[32];
    std::snprintf(name, sizeof name, "in/f_%03d.csv", f);
    std::ofstream out(dir / name);
    out << "x,y,z\n";
    for (int i = 0; i < 6000; ++i) {  // columns whose tops fall along -y, the floor staying
      const int x = i % 20, y = i / 20 % 15, z = i / 300;
      out << x * 0.02 + (i % 7) * 1e-4 << ',' << y * 0.02 * (1 - 0.02 * f) << ',' << z * 0.02 << '\n';
    }
  }
  std::ofstream(dir / "in/f_020.csv") << "x,y,z\n1,2\n";
  const Result c = sluice("convert \"" + (dir / "in/f_*.csv").string() + "\" -o " + (dir / "cut.sluice").string() + " -q");
  EXPECT_NE(c.status, 0) << c.out;
  const Result info = sluice("info " + (dir / "cut.sluice").string());
  EXPECT_NE(info.out.find("+y (found from the fluid's fall"), std::string::npos) << info.out;
}

// Degenerate frames and repeated ids: spacing from a frame that shows it,
// a radius, and LOD values that still thin.
TEST(Degenerate, EmptyFirstFrameAndRepeatedIds) {
  const fs::path dir = fresh_dir("degenerate");
  fs::create_directories(dir / "in");
  std::ofstream(dir / "in/s_000.csv") << "x,y,z,id\n";
  std::ofstream(dir / "in/s_001.csv") << "x,y,z,id\n0.5,0.5,0.5,7\n";
  for (int f = 2; f < 5; ++f) {
    std::ofstream out(dir / ("in/s_00" + std::to_string(f) + ".csv"));
    out << "x,y,z,id\n";
    for (int i = 0; i < 4000; ++i) out << (i % 20) * 0.02 << ',' << (i / 20 % 20) * 0.02 << ',' << (i / 400) * 0.02 + 0.001 * f << ",7\n";
  }
  const fs::path file = dir / "d.sluice";
  // --jobs 4: frames 1-4 are read ahead, with their ids, while frame 0
  // decides; the ids found repeating must be dropped from those too.
  const Result c = sluice("convert \"" + (dir / "in/s_*.csv").string() + "\" --jobs 4 -o " + file.string());
  ASSERT_EQ(c.status, 0) << c.out;
  EXPECT_NE(c.out.find("repeats ids"), std::string::npos) << c.out;
  const Result info = sluice("info " + file.string());
  EXPECT_NE(info.out.find("spacing       0.02"), std::string::npos) << info.out;
  const Result e = sluice("export " + file.string() + " --frames 3 --lod-level 0.5 -o " + (dir / "half.csv").string());
  ASSERT_EQ(e.status, 0) << e.out;
  const std::string half = text_of(dir / "half.csv");
  const auto lines = std::count(half.begin(), half.end(), '\n') - 1;
  EXPECT_GT(lines, 1000) << "LOD 0.5 keeps about half of 4,000 particles";
  EXPECT_LT(lines, 3000);
}

// Far particles through the command line: a warning naming the farthest,
// and the file's bounds those of the fluid.
TEST(FarParticles, ConvertWarnsAndFramesTheFluid) {
  const fs::path dir = fresh_dir("far");
  std::ofstream out(dir / "far.csv");
  out << "x,y,z\n";
  for (int i = 0; i < 8000; ++i) out << (i % 20) * 0.02 << ',' << (i / 20 % 20) * 0.02 << ',' << (i / 400) * 0.02 << '\n';
  out << "1e6,0.1,0.1\n-1e30,0.2,0.2\n";
  out.close();
  const Result c = sluice("convert " + (dir / "far.csv").string() + " -o " + (dir / "far.sluice").string());
  ASSERT_EQ(c.status, 0) << c.out;
  EXPECT_NE(c.out.find("2 particles lie more than"), std::string::npos) << c.out;
  EXPECT_NE(c.out.find("-1e+30"), std::string::npos) << c.out;
  const Result info = sluice("info " + (dir / "far.sluice").string());
  EXPECT_NE(info.out.find("bounds        [0, 0, 0] .. [0.38, 0.38, 0.38]"), std::string::npos) << info.out;
  EXPECT_NE(info.out.find("1/1024 of the spacing"), std::string::npos) << info.out;
  EXPECT_EQ(sluice("verify -q " + (dir / "far.sluice").string()).status, 0);
  const Result d = sluice("convert " + (dir / "far.csv").string() + " -o " + (dir / "near.sluice").string() + " --drop-outliers 100");
  ASSERT_EQ(d.status, 0) << d.out;
  EXPECT_NE(d.out.find("dropped"), std::string::npos) << d.out;
  EXPECT_NE(sluice("info " + (dir / "near.sluice").string()).out.find("8,000 per frame"), std::string::npos);
}

}  // namespace
