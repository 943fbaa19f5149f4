// The data in the room and the eyes' views of it (see placement.h).
#include "sluice/xr/placement.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace sluice::xr {

Vec3 to_room(const Placement& placement, Vec3 data_point) {
  return transform(placement.pose, placement.scale * data_point);
}

Placement initial_placement(const render::SceneInfo& scene, Floor floor, const PlacementOptions& options) {
  const render::Bounds& b = scene.bounds;
  Placement p;
  // The scene's up to the room's +y.
  p.pose.orientation = rotation_between(scene.up, {0, 1, 0});
  float extent = 0;
  for (int i = 0; i < 3; ++i) extent = std::max(extent, b.max[i] - b.min[i]);
  p.scale = std::isfinite(extent) && extent > 0 ? options.size / extent : 1.0f;
  // The box's corners in the room (rotated and scaled, not yet moved).
  Vec3 lo{std::numeric_limits<float>::max(), std::numeric_limits<float>::max(), std::numeric_limits<float>::max()};
  Vec3 hi = -lo;
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3 c{(corner & 1) ? b.max.x : b.min.x, (corner & 2) ? b.max.y : b.min.y, (corner & 4) ? b.max.z : b.min.z};
    const Vec3 r = rotate(p.pose.orientation, p.scale * c);
    for (int i = 0; i < 3; ++i) {
      lo[i] = std::min(lo[i], r[i]);
      hi[i] = std::max(hi[i], r[i]);
    }
  }
  if (!(hi.x >= lo.x)) return p;  // empty bounds: stay at the origin
  const float floor_y = floor == Floor::Stage ? 0.0f : -options.eye_height;
  p.pose.position = {-(lo.x + hi.x) * 0.5f, floor_y - lo.y, -options.distance - (lo.z + hi.z) * 0.5f};
  return p;
}

Mat4 fov_projection(const Fov& fov, float near, float far) {
  const float l = std::tan(fov.left), r = std::tan(fov.right), u = std::tan(fov.up), d = std::tan(fov.down);
  Mat4 m;  // zero
  // x_ndc = (x / -z * 2 - (r + l)) / (r - l); y_ndc flipped (Vulkan's y points down).
  m.at(0, 0) = 2.0f / (r - l);
  m.at(0, 2) = (r + l) / (r - l);
  m.at(1, 1) = -2.0f / (u - d);
  m.at(1, 2) = -(u + d) / (u - d);
  m.at(3, 2) = -1.0f;
  // Reversed depth: clip.z = A z + B with depth = clip.z / -z.
  if (std::isinf(far)) {
    m.at(2, 2) = 0;
    m.at(2, 3) = near;
  } else {
    m.at(2, 2) = near / (far - near);
    m.at(2, 3) = near * far / (far - near);
  }
  return m;
}

render::View eye_view(const Pose& eye, const Fov& fov, const Placement& placement, float near_m, float far_m,
                      const render::Viewport& viewport) {
  // Room -> eye, then data -> room; the rigid part of eye^-1 * placement,
  // its translation in data units (divided by the scale).
  const Pose rigid = inverse(eye) * placement.pose;
  const float s = placement.scale > 0 ? placement.scale : 1.0f;
  render::View v;
  v.view = to_matrix({rigid.orientation, rigid.position * (1.0f / s)});
  v.projection = fov_projection(fov, near_m / s, far_m / s);
  v.viewport = viewport;
  return v;
}

}  // namespace sluice::xr
