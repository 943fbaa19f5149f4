#include "sequence.h"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <atomic>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "arrays.h"
#include "callback.h"
#include "convert.h"
#include "frame.h"
#include "sluice/import/playable.h"
#include "sluice/error.h"
#include "sluice/io/particles.h"
#include "sluice/io/reader.h"
#include "sluice/io/up_axis.h"
#include "sluice/runtime/particle_stream.h"

namespace py = pybind11;

namespace sluice::python {
namespace {

// What a Python call asks of a frame, checked against the file.
struct Request {
  io::ParticleQuery query;
  std::vector<std::string> names;  // of query.attributes
};

io::LayerSet layer_set(const std::string& layers) {
  if (layers == "all") return io::LayerSet::particles();
  if (layers == "surface") return io::LayerSet::surface();
  throw py::value_error("layers must be 'all' (every particle) or 'surface' (the narrow band and the blobs standing "
                        "in for the interior), not '" + layers + "'");
}

class Sequence {
 public:
  // A .sluice file as it is; anything `sluice convert` reads (a file, glob,
  // .pvd or folder) converted once into the players' cache (or a temporary
  // file, kept while the sequence lives) with `progress` per frame.
  Sequence(const std::string& input, bool cache, std::optional<std::filesystem::path> cache_dir, py::object progress) {
    const bool glob = input.find_first_of("*?[") != std::string::npos;
    if (!glob && !std::filesystem::exists(input)) {
      PyErr_SetString(PyExc_FileNotFoundError, (input + ": no such file").c_str());
      throw py::error_already_set();
    }
    if (std::filesystem::path(input).extension() == ".sluice") {
      py::gil_scoped_release unlocked;
      reader_ = std::make_shared<io::ContainerReader>(input);
      return;
    }
    import::PlayableOptions o;
    o.use = cache ? import::CacheUse::Cache : import::CacheUse::Temporary;
    if (cache_dir) o.cache_folder = *cache_dir;
    PythonCallback callback(std::move(progress));
    o.observer.progressed = [&](const import::ConvertProgress& p) { callback.call_with([&] { return progress_dict(p); }); };
    try {
      py::gil_scoped_release unlocked;
      converted_ = std::make_shared<import::PlayableFile>(import::open_playable(input, o));
      reader_ = std::make_shared<io::ContainerReader>(converted_->path());
    } catch (const PythonRaised&) {
      callback.raise_saved();
    }
  }

  const io::ContainerReader& reader() const { return *reader_; }
  std::shared_ptr<const io::ContainerReader> shared() const { return reader_; }
  uint64_t size() const { return reader_->frame_count(); }

  std::vector<std::string> attribute_names() const {
    std::vector<std::string> out;
    for (const io::AttributeInfo& a : reader_->header().attributes) out.push_back(a.name);
    return out;
  }

  // The frame number `i` names (negative from the end), or IndexError.
  uint64_t frame_number(int64_t given) const {
    const auto n = int64_t(size());
    const int64_t i = given < 0 ? given + n : given;
    if (i < 0 || i >= n) {
      throw py::index_error("frame " + std::to_string(given) + " is out of range: the file has " + std::to_string(n) +
                            " (0 to " + std::to_string(n - 1) + ", or -" + std::to_string(n) + " to -1 from the end)");
    }
    return uint64_t(i);
  }

  Request request(const std::string& layers, std::optional<float> lod_level,
                  const std::optional<std::vector<std::string>>& attributes) const {
    Request r;
    r.query.layers = layer_set(layers);
    if (lod_level) {
      if (!(*lod_level > 0 && *lod_level <= 1)) throw py::value_error("lod_level must lie in (0, 1]: the fraction of particles kept");
      r.query.lod_level = *lod_level;
    }
    const std::vector<std::string> all = attribute_names();
    for (const std::string& name : attributes ? *attributes : all) {
      const auto at = std::find(all.begin(), all.end(), name);
      if (at == all.end()) {
        std::string have;
        for (const auto& a : all) have += (have.empty() ? "" : ", ") + a;
        throw py::key_error("no attribute '" + name + "' in " + reader_->path() + " (it has: " + (have.empty() ? "none" : have) + ")");
      }
      r.query.attributes.push_back(size_t(at - all.begin()));
      r.names.push_back(name);
    }
    return r;
  }

