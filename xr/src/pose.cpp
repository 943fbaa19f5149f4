// Quaternion and pose arithmetic (see placement.h).
#include "sluice/xr/placement.h"

#include <cmath>

namespace sluice::xr {

Quat operator*(Quat a, Quat b) {
  return {a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y, a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
          a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w, a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z};
}

Quat conjugate(Quat q) { return {-q.x, -q.y, -q.z, q.w}; }

Quat normalize(Quat q) {
  const float n = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
  if (!(n > 0)) return {};
  return {q.x / n, q.y / n, q.z / n, q.w / n};
}

Vec3 rotate(Quat q, Vec3 v) {
  // v + 2w(u x v) + 2u x (u x v), u the vector part.
  const Vec3 u{q.x, q.y, q.z};
  const Vec3 t = 2.0f * render::cross(u, v);
  return v + q.w * t + render::cross(u, t);
}

Quat axis_angle(Vec3 axis, float radians) {
  const Vec3 a = render::normalize(axis);
  if (render::length(a) == 0) return {};
  const float s = std::sin(radians * 0.5f);
  return {a.x * s, a.y * s, a.z * s, std::cos(radians * 0.5f)};
}

Quat rotation_between(Vec3 from, Vec3 to) {
  const Vec3 f = render::normalize(from), t = render::normalize(to);
  const float d = render::dot(f, t);
  if (d < -0.999999f) {
    // Opposite: half a turn about any axis perpendicular to `from`.
    Vec3 axis = render::cross({1, 0, 0}, f);
    if (render::length(axis) < 1e-4f) axis = render::cross({0, 1, 0}, f);
    return axis_angle(axis, 3.14159265f);
  }
  const Vec3 c = render::cross(f, t);
  return normalize({c.x, c.y, c.z, 1.0f + d});
}

Pose operator*(const Pose& a, const Pose& b) {
  return {normalize(a.orientation * b.orientation), transform(a, b.position)};
}

Pose inverse(const Pose& p) {
  const Quat r = conjugate(p.orientation);
  return {r, -rotate(r, p.position)};
}

Vec3 transform(const Pose& pose, Vec3 point) { return rotate(pose.orientation, point) + pose.position; }

Mat4 to_matrix(const Pose& pose) {
  Mat4 m = Mat4::identity();
  const Vec3 axes[3] = {rotate(pose.orientation, {1, 0, 0}), rotate(pose.orientation, {0, 1, 0}),
                        rotate(pose.orientation, {0, 0, 1})};
  for (int c = 0; c < 3; ++c) {
    for (int r = 0; r < 3; ++r) m.at(r, c) = axes[c][r];
  }
  m.at(0, 3) = pose.position.x;
  m.at(1, 3) = pose.position.y;
  m.at(2, 3) = pose.position.z;
  return m;
}

}  // namespace sluice::xr
