#include "live_view.h"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <exception>
#include <filesystem>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "arrays.h"
#include "sluice/error.h"
#include "sluice/io/up_axis.h"
#include "sluice/render/camera.h"
#include "sluice/render/context.h"
#include "sluice/render/offscreen.h"
#include "sluice/stream/stream.h"
#ifdef SLUICE_PYTHON_WINDOW
#include "sluice/desktop/window.h"
#endif

namespace py = pybind11;

namespace sluice::python {
namespace {

struct LiveViewOptions {
  render::Bounds bounds;
  bool window = true;
  uint32_t width = 960, height = 540;
  std::string title = "sluice live";
  stream::LiveOptions live;
  bool keep_all = false;
};

// One pushed frame, owned.
struct OwnedFrame {
  std::vector<float> positions;
  std::vector<uint64_t> ids;
  std::vector<std::vector<float>> attributes;
  double time = 0;
};

class LiveView {
 public:
  explicit LiveView(LiveViewOptions o) : o_(std::move(o)) {
    thread_ = std::thread([this] { run(); });
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [this] { return ready_ || failure_; });
    if (failure_) {
      lock.unlock();
      thread_.join();
      std::rethrow_exception(failure_);
    }
  }
  ~LiveView() {
    try {
      close();
    } catch (...) {  // a destructor reports nothing; close() raised it for whoever called it
    }
  }

  // Hands a frame over; false when the view is closed (the window was closed).
  bool push(OwnedFrame frame) {
    std::unique_lock lock(mutex_);
    rethrow_failure(lock);
    if (closed_) return false;
    if (o_.keep_all) changed_.wait(lock, [this] { return !pending_ || closed_ || failure_; });
    rethrow_failure(lock);
    if (closed_) return false;
    if (pending_) ++dropped_;
    pending_ = std::move(frame);
    ++pushed_;
    changed_.notify_all();
    return true;
  }

  // Stops the view: the frame waiting is drawn first, the recording closed.
  void close() {
    {
      std::lock_guard lock(mutex_);
      closing_ = true;
      changed_.notify_all();
    }
    if (thread_.joinable()) thread_.join();
    std::unique_lock lock(mutex_);
    rethrow_failure(lock);
  }

  bool open() {
    std::lock_guard lock(mutex_);
    return !closed_;
  }
  uint64_t pushed() { return counter(pushed_); }
  uint64_t shown() { return counter(shown_); }
  uint64_t dropped() { return counter(dropped_); }
  std::optional<std::vector<uint8_t>> image() {
    std::lock_guard lock(mutex_);
    return image_;
  }
  std::pair<uint32_t, uint32_t> size() {
    std::lock_guard lock(mutex_);
    return image_size_;
  }
  // What push() takes: fixed at construction.
  bool takes_ids() const { return o_.live.ids; }
  const std::vector<std::string>& attribute_names() const { return o_.live.attributes; }

 private:
  uint64_t counter(const uint64_t& c) {
    std::lock_guard lock(mutex_);
    return c;
  }
  void rethrow_failure(std::unique_lock<std::mutex>& lock) {
    if (!failure_) return;
    std::exception_ptr f = failure_;
    failure_ = nullptr;  // raised once
    lock.unlock();
    std::rethrow_exception(f);
  }

  // The view thread: everything Vulkan (and GLFW) lives and dies here.
  void run() {
    try {
      if (o_.window) run_window();
      else run_offscreen();
    } catch (const sluice::Error& e) {
      // A window that cannot open (no display, a headless machine): say
      // how to do without one.
      std::lock_guard lock(mutex_);
      failure_ = o_.window ? std::make_exception_ptr(sluice::Error(std::string(e.what()) +
                                                                   "; without a display, use LiveView(window=False) and "
                                                                   "image() or record="))
                           : std::current_exception();
    } catch (...) {
      std::lock_guard lock(mutex_);
      failure_ = std::current_exception();
    }
    std::lock_guard lock(mutex_);
    closed_ = true;
    changed_.notify_all();
  }

  stream::StreamOptions stream_options() const {
    stream::StreamOptions so;
    so.layers = io::LayerSet::particles();  // a pushed frame has no layers: every particle, classified on the GPU
    so.motion = stream::ViewMotion::Fixed;
    return so;
  }

