#include "export.h"

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "callback.h"
#include "sluice/io/export.h"
#include "sluice/io/reader.h"

namespace py = pybind11;

namespace sluice::python {
namespace {

// A Sequence (its path) or a path.
std::string path_of(const py::object& seq) {
  if (py::hasattr(seq, "path") && !py::isinstance<py::str>(seq)) {
    const py::object p = seq.attr("path");
    if (py::isinstance<py::str>(p)) return p.cast<std::string>();
  }
  const std::string path = py::str(py::module_::import("os").attr("fspath")(seq)).cast<std::string>();
  if (io::is_container(path)) return path;
  // Anything else sluice.open() takes (solver output, a glob): converted
  // once into its cache, as open() does, and that file exported.
  return py::module_::import("sluice").attr("open")(path).attr("path").cast<std::string>();
}

const char* kExportDoc = R"(Writes frames of a .sluice file as .vtp (ParaView), .csv or .ply.

The same export as `sluice export`: x, y, z (world units, float32), the
stable LOD value `lod` and the attributes (float32); .vtp also stores the
time, and several .vtp frames get a .pvd collection ParaView opens as a
time series.

Args:
    seq: a sluice.Sequence or the path of a .sluice file.
    output: one file for one frame; for several, out.vtp becomes
        out_00002.vtp ... (the file's frame numbers) and out.pvd; or a
        pattern such as 'frames/shot_%04d.vtp'. The extension picks the format.
    frames: frame numbers (any iterable); None writes every frame.
    lod_level: keep this fraction of the particles, the same ones every
        frame (the stable LOD value); None keeps all.
    attributes: names to write; None writes every attribute.
    force: replace outputs that exist (otherwise sluice.Error, nothing written).
    progress: called once per frame with a dict (frames_done, frames,
        bytes_in, bytes_out); raising from it stops the export.

Returns:
    a dict: files (by frame number), pvd (or None), frames, particles,
    kept, bytes_out.
)";

}  // namespace

void bind_export(py::module_& m) {
  m.def("export",
        [](const py::object& seq, const std::filesystem::path& output, const py::object& frames_given,
           std::optional<float> lod_level, std::optional<std::vector<std::string>> attributes, bool force,
           py::object progress) {
          const std::string path = path_of(seq);
          // Any iterable of frame numbers (a list, a range, a generator).
          std::optional<std::vector<int64_t>> frames;
          if (!frames_given.is_none()) {
            frames.emplace();
            for (const py::handle f : py::iter(frames_given)) {
              if (!py::isinstance<py::int_>(f)) throw py::type_error("frames: expected frame numbers (int), got " +
                                                                      py::str(f.get_type()).cast<std::string>());
              frames->push_back(f.cast<int64_t>());
            }
          }
          // As Sequence.frame(): a level outside (0, 1] is a ValueError.
          if (lod_level && !(*lod_level > 0 && *lod_level <= 1)) {
            throw py::value_error("lod_level must lie in (0, 1]: the fraction of particles kept");
          }
          io::SeriesOptions o;
          o.out = output.string();
          o.force = force;
          if (attributes) o.attributes = *attributes;
          if (lod_level) o.lod_level = *lod_level;
          PythonCallback callback(std::move(progress));
          std::optional<io::SeriesSummary> summary;
          try {
            py::gil_scoped_release unlocked;
            const io::ContainerReader reader(path);
            if (frames) {
              for (const int64_t f : *frames) {
                const int64_t n = int64_t(reader.frame_count());
                const int64_t at = f < 0 ? f + n : f;
                if (at < 0 || at >= n) {
                  py::gil_scoped_acquire locked;
                  throw py::index_error("frame " + std::to_string(f) + " is out of range: the file has " + std::to_string(n));
                }
                o.frames.push_back(uint64_t(at));
              }
            }
            summary = io::export_series(reader, o, [&](const io::SeriesProgress& p) {
              callback.call_with([&] {
                py::dict d;
                d["frames_done"] = p.frames_done;
                d["frames"] = p.frames;
                d["bytes_in"] = p.bytes_in;
                d["bytes_out"] = p.bytes_out;
                return d;
              });
            });
          } catch (const PythonRaised&) {
            callback.raise_saved();
          } catch (const io::OutputsExist& e) {
            throw io::Error(e.where(), e.message() + "; pass force=True to overwrite, or another output");
          }
          py::dict d;
          py::dict files;
          for (const auto& [f, file] : summary->plan.files) files[py::int_(f)] = file;
          d["files"] = files;
          d["pvd"] = summary->plan.pvd.empty() ? py::object(py::none()) : py::object(py::str(summary->plan.pvd));
          d["frames"] = summary->frames;
          d["particles"] = summary->particles;
          d["kept"] = summary->kept;
          d["bytes_out"] = summary->bytes_out;
          return d;
        },
        kExportDoc, py::arg("seq"), py::arg("output"), py::kw_only(), py::arg("frames") = py::none(),
        py::arg("lod_level") = py::none(), py::arg("attributes") = py::none(), py::arg("force") = false,
        py::arg("progress") = py::none());
}

}  // namespace sluice::python
