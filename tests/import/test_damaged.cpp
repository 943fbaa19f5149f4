// Damaged copies of real solver output: every one gives an io::Error naming
// the file (and, for short data, what was expected against what was
// found), or reads the same particles; none crashes, hangs or reads zeros
// where the data ended.
//
// The copies are made here from frame 0 of the bundled PySPH dam break
// (9,360 particles), written by VTK's own writers in every flavour the
// importer takes, then cut at several points, with counts raised, bytes
// flipped and text values made non-numeric.
#include <gtest/gtest.h>

#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkPolyDataWriter.h>
#include <vtkUnstructuredGrid.h>
#include <vtkUnstructuredGridWriter.h>
#include <vtkXMLPolyDataWriter.h>
#include <vtkXMLUnstructuredGridReader.h>
#include <vtkXMLUnstructuredGridWriter.h>
#include <vtkCellArray.h>
#include <vtkCellType.h>
#include <vtkPoints.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "sluice/error.h"
#include "sluice/import/source.h"

namespace fs = std::filesystem;
using sluice::io::Error;
using sluice::import::SourceOptions;
using sluice::io::ParticleFrame;

namespace {

const fs::path kSample = fs::path(SLUICE_SAMPLE_DIR) / "dam_break_3d_fluid_00000.vtu";

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void spill(const fs::path& p, const std::string& bytes) {
  std::ofstream out(p, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// The flavours, written once per test binary from the real frame.
struct Flavour {
  std::string name;  // file name, its extension picks the reader
  bool text;         // legacy ASCII: values can be made non-numeric
};

const std::vector<Flavour>& flavours() {
  static const std::vector<Flavour> kAll = {
      {"legacy_ug_binary_51.vtk", false}, {"legacy_pd_binary_42.vtk", false}, {"legacy_ug_ascii_42.vtk", true},
      {"legacy_pd_ascii_51.vtk", true},   {"xml_ug_raw.vtu", false},          {"xml_ug_zlib_raw.vtu", false},
      {"xml_ug_zlib_base64.vtu", false},  {"xml_pd_inline_base64.vtp", false}, {"xml_pd_ascii.vtp", true}};
  return kAll;
}

class Corpus {
 public:
  static Corpus& get() {
    static Corpus c;
    return c;
  }
  fs::path dir;
  uint64_t particles = 0;

 private:
  Corpus() {
    dir = fs::temp_directory_path() / ("sluice_damaged_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    vtkNew<vtkXMLUnstructuredGridReader> reader;
    reader->SetFileName(kSample.c_str());
    reader->Update();
    vtkUnstructuredGrid* ug = reader->GetOutput();
    particles = static_cast<uint64_t>(ug->GetNumberOfPoints());
    vtkNew<vtkPolyData> pd;
    pd->SetPoints(ug->GetPoints());
    vtkNew<vtkCellArray> verts;
    for (vtkIdType i = 0; i < ug->GetNumberOfPoints(); ++i) verts->InsertNextCell(1, &i);
    pd->SetVerts(verts);
    pd->GetPointData()->ShallowCopy(ug->GetPointData());

    const auto legacy = [&](auto writer, vtkDataObject* data, const char* name, bool binary, int version) {
      writer->SetInputData(data);
      writer->SetFileName((dir / name).c_str());
      if (binary) writer->SetFileTypeToBinary();
      else writer->SetFileTypeToASCII();
      writer->SetFileVersion(version);
      ASSERT_EQ(writer->Write(), 1) << name;
    };
    legacy(vtkNew<vtkUnstructuredGridWriter>().Get(), ug, "legacy_ug_binary_51.vtk", true, 51);
    legacy(vtkNew<vtkPolyDataWriter>().Get(), pd, "legacy_pd_binary_42.vtk", true, 42);
    legacy(vtkNew<vtkUnstructuredGridWriter>().Get(), ug, "legacy_ug_ascii_42.vtk", false, 42);
    legacy(vtkNew<vtkPolyDataWriter>().Get(), pd, "legacy_pd_ascii_51.vtk", false, 51);

    const auto xml = [&](auto writer, vtkDataObject* data, const char* name, const char* mode, bool zlib, bool encode) {
      writer->SetInputData(data);
      writer->SetFileName((dir / name).c_str());
      if (std::string(mode) == "appended") writer->SetDataModeToAppended();
      else if (std::string(mode) == "binary") writer->SetDataModeToBinary();
      else writer->SetDataModeToAscii();
      if (zlib) writer->SetCompressorTypeToZLib();
      else writer->SetCompressorTypeToNone();
      writer->SetEncodeAppendedData(encode);
      ASSERT_EQ(writer->Write(), 1) << name;
    };
    xml(vtkNew<vtkXMLUnstructuredGridWriter>().Get(), ug, "xml_ug_raw.vtu", "appended", false, false);
    xml(vtkNew<vtkXMLUnstructuredGridWriter>().Get(), ug, "xml_ug_zlib_raw.vtu", "appended", true, false);
    xml(vtkNew<vtkXMLUnstructuredGridWriter>().Get(), ug, "xml_ug_zlib_base64.vtu", "appended", true, true);
    xml(vtkNew<vtkXMLPolyDataWriter>().Get(), pd, "xml_pd_inline_base64.vtp", "binary", false, true);
    xml(vtkNew<vtkXMLPolyDataWriter>().Get(), pd, "xml_pd_ascii.vtp", "ascii", false, false);
  }
  ~Corpus() {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
};

SourceOptions options() {
  SourceOptions o;
  o.attributes = {"rho", "velocity"};
  o.id_array = "gid";
  return o;
}

ParticleFrame read(const fs::path& p) { return sluice::import::open_source(p.string(), options())->read(0); }

// Reads `p`, which must fail with an io::Error naming it and containing
// every one of `words`.
void expect_error(const fs::path& p, const std::vector<std::string>& words, const std::string& label) {
  try {
    const ParticleFrame f = read(p);
    ADD_FAILURE() << label << ": read " << f.count() << " particles without an error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(p.filename().string()), std::string::npos) << label << ": " << what;
    for (const auto& w : words) EXPECT_NE(what.find(w), std::string::npos) << label << ": '" << w << "' not in: " << what;
  }
}

class Damaged : public ::testing::TestWithParam<Flavour> {
 protected:
  fs::path original() const { return Corpus::get().dir / GetParam().name; }
  fs::path copy(const std::string& tag, const std::string& bytes) const {
    const fs::path p = Corpus::get().dir / (tag + "_" + GetParam().name);
    spill(p, bytes);
    return p;
  }
};

TEST_P(Damaged, IntactCopyReadsEveryParticle) {
  const ParticleFrame f = read(original());
  EXPECT_EQ(f.count(), Corpus::get().particles);
  EXPECT_EQ(f.ids.size(), f.count());
  ASSERT_EQ(f.attributes.size(), 2u);
  // Same particles as the .vtu the flavour was written from (VTK's reader).
  const ParticleFrame reference = read(kSample);
  EXPECT_EQ(f.positions, reference.positions);
  EXPECT_EQ(f.ids, reference.ids);
  EXPECT_EQ(f.attributes, reference.attributes);
}

// A copy cut short (a crashed solver, a copy interrupted) never reads as
// fewer particles or as zeros.
TEST_P(Damaged, CutShortGivesAnError) {
  const std::string bytes = slurp(original());
  for (const double at : {0.02, 0.1, 0.3, 0.5, 0.7, 0.9, 0.99}) {
    const auto cut = static_cast<size_t>(static_cast<double>(bytes.size()) * at);
    const fs::path p = copy("cut" + std::to_string(cut), bytes.substr(0, cut));
    expect_error(p, {}, "cut at " + std::to_string(cut) + " of " + std::to_string(bytes.size()));
  }
}

// The point count raised: the declared size is compared with what is there
// before anything is allocated.
TEST_P(Damaged, RaisedCountGivesAnError) {
  std::string bytes = slurp(original());
  const std::string count = std::to_string(Corpus::get().particles);
  const bool legacy = GetParam().name.rfind("legacy", 0) == 0;
  const std::string key = legacy ? "POINTS " + count : "NumberOfPoints=\"" + count;
  const size_t at = bytes.find(key);
  ASSERT_NE(at, std::string::npos);
  bytes.replace(at, key.size(), legacy ? "POINTS 99999999" : "NumberOfPoints=\"99999999");
  expect_error(copy("raised", bytes), {"99999999"}, "count raised");
}

// Bytes changed anywhere: an error naming the file, or particles; never a
// crash (the sanitizer builds run this too).
TEST_P(Damaged, FlippedBytesNeverCrash) {
  const std::string bytes = slurp(original());
  std::mt19937_64 rng(1234);
  int errors = 0;
  for (int round = 0; round < 12; ++round) {
    std::string damaged = bytes;
    for (int k = 0; k < 200; ++k) damaged[rng() % damaged.size()] = static_cast<char>(rng());
    const fs::path p = copy("flip" + std::to_string(round), damaged);
    try {
      (void)read(p);
    } catch (const Error& e) {
      ++errors;
      EXPECT_NE(std::string(e.what()).find(p.filename().string()), std::string::npos) << e.what();
    }
  }
  RecordProperty("errors", errors);
}

// The flavours that hold their values as text.
class DamagedText : public Damaged {};

std::vector<Flavour> text_flavours() {
  std::vector<Flavour> out;
  for (const auto& f : flavours()) {
    if (f.text) out.push_back(f);
  }
  return out;
}

TEST_P(DamagedText, NonNumericTextNamesTheValue) {
  std::string bytes = slurp(original());
  // A value in the middle of the file: its digits become letters.
  size_t at = bytes.size() / 2;
  while (at < bytes.size() && !std::isdigit(static_cast<unsigned char>(bytes[at]))) ++at;
  ASSERT_LT(at, bytes.size());
  bytes[at] = 'x';
  const fs::path p = copy("text", bytes);
  if (GetParam().name.rfind("legacy", 0) == 0) {
    expect_error(p, {"', not "}, "non-numeric value");
  } else {
    expect_error(p, {"not a number"}, "non-numeric value");
  }
}

std::string test_name(const ::testing::TestParamInfo<Flavour>& info) {
  std::string n = info.param.name;
  for (char& c : n) {
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  }
  return n;
}

INSTANTIATE_TEST_SUITE_P(EveryFlavour, Damaged, ::testing::ValuesIn(flavours()), test_name);
INSTANTIATE_TEST_SUITE_P(TextFlavours, DamagedText, ::testing::ValuesIn(text_flavours()), test_name);

// The four cases of the reliability issue, on a legacy binary file.
TEST(DamagedLegacy, CutPolydataNamesTheSection) {
  const std::string bytes = slurp(Corpus::get().dir / "legacy_pd_binary_42.vtk");
  const fs::path p = Corpus::get().dir / "cut_half.vtk";
  spill(p, bytes.substr(0, bytes.size() / 2));
  expect_error(p, {"bytes", "cut short"}, "legacy cut in half");
}

TEST(DamagedLegacy, RaisedPointsCountSaysExpectedAndFound) {
  std::string bytes = slurp(Corpus::get().dir / "legacy_pd_binary_42.vtk");
  const std::string key = "POINTS " + std::to_string(Corpus::get().particles);
  bytes.replace(bytes.find(key), key.size(), "POINTS 99999999");
  const fs::path p = Corpus::get().dir / "raised.vtk";
  spill(p, bytes);
  expect_error(p, {"POINTS", "99999999", "need", "bytes", "the file has"}, "POINTS raised");
}

TEST(DamagedLegacy, CutUnstructuredGridNeverReadsZeros) {
  const std::string bytes = slurp(Corpus::get().dir / "legacy_ug_binary_51.vtk");
  // Cut inside the POINTS block: VTK's reader filled the rest with zeros.
  const size_t points = bytes.find("POINTS");
  const fs::path p = Corpus::get().dir / "cut_points.vtk";
  spill(p, bytes.substr(0, points + 40000));
  expect_error(p, {"POINTS", "cut short"}, "cut inside POINTS");
}

}  // namespace

namespace {

// Every input the fuzzer (fuzz_vtk_import) found a fault with is kept in
// tests/data/fuzz/vtk and must give an error naming it, or read.
TEST(FuzzFindings, EachGivesAnErrorOrReads) {
  const fs::path dir = fs::path(__FILE__).parent_path().parent_path() / "data" / "fuzz" / "vtk";
  int files = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    ++files;
    try {
      (void)read(entry.path());
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(entry.path().filename().string()), std::string::npos) << e.what();
    }
  }
  EXPECT_GT(files, 0);
}

}  // namespace

namespace {

// Cells are not read by VTK's reader (only points and point arrays): the
// kinds of cells a mesh file holds come from sluice's checks, in every
// encoding, and are named in the repair note.
TEST(XmlCells, MeshCellsAreNamedInEveryEncoding) {
  vtkNew<vtkPoints> points;
  for (int i = 0; i < 5; ++i) points->InsertNextPoint(i, i % 2, i % 3);
  vtkNew<vtkUnstructuredGrid> grid;
  grid->SetPoints(points);
  const vtkIdType tetra[4] = {0, 1, 2, 3};
  grid->InsertNextCell(VTK_TETRA, 4, tetra);
  const vtkIdType vertex = 4;
  grid->InsertNextCell(VTK_VERTEX, 1, &vertex);
  const fs::path dir = Corpus::get().dir;
  struct Mode {
    const char* name;
    const char* mode;
    bool zlib;
    bool encode;
  };
  for (const Mode& m : {Mode{"mesh_raw.vtu", "appended", false, false}, Mode{"mesh_zlib.vtu", "appended", true, true},
                        Mode{"mesh_inline.vtu", "binary", true, true}, Mode{"mesh_ascii.vtu", "ascii", false, false}}) {
    vtkNew<vtkXMLUnstructuredGridWriter> w;
    w->SetInputData(grid);
    w->SetFileName((dir / m.name).c_str());
    if (std::string(m.mode) == "appended") w->SetDataModeToAppended();
    else if (std::string(m.mode) == "binary") w->SetDataModeToBinary();
    else w->SetDataModeToAscii();
    if (m.zlib) w->SetCompressorTypeToZLib();
    else w->SetCompressorTypeToNone();
    w->SetEncodeAppendedData(m.encode);
    ASSERT_EQ(w->Write(), 1);
    const ParticleFrame f = sluice::import::open_source((dir / m.name).string(), {})->read(0);
    EXPECT_EQ(f.count(), 5u) << m.name;
    ASSERT_EQ(f.repairs.size(), 1u) << m.name;
    EXPECT_EQ(f.repairs[0], "cells of type TETRA ignored: using the 5 points as particles") << m.name;
  }
  // Polydata: the cell lists other than vertices.
  vtkNew<vtkPolyData> poly;
  poly->SetPoints(points);
  vtkNew<vtkCellArray> lines;
  const vtkIdType line[2] = {0, 1};
  lines->InsertNextCell(2, line);
  poly->SetLines(lines);
  vtkNew<vtkXMLPolyDataWriter> w;
  w->SetInputData(poly);
  w->SetFileName((dir / "lines.vtp").c_str());
  ASSERT_EQ(w->Write(), 1);
  const ParticleFrame f = sluice::import::open_source((dir / "lines.vtp").string(), {})->read(0);
  ASSERT_EQ(f.repairs.size(), 1u);
  EXPECT_EQ(f.repairs[0], "cells of type LINES ignored: using the 5 points as particles");
}

}  // namespace
