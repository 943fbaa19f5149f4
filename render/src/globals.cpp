// Per-frame uniforms from camera, scene and options (see globals.h).
#include "globals.h"

#include <algorithm>
#include <cmath>

#include "sluice/render/lod.h"
#include "sluice/render/draw.h"
#include "sluice/render/options.h"

namespace sluice::render {
namespace {

void set4(float* d, float a, float b, float c, float e) {
  d[0] = a;
  d[1] = b;
  d[2] = c;
  d[3] = e;
}

// The vectorial row `r` of a column-major matrix.
Vec4 row(const Mat4& m, int r) { return {m.at(r, 0), m.at(r, 1), m.at(r, 2), m.at(r, 3)}; }

}  // namespace

float effective_radius(const FluidOptions& options, const SceneInfo& scene) {
  if (options.particle_radius > 0) return options.particle_radius;
  if (scene.particle_spacing > 0) return scene.particle_spacing;
  if (scene.particle_radius > 0) return 2 * scene.particle_radius;
  return std::max(scene.bounds.diagonal() * 1e-3f, 1e-6f);
}

bool depth_filtered(const FluidOptions& o) {
  const auto m = o.display_mode;
  return o.surface_filter_iterations > 0 && m != DisplayMode::UnfilteredOpaqueSurface &&
         m != DisplayMode::UnfilteredSurfaceNormal && m != DisplayMode::UnfilteredDepth;
}

bool thickness_filtered(const FluidOptions& o) {
  return o.thickness_and_volume_color_filter_iterations > 0 && o.thickness_and_volume_color_filter_radius > 0 &&
         o.display_mode != DisplayMode::ThicknessBuffer;
}

namespace {

// The camera: matrices, frustum planes, the eye, viewports and each
// pixel's eye ray.
void set_camera(Globals& g, const View& view_in, const ViewSetup& v) {
  const Mat4& view = view_in.view;
  const Mat4& proj = view_in.projection;
  g.view = view;
  g.inv_view = inverse(view);
  // Target depth of a point at distance d along the view axis: A + B / d
  // (perspective projections only). B > 0: reversed depth (near is 1).
  const float depth_a = -proj.at(2, 2), depth_b = proj.at(2, 3);
  const bool reversed = depth_b > 0;
  const float near = reversed ? depth_b / std::max(1.0f - depth_a, 1e-20f) : -depth_b / std::max(depth_a, 1e-20f);
  const Mat4 vp = proj * view;
  const Vec4 r0 = row(vp, 0), r1 = row(vp, 1), r2 = row(vp, 2), r3 = row(vp, 3);
  const Vec4 near_plane = reversed ? Vec4{r3.x - r2.x, r3.y - r2.y, r3.z - r2.z, r3.w - r2.w}  // z <= w
                                   : r2;                                                      // z >= 0
  const Vec4 planes[5] = {
      {r3.x + r0.x, r3.y + r0.y, r3.z + r0.z, r3.w + r0.w},  // left
      {r3.x - r0.x, r3.y - r0.y, r3.z - r0.z, r3.w - r0.w},  // right
      {r3.x + r1.x, r3.y + r1.y, r3.z + r1.z, r3.w + r1.w},  // y = -w
      {r3.x - r1.x, r3.y - r1.y, r3.z - r1.z, r3.w - r1.w},  // y = +w
      near_plane,
  };
  for (int i = 0; i < 5; ++i) {
    const float len = std::sqrt(planes[i].x * planes[i].x + planes[i].y * planes[i].y + planes[i].z * planes[i].z);
    const float s = len > 0 ? 1.0f / len : 0.0f;
    set4(g.planes[i], planes[i].x * s, planes[i].y * s, planes[i].z * s, planes[i].w * s);
  }
  const Vec4 eye = g.inv_view * Vec4{0, 0, 0, 1};
  set4(g.eye, eye.x, eye.y, eye.z, near);
  set4(g.viewport, float(v.width), float(v.height), 1.0f / float(v.width), 1.0f / float(v.height));
  set4(g.thick_viewport, float(v.thick_width), float(v.thick_height), 1.0f / float(v.thick_width),
       1.0f / float(v.thick_height));
  const float y_scale = -proj.at(1, 1);
  set4(g.proj, proj.at(0, 0), y_scale, y_scale != 0 ? 1.0f / std::abs(y_scale) : 1.0f, reversed ? 0.0f : 1.0f);
  set4(g.frustum, -proj.at(0, 2), -proj.at(1, 2), depth_a, depth_b);
  // Pixel centre -> eye ray: ndc = px * 2 / w - 1; tan = (ndc - offset) / scale.
  const float sx = proj.at(0, 0) != 0 ? proj.at(0, 0) : 1.0f, sy = y_scale != 0 ? y_scale : 1.0f;
  const auto ray = [&](float* k, float w, float h) {
    set4(k, 2.0f / (w * sx), (-1.0f - g.frustum[0]) / sx, -2.0f / (h * sy), (1.0f + g.frustum[1]) / sy);
  };
  ray(g.ray, float(v.width), float(v.height));
  ray(g.thick_ray, float(v.thick_width), float(v.thick_height));
}

// The splats' size, the LOD rule and the colour mapping.
void set_lod_and_color(Globals& g, const SceneInfo& scene, const FluidOptions& o, const LodOptions& lod,
                       const ViewSetup& v, float radius) {
  const float max_splat = lod.max_splat_pixels > 0 ? std::min(lod.max_splat_pixels, v.max_point_size) : v.max_point_size;
  set4(g.radius, radius, v.max_point_size, max_splat, std::max(lod.near_cull_distance, 0.0f));

  const float level = std::clamp(lod.level, 0.0f, 1.0f);
  const float threshold = level > 0 ? -std::log(level) : 1e30f;
  const float d_ref = lod.reference_distance > 0 ? lod.reference_distance : std::max(scene.bounds.diagonal(), 1e-6f);
  set4(g.lod, level, threshold, 1.0f / d_ref, std::max(lod.max_splat_scale, 1.0f));
  const bool attribute = o.color_attribute >= 0 && size_t(o.color_attribute) < scene.attribute_names.size();
  g.modes[0] = uint32_t(lod.mode);
  g.modes[1] = uint32_t(lod.random);
  g.modes[2] = scene.coding == io::PositionCoding::Quantized16 ? 0u : 1u;
  g.modes[3] = attribute && o.scalar_visibility ? 1u : 0u;

  float cmin = 0, cmax = 1;
  if (attribute) {
    cmin = scene.attribute_ranges[size_t(o.color_attribute)][0];
    cmax = scene.attribute_ranges[size_t(o.color_attribute)][1];
  }
  if (o.color_min) cmin = *o.color_min;
  if (o.color_max) cmax = *o.color_max;
  set4(g.color, cmin, cmax > cmin ? 1.0f / (cmax - cmin) : 0.0f, g.modes[3] ? 1.0f : 0.0f, float(uint32_t(o.colormap)));
}

// The screen-space filters and the shading.
void set_filters_and_shading(Globals& g, const SceneInfo& scene, const FluidOptions& o, const LodOptions& lod,
                             const ViewSetup& v, float radius) {
  // Filter scales in world units, relative to the sphere radius: sigma of
  // half a radius smooths the bumps between overlapping spheres; delta and mu
  // are the narrow-range thresholds (Truong & Yuksel).
  // In density-preserving LOD the kept splats are larger and sparser: scale
  // the filter by their typical growth (importance 1: level^(-1/3)).
  const float level = std::clamp(lod.level, 0.0f, 1.0f);
  const float growth = lod.mode == LodMode::DensityPreserving && level > 0
                           ? std::min(std::cbrt(1.0f / level), std::max(lod.max_splat_scale, 1.0f))
                           : 1.0f;
  const float fr = radius * growth;
  set4(g.filter_params, 0.5f * fr, float(std::max(o.surface_filter_radius, 0)), 1.0f * fr, 0.1f * fr);
  g.filter_modes[0] = uint32_t(o.surface_filter_method);
  g.filter_modes[1] = uint32_t(std::max(o.surface_filter_iterations, 0));
  g.filter_modes[2] = uint32_t(std::max(o.thickness_and_volume_color_filter_radius, 0));
  g.filter_modes[3] = thickness_filtered(o) ? 1u : 0u;
  const float attenuation = o.attenuation_scale > 0 ? o.attenuation_scale : 6.0f / std::max(scene.bounds.diagonal(), 1e-6f);
  set4(g.shade, o.refractive_index, o.refraction_scale, o.additional_reflection, attenuation);
  set4(g.attenuation, o.attenuation_color.x, o.attenuation_color.y, o.attenuation_color.z, 0);
  set4(g.opaque_color, o.opaque_color.x, o.opaque_color.y, o.opaque_color.z, 1);
  g.display[0] = uint32_t(o.display_mode);
  g.display[1] = o.ground ? 1u : 0u;
  g.display[2] = v.write_aux ? 1u : 0u;
  g.display[3] = depth_filtered(o) ? 1u : 0u;
}

// The ground, the light, the scene's extent and the splat pass's fixed point.
void set_scene(Globals& g, const SceneInfo& scene, const FluidOptions& o, float radius) {
  const Vec3 up = length(o.up) > 0 ? normalize(o.up) : Vec3{0, 0, 1};
  // The ground touches the bounds' lowest corner along up, a radius below.
  float lowest = dot(scene.bounds.min, up);
  for (int corner = 1; corner < 8; ++corner) {
    const Vec3 p{(corner & 1) ? scene.bounds.max.x : scene.bounds.min.x, (corner & 2) ? scene.bounds.max.y : scene.bounds.min.y,
                 (corner & 4) ? scene.bounds.max.z : scene.bounds.min.z};
    lowest = std::min(lowest, dot(p, up));
  }
  set4(g.up, up.x, up.y, up.z, lowest - radius);
  // The light is given with z up; turn it to the scene's up.
  const Vec3 li = o.light_direction;
  Vec3 across_a, across_b;
  frame_across(up, across_a, across_b);
  const Vec3 l = normalize(across_a * li.x + across_b * li.y + up * li.z);
  set4(g.light, l.x, l.y, l.z, 0);
  const Vec3 c = scene.bounds.center();
  set4(g.scene, c.x, c.y, c.z, std::max(scene.bounds.diagonal(), 1e-6f));
  // Thickness in fixed point: 1/1024 of a radius per unit keeps the chord of
  // a sphere grown 4x under 2^13 units, room for 2^19 of them on one pixel.
  const float fixed = 1024.0f / radius;
  // Splats of up to 1024 pixels are one thread's loop; larger ones get a
  // workgroup each. At 64 the workgroups' overhead made the splat pass 2x
  // slower on the H100 (10M particles, both eyes of 2064x2208: 9.53 against
  // 4.77 ms; 256: 4.83, 1024: 4.77, 16384: 4.84; docs/measurements.md).
  set4(g.splat, fixed, 1.0f / fixed, 1024.0f, 0);
}

}  // namespace

Globals make_globals(const SceneInfo& scene, const View& view_in, const FluidOptions& o, const LodOptions& lod,
                     const ViewSetup& v) {
  Globals g{};
  set_camera(g, view_in, v);
  const float radius = effective_radius(o, scene);
  set_lod_and_color(g, scene, o, lod, v, radius);
  set_filters_and_shading(g, scene, o, lod, v, radius);
  set_scene(g, scene, o, radius);
  return g;
}

}  // namespace sluice::render
