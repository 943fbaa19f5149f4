#include "convert.h"

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "callback.h"
#include "sluice/import/convert.h"
#include "sluice/io/up_axis.h"

namespace py = pybind11;

namespace sluice::python {
namespace {

// The conversion's observer: progress to the Python callable, notes kept.
class PythonObserver {
 public:
  explicit PythonObserver(py::object progress) : progress_(std::move(progress)) {}

  import::ConvertObserver observer() {
    import::ConvertObserver o;
    o.progressed = [this](const import::ConvertProgress& p) { progress_.call_with([&] { return progress_dict(p); }); };
    o.noted = [this](const import::Note& n) { notes_.push_back(n.text); };
    return o;
  }
  const std::vector<std::string>& notes() const { return notes_; }
  void raise_saved() { progress_.raise_saved(); }

 private:
  PythonCallback progress_;
  std::vector<std::string> notes_;
};

std::optional<io::UpAxis> up_axis(const std::optional<std::string>& up) {
  if (!up) return std::nullopt;
  const auto axis = io::parse_up_axis(*up);
  if (!axis) throw py::value_error("up must be an axis such as '+z', 'y' or '-x', not '" + *up + "'");
  return axis;
}

py::dict summary_dict(const import::ConvertSummary& s, const std::vector<std::string>& notes) {
  py::dict d;
  d["frames"] = s.frames;
  d["particles"] = s.particles;
  d["input_bytes"] = s.input_bytes;
  d["seconds"] = s.elapsed.count();
  d["up"] = io::up_axis_name(s.header.up);
  d["up_evidence"] = io::up_evidence_name(s.header.up_evidence);
  d["spacing"] = s.header.particle_spacing;
  py::list skipped;
  for (const import::SkippedFrame& f : s.skipped) skipped.append(py::make_tuple(f.frame, f.name, f.error));
  d["skipped"] = skipped;
  d["notes"] = notes;
  return d;
}

const char* kConvertDoc = R"(Converts simulation output into a .sluice file.

The same conversion as `sluice convert`: spacing, radius, particle ids,
times and the up axis are found in the data unless given.

Args:
    input: a file, a glob ('out/part_*.vtk'), a .pvd collection or a
        directory (VTK legacy/XML, CSV, XYZ: see docs/import.md).
    output: the .sluice file to write (written as output + '.partial' and
        renamed when complete); one that exists is kept (sluice.Error)
        unless force=True.
    progress: called once per frame with a dict (frames_done, frames,
        input_bytes, output_bytes); raising from it stops the conversion.
    attributes: point arrays to carry for colouring; None carries none
        unless all_attributes.
    spacing, radius: world units (0: estimated; radius = spacing / 2).
    fps: playback frame rate; also the time step for inputs without times.
    dt: seconds between frames for inputs without times.
    up: '+z', 'y', '-x', ... (None: found from the data).
    ids: the particle id array (None: found); no_ids: LOD follows order.
    lossless: float32 positions instead of 16-bit quantized.
    layers: classify the narrow band (surface, interior, blobs).
    skip_bad: leave out frames that cannot be read (listed in the result).
    jobs: threads (0: every core).
    isolate: read third-party formats in worker processes (a crashing
        reader costs one frame, not the interpreter).
    read_timeout: seconds a worker may take for one frame before it is
        killed and the frame is bad.
    precision: the largest position error relative to the spacing (0:
        1/1024); drop_outliers: leave out particles this many spacings
        outside the rest (0: keep and note them).
    chunk: most particles per chunk; level: zstd level 1-19; planes:
        'packed' (default), 'smallest' (zstd wherever smaller) or
        'gpu-decodable'; tiers: write LOD tiers; band_voxel, band_f2: the
        narrow band's voxel (0: twice the spacing) and F2 test ('all' or
        'asymmetry'). As `sluice convert --help` explains them.
    force: replace an output that exists.

Returns:
    a dict: frames, particles, input_bytes, seconds, up, up_evidence,
    spacing, skipped [(frame, name, error)], notes [str].

Raises:
    sluice.Error: bad input or options (naming the file and frame).
    KeyboardInterrupt (Ctrl-C) or the callback's exception: the
    conversion stops between frames; output + '.partial' keeps the frames
    written so far (`sluice recover` makes it a file).
)";

}  // namespace

