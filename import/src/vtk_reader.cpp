// One VTK file into a ParticleFrame, through VTK's own readers.
#include "vtk_reader.h"

#include <vtkCellType.h>
#include <vtkCellTypes.h>
#include <vtkDataArray.h>
#include <vtkDataArraySelection.h>
#include <vtkDataSet.h>
#include <vtkFieldData.h>
#include <vtkLogger.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkOutputWindow.h>
#include <vtkPointData.h>
#include <vtkPointSet.h>
#include <vtkPoints.h>
#include <vtkSmartPointer.h>
#include <vtkXMLPPolyDataReader.h>
#include <vtkXMLPUnstructuredDataReader.h>
#include <vtkXMLUnstructuredDataReader.h>
#include <vtkXMLPUnstructuredGridReader.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLUnstructuredGridReader.h>
#include <vtkPolyData.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnstructuredGrid.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <type_traits>

#include "cell_types.h"
#include "values.h"
#include "sluice/error.h"

namespace sluice::import::detail {

using namespace sluice::io;  // the container's types: frames, errors, shapes
using io::Error;  // (not sluice::Error, its base)
namespace {

// ------------------------------------------------ VTK's messages, per thread

// VTK reports errors through a process-wide output window instead of
// throwing. Our window appends them to the capture buffer of the calling
// thread, so concurrent reads each see only their own errors.
thread_local std::vector<std::string>* t_capture = nullptr;

// "ERROR: In /src/vtkXMLReader.cxx, line 42\nvtkXMLUnstructuredGridReader
// (0x55d1): Error opening file\n\n" -> "vtkXMLUnstructuredGridReader: Error
// opening file".
std::string clean_message(const char* text) {
  std::string s = text ? text : "";
  if (s.rfind("ERROR: In ", 0) == 0 || s.rfind("Warning: In ", 0) == 0) {
    const size_t nl = s.find('\n');
    s = nl == std::string::npos ? std::string() : s.substr(nl + 1);
  }
  if (const size_t open = s.find(" (0x"); open != std::string::npos) {
    const size_t close = s.find("):", open);
    if (close != std::string::npos) s.erase(open, close + 1 - open);
  }
  // One line, single spaces.
  std::string out;
  for (char c : s) {
    const bool space = c == ' ' || c == '\n' || c == '\r' || c == '\t';
    if (space && (out.empty() || out.back() == ' ')) continue;
    out += space ? ' ' : c;
  }
  while (!out.empty() && out.back() == ' ') out.pop_back();
  return out;
}

// The pipeline's own "algorithm returned failure" follows the reader's
// real message and only adds noise (a dump of the request).
bool is_pipeline_echo(const std::string& m) {
  return m.rfind("vtkCompositeDataPipeline:", 0) == 0 || m.rfind("vtkStreamingDemandDrivenPipeline:", 0) == 0 ||
         m.rfind("vtkDemandDrivenPipeline:", 0) == 0 || m.rfind("vtkExecutive:", 0) == 0;
}

class CaptureWindow : public vtkOutputWindow {
 public:
  static CaptureWindow* New();
  vtkTypeMacro(CaptureWindow, vtkOutputWindow)

  void DisplayErrorText(const char* text) override {
    if (t_capture) {
      t_capture->push_back(clean_message(text));
    } else {
      std::fprintf(stderr, "VTK: %s\n", clean_message(text).c_str());  // VTK used outside a read
    }
  }
  // Warnings and chatter would interleave with sluice's own output; a read
  // either succeeds or its errors are thrown.
  void DisplayText(const char*) override {}
  void DisplayWarningText(const char*) override {}
  void DisplayGenericWarningText(const char*) override {}
  void DisplayDebugText(const char*) override {}
};
vtkStandardNewMacro(CaptureWindow);

// Collects VTK errors raised on this thread while it lives.
class ErrorCapture {
 public:
  ErrorCapture() : previous_(t_capture) {
    static std::once_flag installed;
    std::call_once(installed, [] {
      vtkNew<CaptureWindow> window;
      vtkOutputWindow::SetInstance(window);
      // VTK 9 also logs every error to stderr itself; the window has it.
      vtkLogger::SetStderrVerbosity(vtkLogger::VERBOSITY_OFF);
    });
    t_capture = &errors_;
  }
  ~ErrorCapture() { t_capture = previous_; }
  ErrorCapture(const ErrorCapture&) = delete;
  ErrorCapture& operator=(const ErrorCapture&) = delete;

