// Options shared by `sluice render` and `sluice play`: camera, device, look
// (vtkOpenGLFluidMapper names) and level of detail, as the command line
// gives them, and their conversion into the renderer's types.
#pragma once

#include <CLI/CLI.hpp>

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "sluice/io/reader.h"
#include "sluice/render/camera.h"
#include "sluice/render/context.h"
#include "sluice/render/frame.h"
#include "sluice/render/options.h"
#include "sluice/render/renderer.h"

namespace sluice::app {

struct ViewSettings {
  std::string camera_text, up, device;  // up: empty = the file's
  float fov = 40.0f;
  bool validation = false;
  render::FluidOptions fluid;
  std::string display = "transparent", filter = "narrow-range", colormap = "viridis", color_by, splat = "auto";
  std::vector<float> color_range, attenuation_color;
  bool no_ground = false, full_res_thickness = false;
  std::string lod_mode = "off";
  std::string environment;  // equirectangular PNG; empty: the procedural sky
  std::string particles = "auto";  // --particles: auto, spheres or ellipsoids (anisotropic)
  render::LodOptions lod;

  render::ContextOptions context_options() const;
  // Throws std::runtime_error on a bad name (display, filter, attribute, ...).
  render::FluidOptions fluid_options(const render::SceneInfo& scene) const;
  render::LodOptions lod_options() const;
  // The default framing (in `free`, the part of the image left uncovered)
  // or --camera.
  render::Camera camera(const render::SceneInfo& scene, float aspect, render::ScreenRect free = {}) const;
  // --up, else the file's.
  render::Vec3 up_direction(const render::SceneInfo& scene) const;
  // --up if given (stream::StreamOptions::up).
  std::optional<render::Vec3> up_override() const;
  // Loads --environment into the renderer, if given. Throws with the file named.
  void apply_environment(render::Renderer& renderer) const;
};

void add_view_options(CLI::App& cmd, ViewSettings& v);

// How `reader`'s frame `frame` is drawn under `options` (render::
// apply_particles): "ellipsoids", "spheres", or either with auto's reason.
std::string particles_text(const render::RendererOptions& options, const io::ContainerReader& reader, uint64_t frame);

// "1920x1080" -> {1920, 1080}; throws std::runtime_error naming --size otherwise.
std::pair<uint32_t, uint32_t> parse_size(const std::string& text);

}  // namespace sluice::app