  // Takes the waiting frame, if any, into the stream; true if one came.
  bool take(stream::Stream& stream) {
    std::optional<OwnedFrame> frame;
    {
      std::lock_guard lock(mutex_);
      frame.swap(pending_);
      changed_.notify_all();
    }
    if (!frame) return false;
    stream::LiveFrame live{frame->positions, frame->ids, {}, frame->time};
    for (const auto& a : frame->attributes) live.attributes.emplace_back(a);
    stream.push(live);
    std::lock_guard lock(mutex_);
    ++shown_;
    return true;
  }

  // Waits for a frame or for closing; false when closing with nothing left.
  bool wait_for_frame() {
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [this] { return pending_ || closing_; });
    return pending_.has_value();
  }

  void mark_ready() {
    std::lock_guard lock(mutex_);
    ready_ = true;
    changed_.notify_all();
  }

  void run_offscreen() {
    render::Context context(render::ContextOptions{});
    stream::Stream stream(context, o_.bounds, o_.live, stream_options());
    render::OffscreenTarget target(context, o_.width, o_.height);
    const render::Camera camera = render::Camera::framing(o_.bounds, stream.fluid().up, float(o_.width) / float(o_.height));
    mark_ready();
    while (wait_for_frame()) {
      if (!take(stream)) continue;
      stream.renderer().wait_upload(stream.update().ticket);
      target.render(stream.renderer(), camera, stream.fluid(), stream.lod());
      std::vector<uint8_t> rgba = target.read_rgba8();
      std::lock_guard lock(mutex_);
      image_ = std::move(rgba);
      image_size_ = {o_.width, o_.height};
    }
    stream.finish();
  }

#ifdef SLUICE_PYTHON_WINDOW
  void run_window() {
    render::ContextOptions co;
    co.instance_extensions = desktop::window_instance_extensions();
    co.presentation = true;
    render::Context context(co);
    stream::Stream stream(context, o_.bounds, o_.live, stream_options());
    desktop::WindowOptions wo;
    wo.width = o_.width;
    wo.height = o_.height;
    wo.title = o_.title;
    desktop::Window window(context, wo);
    mark_ready();
    for (;;) {
      desktop::poll_window_events();
      if (window.should_close()) break;
      {
        std::lock_guard lock(mutex_);
        if (closing_ && !pending_) break;
      }
      take(stream);
      stream.update();
      if (window.width() == 0 || window.height() == 0) continue;  // minimized
      const render::Camera camera =
          render::Camera::framing(o_.bounds, stream.fluid().up, float(window.width()) / float(window.height()));
      window.new_ui_frame();
      window.present(stream.renderer(), camera, stream.fluid(), stream.lod(), false);
    }
    stream.finish();
  }
#else
  void run_window() { throw sluice::Error("this sluice module was built without windows (GLFW): use LiveView(window=False)"); }
#endif

  LiveViewOptions o_;
  std::thread thread_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::optional<OwnedFrame> pending_;
  bool ready_ = false, closing_ = false, closed_ = false;
  std::exception_ptr failure_;
  uint64_t pushed_ = 0, shown_ = 0, dropped_ = 0;
  std::optional<std::vector<uint8_t>> image_;
  std::pair<uint32_t, uint32_t> image_size_{0, 0};
};

using Vec3Tuple = std::tuple<float, float, float>;

// push()'s attributes by the names given at construction, each one value
// per particle, finite. A missing or unknown name is a TypeError (as
// Python's own for keywords), a bad array a ValueError naming the particle.
std::vector<std::vector<float>> attributes_of(const py::kwargs& given, const std::vector<std::string>& names, size_t n) {
  for (auto item : given) {
    const std::string name = py::str(item.first).cast<std::string>();
    if (std::find(names.begin(), names.end(), name) == names.end()) {
      std::string known;
      for (const std::string& k : names) known += (known.empty() ? "" : ", ") + k;
      throw py::type_error("push() got an unexpected keyword '" + name + "': the view's attributes are " +
                           (known.empty() ? "none (LiveView(attributes=[...]) names them)" : known));
    }
  }
  std::vector<std::vector<float>> out;
  for (const std::string& name : names) {
    if (!given.contains(name)) throw py::type_error("push() missing attribute '" + name + "' (one value per particle)");
    auto a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(given[py::str(name)]);
    if (!a || a.ndim() != 1 || size_t(a.size()) != n) {
      throw py::value_error("attribute '" + name + "' must be one value per particle (" + std::to_string(n) + ")");
    }
    const float* v = a.data();
    for (size_t i = 0; i < n; ++i) {
      if (!std::isfinite(v[i])) {
        throw py::value_error("attribute '" + name + "': particle " + std::to_string(i) + " is not finite (" +
                              std::to_string(v[i]) + ")");
      }
    }
    out.emplace_back(v, v + n);
  }
  return out;
}

