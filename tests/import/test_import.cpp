// Importer tests: every input format reads back the same particles, series
// are ordered and timed correctly, and every bad input either throws an
// io::Error naming the file (and the array) or is repaired with a note.
//
// Binary VTK inputs live in tests/data/import/ (written by VTK's own writers,
// see generate.py there); text inputs are written to a temp dir at run time.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "sluice/error.h"
#include "sluice/import/source.h"

namespace fs = std::filesystem;
using sluice::io::Error;
using sluice::import::SourceOptions;
using sluice::io::ParticleFrame;
using sluice::import::open_source;

namespace {

const fs::path kData = fs::path(__FILE__).parent_path().parent_path() / "data" / "import";

// The reference particles of generate.py: exact binary fractions.
constexpr size_t kN = 7;
float ref_x(size_t i) { return static_cast<float>(i) / 8.0f; }
float ref_y(size_t i) { return -0.5f + static_cast<float>(i) / 4.0f; }
float ref_z(size_t i) { return 1.0f + static_cast<float>(i * i) / 16.0f; }
uint64_t ref_gid(size_t i) { return 100 + 3 * (6 - i); }
float ref_rho(size_t i) { return 1000.0f + static_cast<float>(i) / 2.0f; }
float ref_speed(size_t i) { return 3.0f * static_cast<float>(i); }

SourceOptions with_attributes(std::vector<std::string> attributes) {
  SourceOptions o;
  o.attributes = std::move(attributes);
  return o;
}

// Checks particles `indices` of the reference, in that order.
void expect_reference(const ParticleFrame& f, const std::vector<size_t>& indices, bool ids, bool attributes) {
  ASSERT_EQ(f.count(), indices.size());
  for (size_t k = 0; k < indices.size(); ++k) {
    const size_t i = indices[k];
    EXPECT_EQ(f.positions[3 * k + 0], ref_x(i)) << "particle " << k;
    EXPECT_EQ(f.positions[3 * k + 1], ref_y(i)) << "particle " << k;
    EXPECT_EQ(f.positions[3 * k + 2], ref_z(i)) << "particle " << k;
  }
  if (ids) {
    ASSERT_EQ(f.ids.size(), indices.size());
    for (size_t k = 0; k < indices.size(); ++k) EXPECT_EQ(f.ids[k], ref_gid(indices[k])) << "particle " << k;
  } else {
    EXPECT_TRUE(f.ids.empty());
  }
  if (attributes) {
    ASSERT_EQ(f.attributes.size(), 2u);
    ASSERT_EQ(f.attributes[0].size(), indices.size());
    ASSERT_EQ(f.attributes[1].size(), indices.size());
    for (size_t k = 0; k < indices.size(); ++k) {
      EXPECT_EQ(f.attributes[0][k], ref_rho(indices[k])) << "rho of particle " << k;
      EXPECT_EQ(f.attributes[1][k], ref_speed(indices[k])) << "|velocity| of particle " << k;
    }
  }
}

std::vector<size_t> all_reference() {
  std::vector<size_t> v(kN);
  for (size_t i = 0; i < kN; ++i) v[i] = i;
  return v;
}

// Runs `f`, expects an io::Error whose what() contains every one of `parts`.
void expect_error(const std::function<void()>& f, const std::vector<std::string>& parts) {
  try {
    f();
  } catch (const Error& e) {
    const std::string what = e.what();
    for (const auto& p : parts) EXPECT_NE(what.find(p), std::string::npos) << "'" << p << "' missing in: " << what;
    return;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected io::Error, got: " << e.what();
    return;
  }
  ADD_FAILURE() << "expected an io::Error";
}

ParticleFrame read_one(const std::string& spec, const SourceOptions& options = {}) {
  auto src = open_source(spec, options);
  EXPECT_EQ(src->frame_count(), 1u);
  return src->read(0);
}

bool has_repair(const ParticleFrame& f, const std::string& text) {
  return std::any_of(f.repairs.begin(), f.repairs.end(),
                     [&](const std::string& r) { return r.find(text) != std::string::npos; });
}

std::string repairs_of(const ParticleFrame& f) {
  std::string out;
  for (const auto& r : f.repairs) out += "[" + r + "] ";
  return out;
}

// A fresh directory removed at the end of the test.
class TempDir {
 public:
  TempDir() {
    std::string tmpl = (fs::temp_directory_path() / "sluice_import_XXXXXX").string();
    if (!mkdtemp(tmpl.data())) throw std::runtime_error("mkdtemp failed");
    path_ = tmpl;
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  std::string file(const std::string& name) const { return (path_ / name).string(); }
  std::string write(const std::string& name, const std::string& text) const {
    const std::string p = file(name);
    fs::create_directories(fs::path(p).parent_path());
    std::ofstream(p, std::ios::binary) << text;
    return p;
  }
  std::string copy(const std::string& data_name, const std::string& name) const {
    const std::string p = file(name);
    fs::create_directories(fs::path(p).parent_path());
    fs::copy_file(kData / data_name, p, fs::copy_options::overwrite_existing);
    return p;
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

// The reference particles as CSV: ParaView's spreadsheet export header.
std::string paraview_csv() {
  std::string s = "\"gid\",\"rho\",\"velocity:0\",\"velocity:1\",\"velocity:2\",\"Points:0\",\"Points:1\",\"Points:2\"\n";
  for (size_t i = 0; i < kN; ++i) {
    s += std::to_string(ref_gid(i)) + "," + std::to_string(ref_rho(i)) + "," + std::to_string(i) + "," +
         std::to_string(2 * i) + "," + std::to_string(2 * i) + "," + std::to_string(ref_x(i)) + "," +
         std::to_string(ref_y(i)) + "," + std::to_string(ref_z(i)) + "\n";
  }
  return s;
}

}  // namespace

// ------------------------------------------------------------ natural sort

TEST(NaturalSort, DigitRunsCompareAsNumbers) {
  using sluice::import::natural_less;
  EXPECT_TRUE(natural_less("frame_2.vtu", "frame_10.vtu"));
  EXPECT_FALSE(natural_less("frame_10.vtu", "frame_2.vtu"));
  EXPECT_TRUE(natural_less("a_fluid_00100.vtu", "a_fluid_00564.vtu"));
  EXPECT_TRUE(natural_less("run3_frame_9", "run3_frame_10"));
  EXPECT_TRUE(natural_less("frame_9", "frame_9a"));
  EXPECT_TRUE(natural_less("a", "b"));
  EXPECT_TRUE(natural_less("x99999999999999999999999", "x100000000000000000000000"));  // beyond uint64
  // Zero padding: equal numbers, still a strict order (no ties).
  EXPECT_NE(natural_less("frame_01", "frame_1"), natural_less("frame_1", "frame_01"));
  EXPECT_FALSE(natural_less("frame_1", "frame_1"));

  std::vector<std::string> names = {"f_10", "f_2", "f_1", "f_100", "f_20", "f_02"};
  std::sort(names.begin(), names.end(), sluice::import::natural_less);
  EXPECT_EQ(names, (std::vector<std::string>{"f_1", "f_02", "f_2", "f_10", "f_20", "f_100"}));
}

TEST(NaturalSort, GlobExpandsInNaturalOrder) {
  TempDir dir;
  for (const char* name : {"frame_10.csv", "frame_2.csv", "frame_1.csv", "frame_9.csv", "other.txt"}) {
    dir.write(name, "x,y,z\n");
  }
  fs::create_directories(dir.path() / "frame_5.csv");  // a directory is not a frame
  const auto files = sluice::import::expand_glob_natural(dir.file("frame_*.csv"));
  ASSERT_EQ(files.size(), 4u);
  EXPECT_EQ(fs::path(files[0]).filename(), "frame_1.csv");
  EXPECT_EQ(fs::path(files[1]).filename(), "frame_2.csv");
  EXPECT_EQ(fs::path(files[2]).filename(), "frame_9.csv");
  EXPECT_EQ(fs::path(files[3]).filename(), "frame_10.csv");
  EXPECT_TRUE(sluice::import::expand_glob_natural(dir.file("nothing_*.vtu")).empty());
}

TEST(NaturalSort, GlobSourceReadsFramesInOrder) {
  TempDir dir;
  for (int n : {10, 2, 1}) dir.write("frame_" + std::to_string(n) + ".csv", "x,y,z\n" + std::to_string(n) + ",0,0\n");
  auto src = open_source(dir.file("frame_*.csv"), {});
  ASSERT_EQ(src->frame_count(), 3u);
  EXPECT_NE(src->info().description.find("3 files matching"), std::string::npos) << src->info().description;
  const float expected[] = {1, 2, 10};
  for (uint64_t i = 0; i < 3; ++i) {
    const ParticleFrame f = src->read(i);
    ASSERT_EQ(f.count(), 1u);
    EXPECT_EQ(f.positions[0], expected[i]);
    EXPECT_EQ(f.time, static_cast<double>(i)) << "no time in the file: the frame number";
  }
  expect_error([&] { open_source(dir.file("nothing_*.vtu"), {}); }, {"nothing_*.vtu", "no files match"});
}

// ------------------------------------------------------------ id detection

TEST(IdArray, DetectionOrder) {
  using sluice::import::detect_id_array;
  EXPECT_EQ(detect_id_array({"rho", "gid", "velocity"}), "gid");
  EXPECT_EQ(detect_id_array({"Idp", "Vel", "Rhop"}), "Idp");
  EXPECT_EQ(detect_id_array({"x", "id"}), "id");
  EXPECT_EQ(detect_id_array({"gid", "id"}), "id");  // the documented preference order
  EXPECT_EQ(detect_id_array({"ParticleId", "gid"}), "gid");
  EXPECT_EQ(detect_id_array({"ParticleID"}), "ParticleID");
  EXPECT_EQ(detect_id_array({"rho", "pid", "tag"}), "");
  EXPECT_EQ(detect_id_array({}), "");
}

// ---------------------------------------------------------------- text

TEST(TextImport, ParaViewCsv) {
  TempDir dir;
  const std::string path = dir.write("pv.csv", paraview_csv());
  auto src = open_source(path, with_attributes({"rho", "velocity"}));
  EXPECT_EQ(src->info().id_array, "gid");
  EXPECT_EQ(src->info().arrays, (std::vector<std::string>{"gid", "rho", "velocity"}));
  const ParticleFrame f = src->read(0);
  expect_reference(f, all_reference(), true, true);
  EXPECT_TRUE(f.repairs.empty()) << repairs_of(f);
}

TEST(TextImport, CsvWithXyzColumnsAnyCaseAndOtherLayouts) {
  TempDir dir;
  // Tab separated, CRLF, upper-case names, columns in any order, a '+' sign.
  const std::string path = dir.write("t.csv", "ID\tZ\tY\tX\r\n5\t1\t+2\t3\r\n\r\n6\t4\t5\t6e0\r\n");
  auto src = open_source(path, {});
  EXPECT_EQ(src->info().id_array, "ID");
  const ParticleFrame f = src->read(0);
  ASSERT_EQ(f.count(), 2u);
  EXPECT_EQ(f.positions, (std::vector<float>{3, 2, 1, 6, 5, 4}));
  EXPECT_EQ(f.ids, (std::vector<uint64_t>{5, 6}));

  // The id column can also be carried as an attribute.
  const ParticleFrame both = read_one(path, with_attributes({"ID"}));
  EXPECT_EQ(both.ids, (std::vector<uint64_t>{5, 6}));
  EXPECT_EQ(both.attributes[0], (std::vector<float>{5, 6}));

  SourceOptions no_ids;
  no_ids.no_ids = true;
  EXPECT_TRUE(open_source(path, no_ids)->read(0).ids.empty());
}

TEST(TextImport, Xyz) {
  TempDir dir;
  const std::string path = dir.write("p.xyz",
                                     "# x y z rho\n"
                                     "0 -0.5 1 1000   # first particle\n"
                                     "\n"
                                     "0.125\t-0.25 1.0625 1000.5\n");
  auto src = open_source(path, with_attributes({"col4"}));
  EXPECT_EQ(src->info().arrays, (std::vector<std::string>{"col4"}));
  EXPECT_EQ(src->info().id_array, "");
  const ParticleFrame f = src->read(0);
  ASSERT_EQ(f.count(), 2u);
  EXPECT_EQ(f.positions, (std::vector<float>{ref_x(0), ref_y(0), ref_z(0), ref_x(1), ref_y(1), ref_z(1)}));
  ASSERT_EQ(f.attributes.size(), 1u);
  EXPECT_EQ(f.attributes[0], (std::vector<float>{ref_rho(0), ref_rho(1)}));
  // .txt is read the same way.
  EXPECT_EQ(read_one(dir.write("p.txt", "1 2 3\n")).positions, (std::vector<float>{1, 2, 3}));
}

TEST(TextImport, BadNumbersNameFileAndLine) {
  TempDir dir;
  const std::string csv = dir.write("bad.csv", "x,y,z,rho\n1,2,3,4\n1,2,abc,4\n");
  expect_error([&] { read_one(csv, with_attributes({"rho"})); }, {"bad.csv", "frame 0", "line 3", "'abc'", "'z'"});
  const std::string fields = dir.write("fields.csv", "x,y,z\n1,2,3\n1,2\n");
  expect_error([&] { read_one(fields); }, {"fields.csv", "line 3", "2 fields", "3 columns"});
  const std::string nopos = dir.write("nopos.csv", "a,b,c\n1,2,3\n");
  expect_error([&] { read_one(nopos); }, {"nopos.csv", "no position columns", "Points:0"});
  const std::string xyz = dir.write("bad.xyz", "1 2 3\n1 2\n");
  expect_error([&] { read_one(xyz); }, {"bad.xyz", "line 2", "2 columns"});
  const std::string header = dir.write("header.xyz", "x y z\n1 2 3\n");
  expect_error([&] { read_one(header); }, {"header.xyz", "line 1", "'x'", "no header"});
  const std::string few = dir.write("few.xyz", "1 2\n");
  expect_error([&] { read_one(few); }, {"few.xyz", "line 1", "at least 3"});
}

TEST(TextImport, BadIdsAreErrors) {
  TempDir dir;
  const std::string neg = dir.write("neg.csv", "id,x,y,z\n1,0,0,0\n-3,0,0,0\n");
  expect_error([&] { read_one(neg); }, {"neg.csv", "line 3", "'-3'", "'id'", "non-negative integer"});
  const std::string frac = dir.write("frac.csv", "id,x,y,z\n1.5,0,0,0\n");
  expect_error([&] { read_one(frac); }, {"frac.csv", "line 2", "'1.5'"});
  // An integral id written as a float is fine.
  EXPECT_EQ(read_one(dir.write("float.csv", "id,x,y,z\n7.0,0,0,0\n")).ids, (std::vector<uint64_t>{7}));
}

TEST(TextImport, MissingArraysListWhatExists) {
  TempDir dir;
  const std::string path = dir.write("a.csv", "x,y,z,rho,velocity:0,velocity:1\n0,0,0,1,1,1\n");
  expect_error([&] { open_source(path, with_attributes({"pressure"})); },
               {"a.csv", "'pressure'", "rho, velocity"});
  SourceOptions o;
  o.id_array = "gid";
  expect_error([&] { open_source(path, o); }, {"a.csv", "'gid'", "rho, velocity"});
}

TEST(TextImport, NonFiniteValuesAreRepaired) {
  TempDir dir;
  const std::string path = dir.write("nan.csv",
                                     "id,x,y,z,rho\n"
                                     "0,0,0,0,1\n"
                                     "1,nan,0,0,2\n"
                                     "2,0,0,0,inf\n"
                                     "3,0,-inf,0,nan\n"
                                     "4,1,1,1,5\n");
  const ParticleFrame f = read_one(path, with_attributes({"rho"}));
  EXPECT_EQ(f.ids, (std::vector<uint64_t>{0, 2, 4}));
  EXPECT_EQ(f.attributes[0], (std::vector<float>{1, 0, 5}));
  EXPECT_TRUE(has_repair(f, "dropped 2 particles with non-finite positions (first at index 1)")) << repairs_of(f);
  EXPECT_TRUE(has_repair(f, "replaced 1 non-finite value of 'rho' by 0 (first at index 2)")) << repairs_of(f);
}

TEST(TextImport, DuplicateIdsAreKeptWithANote) {
  TempDir dir;
  const std::string path = dir.write("dup.csv", "id,x,y,z\n5,0,0,0\n3,1,0,0\n5,2,0,0\n5,3,0,0\n3,4,0,0\n1,5,0,0\n");
  const ParticleFrame f = read_one(path);
  EXPECT_EQ(f.count(), 6u);
  EXPECT_TRUE(has_repair(f, "2 particle ids occur more than once (3 extra particles, e.g. id 3)")) << repairs_of(f);
}

TEST(TextImport, EmptyFilesGiveEmptyFrames) {
  TempDir dir;
  const ParticleFrame header_only = read_one(dir.write("h.csv", "x,y,z,rho\n"), with_attributes({"rho"}));
  EXPECT_EQ(header_only.count(), 0u);
  ASSERT_EQ(header_only.attributes.size(), 1u);
  EXPECT_TRUE(header_only.attributes[0].empty());
  EXPECT_TRUE(has_repair(header_only, "file has no points: empty frame")) << repairs_of(header_only);
  const ParticleFrame comments = read_one(dir.write("c.xyz", "# nothing yet\n\n"));
  EXPECT_EQ(comments.count(), 0u);
  EXPECT_TRUE(has_repair(comments, "file has no points: empty frame"));
}

// ------------------------------------------------------------- specs

TEST(Spec, MissingFileAndUnknownExtension) {
  expect_error([] { open_source("/nonexistent/dir/frame.vtu", {}); }, {"/nonexistent/dir/frame.vtu", "no such file"});
  TempDir dir;
  const std::string h5 = dir.write("frame.h5", "");
  expect_error([&] { open_source(h5, {}); }, {"frame.h5", "unsupported", ".h5", ".vtu", ".vtp", ".vtk", ".pvd", ".csv",
                                              ".xyz"});
  // A file that vanishes after open is reported at read time.
  const std::string csv = dir.write("gone.csv", "x,y,z\n1,2,3\n");
  auto src = open_source(csv, {});
  fs::remove(csv);
  expect_error([&] { src->read(0); }, {"gone.csv", "frame 0", "not found"});
}

TEST(Spec, DirectoryWithOneSeries) {
  TempDir dir;
  for (int n : {20, 3, 100}) dir.write("run_" + std::to_string(n) + ".csv", "x,y,z\n" + std::to_string(n) + ",0,0\n");
  dir.write("notes.md", "ignored");
  dir.write(".hidden.csv", "x,y,z\n");
  auto src = open_source(dir.path().string(), {});
  ASSERT_EQ(src->frame_count(), 3u);
  EXPECT_EQ(fs::path(src->frame_name(0)).filename(), "run_3.csv");
  EXPECT_EQ(fs::path(src->frame_name(2)).filename(), "run_100.csv");
  EXPECT_EQ(src->read(1).positions[0], 20.0f);
}

TEST(Spec, DirectoryWithSeveralGroupsAsksForAGlob) {
  TempDir dir;
  for (const char* set : {"fluid", "boundary"}) {
    for (int n : {0, 100}) {
      dir.write(std::string("dam_") + set + "_" + std::to_string(n) + ".csv", "x,y,z\n0,0,0\n");
    }
  }
  expect_error([&] { open_source(dir.path().string(), {}); },
               {dir.path().string(), "dam_fluid_*.csv", "dam_boundary_*.csv", "(2 files)", "glob"});
  expect_error([&] { open_source(TempDir().path().string(), {}); }, {"no particle files", ".vtu"});
}

// -------------------------------------------------------------------- VTK

#ifdef SLUICE_WITH_VTK

class VtkFormats : public ::testing::TestWithParam<const char*> {};

TEST_P(VtkFormats, ReadsTheReferenceParticles) {
  const std::string path = (kData / GetParam()).string();
  auto src = open_source(path, with_attributes({"rho", "velocity"}));
  const bool dualsph = std::string(GetParam()).rfind("pd_", 0) == 0;
  EXPECT_EQ(src->info().id_array, dualsph ? "Idp" : "gid");
  std::vector<std::string> arrays = src->info().arrays;
  std::sort(arrays.begin(), arrays.end());
  EXPECT_EQ(arrays, (std::vector<std::string>{dualsph ? "Idp" : "gid", "rho", "velocity"}));
  ASSERT_EQ(src->frame_count(), 1u);
  const ParticleFrame f = src->read(0);
  expect_reference(f, all_reference(), true, true);
  EXPECT_EQ(f.time, 0.0);
  EXPECT_TRUE(f.repairs.empty()) << repairs_of(f);
}

INSTANTIATE_TEST_SUITE_P(AllEncodings, VtkFormats,
                         ::testing::Values("ug_ascii.vtu", "ug_binary.vtu", "ug_binary_zlib.vtu", "ug_appended_raw.vtu",
                                           "ug_appended_zlib.vtu", "ug_ascii.vtk", "ug_binary.vtk",
                                           "pd_appended_zlib.vtp", "pd_binary.vtk", "pieces.pvtu", "pieces.pvtp"),
                         [](const ::testing::TestParamInfo<const char*>& param) {
                           std::string name = param.param;
                           std::replace(name.begin(), name.end(), '.', '_');
                           return name;
                         });

TEST(VtkImport, WithoutAttributesOrIds) {
  SourceOptions o;
  o.no_ids = true;
  const ParticleFrame f = read_one((kData / "ug_appended_zlib.vtu").string(), o);
  expect_reference(f, all_reference(), false, false);
  EXPECT_TRUE(f.attributes.empty());
}

TEST(VtkImport, ExplicitIdArrayOfFloatType) {
  // rho holds integral values >= 1000 at even indices only: not valid ids.
  SourceOptions o;
  o.id_array = "rho";
  expect_error([&] { read_one((kData / "ug_binary.vtu").string(), o); },
               {"ug_binary.vtu", "'rho'", "1000.5", "index 1", "non-negative integers"});
}

TEST(VtkImport, TimeFromFieldData) {
  EXPECT_EQ(read_one((kData / "time_value.vtu").string()).time, 0.75);
}

TEST(VtkImport, PvdTimesAndPieces) {
  TempDir dir;
  dir.copy("piece_0.vtu", "parts/p0.vtu");
  dir.copy("piece_1.vtu", "parts/p1.vtu");
  dir.copy("ug_binary.vtu", "parts/whole & one.vtu");
  const std::string pvd = dir.write("series.pvd",
                                    "<?xml version=\"1.0\"?>\n"
                                    "<!-- written by hand: parts out of order, times out of order -->\n"
                                    "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
                                    "  <Collection>\n"
                                    "    <DataSet timestep=\"0.5\" group=\"\" part=\"1\" file=\"parts/p1.vtu\"/>\n"
                                    "    <DataSet timestep=\"0.5\" group=\"\" part=\"0\" file='parts/p0.vtu'/>\n"
                                    "    <DataSet timestep=\"0.25\" group=\"\" part=\"0\" file=\"parts/whole &amp; one.vtu\"/>\n"
                                    "  </Collection>\n"
                                    "</VTKFile>\n");
  auto src = open_source(pvd, with_attributes({"rho", "velocity"}));
  ASSERT_EQ(src->frame_count(), 2u);
  EXPECT_EQ(src->info().id_array, "gid");
  const ParticleFrame first = src->read(0);
  EXPECT_EQ(first.time, 0.25);
  expect_reference(first, all_reference(), true, true);
  const ParticleFrame second = src->read(1);
  EXPECT_EQ(second.time, 0.5);
  expect_reference(second, all_reference(), true, true);  // p0 (particles 0-3) then p1 (4-6)
  EXPECT_NE(src->frame_name(1).find("p0.vtu"), std::string::npos);
  EXPECT_NE(src->frame_name(1).find("p1.vtu"), std::string::npos);
  // A directory holding only the collection (pieces in a subdirectory) opens it.
  EXPECT_EQ(open_source(dir.path().string(), {})->frame_count(), 2u);
  // Next to other particle files, the collection is what the error suggests.
  dir.copy("ug_binary.vtu", "frame_0.vtu");
  expect_error([&] { open_source(dir.path().string(), {}); }, {"several particle sets", "e.g. '" + pvd + "'"});
  fs::remove(dir.file("parts/whole & one.vtu"));
  expect_error([&] { open_source(pvd, {}); }, {"series.pvd", "line 7", "whole & one.vtu", "does not exist"});
}

TEST(VtkImport, PvdErrors) {
  TempDir dir;
  dir.copy("ug_binary.vtu", "a_fluid_0.vtu");
  dir.copy("ug_binary.vtu", "a_wall_0.vtu");
  const std::string groups = dir.write("groups.pvd",
                                       "<VTKFile type=\"Collection\"><Collection>\n"
                                       "<DataSet timestep=\"0\" group=\"fluid\" file=\"a_fluid_0.vtu\"/>\n"
                                       "<DataSet timestep=\"0\" group=\"wall\" file=\"a_wall_0.vtu\"/>\n"
                                       "</Collection></VTKFile>\n");
  expect_error([&] { open_source(groups, {}); }, {"groups.pvd", "several groups", "'fluid'", "'wall'", "a_fluid_*.vtu", "glob"});
  const std::string notpvd = dir.copy("ug_binary.vtu", "grid.pvd");
  expect_error([&] { open_source(notpvd, {}); }, {"grid.pvd", "not a ParaView collection", "UnstructuredGrid"});
  const std::string broken = dir.write("broken.pvd", "<VTKFile type=\"Collection\">\n<Collection>\n<DataSet timestep=0 />\n");
  expect_error([&] { open_source(broken, {}); }, {"broken.pvd", "line 3", "timestep"});
  const std::string nofile = dir.write("nofile.pvd", "<VTKFile type=\"Collection\">\n<DataSet timestep=\"1\"/>\n");
  expect_error([&] { open_source(nofile, {}); }, {"nofile.pvd", "line 2", "no file attribute"});
  const std::string empty = dir.write("empty.pvd", "<VTKFile type=\"Collection\"><Collection/></VTKFile>");
  expect_error([&] { open_source(empty, {}); }, {"empty.pvd", "no DataSet"});
}

TEST(VtkImport, GlobOfVtuSeries) {
  TempDir dir;
  for (int n : {10, 2, 1}) dir.copy("ug_appended_zlib.vtu", "out/fluid_" + std::to_string(n) + ".vtu");
  auto src = open_source(dir.file("out/fluid_*.vtu"), {});
  ASSERT_EQ(src->frame_count(), 3u);
  EXPECT_NE(src->info().description.find("(VTK XML unstructured grid)"), std::string::npos);
  EXPECT_EQ(fs::path(src->frame_name(0)).filename(), "fluid_1.vtu");
  EXPECT_EQ(fs::path(src->frame_name(1)).filename(), "fluid_2.vtu");
  EXPECT_EQ(fs::path(src->frame_name(2)).filename(), "fluid_10.vtu");
  for (uint64_t i = 0; i < 3; ++i) EXPECT_EQ(src->read(i).time, static_cast<double>(i));
}

TEST(VtkImport, NonFiniteValuesAreRepaired) {
  const ParticleFrame f = read_one((kData / "nonfinite.vtu").string(), with_attributes({"rho", "velocity"}));
  ASSERT_EQ(f.count(), 5u);
  EXPECT_EQ(f.ids, (std::vector<uint64_t>{ref_gid(0), ref_gid(1), ref_gid(3), ref_gid(5), ref_gid(6)}));
  EXPECT_EQ(f.attributes[0], (std::vector<float>{ref_rho(0), 0.0f, ref_rho(3), 0.0f, ref_rho(6)}));
  EXPECT_EQ(f.attributes[1], (std::vector<float>{ref_speed(0), ref_speed(1), ref_speed(3), ref_speed(5), ref_speed(6)}));
  EXPECT_TRUE(has_repair(f, "dropped 2 particles with non-finite positions (first at index 2)")) << repairs_of(f);
  EXPECT_TRUE(has_repair(f, "replaced 2 non-finite values of 'rho' by 0 (first at index 1)")) << repairs_of(f);
  EXPECT_EQ(f.repairs.size(), 2u) << repairs_of(f);
}

TEST(VtkImport, EmptyFileGivesEmptyFrame) {
  const ParticleFrame f = read_one((kData / "empty.vtp").string());
  EXPECT_EQ(f.count(), 0u);
  EXPECT_TRUE(has_repair(f, "file has no points: empty frame")) << repairs_of(f);
}

// A legacy ASCII file with `cells` after the points and `point_data` after that.
std::string legacy(const std::string& points, const std::string& cells, const std::string& point_data) {
  return "# vtk DataFile Version 4.2\ntest\nASCII\nDATASET UNSTRUCTURED_GRID\n" + points + cells + point_data;
}

const char* kFourPoints = "POINTS 4 float\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n";

TEST(VtkImport, TetraMeshPointsBecomeParticles) {
  TempDir dir;
  const std::string path =
      dir.write("mesh.vtk", legacy(kFourPoints, "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\n",
                                   "POINT_DATA 4\nSCALARS gid int 1\nLOOKUP_TABLE default\n0 1 2 3\n"));
  const ParticleFrame f = read_one(path);
  EXPECT_EQ(f.count(), 4u);
  EXPECT_EQ(f.ids, (std::vector<uint64_t>{0, 1, 2, 3}));
  EXPECT_TRUE(has_repair(f, "cells of type TETRA ignored: using the 4 points as particles")) << repairs_of(f);
  // Vertex cells need no note.
  const std::string verts = dir.write(
      "verts.vtk", legacy(kFourPoints, "CELLS 2 6\n1 0\n3 1 2 3\nCELL_TYPES 2\n1\n2\n", ""));
  EXPECT_TRUE(read_one(verts).repairs.empty()) << repairs_of(read_one(verts));
}

TEST(VtkImport, StructuredPointsBecomeParticles) {
  TempDir dir;
  const std::string path = dir.write("image.vtk",
                                     "# vtk DataFile Version 3.0\nimage\nASCII\nDATASET STRUCTURED_POINTS\n"
                                     "DIMENSIONS 2 2 1\nORIGIN 1 2 3\nSPACING 0.5 0.25 1\n"
                                     "POINT_DATA 4\nSCALARS rho float 1\nLOOKUP_TABLE default\n1 2 3 4\n");
  const ParticleFrame f = read_one(path, with_attributes({"rho"}));
  EXPECT_EQ(f.positions, (std::vector<float>{1, 2, 3, 1.5f, 2, 3, 1, 2.25f, 3, 1.5f, 2.25f, 3}));
  EXPECT_EQ(f.attributes[0], (std::vector<float>{1, 2, 3, 4}));
  EXPECT_TRUE(has_repair(f, "cells of type PIXEL ignored: using the 4 points as particles")) << repairs_of(f);
}

TEST(VtkImport, ArrayLengthMismatchNamesTheArray) {
  TempDir dir;
  const std::string legacy_path = dir.write(
      "short.vtk", legacy(kFourPoints, "", "POINT_DATA 4\nFIELD FieldData 1\nrho 1 3 float\n1 2 3\n"));
  expect_error([&] { read_one(legacy_path, with_attributes({"rho"})); },
               {"short.vtk", "'rho'", "3 values", "4 points"});
  // XML: VTK itself notices and its message names the array.
  const std::string xml = dir.write("short.vtu",
                                    "<?xml version=\"1.0\"?>\n"
                                    "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
                                    "<UnstructuredGrid><Piece NumberOfPoints=\"3\" NumberOfCells=\"0\">\n"
                                    "<PointData><DataArray type=\"Float32\" Name=\"rho\" format=\"ascii\">1 2</DataArray></PointData>\n"
                                    "<Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">0 0 0 1 1 1 2 2 2</DataArray></Points>\n"
                                    "<Cells><DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\"></DataArray>\n"
                                    "<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\"></DataArray>\n"
                                    "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\"></DataArray></Cells>\n"
                                    "</Piece></UnstructuredGrid></VTKFile>\n");
  expect_error([&] { read_one(xml, with_attributes({"rho"})); }, {"short.vtu", "rho"});
}

TEST(VtkImport, BadIdsAreErrors) {
  TempDir dir;
  const std::string neg =
      dir.write("neg.vtk", legacy(kFourPoints, "", "POINT_DATA 4\nSCALARS gid int 1\nLOOKUP_TABLE default\n0 1 -3 2\n"));
  expect_error([&] { read_one(neg); }, {"neg.vtk", "'gid'", "-3", "index 2"});
  const std::string frac =
      dir.write("frac.vtk", legacy(kFourPoints, "", "POINT_DATA 4\nSCALARS id double 1\nLOOKUP_TABLE default\n0 1 2 2.5\n"));
  expect_error([&] { read_one(frac); }, {"frac.vtk", "'id'", "2.5", "index 3"});
  const std::string ok =
      dir.write("ok.vtk", legacy(kFourPoints, "", "POINT_DATA 4\nSCALARS id double 1\nLOOKUP_TABLE default\n4 3 2 1\n"));
  EXPECT_EQ(read_one(ok).ids, (std::vector<uint64_t>{4, 3, 2, 1}));
}

TEST(VtkImport, DuplicateIdsAreKeptWithANote) {
  TempDir dir;
  const std::string path =
      dir.write("dup.vtk", legacy(kFourPoints, "", "POINT_DATA 4\nSCALARS Idp unsigned_int 1\nLOOKUP_TABLE default\n7 7 8 9\n"));
  const ParticleFrame f = read_one(path);
  EXPECT_EQ(f.ids, (std::vector<uint64_t>{7, 7, 8, 9}));
  EXPECT_TRUE(has_repair(f, "1 particle id occur")) << repairs_of(f);
}

TEST(VtkImport, MissingAttributeListsArrays) {
  const std::string path = (kData / "ug_appended_zlib.vtu").string();
  expect_error([&] { open_source(path, with_attributes({"pressure"})); },
               {"ug_appended_zlib.vtu", "'pressure'", "gid", "rho", "velocity"});
  // A later frame without the array: named at read time, with the frame.
  TempDir dir;
  dir.copy("ug_binary.vtu", "f_0.vtu");
  dir.write("f_1.vtk", legacy(kFourPoints, "", "POINT_DATA 4\nSCALARS gid int 1\nLOOKUP_TABLE default\n0 1 2 3\n"));
  auto src = open_source(dir.file("f_*"), with_attributes({"rho"}));
  EXPECT_EQ(src->read(0).count(), kN);
  try {
    src->read(1);
    ADD_FAILURE() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.where().frame, 1u);
    EXPECT_NE(std::string(e.what()).find("f_1.vtk"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("'rho'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("gid"), std::string::npos) << e.what();
  }
}

TEST(VtkImport, CorruptFilesGiveVtkMessage) {
  TempDir dir;
  const std::string garbage = dir.write("garbage.vtu", "<?xml version=\"1.0\"?>\n<VTKFile type=\"Unstr");
  expect_error([&] { read_one(garbage); }, {"garbage.vtu", "VTK"});
  const std::string legacy_garbage = dir.write("garbage.vtk", "this is not vtk\n");
  expect_error([&] { read_one(legacy_garbage); }, {"garbage.vtk", "VTK"});
  // A .vtu that holds polydata.
  const std::string wrong = dir.copy("pd_appended_zlib.vtp", "wrong.vtu");
  expect_error([&] { read_one(wrong); }, {"wrong.vtu", "VTK"});
  // Truncated appended data.
  const fs::path src = kData / "ug_appended_raw.vtu";
  std::ifstream in(src, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string cut = dir.write("cut.vtu", bytes.substr(0, bytes.size() - 200));
  expect_error([&] { read_one(cut); }, {"cut.vtu"});
}

TEST(VtkImport, ConcurrentReadsAttributeErrorsToTheRightCall) {
  TempDir dir;
  for (int n = 0; n < 8; ++n) {
    if (n % 2) {
      dir.write("mix_" + std::to_string(n) + ".vtu", "<?xml version=\"1.0\"?>\n<VTKFile type=\"Unstr");
    } else {
      dir.copy("ug_appended_zlib.vtu", "mix_" + std::to_string(n) + ".vtu");
    }
  }
  auto src = open_source(dir.file("mix_*.vtu"), with_attributes({"rho"}));
  std::atomic<int> wrong{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&, t] {
      for (int rep = 0; rep < 10; ++rep) {
        for (uint64_t i = static_cast<uint64_t>(t % 2); i < 8; i += 2) {
          const bool bad = i % 2 == 1;
          try {
            const ParticleFrame f = src->read(i);
            if (bad || f.count() != kN) ++wrong;
          } catch (const Error& e) {
            const bool named = std::string(e.what()).find("mix_" + std::to_string(i) + ".vtu") != std::string::npos;
            if (!bad || !named || e.where().frame != i) ++wrong;
          }
        }
      }
    });
  }
  for (auto& th : threads) th.join();
  EXPECT_EQ(wrong.load(), 0);
}

#else  // no VTK in this build

TEST(VtkImport, VtkFilesNeedAVtkBuild) {
  expect_error([] { open_source((kData / "ug_binary.vtu").string(), {}); },
               {"ug_binary.vtu", "no VTK support", "libvtk9-dev", "rebuild"});
}

// Legacy files are sluice's own: they read without VTK.
TEST(VtkImport, LegacyFilesNeedNoVtk) {
  expect_reference(open_source((kData / "ug_ascii.vtk").string(), {})->read(0), all_reference(), true, false);
}

#endif

// ------------------------------------------------------- the real sample

// PySPH's dam break (data/dam_break_3d, see its README): every frame reads,
// positions are finite and gid is the same set of ids in every frame.
TEST(RealSample, PySphDamBreak) {
#ifndef SLUICE_WITH_VTK
  GTEST_SKIP() << "built without VTK";
#else
  const fs::path dir = SLUICE_SAMPLE_DIR;
  std::error_code ec;
  // The sample is part of the repository: without it the test fails.
  ASSERT_TRUE(fs::is_directory(dir, ec)) << dir << " does not exist";
  ASSERT_FALSE(sluice::import::expand_glob_natural((dir / "*.vtu").string()).empty()) << "no .vtu files in " << dir;

  const bool fluid = !sluice::import::expand_glob_natural((dir / "*_fluid_*.vtu").string()).empty();
  const std::string spec = fluid ? (dir / "*_fluid_*.vtu").string() : dir.string();
  auto src = open_source(spec, with_attributes({"rho", "velocity"}));
  ASSERT_GT(src->frame_count(), 0u);
  EXPECT_EQ(src->info().id_array, "gid") << "the sample was exported without gid (dump_vtk -s rho,p,gid)";
  std::vector<uint64_t> first_ids;
  for (uint64_t i = 0; i < src->frame_count(); ++i) {
    const ParticleFrame f = src->read(i);
    SCOPED_TRACE(src->frame_name(i));
    ASSERT_GT(f.count(), 0u);
    EXPECT_TRUE(std::all_of(f.positions.begin(), f.positions.end(), [](float v) { return std::isfinite(v); }));
    EXPECT_TRUE(f.repairs.empty()) << repairs_of(f);
    ASSERT_EQ(f.ids.size(), f.count());
    std::vector<uint64_t> ids = f.ids;
    std::sort(ids.begin(), ids.end());
    EXPECT_TRUE(std::adjacent_find(ids.begin(), ids.end()) == ids.end()) << "duplicate ids";
    if (i == 0) {
      first_ids = ids;
    } else {
      EXPECT_EQ(ids, first_ids) << "ids differ from frame 0";
    }
    for (const auto& a : f.attributes) {
      EXPECT_TRUE(std::all_of(a.begin(), a.end(), [](float v) { return std::isfinite(v); }));
    }
  }
  // The directory itself holds one particle set here, so it opens as is.
  EXPECT_EQ(open_source(dir.string(), {})->frame_count(), src->frame_count());
#endif
}
