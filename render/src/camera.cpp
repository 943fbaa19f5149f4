// Camera interactions and its text form (see camera.h).
#include "sluice/render/camera.h"
#include "sluice/error.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace sluice::render {
namespace {

constexpr float kPi = 3.14159265358979f;

// Rotates v about the unit axis k by angle a (Rodrigues).
Vec3 rotate(Vec3 v, Vec3 k, float a) {
  const float c = std::cos(a), s = std::sin(a);
  return v * c + cross(k, v) * s + k * (dot(k, v) * (1 - c));
}

// `count` comma-separated numbers.
std::vector<float> parse_floats(const std::string& key, const std::string& value, size_t count) {
  const std::string want = count == 3 ? "three numbers x,y,z" : "two numbers x,y";
  std::vector<float> parts;
  std::stringstream ss(value);
  std::string item;
  while (std::getline(ss, item, ',')) {
    try {
      size_t used = 0;
      parts.push_back(std::stof(item, &used));
      if (used != item.size()) throw Error(item);
    } catch (const std::exception&) {
      throw Error("camera: '" + key + "' needs " + want + ", got '" + value + "'");
    }
  }
  if (parts.size() != count) throw Error("camera: '" + key + "' needs " + want + ", got '" + value + "'");
  return parts;
}

Vec3 parse_vec3(const std::string& key, const std::string& value) {
  const std::vector<float> p = parse_floats(key, value, 3);
  return {p[0], p[1], p[2]};
}

float parse_float(const std::string& key, const std::string& value) {
  try {
    size_t used = 0;
    const float f = std::stof(value, &used);
    if (used == value.size()) return f;
  } catch (const std::exception&) {
  }
  throw Error("camera: '" + key + "' needs a number, got '" + value + "'");
}

std::string fmt(Vec3 v) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "%.9g,%.9g,%.9g", double(v.x), double(v.y), double(v.z));
  return buf;
}

}  // namespace

void Camera::orbit(float yaw, float pitch) {
  const Vec3 k = normalize(up);
  Vec3 offset = eye - target;
  offset = rotate(offset, k, yaw);
  // Keep at least ~1 degree from the poles so `up` stays usable.
  const float dist = length(offset);
  if (dist <= 0) return;
  const float elevation = std::asin(std::clamp(dot(offset, k) / dist, -1.0f, 1.0f));
  const float limit = kPi / 2 - 0.02f;
  const float next = std::clamp(elevation + pitch, -limit, limit);
  const Vec3 right = normalize(cross(offset, k));
  if (dot(right, right) > 0) offset = rotate(offset, right, next - elevation);
  eye = target + offset;
}

void Camera::pan(float dx, float dy) {
  const float dist = length(target - eye);
  const float h = 2 * dist * std::tan(fov_deg * kPi / 360.0f);
  const Vec3 f = forward();
  const Vec3 right = normalize(cross(f, up));
  const Vec3 u = cross(right, f);
  const Vec3 move = right * (dx * h) + u * (dy * h);
  eye = eye + move;
  target = target + move;
}

void Camera::zoom(float factor) {
  if (factor <= 0) return;
  eye = target + (eye - target) * factor;
}


void Camera::fit_corners(const Bounds& box, float tan_half_v, float aspect) {
  // Every corner of the box inside 90% of the view: for a corner at
  // (x, y) across the view and z along it from the target, the eye must
  // be at least |x| / tan_h - z (and |y| / tan_v - z) behind the target.
  const float margin = 0.9f;
  const float tan_v = tan_half_v * margin, tan_h = tan_half_v * aspect * margin;
  const Vec3 f = forward(), right = normalize(cross(f, up)), u = cross(right, f);
  target = box.center();
  float dist = 1e-6f;
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3 p{(corner & 1) ? box.max.x : box.min.x, (corner & 2) ? box.max.y : box.min.y,
                 (corner & 4) ? box.max.z : box.min.z};
    const Vec3 d = p - target;
    const float z = dot(d, f);
    dist = std::max({dist, std::abs(dot(d, right)) / tan_h - z, std::abs(dot(d, u)) / tan_v - z});
  }
  eye = target - f * dist;
}