// Copies `a` (N x 3 float32, C order) checking every value is finite.
std::vector<float> positions_of(const py::array_t<float, py::array::c_style | py::array::forcecast>& a) {
  if (a.ndim() != 2 || a.shape(1) != 3) throw py::value_error("positions must be an (N, 3) array");
  const float* p = a.data();
  const auto n = size_t(a.size());
  std::vector<float> out(p, p + n);
  for (size_t i = 0; i < n; ++i) {
    if (!std::isfinite(out[i])) {
      throw py::value_error("positions: particle " + std::to_string(i / 3) + " has a non-finite coordinate");
    }
  }
  return out;
}

const char* kLiveViewDoc = R"(A live view of a running simulation.

    view = sluice.LiveView(bounds=((0, 0, 0), (2, 1, 1)), spacing=0.02,
                           attributes=["speed"], color="speed", record="run.sluice")
    for step in range(1000):
        x = simulate(x)                       # your solver, numpy arrays
        view.push(x, time=step * dt, speed=np.linalg.norm(v, axis=1))
    view.close()                              # finishes the recording

push() copies the arrays and returns at once; the view draws on its own
thread. A frame the view has not taken when the next arrives is dropped
(counted in `dropped`) unless keep_all=True, which makes push() wait for
the view instead. Frames drawn are recorded; dropped ones are not.

Args:
    bounds: ((xmin, ymin, zmin), (xmax, ymax, zmax)) the particles stay in
        (the camera frames it; particles outside are still drawn).
    window: a window (needs a display) or offscreen (image() returns the
        last picture).
    size: (width, height) in pixels.
    spacing, radius: rest spacing and render radius in world units (0:
        radius from the spacing).
    up: which axis points up ('+z', 'y', ...).
    attributes: names of the per-particle values push() takes.
    color: one of them to colour by.
    ids: push() takes stable particle ids (LOD follows them); otherwise LOD
        values follow the particle index.
    record: a .sluice file to record the frames drawn into; one that
        exists is kept (sluice.Error) unless force=True.
    fps: the recording's nominal frame rate.
    keep_all: push() waits for the view rather than dropping frames.
    force: record over a file that exists.
)";

}  // namespace

