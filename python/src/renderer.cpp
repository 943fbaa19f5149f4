#include "renderer.h"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "arrays.h"
#include "sluice/render/camera.h"
#include "sluice/render/context.h"
#include "sluice/error.h"
#include "sluice/render/offscreen.h"
#include "sluice/stream/stream.h"

namespace py = pybind11;

namespace sluice::python {
namespace {

// One Vulkan context per process, shared by every Renderer and destroyed
// after the last one.
std::shared_ptr<render::Context> shared_context() {
  static std::weak_ptr<render::Context> kept;
  if (auto c = kept.lock()) return c;
  auto c = std::make_shared<render::Context>(render::ContextOptions{});
  kept = c;
  return c;
}

io::LayerSet layer_set(const std::string& layers) {
  if (layers == "surface") return io::LayerSet::surface();
  if (layers == "all") return io::LayerSet::particles();
  throw py::value_error("layers must be 'surface' (the narrow band and blobs, drawn by default) or 'all', not '" + layers + "'");
}


class Renderer {
 public:
  Renderer(const std::filesystem::path& path, std::pair<uint32_t, uint32_t> size, const std::string& layers,
           std::optional<std::string> color, const std::string& particles)
      : context_(shared_context()), color_(std::move(color)) {
    if (size.first < 16 || size.second < 16 || size.first > 16384 || size.second > 16384) {
      throw py::value_error("size must be (width, height) between 16 and 16384 pixels");
    }
    if (!std::filesystem::exists(path)) {
      PyErr_SetString(PyExc_FileNotFoundError, (path.string() + ": no such file").c_str());
      throw py::error_already_set();
    }
    stream::StreamOptions so;
    so.player.frame_rate = 1e9;  // every frame due at once: a render waits for its frame, not the clock
    so.player.end = runtime::EndMode::Stop;
    so.player.policy = runtime::RealTimePolicy::HoldLastFrame;
    so.player.on_error = runtime::ErrorPolicy::Stop;
    so.layers = layer_set(layers);
    so.motion = stream::ViewMotion::Fixed;
    try {
      render::apply_particles(particles, so.renderer);
    } catch (const sluice::Error& e) {
      throw py::value_error(std::string("particles: ") + e.what());
    }
    stream_ = std::make_unique<stream::Stream>(*context_, path, so);
    target_ = std::make_unique<render::OffscreenTarget>(*context_, size.first, size.second);
    if (color_) {
      const auto& names = stream_->scene().attribute_names;
      const auto at = std::find(names.begin(), names.end(), *color_);
      if (at == names.end()) {
        std::string have;
        for (const auto& n : names) have += (have.empty() ? "" : ", ") + n;
        throw py::key_error("no attribute '" + *color_ + "' to colour by (the file has: " + (have.empty() ? "none" : have) + ")");
      }
      color_attribute_ = int(at - names.begin());
    }
    // The attribute decoded is fixed once the player starts: set it now.
    stream_->set_look(look(stream_->fluid(), "transparent", true), {});
  }
  ~Renderer() {
    target_.reset();
    stream_.reset();
  }

  py::array_t<uint8_t> draw(int64_t i, std::optional<std::string> camera_text, std::optional<float> lod_level,
                            const std::string& display, bool ground) {
    const uint64_t frame = frame_number(i);
    const render::FluidOptions fluid = look(stream_->fluid(), display, ground);
    render::LodOptions lod;
    if (lod_level) {
      if (!(*lod_level > 0 && *lod_level <= 1)) throw py::value_error("lod_level must lie in (0, 1]");
      lod.mode = render::LodMode::DensityPreserving;
      lod.level = *lod_level;
    }
    camera_ = camera(camera_text);
    const render::View view = render::camera_view(camera_, {0, 0, target_->width(), target_->height()});
    std::vector<uint8_t> rgba;
    {
      py::gil_scoped_release unlocked;
      stream_->set_look(fluid, lod);
      stream_->set_views({&view, 1});
      show(frame);
      target_->render(stream_->renderer(), camera_, stream_->fluid(), stream_->lod());
      rgba = target_->read_rgba8();
    }
    return hand_over(std::move(rgba), {py::ssize_t(target_->height()), py::ssize_t(target_->width()), 4});
  }

  std::string camera_string() const { return camera_.to_string(); }
  std::optional<std::string> color() const { return color_; }
  std::string device() const { return context_->device().name + " (" + context_->device().type + ")"; }

