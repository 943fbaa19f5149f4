// Host-side linear algebra (see math.h).
#include "sluice/render/math.h"

#include <utility>

namespace sluice::render {

Mat4 operator*(const Mat4& a, const Mat4& b) {
  Mat4 r;
  for (int c = 0; c < 4; ++c) {
    for (int rr = 0; rr < 4; ++rr) {
      float s = 0;
      for (int k = 0; k < 4; ++k) s += a.at(rr, k) * b.at(k, c);
      r.at(rr, c) = s;
    }
  }
  return r;
}

Vec4 operator*(const Mat4& a, Vec4 v) {
  const float in[4] = {v.x, v.y, v.z, v.w};
  float out[4];
  for (int r = 0; r < 4; ++r) out[r] = a.at(r, 0) * in[0] + a.at(r, 1) * in[1] + a.at(r, 2) * in[2] + a.at(r, 3) * in[3];
  return {out[0], out[1], out[2], out[3]};
}

Mat4 inverse(const Mat4& a) {
  // Gauss-Jordan with partial pivoting, in double.
  double m[4][8];
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      m[r][c] = a.at(r, c);
      m[r][c + 4] = r == c ? 1.0 : 0.0;
    }
  }
  for (int c = 0; c < 4; ++c) {
    int pivot = c;
    for (int r = c + 1; r < 4; ++r) {
      if (std::fabs(m[r][c]) > std::fabs(m[pivot][c])) pivot = r;
    }
    if (std::fabs(m[pivot][c]) < 1e-300) return Mat4::identity();
    if (pivot != c) {
      for (int k = 0; k < 8; ++k) std::swap(m[c][k], m[pivot][k]);
    }
    const double inv = 1.0 / m[c][c];
    for (int k = 0; k < 8; ++k) m[c][k] *= inv;
    for (int r = 0; r < 4; ++r) {
      if (r == c) continue;
      const double f = m[r][c];
      for (int k = 0; k < 8; ++k) m[r][k] -= f * m[c][k];
    }
  }
  Mat4 out;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) out.at(r, c) = float(m[r][c + 4]);
  }
  return out;
}

Mat4 look_at(Vec3 eye, Vec3 target, Vec3 up) {
  const Vec3 f = normalize(target - eye);
  Vec3 s = cross(f, up);
  if (dot(s, s) < 1e-12f) s = cross(f, std::fabs(f.x) < 0.9f ? Vec3{1, 0, 0} : Vec3{0, 1, 0});
  s = normalize(s);
  const Vec3 u = cross(s, f);
  Mat4 m = Mat4::identity();
  m.at(0, 0) = s.x;
  m.at(0, 1) = s.y;
  m.at(0, 2) = s.z;
  m.at(1, 0) = u.x;
  m.at(1, 1) = u.y;
  m.at(1, 2) = u.z;
  m.at(2, 0) = -f.x;
  m.at(2, 1) = -f.y;
  m.at(2, 2) = -f.z;
  m.at(0, 3) = -dot(s, eye);
  m.at(1, 3) = -dot(u, eye);
  m.at(2, 3) = dot(f, eye);
  return m;
}

Mat4 perspective_reverse_z(float fov_y, float aspect, float near) {
  const float f = 1.0f / std::tan(fov_y * 0.5f);
  Mat4 m;
  m.at(0, 0) = f / aspect;
  m.at(1, 1) = -f;  // Vulkan: +y in clip space is down the image
  m.at(2, 3) = near;
  m.at(3, 2) = -1.0f;
  return m;
}

void frame_across(Vec3 up, Vec3& a, Vec3& b) {
  const Vec3 u = normalize(up);
  const Vec3 seed = std::abs(u.x) < 0.9f ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
  a = normalize(seed - u * dot(u, seed));
  b = cross(u, a);
}

}  // namespace sluice::render