py::dict progress_dict(const import::ConvertProgress& p) {
  py::dict d;
  d["frames_done"] = p.frames_done;
  d["frames"] = p.frames;
  d["input_bytes"] = p.input_bytes;
  d["output_bytes"] = p.output_bytes;
  return d;
}

void bind_convert(py::module_& m) {
  m.def("convert",
        [](const std::filesystem::path& input, const std::filesystem::path& output, py::object progress,
           std::optional<std::vector<std::string>> attributes, bool all_attributes, float spacing, float radius, double fps,
           double dt, std::optional<std::string> up, std::optional<std::string> ids, bool no_ids, bool lossless, bool layers,
           bool skip_bad, int jobs, bool isolate, double precision, float drop_outliers, uint32_t chunk, int level,
           const std::string& planes, bool tiers, float band_voxel, const std::string& band_f2, double read_timeout,
           bool force) {
          // As the CLI: an existing output is kept unless asked.
          if (!force && std::filesystem::exists(output)) {
            throw io::Error({output.string()}, "exists; pass force=True to overwrite, or another output");
          }
          import::ConvertOptions o;
          o.precision = precision;
          o.drop_outliers = drop_outliers;
          if (chunk < 1) throw py::value_error("chunk must be at least 1 particle");
          o.chunk = chunk;
          if (level < 1 || level > 19) throw py::value_error("level must be a zstd level, 1 to 19");
          o.level = level;
          if (planes == "packed") o.planes = io::PlaneCoding::Packed;
          else if (planes == "smallest") o.planes = io::PlaneCoding::Zstd;
          else if (planes == "gpu-decodable") o.planes = io::PlaneCoding::GpuDecodable;
          else throw py::value_error("planes must be 'packed', 'smallest' or 'gpu-decodable', not '" + planes + "'");
          o.lod_tiers = tiers;
          o.band_voxel = band_voxel;
          if (band_f2 != "all" && band_f2 != "asymmetry") throw py::value_error("band_f2 must be 'all' or 'asymmetry'");
          o.band_f2 = band_f2 == "asymmetry" ? io::F2Test::Asymmetry : io::F2Test::All;
          if (!(read_timeout > 0)) throw py::value_error("read_timeout must be positive (seconds)");
          o.isolation.read_limit = std::chrono::seconds(int64_t(std::ceil(read_timeout)));
          o.input = input.string();
          if (attributes) o.attributes = *attributes;
          o.all_attributes = all_attributes;
          o.spacing = spacing;
          o.radius = radius;
          o.fps = fps;
          o.dt = dt;
          o.up = up_axis(up);
          if (ids) o.id_array = *ids;
          o.no_ids = no_ids;
          o.lossless = lossless;
          o.layers = layers;
          o.skip_bad = skip_bad;
          o.jobs = jobs;
          o.isolation.mode = isolate ? import::Isolation::WorkerProcesses : import::Isolation::InProcess;
          PythonObserver observer(std::move(progress));
          std::optional<import::ConvertSummary> summary;
          try {
            py::gil_scoped_release unlocked;
            summary = import::convert(o, output.string(), observer.observer());
          } catch (const PythonRaised&) {
            observer.raise_saved();
          }
          return summary_dict(*summary, observer.notes());
        },
        kConvertDoc, py::arg("input"), py::arg("output"), py::kw_only(), py::arg("progress") = py::none(),
        py::arg("attributes") = py::none(), py::arg("all_attributes") = false, py::arg("spacing") = 0.0f,
        py::arg("radius") = 0.0f, py::arg("fps") = 0.0, py::arg("dt") = 0.0, py::arg("up") = py::none(),
        py::arg("ids") = py::none(), py::arg("no_ids") = false, py::arg("lossless") = false, py::arg("layers") = true,
        py::arg("skip_bad") = false, py::arg("jobs") = 0, py::arg("isolate") = true, py::arg("precision") = 0.0,
        py::arg("drop_outliers") = 0.0f, py::arg("chunk") = 65536u, py::arg("level") = 3, py::arg("planes") = "packed",
        py::arg("tiers") = true, py::arg("band_voxel") = 0.0f, py::arg("band_f2") = "all", py::arg("read_timeout") = 120.0,
        py::arg("force") = false);
}

}  // namespace sluice::python