  Frame frame(int64_t i, const Request& r) const {
    const uint64_t number = frame_number(i);
    io::ParticleArrays arrays = spare_arrays(*pool_, r.names.size());
    {
      py::gil_scoped_release unlocked;
      // One scratch, kept between calls; a second thread reading at the
      // same time uses one of its own.
      std::unique_lock lock(scratch_mutex_, std::try_to_lock);
      io::ParticleScratch own;
      io::read_particles(*reader_, number, r.query, arrays, lock.owns_lock() ? scratch_ : own);
    }
    return make_frame(number, std::move(arrays), r.names, io::times_stated(reader_->header()), pool_.get());
  }

  py::dict info() const {
    const io::FileHeader& h = reader_->header();
    const io::FrameIndex& index = reader_->index();
    py::dict d;
    d["path"] = reader_->path();
    d["frames"] = size();
    d["format"] = std::to_string(h.version_major) + "." + std::to_string(h.version_minor);
    d["positions"] = h.position_coding == io::PositionCoding::Quantized16 ? "quantized16" : "float32";
    d["spacing"] = h.particle_spacing;
    d["radius"] = h.particle_radius;
    d["frame_rate"] = h.frame_rate;
    d["up"] = io::up_axis_name(h.up);
    d["up_evidence"] = io::up_evidence_name(h.up_evidence);
    d["attributes"] = attribute_names();
    d["lod_id_array"] = h.lod_id_array;
    d["source"] = h.source;
    d["file_bytes"] = reader_->file_size();
    uint64_t particles = 0;  // as `sluice info`: surface and interior, not blobs
    for (const io::FrameIndexEntry& e : index.frames) particles += e.count_in(io::LayerSet::particles());
    d["particles"] = particles;
    d["times"] = io::times_stated(h) ? io::time_source_name(h.time_source) : "none";
    d["bounds"] = py::make_tuple(py::make_tuple(index.bounds.min[0], index.bounds.min[1], index.bounds.min[2]),
                                 py::make_tuple(index.bounds.max[0], index.bounds.max[1], index.bounds.max[2]));
    return d;
  }

 private:
  std::shared_ptr<import::PlayableFile> converted_;  // a conversion of the input (removed with it when temporary)
  std::shared_ptr<io::ContainerReader> reader_;
  // Reused frame after frame: the arrays Python let go of, and what a
  // frame is read and decoded into.
  std::shared_ptr<ArrayPool> pool_ = std::make_shared<ArrayPool>();
  mutable std::mutex scratch_mutex_;
  mutable io::ParticleScratch scratch_;
};

// Iterates frames through the pipeline; outlives its sequence. Frames come
// as arrays over the pipeline's own buffers (lent, no copy) while Python
// holds few of them; a loop that keeps more gets copies, so the pipeline
// can always read ahead.
class Stream {
 public:
  Stream(std::shared_ptr<const io::ContainerReader> reader, runtime::StreamRange range, Request r, uint64_t memory,
         uint32_t window = 0)
      : names_(std::move(r.names)),
        loop_(range.loop),
        timed_(io::times_stated(reader->header())),
        lender_(std::make_shared<Lender>(std::move(reader), range, std::move(r.query), memory, window)) {}

  Frame next() {
    std::optional<runtime::LentFrame> lent;
    std::optional<runtime::StreamedFrame> copied;
    {
      py::gil_scoped_release unlocked;
      lender_->release_returned();
      if (lender_->lent.load() < lender_->frames.most_lent()) {
        lent = lender_->frames.next_lent();
      } else {
        copied = lender_->frames.next(spare_arrays(*pool_, names_.size()));
      }
    }
    if (copied) return make_frame(copied->index, std::move(copied->arrays), names_, timed_, pool_.get());
    if (!lent) throw py::stop_iteration();
    return lend_frame(std::move(*lent));
  }
  uint64_t remaining() const {
    if (loop_) throw py::type_error("a looping stream has no length");
    return lender_->frames.remaining();
  }
  uint32_t window() const { return lender_->frames.window_frames(); }

 private:
  // The stream, shared with the arrays of the frames it lent: it lives
  // until the last of them dies.
  struct Lender {
    Lender(std::shared_ptr<const io::ContainerReader> reader, runtime::StreamRange range, io::ParticleQuery query,
           uint64_t memory, uint32_t window)
        : frames(std::move(reader), range, std::move(query), memory, window) {}
    // Gives the pipeline back the buffers of frames whose arrays died
    // (their handles are released here, on the stream's thread, not on
    // whichever thread dropped the last array).
    void release_returned() {
      std::vector<runtime::FrameHandle> done;
      {
        const std::lock_guard lock(mutex);
        done.swap(returned);
      }
      done.clear();
    }