void Camera::fit(const Bounds& box, float aspect) {
  const float radius = std::max(box.diagonal() * 0.5f, 1e-6f);
  const float half_v = fov_deg * kPi / 360.0f;
  const float half_h = std::atan(std::tan(half_v) * aspect);
  const float half = std::min(half_v, half_h);
  const float dist = radius / std::sin(half);
  Vec3 dir = forward();
  if (dot(dir, dir) == 0) dir = {0, 1, 0};
  target = box.center();
  eye = target - dir * dist;
}

Camera Camera::framing(const Bounds& box, Vec3 up_direction, float aspect, float fov_deg, ScreenRect free) {
  Camera c;
  c.fov_deg = fov_deg;
  const Vec3 up = length(up_direction) > 0 ? normalize(up_direction) : Vec3{0, 0, 1};
  c.up = up;
  // From the front-left, a little above: the view a ParaView user starts with.
  Vec3 a, b;
  frame_across(up, a, b);
  const Vec3 dir = normalize(a * 0.55f + b * 0.8f - up * 0.45f);
  c.target = box.center();
  c.eye = c.target - dir;
  // Fit into the free part: its share of the image's height narrows the
  // field of view, its shape sets the aspect; the shift moves it there.
  const float w = std::clamp(free.x1 - free.x0, 0.05f, 1.0f), h = std::clamp(free.y1 - free.y0, 0.05f, 1.0f);
  c.fit_corners(box, std::tan(fov_deg * kPi / 360.0f) * h, aspect * w / h);
  c.shift_x = free.x0 + free.x1 - 1.0f;
  c.shift_y = free.y0 + free.y1 - 1.0f;
  return c;
}

float Camera::near_plane() const {
  if (near > 0) return near;
  return std::max(length(target - eye) * 1e-3f, 1e-6f);
}

Mat4 Camera::projection(float aspect) const {
  Mat4 m = perspective_reverse_z(fov_deg * kPi / 180.0f, aspect, near_plane());
  // Shifting clip x (y) by shift * w moves the image centre; w = -z here.
  m.at(0, 2) -= shift_x;
  m.at(1, 2) -= shift_y;
  return m;
}

std::string Camera::to_string() const {
  char fov[32];
  std::snprintf(fov, sizeof fov, "%.9g", double(fov_deg));
  std::string s = "eye=" + fmt(eye) + ";target=" + fmt(target) + ";up=" + fmt(up) + ";fov=" + fov;
  if (near > 0) {
    char n[32];
    std::snprintf(n, sizeof n, "%.9g", double(near));
    s += ";near=" + std::string(n);
  }
  if (shift_x != 0 || shift_y != 0) {
    char n[64];
    std::snprintf(n, sizeof n, "%.9g,%.9g", double(shift_x), double(shift_y));
    s += ";shift=" + std::string(n);
  }
  return s;
}

void Camera::apply(const std::string& text) {
  Camera next = *this;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ';')) {
    if (item.empty()) continue;
    const size_t eq = item.find('=');
    if (eq == std::string::npos) throw Error("camera: expected key=value, got '" + item + "'");
    const std::string key = item.substr(0, eq), value = item.substr(eq + 1);
    if (key == "eye") next.eye = parse_vec3(key, value);
    else if (key == "target") next.target = parse_vec3(key, value);
    else if (key == "up") next.up = parse_vec3(key, value);
    else if (key == "fov") next.fov_deg = parse_float(key, value);
    else if (key == "near") next.near = parse_float(key, value);
    else if (key == "shift") {
      const std::vector<float> xy = parse_floats(key, value, 2);
      next.shift_x = xy[0];
      next.shift_y = xy[1];
    } else throw Error("camera: unknown key '" + key + "' (eye, target, up, fov, near, shift)");
  }
  if (!(next.fov_deg > 0 && next.fov_deg < 179)) throw Error("camera: fov must be in (0, 179) degrees");
  if (length(next.eye - next.target) <= 0) throw Error("camera: eye and target coincide");
  if (length(next.up) <= 0) throw Error("camera: up is zero");
  *this = next;
}

View camera_view(const Camera& camera, const Viewport& viewport) {
  View v;
  v.view = camera.view();
  v.projection = camera.projection(float(viewport.width) / float(std::max(viewport.height, 1u)));
  v.viewport = viewport;
  return v;
}

}  // namespace sluice::render