  // Removes the messages containing `text`; true if there were any.
  bool take(const char* text) {
    const auto has = [&](const std::string& m) { return m.find(text) != std::string::npos; };
    const auto it = std::remove_if(errors_.begin(), errors_.end(), has);
    const bool found = it != errors_.end();
    errors_.erase(it, errors_.end());
    return found;
  }

  void throw_if_any(const std::string& path) const {
    if (errors_.empty()) return;
    std::vector<std::string> shown;
    for (const auto& m : errors_) {
      if (!is_pipeline_echo(m) && shown.size() < 3) shown.push_back(m);
    }
    if (shown.empty()) shown.push_back(errors_.front());
    std::string msg = "VTK could not read the file: " + shown.front();
    for (size_t k = 1; k < shown.size(); ++k) msg += "; " + shown[k];
    throw Error({path}, msg);
  }

 private:
  std::vector<std::string> errors_;
  std::vector<std::string>* previous_;
};

// ----------------------------------------------------------- opening files

enum class Kind { kVtu, kVtp, kPvtu, kPvtp };

Kind kind_of(const std::string& path) {
  const size_t dot = path.rfind('.');
  std::string ext = dot == std::string::npos ? "" : path.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == "vtu") return Kind::kVtu;
  if (ext == "vtp") return Kind::kVtp;
  if (ext == "pvtu") return Kind::kPvtu;
  if (ext == "pvtp") return Kind::kPvtp;
  return Kind::kVtu;
}

// VTK's XML readers without the cells: sluice takes points and point
// arrays only, and the cells (connectivity, offsets, types: more bytes than
// the points for one vertex per particle) would be read, allocated and
// sized by their own offsets for nothing. Each reader reads its piece as
// its base class does, minus the cell lists; the parallel readers make such
// piece readers and do not copy cells. The kinds of cells, for the note,
// come from the checks (xml_check.h).
class GridPointsReader : public vtkXMLUnstructuredGridReader {
 public:
  static GridPointsReader* New();
  vtkTypeMacro(GridPointsReader, vtkXMLUnstructuredGridReader)

 protected:
  int ReadPieceData() override { return vtkXMLUnstructuredDataReader::ReadPieceData(); }
};
vtkStandardNewMacro(GridPointsReader);

class PolyPointsReader : public vtkXMLPolyDataReader {
 public:
  static PolyPointsReader* New();
  vtkTypeMacro(PolyPointsReader, vtkXMLPolyDataReader)

 protected:
  int ReadPieceData() override { return vtkXMLUnstructuredDataReader::ReadPieceData(); }
};
vtkStandardNewMacro(PolyPointsReader);

class ParallelGridPointsReader : public vtkXMLPUnstructuredGridReader {
 public:
  static ParallelGridPointsReader* New();
  vtkTypeMacro(ParallelGridPointsReader, vtkXMLPUnstructuredGridReader)

 protected:
  int ReadPieceData() override { return vtkXMLPUnstructuredDataReader::ReadPieceData(); }
  vtkXMLDataReader* CreatePieceReader() override { return GridPointsReader::New(); }
};
vtkStandardNewMacro(ParallelGridPointsReader);

class ParallelPolyPointsReader : public vtkXMLPPolyDataReader {
 public:
  static ParallelPolyPointsReader* New();
  vtkTypeMacro(ParallelPolyPointsReader, vtkXMLPPolyDataReader)