    runtime::ParticleStream frames;
    std::atomic<uint32_t> lent{0};  // frames whose arrays are alive
    std::mutex mutex;
    std::vector<runtime::FrameHandle> returned;  // after `frames`: released before the stream is destroyed
  };

  // What a lent frame's arrays share: when the last dies, its handle goes
  // back to the stream.
  struct Loan {
    Loan(std::shared_ptr<Lender> l, runtime::FrameHandle h) : lender(std::move(l)), handle(std::move(h)) {}
    Loan(const Loan&) = delete;
    Loan& operator=(const Loan&) = delete;
    std::shared_ptr<Lender> lender;
    runtime::FrameHandle handle;
    ~Loan() {
      const std::lock_guard lock(lender->mutex);
      lender->returned.push_back(std::move(handle));
      lender->lent.fetch_sub(1);
    }
  };

  template <class T>
  static py::array_t<T> lend(const std::shared_ptr<Loan>& loan, T* data, std::vector<py::ssize_t> shape) {
    auto* owner = new std::shared_ptr<Loan>(loan);
    py::capsule capsule(owner, [](void* p) { delete static_cast<std::shared_ptr<Loan>*>(p); });
    return py::array_t<T>(std::move(shape), data, capsule);
  }

  Frame lend_frame(runtime::LentFrame&& f) {
    lender_->lent.fetch_add(1);
    auto loan = std::make_shared<Loan>(lender_, std::move(f.handle));
    Frame out;
    out.index = f.index;
    if (timed_) out.time = f.time;
    const auto n = py::ssize_t(f.arrays.count);
    out.positions = lend(loan, f.arrays.positions, {n, 3});
    out.lod = lend(loan, f.arrays.lod, {n});
    out.layer = lend(loan, f.arrays.layer, {n});
    for (size_t k = 0; k < names_.size(); ++k) out.attributes[py::str(names_[k])] = lend(loan, f.arrays.attributes[k], {n});
    return out;
  }

  std::vector<std::string> names_;
  bool loop_ = false;
  bool timed_ = true;  // the file states times (io::times_stated())
  std::shared_ptr<ArrayPool> pool_ = std::make_shared<ArrayPool>();  // the arrays of copied frames Python let go of
  std::shared_ptr<Lender> lender_;
};

const char* kFrameDoc = R"(Reads frame i (negative counts from the end) into numpy arrays.

Args:
    i: frame number.
    layers: 'all' (every particle, the default) or 'surface' (the narrow
        band and the blobs standing in for the interior, what the player
        draws; a file without layers gives every particle either way).
    lod_level: the fraction of particles kept, in (0, 1]; None keeps all.
        The same particles are kept in every frame (the stable LOD value),
        and only the file's LOD tiers holding them are read from disk.
    attributes: names of the attributes to load; None loads all of them.

Returns:
    a sluice.Frame.

Raises:
    IndexError: no such frame. KeyError: no such attribute.
    sluice.Error: the frame is damaged (the message names file, frame and chunk).
)";

const char* kFramesDoc = R"(Streams frames start, start+step, ... below stop through the prefetch pipeline.

Reading and decoding run ahead on worker threads while your loop works on
the current frame; the window of frames in flight is sized from the
memory available (or `memory`, in bytes; `window` caps it in frames).
loop=True goes round again from frame 0 after `stop` (the first `stop`
frames over and over, never ending: a replay). Other arguments as for
frame(). Iterating the sequence itself (`for f in seq`) streams every frame.

Returns:
    an iterator of sluice.Frame.
)";

}  // namespace