 private:
  uint64_t frame_number(int64_t i) const {
    const auto n = int64_t(stream_->reader().frame_count());
    if (i < 0) i += n;
    if (i < 0 || i >= n) throw py::index_error("frame " + std::to_string(i) + " is out of range: the file has " + std::to_string(n));
    return uint64_t(i);
  }

  render::FluidOptions look(render::FluidOptions f, const std::string& display, bool ground) const {
    try {
      f.display_mode = render::parse_display_mode(display);
    } catch (const sluice::Error& e) {
      throw py::value_error(e.what());
    }
    f.ground = ground;
    f.scalar_visibility = color_.has_value();
    if (color_) f.color_attribute = color_attribute_;
    return f;
  }

  render::Camera camera(const std::optional<std::string>& text) const {
    const render::SceneInfo& scene = stream_->scene();
    render::Camera c = render::Camera::framing(scene.bounds, stream_->fluid().up,
                                               float(target_->width()) / float(target_->height()));
    if (text) {
      c.shift_x = c.shift_y = 0;
      try {
        c.apply(*text);
      } catch (const sluice::Error& e) {
        throw py::value_error(e.what());  // "camera: ..." already
      }
    }
    return c;
  }

  // Commits `frame` and waits for its copy: the player seeks there and the
  // stream is updated until that frame is the newest committed one.
  void show(uint64_t frame) {
    runtime::Player& player = stream_->player();
    if (!shown_ || *shown_ != frame) player.seek(frame);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
    for (;;) {
      player.wait_for_due();
      const stream::FeedUpdate fed = stream_->update();
      if (const auto error = player.pop_error()) throw io::Error(error->where, error->message);
      if (fed.has_frame && fed.frame == frame) {
        stream_->renderer().wait_upload(fed.ticket);
        shown_ = frame;
        return;
      }
      if (std::chrono::steady_clock::now() > deadline) throw render::Error("frame " + std::to_string(frame) + " did not arrive in 120 s");
    }
  }

  std::shared_ptr<render::Context> context_;
  std::unique_ptr<stream::Stream> stream_;
  std::unique_ptr<render::OffscreenTarget> target_;
  std::optional<std::string> color_;
  int color_attribute_ = 0;
  render::Camera camera_;
  std::optional<uint64_t> shown_;
};

const char* kRenderDoc = R"(Draws frame i as liquid and returns the image.

Args:
    i: frame number (negative counts from the end).
    camera: None frames the data as `sluice render` does; a string in the
        CLI's --camera form ('eye=4,-3,2;target=1,0,0.3;fov=40') sets it.
    lod_level: keep this fraction of the particles (density-preserving
        cLOD); None draws every particle.
    display: 'transparent' (refracting liquid, the default), 'opaque',
        'normals', 'depth', 'thickness' (and their '-unfiltered' forms).
        (`sluice render --help` lists the display modes).
    ground: draw the checkered ground under the data.

Returns:
    uint8 array (height, width, 4), RGBA, top row first.
)";

}  // namespace

void bind_renderer(py::module_& m) {
  py::class_<Renderer>(m, "Renderer", R"(Draws a sequence's frames offscreen into numpy images.

    r = sluice.Renderer("run.sluice", size=(960, 540), color="rho")
    img = r.render(10)                        # (540, 960, 4) uint8
    plt.imshow(img)

color: an attribute to colour by (viridis over the file's range); fixed
for the Renderer's life, since frames decode only that attribute.
particles: 'auto' (ellipsoids for frames of up to 2M particles, spheres
above), 'spheres', or 'ellipsoids': each particle flattened and stretched
along its neighbours (anisotropic, `sluice render --particles`).
Uses the first discrete GPU, else an integrated one, else lavapipe (CPU).
One Vulkan context is shared by every Renderer of the process.
)")
      .def(py::init<const std::filesystem::path&, std::pair<uint32_t, uint32_t>, const std::string&, std::optional<std::string>,
                    const std::string&>(),
           py::arg("path"), py::kw_only(), py::arg("size") = std::pair<uint32_t, uint32_t>{960, 540},
           py::arg("layers") = "surface", py::arg("color") = py::none(), py::arg("particles") = "auto")
      .def("render", &Renderer::draw, kRenderDoc, py::arg("i"), py::kw_only(), py::arg("camera") = py::none(),
           py::arg("lod_level") = py::none(), py::arg("display") = "transparent", py::arg("ground") = true)
      .def_property_readonly("color", &Renderer::color, "The attribute coloured by, or None.")
      .def_property_readonly("camera", &Renderer::camera_string, "The last render's camera, in the --camera form.")
      .def_property_readonly("device", &Renderer::device, "The Vulkan device drawing.");
}

}  // namespace sluice::python
