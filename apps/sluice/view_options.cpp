// The view options `sluice render` and `sluice play` share, and their
// conversion into the renderer's types.
#include "view_options.h"

#include <sstream>
#include <stdexcept>

#include "sluice/render/image_io.h"

namespace sluice::app {

render::ContextOptions ViewSettings::context_options() const {
  render::ContextOptions c;
  c.validation = validation;
  c.device = device;
  return c;
}

render::FluidOptions ViewSettings::fluid_options(const render::SceneInfo& scene) const {
  render::FluidOptions f = fluid;
  f.display_mode = render::parse_display_mode(display);
  f.surface_filter_method = render::parse_filter_method(filter);
  f.colormap = render::parse_colormap(colormap);
  f.splatting = render::parse_splatting(splat);
  f.up = up_direction(scene);
  f.ground = !no_ground;
  f.half_resolution_thickness = !full_res_thickness;
  f.scalar_visibility = !color_by.empty();
  if (!color_by.empty()) {
    f.color_attribute = -1;
    for (size_t a = 0; a < scene.attribute_names.size(); ++a) {
      if (scene.attribute_names[a] == color_by) f.color_attribute = int(a);
    }
    if (f.color_attribute < 0) {
      std::string names;
      for (const std::string& n : scene.attribute_names) names += (names.empty() ? "" : ", ") + n;
      throw std::runtime_error("--color-by " + color_by + ": the file has no such attribute (it has: " +
                               (names.empty() ? "none" : names) +
                               "). `sluice convert` keeps only the arrays it is asked for: convert again with -a " +
                               color_by + " (play and render of solver output keep every array)");
    }
  }
  if (color_range.size() == 2) {
    f.color_min = color_range[0];
    f.color_max = color_range[1];
  }
  if (attenuation_color.size() == 3) f.attenuation_color = {attenuation_color[0], attenuation_color[1], attenuation_color[2]};
  return f;
}

std::optional<render::Vec3> ViewSettings::up_override() const {
  if (up.empty()) return std::nullopt;
  try {
    return render::parse_up(up);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(std::string("--up: ") + e.what());
  }
}

render::Vec3 ViewSettings::up_direction(const render::SceneInfo& scene) const { return up_override().value_or(scene.up); }

render::LodOptions ViewSettings::lod_options() const {
  render::LodOptions l = lod;
  l.mode = render::parse_lod_mode(lod_mode);
  return l;
}

std::string particles_text(const render::RendererOptions& options, const io::ContainerReader& reader, uint64_t frame) {
  if (!options.anisotropic) return "spheres";
  if (options.anisotropic_limit == 0) return "ellipsoids";
  const std::string limit = std::to_string(options.anisotropic_limit / 1'000'000) + "M";
  const auto& frames = reader.index().frames;
  const uint64_t frame_particles = frame < frames.size() ? frames[frame].particle_count : 0;
  return frame_particles <= options.anisotropic_limit
             ? "ellipsoids (auto: up to " + limit + " particles a frame)"
             : "spheres (auto: more than " + limit + " particles a frame; --particles ellipsoids draws them)";
}

render::Camera ViewSettings::camera(const render::SceneInfo& scene, float aspect, render::ScreenRect free) const {
  render::Camera c = render::Camera::framing(scene.bounds, up_direction(scene), aspect, fov, free);
  if (!camera_text.empty()) {
    // A given view is shown as given: centred, unless it says otherwise.
    c.shift_x = c.shift_y = 0;
    try {
      c.apply(camera_text);
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error(std::string("--camera: ") + e.what());
    }
  }
  return c;
}

std::pair<uint32_t, uint32_t> parse_size(const std::string& s) {
  unsigned w = 0, h = 0;
  char x = 0;
  std::istringstream in(s);
  if (!(in >> w >> x >> h) || (x != 'x' && x != 'X') || w == 0 || h == 0 || w > 16384 || h > 16384 || !in.eof()) {
    throw std::runtime_error("--size: expected WIDTHxHEIGHT (e.g. 1920x1080), got '" + s + "'");
  }
  return {w, h};
}

void ViewSettings::apply_environment(render::Renderer& renderer) const {
  if (environment.empty()) return;
  try {
    renderer.set_environment(render::read_png(environment));
  } catch (const std::exception& e) {
    throw std::runtime_error("--environment " + environment + ": " + e.what());
  }
}

void add_view_options(CLI::App& cmd, ViewSettings& v) {
  cmd.add_option("--camera", v.camera_text,
                 "View as \"eye=x,y,z;target=x,y,z;up=x,y,z;fov=deg\" (any subset; default: framing the data)");
  cmd.add_option("--fov", v.fov, "Vertical field of view in degrees for the default view")->capture_default_str();
  cmd.add_option("--up", v.up, "World axis that points up: x, y, z, -x, -y or -z (default: the file's, see `info`)");
  cmd.add_option("--device", v.device, "Vulkan device: index or part of its name (default: first discrete GPU)");
  cmd.add_flag("--validation", v.validation, "Enable the Vulkan validation layer; errors make the command fail");
  auto& f = v.fluid;
  const std::string look = "Look (vtkOpenGLFluidMapper names)";
  cmd.add_option("--display", v.display,
                 "transparent, opaque, normals, depth, thickness (and *-unfiltered), or a VTK DisplayMode name")
      ->capture_default_str()->group(look);
  cmd.add_option("--radius", f.particle_radius, "ParticleRadius in world units (default: the file's spacing)")->group(look);
  cmd.add_option("--filter", v.filter, "SurfaceFilterMethod: narrow-range or bilateral")->capture_default_str()->group(look);
  cmd.add_option("--filter-radius", f.surface_filter_radius, "SurfaceFilterRadius: largest depth-filter kernel radius, px")
      ->capture_default_str()->group(look);
  cmd.add_option("--filter-iterations", f.surface_filter_iterations, "SurfaceFilterIterations (0 = unfiltered)")
      ->capture_default_str()->check(CLI::Range(0, 8))->group(look);
  cmd.add_option("--thickness-radius", f.thickness_and_volume_color_filter_radius,
                 "ThicknessAndVolumeColorFilterRadius, px of the thickness buffer")->capture_default_str()->group(look);
  cmd.add_option("--thickness-iterations", f.thickness_and_volume_color_filter_iterations,
                 "ThicknessAndVolumeColorFilterIterations")->capture_default_str()->group(look);
  cmd.add_option("--particles", v.particles,
                 "ellipsoids: each particle flattened and stretched along its neighbours (anisotropic, Yu & Turk\n"
                 "2013), so resting water shades flat; costs a pass once per frame (about 3 ms per million particles\n"
                 "on an H100) and 20 bytes a particle. spheres: every particle round. auto: ellipsoids for frames of\n"
                 "up to " + std::to_string(render::kAutoAnisotropicLimit / 1'000'000) + "M particles, spheres above")
      ->capture_default_str()
      ->group(look);
  cmd.add_option("--splat", v.splat, "Sphere splatting: compute (atomics), raster (point sprites) or auto (raster on CPU devices)")
      ->capture_default_str()->group(look);
  cmd.add_flag("--full-res-thickness", v.full_res_thickness, "Thickness buffer at full resolution (default: half)")->group(look);
  cmd.add_option("--ior", f.refractive_index, "RefractiveIndex")->capture_default_str()->group(look);
  cmd.add_option("--refraction-scale", f.refraction_scale, "RefractionScale")->capture_default_str()->group(look);
  cmd.add_option("--additional-reflection", f.additional_reflection, "AdditionalReflection, 0..1")
      ->capture_default_str()->group(look);
  cmd.add_option("--attenuation-color", v.attenuation_color, "AttenuationColor r,g,b (absorbed per unit thickness)")
      ->delimiter(',')->expected(3)->group(look);
  cmd.add_option("--attenuation-scale", f.attenuation_scale, "AttenuationScale per world unit (default: 6 / data diagonal)")->group(look);
  cmd.add_option("--color-by", v.color_by, "Colour by this attribute (ScalarVisibility on)")->group(look);
  cmd.add_option("--colormap", v.colormap, "viridis, coolwarm, turbo or blues")->capture_default_str()->group(look);
  cmd.add_option("--color-range", v.color_range, "Colour range min,max (default: the file's)")
      ->delimiter(',')->expected(2)->group(look);
  cmd.add_flag("--no-ground", v.no_ground, "No ground plane under the data")->group(look);
  cmd.add_option("--environment", v.environment,
                 "Equirectangular PNG reflected by and seen behind the fluid (default: a procedural sky)")
      ->check(CLI::ExistingFile)->group(look);
  const std::string lod = "Level of detail";
  cmd.add_option("--lod", v.lod_mode, "off, clod (thesis formula 3.1) or density (cLOD, kept splats grow)")
      ->capture_default_str()->group(lod);
  cmd.add_option("--lod-level", v.lod.level, "cLOD threshold 0..1 (1 keeps everything)")
      ->capture_default_str()->check(CLI::Range(0.0, 1.0))->group(lod);
  cmd.add_option("--near-cull", v.lod.near_cull_distance, "Drop particles nearer the eye than this (world units)")->group(lod);
  cmd.add_option("--max-splat", v.lod.max_splat_pixels, "Drop particles covering more pixels across than this")->group(lod);
  cmd.add_option("--position-error", v.lod.position_error_pixels,
                 "Format 3.0 files: read a record without the low bits of its positions when that moves none of\n"
                 "its particles more than this many pixels on screen (0: always at full precision)")
      ->capture_default_str()->check(CLI::Range(0.0, 16.0))->group(lod);
}

}  // namespace sluice::app