namespace {

void bind_frame_stream(py::module_& m) {
  py::class_<Stream>(m, "FrameStream", "Frames streamed through the prefetch pipeline (Sequence.frames()).")
      .def("__iter__", [](Stream& s) -> Stream& { return s; })
      .def("__next__", &Stream::next)
      .def("__len__", &Stream::remaining, "Frames left.")
      .def_property_readonly("window", &Stream::window, "Frames the prefetch window holds at once, as planned.");

}

void bind_sequence_class(py::module_& m) {
  py::class_<Sequence>(m, "Sequence", "A .sluice file: its description, its frames by number, and streaming.")
      .def("__len__", &Sequence::size, "Number of frames.")
      .def("__getitem__", [](const Sequence& s, int64_t i) { return s.frame(i, s.request("all", std::nullopt, std::nullopt)); },
           "seq[i]: frame i with every particle and attribute (see frame()).")
      .def("__getitem__", [](const Sequence& s, const py::slice& range) {
             size_t start = 0, stop = 0, step = 0, count = 0;
             if (!range.compute(s.size(), &start, &stop, &step, &count)) throw py::error_already_set();
             py::list frames;
             const Request r = s.request("all", std::nullopt, std::nullopt);
             for (size_t k = 0; k < count; ++k) frames.append(s.frame(int64_t(start + k * step), r));
             return frames;
           }, "seq[a:b:c]: a list of those frames, each read whole (frames() streams them instead).")
      .def("frame", [](const Sequence& s, int64_t i, const std::string& layers, std::optional<float> lod_level,
                       std::optional<std::vector<std::string>> attributes) { return s.frame(i, s.request(layers, lod_level, attributes)); },
           kFrameDoc, py::arg("i"), py::kw_only(), py::arg("layers") = "all", py::arg("lod_level") = py::none(),
           py::arg("attributes") = py::none())
      .def("frames", [](const Sequence& s, int64_t start, std::optional<int64_t> stop, int64_t step, const std::string& layers,
                        std::optional<float> lod_level, std::optional<std::vector<std::string>> attributes, uint64_t memory,
                        uint32_t window, bool loop) {
             if (step < 1) throw py::value_error("step must be at least 1");
             const auto n = int64_t(s.size());
             const int64_t begin = start < 0 ? std::max<int64_t>(0, start + n) : std::min(start, n);
             const int64_t end = !stop ? n : *stop < 0 ? std::max<int64_t>(0, *stop + n) : std::min(*stop, n);
             if (end <= begin) {
               throw py::value_error("frames(" + std::to_string(start) + ", " + (stop ? std::to_string(*stop) : "None") +
                                     "): no frames in that range (the file has " + std::to_string(n) + ")");
             }
             const runtime::StreamRange range{uint64_t(begin), uint64_t(end), uint32_t(step), loop};
             Request r = s.request(layers, lod_level, attributes);
             // A cap that holds no frame would be raised silently (the
             // window keeps two frames at least): say so instead.
             uint64_t largest = 0;
             for (const io::FrameIndexEntry& e : s.reader().index().frames) largest = std::max(largest, e.count_in(r.query.layers));
             const uint64_t frame_bytes = largest * io::world_particle_bytes(r.query.attributes.size());
             if (memory > 0 && memory < 2 * frame_bytes) {
               throw py::value_error("memory=" + std::to_string(memory) + " bytes holds less than two frames of this file (" +
                                     std::to_string(frame_bytes) + " bytes each, converted): give at least " +
                                     std::to_string(2 * frame_bytes) + ", or 0 for half the available memory");
             }
             return std::make_unique<Stream>(s.shared(), range, std::move(r), memory, window);
           }, kFramesDoc, py::arg("start") = 0, py::arg("stop") = py::none(), py::arg("step") = 1, py::kw_only(),
           py::arg("layers") = "all", py::arg("lod_level") = py::none(), py::arg("attributes") = py::none(), py::arg("memory") = 0,
           py::arg("window") = 0, py::arg("loop") = false)
      .def("__iter__", [](const Sequence& s) {
             return std::make_unique<Stream>(s.shared(), runtime::StreamRange{0, s.size(), 1}, s.request("all", std::nullopt, std::nullopt), 0);
           }, "Streams every frame (see frames()).")
      .def_property_readonly("path", [](const Sequence& s) { return s.reader().path(); })
      .def_property_readonly("times", [](const Sequence& s) -> py::object {
             if (!io::times_stated(s.reader().header())) return py::none();
             std::vector<double> t;
             for (const io::FrameIndexEntry& e : s.reader().index().frames) t.push_back(e.time);
             return py::array_t<double>(py::ssize_t(t.size()), t.data());
           }, "Each frame's time in seconds (float64 array), or None when the input stated no times.")
      .def_property_readonly("counts", [](const Sequence& s) {
             std::vector<uint64_t> c;
             for (const io::FrameIndexEntry& e : s.reader().index().frames) c.push_back(e.count_in(io::LayerSet::particles()));
             return py::array_t<uint64_t>(py::ssize_t(c.size()), c.data());
           }, "Each frame's number of particles, surface and interior (uint64 array): len(seq[i]). Voxel blobs\n"
              "(layers='surface') stand in for interior particles and are not counted.")
      .def_property_readonly("bounds", [](const Sequence& s) {
             const io::Aabb& b = s.reader().index().bounds;
             return py::make_tuple(py::make_tuple(b.min[0], b.min[1], b.min[2]), py::make_tuple(b.max[0], b.max[1], b.max[2]));
           }, "((xmin, ymin, zmin), (xmax, ymax, zmax)) over every frame, world units.")
      .def_property_readonly("up", [](const Sequence& s) { return io::up_axis_name(s.reader().header().up); },
                             "Which world axis points up: '+z', '-y', ...")
      .def_property_readonly("spacing", [](const Sequence& s) { return s.reader().header().particle_spacing; },
                             "Rest spacing of the particles, world units (0: not stated).")
      .def_property_readonly("radius", [](const Sequence& s) { return s.reader().header().particle_radius; },
                             "Render radius, world units.")
      .def_property_readonly("frame_rate", [](const Sequence& s) { return s.reader().header().frame_rate; },
                             "Playback frames per second (0: not stated).")
      .def_property_readonly("attributes", &Sequence::attribute_names, "Names of the per-particle attributes.")
      .def_property_readonly("layers", [](const Sequence& s) {
             std::vector<std::string> out;
             std::array<uint64_t, io::kLayerCount> total{};
             for (const io::FrameIndexEntry& e : s.reader().index().frames) {
               for (int l = 0; l < io::kLayerCount; ++l) total[size_t(l)] += e.layer_particles[size_t(l)];
             }
             for (int l = 0; l < io::kLayerCount; ++l) {
               if (total[size_t(l)] > 0) out.push_back(io::layer_name(io::Layer(l)));
             }
             return out;
           }, "Names of the layers the file holds ('all' for an unlayered file; 'surface', 'interior', 'blobs').")
      .def("info", &Sequence::info, "The file's header and totals as a dict (what `sluice info` prints).")
      .def("__repr__", [](const Sequence& s) {
        return "<sluice.Sequence '" + s.reader().path() + "': " + std::to_string(s.size()) + " frames>";
      });

}

void bind_open(py::module_& m) {
  m.def("open", [](const py::object& path, bool cache, std::optional<std::filesystem::path> cache_dir, py::object progress) {
          return std::make_unique<Sequence>(py::str(py::module_::import("os").attr("fspath")(path)).cast<std::string>(),
                                            cache, std::move(cache_dir), std::move(progress));
        },
        R"(Opens a .sluice file, or a solver's output.

A .sluice file is opened as it is: the header and the frame index only
(one seek per frame later). Anything `sluice convert` reads (a VTK, CSV or
XYZ file, a quoted glob such as 'out/fluid_*.vtu', a .pvd series, a folder)
is converted once, as `sluice play` does, into .sluice-cache/ beside it (or
~/.cache/sluice where that folder is not writable), or into cache_dir when
given, and reused while the input files are unchanged; cache=False converts
into a temporary file kept while the sequence lives. seq.path names the
converted file.
progress, if given, is called once per converted frame with a dict
(frames_done, frames, input_bytes, output_bytes).

    seq = sluice.open("run.sluice")
    len(seq), seq.times, seq.bounds, seq.up, seq.attributes
    f = seq[10]                      # every particle, every attribute
    f.positions                      # float32 (N, 3), world units
    f = seq.frame(10, lod_level=0.1, attributes=["rho"])  # reads ~1/10
    for f in seq.frames(0, None, 5): # streamed, read ahead on threads
        print(f.index, f.time, len(f))

Raises:
    FileNotFoundError: no file at path.
    sluice.Error: a damaged .sluice file (run `sluice recover`), or input
        that cannot be converted (the message names the file and frame).
)", py::arg("path"), py::kw_only(), py::arg("cache") = true, py::arg("cache_dir") = py::none(),
        py::arg("progress") = py::none());
}

}  // namespace

void bind_sequence(py::module_& m) {
  bind_frame_stream(m);
  bind_sequence_class(m);
  bind_open(m);
}

}  // namespace sluice::python