 protected:
  int ReadPieceData() override { return vtkXMLPUnstructuredDataReader::ReadPieceData(); }
  vtkXMLDataReader* CreatePieceReader() override { return PolyPointsReader::New(); }
};
vtkStandardNewMacro(ParallelPolyPointsReader);

vtkSmartPointer<vtkXMLReader> make_xml_reader(Kind kind) {
  switch (kind) {
    case Kind::kVtu: return vtkSmartPointer<GridPointsReader>::New();
    case Kind::kVtp: return vtkSmartPointer<PolyPointsReader>::New();
    case Kind::kPvtu: return vtkSmartPointer<ParallelGridPointsReader>::New();
    case Kind::kPvtp: return vtkSmartPointer<ParallelPolyPointsReader>::New();
  }
  return nullptr;
}

// A dataset and what keeps it alive.
struct Loaded {
  vtkSmartPointer<vtkAlgorithm> reader;
  vtkDataSet* data = nullptr;
  std::vector<std::string> arrays;  // point-data arrays in the file
};

std::vector<std::string> selection_names(vtkDataArraySelection* sel) {
  std::vector<std::string> names;
  for (int k = 0; k < sel->GetNumberOfArrays(); ++k) names.emplace_back(sel->GetArrayName(k));
  return names;
}

constexpr const char* kNoPointsElement = "No Points element available in first piece";

// Reads the XML header only; `wanted` == nullptr stops there. Otherwise
// only the wanted point arrays are decoded: PySPH files carry arrays we
// would decompress for nothing.
Loaded load_xml(const std::string& path, Kind kind, const std::vector<std::string>* wanted) {
  ErrorCapture capture;
  Loaded out;
  vtkSmartPointer<vtkXMLReader> reader = make_xml_reader(kind);
  out.reader = reader;
  reader->SetFileName(path.c_str());
  reader->UpdateInformation();
  // VTK's writers store an empty dataset with an empty <Points/>, which its
  // reader then reports as an error although it reads the file fine.
  bool no_points_element = capture.take(kNoPointsElement);
  capture.throw_if_any(path);
  out.arrays = selection_names(reader->GetPointDataArraySelection());
  if (!wanted) return out;
  reader->GetPointDataArraySelection()->DisableAllArrays();
  for (const auto& name : *wanted) reader->GetPointDataArraySelection()->EnableArray(name.c_str());
  reader->GetCellDataArraySelection()->DisableAllArrays();
  reader->Update();
  no_points_element = capture.take(kNoPointsElement) || no_points_element;
  capture.throw_if_any(path);
  out.data = reader->GetOutputAsDataSet();
  if (!out.data) throw Error({path}, "VTK could not read the file (no dataset)");
  if (no_points_element && out.data->GetNumberOfPoints() != 0) {
    throw Error({path}, std::string("VTK could not read the file: ") + kNoPointsElement);
  }
  return out;
}

Loaded load(const std::string& path, const std::vector<std::string>* wanted) {
  return load_xml(path, kind_of(path), wanted);
}

// ------------------------------------------------------- array conversion

std::string join(const std::vector<std::string>& names) {
  if (names.empty()) return "(none)";
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

// All values of `a` as float, tuple-major. Typed access on contiguous
// arrays (every array a reader makes); GetComponent only as a fallback.
void copy_as_float(vtkDataArray* a, std::vector<float>& out) {
  const size_t count = static_cast<size_t>(a->GetNumberOfTuples()) * a->GetNumberOfComponents();
  if (count == 0) return out.clear();
  if (a->HasStandardMemoryLayout()) {
    void* raw = a->GetVoidPointer(0);
    switch (a->GetDataType()) {
      vtkTemplateMacro(assign_values(static_cast<const VTK_TT*>(raw), count, out); return);
      default: break;
    }
  }
  out.resize(count);
  const int comps = a->GetNumberOfComponents();
  for (size_t k = 0; k < count; ++k) {
    out[k] = static_cast<float>(a->GetComponent(static_cast<vtkIdType>(k / comps), static_cast<int>(k % comps)));
  }
}

// One float per tuple: the value itself, or the magnitude of a vector.
void copy_scalar(vtkDataArray* a, std::vector<float>& values) {
  const size_t comps = static_cast<size_t>(a->GetNumberOfComponents());
  if (comps == 1) {
    copy_as_float(a, values);
    return;
  }
  values.resize(static_cast<size_t>(a->GetNumberOfTuples()));
  float* out = values.data();
  const size_t tuples = static_cast<size_t>(a->GetNumberOfTuples());
  if (a->HasStandardMemoryLayout()) {
    void* raw = a->GetVoidPointer(0);
    switch (a->GetDataType()) {
      vtkTemplateMacro(magnitudes(static_cast<const VTK_TT*>(raw), tuples, comps, out); return);
      default: break;
    }
  }
  std::vector<double> tuple(comps);
  for (size_t t = 0; t < tuples; ++t) {
    a->GetTuple(static_cast<vtkIdType>(t), tuple.data());
    double sum = 0.0;
    for (double v : tuple) sum += v * v;
    out[t] = static_cast<float>(std::sqrt(sum));
  }
}

size_t copy_ids(vtkDataArray* a, std::vector<uint64_t>& out) {
  const size_t count = static_cast<size_t>(a->GetNumberOfTuples());
  if (count == 0) return 0;
  if (a->HasStandardMemoryLayout()) {
    void* raw = a->GetVoidPointer(0);
    switch (a->GetDataType()) {
      vtkTemplateMacro(return assign_ids(static_cast<const VTK_TT*>(raw), count, out));
      default: break;
    }
  }
  out.resize(count);
  for (size_t k = 0; k < count; ++k) {
    const double v = a->GetComponent(static_cast<vtkIdType>(k), 0);
    if (!(v >= 0) || std::floor(v) != v || v >= 18446744073709551616.0) return k;
    out[k] = static_cast<uint64_t>(v);
  }
  return count;
}

// ------------------------------------------------------- dataset -> frame

void copy_positions(const std::string& path, vtkDataSet* ds, std::vector<float>& out) {
  const vtkIdType n = ds->GetNumberOfPoints();
  auto* ps = vtkPointSet::SafeDownCast(ds);
  if (ps && ps->GetPoints()) {
    vtkDataArray* a = ps->GetPoints()->GetData();
    if (a->GetNumberOfComponents() != 3) throw Error({path}, "points do not have 3 components");
    copy_as_float(a, out);
    return;
  }
  out.resize(static_cast<size_t>(n) * 3);
  // Image and rectilinear data: points are implicit, generate them.
  double p[3];
  for (vtkIdType i = 0; i < n; ++i) {
    ds->GetPoint(i, p);
    for (int c = 0; c < 3; ++c) out[static_cast<size_t>(i) * 3 + c] = static_cast<float>(p[c]);
  }
}

// The point array `name`, checked to be numeric and of the right length.
vtkDataArray* point_array(const std::string& path, vtkDataSet* ds, const std::string& name,
                          const std::vector<std::string>& existing, const char* what) {
  vtkPointData* pd = ds->GetPointData();
  vtkDataArray* a = pd->GetArray(name.c_str());
  if (!a) {
    if (pd->GetAbstractArray(name.c_str())) throw Error({path}, std::string(what) + " '" + name + "' is not numeric");
    throw Error({path}, "no point array '" + name + "' (" + what + "); arrays in the file: " + join(existing));
  }
  const vtkIdType n = ds->GetNumberOfPoints();
  if (a->GetNumberOfTuples() != n) {
    throw Error({path}, "array '" + name + "' has " + std::to_string(a->GetNumberOfTuples()) +
                            " values but the file has " + std::to_string(n) + " points");
  }
  return a;
}

void copy_id_array(const std::string& path, vtkDataArray* a, const std::string& name, std::vector<uint64_t>& out) {
  if (a->GetNumberOfComponents() != 1) {
    throw Error({path}, "id array '" + name + "' has " + std::to_string(a->GetNumberOfComponents()) +
                            " components; ids need 1");
  }
  const size_t bad = copy_ids(a, out);
  if (bad < static_cast<size_t>(a->GetNumberOfTuples())) {
    char value[64];
    std::snprintf(value, sizeof value, "%.17g", a->GetComponent(static_cast<vtkIdType>(bad), 0));
    throw Error({path}, "id array '" + name + "' holds " + value + " at index " + std::to_string(bad) +
                            ": ids must be non-negative integers");
  }
}

// Simulation time, when a writer stored it (VTK's TimeValue convention, or TIME).
std::optional<double> field_time(vtkDataSet* ds) {
  vtkFieldData* fd = ds->GetFieldData();
  if (!fd) return std::nullopt;
  for (int k = 0; k < fd->GetNumberOfArrays(); ++k) {
    vtkDataArray* a = fd->GetArray(k);
    if (!a || !a->GetName() || a->GetNumberOfTuples() < 1) continue;
    std::string name = a->GetName();
    std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (name != "timevalue" && name != "time") continue;
    const double t = a->GetComponent(0, 0);
    if (std::isfinite(t)) return t;
  }
  return std::nullopt;
}

}  // namespace

std::vector<std::string> vtk_arrays(const std::string& path) { return load(path, nullptr).arrays; }

VtkRead read_vtk(const std::string& path, const std::vector<std::string>& attributes, const std::string& id_array,
                 const std::vector<std::string>& non_vertex_cells) {
  std::vector<std::string> wanted = attributes;
  if (!id_array.empty()) wanted.push_back(id_array);
  const Loaded loaded = load(path, &wanted);
  vtkDataSet* ds = loaded.data;

  VtkRead out;
  out.time = field_time(ds);
  ParticleFrame& f = out.frame;
  f.attributes.resize(attributes.size());
  // An empty file often declares no arrays at all: nothing to look up.
  if (ds->GetNumberOfPoints() == 0) return out;

  copy_positions(path, ds, f.positions);
  const size_t n = f.count();
  if (!id_array.empty()) {
    copy_id_array(path, point_array(path, ds, id_array, loaded.arrays, "id array"), id_array, f.ids);
  }
  for (size_t k = 0; k < attributes.size(); ++k) {
    vtkDataArray* a = point_array(path, ds, attributes[k], loaded.arrays, "attribute");
    copy_scalar(a, f.attributes[k]);
  }
  if (!non_vertex_cells.empty()) f.repairs.push_back(ignored_cells_note(non_vertex_cells, n));
  return out;
}

}  // namespace sluice::import::detail
