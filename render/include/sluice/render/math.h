// sluice/render/math.h: the little linear algebra the renderer's host side
// needs (camera, frustum, uniforms). Plain values, column-major matrices laid
// out exactly as GLSL's mat4 so they can be copied into uniform buffers.
#pragma once

#include <array>
#include <cmath>

namespace sluice::render {

struct Vec3 {
  float x = 0, y = 0, z = 0;
  constexpr float& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr float operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr bool operator==(const Vec3&) const = default;
};

constexpr Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
constexpr Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
constexpr Vec3 operator-(Vec3 a) { return {-a.x, -a.y, -a.z}; }
constexpr Vec3 operator*(Vec3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
constexpr Vec3 operator*(float s, Vec3 a) { return a * s; }
constexpr float dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
constexpr Vec3 cross(Vec3 a, Vec3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline float length(Vec3 a) { return std::sqrt(dot(a, a)); }
inline Vec3 normalize(Vec3 a) {
  const float l = length(a);
  return l > 0 ? a * (1.0f / l) : Vec3{0, 0, 0};
}

struct Vec4 {
  float x = 0, y = 0, z = 0, w = 0;
};

// Column-major 4x4: m[column * 4 + row], as GLSL stores a mat4.
struct Mat4 {
  std::array<float, 16> m{};
  constexpr float& at(int row, int col) { return m[size_t(col * 4 + row)]; }
  constexpr float at(int row, int col) const { return m[size_t(col * 4 + row)]; }
  static constexpr Mat4 identity() {
    Mat4 r;
    for (int i = 0; i < 4; ++i) r.at(i, i) = 1;
    return r;
  }
};

Mat4 operator*(const Mat4& a, const Mat4& b);
Vec4 operator*(const Mat4& a, Vec4 v);
Mat4 inverse(const Mat4& a);  // general inverse; identity if singular

// World -> eye: right-handed, the camera looks down -z with +y up.
Mat4 look_at(Vec3 eye, Vec3 target, Vec3 up);

// Eye -> Vulkan clip space with reversed depth and an infinite far plane:
// depth = near / distance (1 at the near plane, 0 at infinity), so a 32-bit
// float depth buffer keeps precision everywhere. Image y points down (row 0
// at the top), as PNG rows are stored. fov_y in radians.
Mat4 perspective_reverse_z(float fov_y, float aspect, float near);

// Two unit vectors across `up` completing a right-handed frame (a, b, up):
// for +z they are x and y.
void frame_across(Vec3 up, Vec3& a, Vec3& b);

}  // namespace sluice::render