void bind_live_view(py::module_& m) {
  py::class_<LiveView>(m, "LiveView", kLiveViewDoc)
      .def(py::init([](std::pair<Vec3Tuple, Vec3Tuple> bounds, bool window, std::pair<uint32_t, uint32_t> size,
                       float spacing, float radius, const std::string& up, std::vector<std::string> attributes,
                       std::optional<std::string> color, bool ids, std::optional<std::filesystem::path> record, float fps,
                       bool keep_all, std::string title, bool force) {
             // As the CLI: an existing recording is kept unless asked.
             if (record && !force && std::filesystem::exists(*record)) {
               throw io::Error({record->string()}, "exists; pass force=True to record over it, or another record=");
             }
             LiveViewOptions o;
             const auto [lo, hi] = bounds;
             o.bounds = {{std::get<0>(lo), std::get<1>(lo), std::get<2>(lo)}, {std::get<0>(hi), std::get<1>(hi), std::get<2>(hi)}};
             for (int a = 0; a < 3; ++a) {
               const float l = a == 0 ? o.bounds.min.x : a == 1 ? o.bounds.min.y : o.bounds.min.z;
               const float h = a == 0 ? o.bounds.max.x : a == 1 ? o.bounds.max.y : o.bounds.max.z;
               if (!(std::isfinite(l) && std::isfinite(h) && l < h)) throw py::value_error("bounds must be finite, each min below its max");
             }
             if (size.first < 16 || size.second < 16 || size.first > 16384 || size.second > 16384) {
               throw py::value_error("size must be (width, height) between 16 and 16384 pixels");
             }
             o.window = window;
             o.width = size.first;
             o.height = size.second;
             o.title = std::move(title);
             const auto axis = io::parse_up_axis(up);
             if (!axis) throw py::value_error("up must be an axis such as '+z', 'y' or '-x', not '" + up + "'");
             o.live.up = *axis;
             o.live.particle_spacing = spacing;
             o.live.particle_radius = radius;
             o.live.frame_rate = fps;
             o.live.ids = ids;
             if (color) {
               const auto at = std::find(attributes.begin(), attributes.end(), *color);
               if (at == attributes.end()) throw py::key_error("color '" + *color + "' is not one of the attributes");
               o.live.color_attribute = int(at - attributes.begin());
             }
             o.live.attributes = std::move(attributes);
             if (record) o.live.record = *record;
             o.keep_all = keep_all;
             py::gil_scoped_release unlocked;
             return std::make_unique<LiveView>(std::move(o));
           }),
           py::arg("bounds"), py::kw_only(), py::arg("window") = true,
           py::arg("size") = std::pair<uint32_t, uint32_t>{960, 540}, py::arg("spacing") = 0.0f, py::arg("radius") = 0.0f,
           py::arg("up") = "+z", py::arg("attributes") = std::vector<std::string>{}, py::arg("color") = py::none(),
           py::arg("ids") = false, py::arg("record") = py::none(), py::arg("fps") = 30.0f, py::arg("keep_all") = false,
           py::arg("title") = "sluice live", py::arg("force") = false)
      .def("push",
           [](LiveView& v, py::array_t<float, py::array::c_style | py::array::forcecast> positions, py::object ids,
              std::optional<double> time, py::kwargs attributes) {
             OwnedFrame f;
             f.positions = positions_of(positions);
             const size_t n = f.positions.size() / 3;
             if (ids.is_none() == v.takes_ids()) {
               throw py::value_error(v.takes_ids() ? "ids: the view was made with ids=True: pass one id per particle"
                                                   : "ids: the view was made without ids=True: LOD follows the particle "
                                                     "index, ids would be ignored");
             }
             if (!ids.is_none()) {
               auto a = py::array_t<uint64_t, py::array::c_style | py::array::forcecast>::ensure(ids);
               if (!a || a.ndim() != 1 || size_t(a.size()) != n) {
                 throw py::value_error("ids must be one integer per particle (" + std::to_string(n) + ")");
               }
               f.ids.assign(a.data(), a.data() + n);
             }
             if (time && !std::isfinite(*time)) throw py::value_error("time must be finite (seconds)");
             f.time = time.value_or(double(v.pushed()));
             f.attributes = attributes_of(attributes, v.attribute_names(), n);
             py::gil_scoped_release unlocked;
             return v.push(std::move(f));
           },
           R"(Hands a frame to the view: positions (N, 3), optionally ids (N,), the
time in seconds (default: the frame's number) and each attribute named at
construction as a keyword (N,). Returns False once the view is closed (its
window was closed), True otherwise. Raises ValueError for a bad array and
sluice.Error when the view failed (the frame before was bad, or Vulkan).)",
           py::arg("positions"), py::arg("ids") = py::none(), py::arg("time") = py::none())
      .def("close", [](LiveView& v) {
             py::gil_scoped_release unlocked;
             v.close();
           }, "Draws the frame waiting, closes the recording and the window.")
      .def("image", [](LiveView& v) -> py::object {
             auto rgba = v.image();
             if (!rgba) return py::none();
             const auto [w, h] = v.size();
             return hand_over(std::move(*rgba), {py::ssize_t(h), py::ssize_t(w), 4});
           }, "The last picture drawn offscreen (uint8 (height, width, 4)), or None.")
      .def_property_readonly("open", &LiveView::open, "False once the view has closed.")
      .def_property_readonly("pushed", &LiveView::pushed, "Frames pushed.")
      .def_property_readonly("shown", &LiveView::shown, "Frames the view took (drawn, and recorded when recording).")
      .def_property_readonly("dropped", &LiveView::dropped, "Frames replaced before the view took them.")
      .def("__enter__", [](LiveView& v) -> LiveView& { return v; })
      .def("__exit__", [](LiveView& v, py::object, py::object, py::object) {
        py::gil_scoped_release unlocked;
        v.close();
      });
}

}  // namespace sluice::python
