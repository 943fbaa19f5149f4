// Views and a scattered, tiered file for the tests of the view's demand
// (test_demand.cpp) and of relayed reads by it (test_relay.cpp).
#pragma once

#include <array>
#include <cmath>
#include <filesystem>
#include <random>
#include <vector>

#include "sluice/io/codec.h"
#include "sluice/io/lod.h"
#include "sluice/io/writer.h"
#include "sluice/runtime/demand.h"

namespace sluice::test {

using runtime::ViewDemand;

using Mat = std::array<float, 16>;  // column-major

inline float& at(Mat& m, int r, int c) { return m[size_t(c) * 4 + size_t(r)]; }

// World -> eye, looking from `eye` at `target` with +z up.
inline Mat look_at(std::array<float, 3> eye, std::array<float, 3> target) {
  auto sub = [](auto a, auto b) { return std::array<float, 3>{a[0] - b[0], a[1] - b[1], a[2] - b[2]}; };
  auto norm = [](std::array<float, 3> v) {
    const float l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    return std::array<float, 3>{v[0] / l, v[1] / l, v[2] / l};
  };
  auto cross = [](auto a, auto b) {
    return std::array<float, 3>{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
  };
  auto dot = [](auto a, auto b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
  const auto f = norm(sub(target, eye));
  const auto s = norm(cross(f, std::array<float, 3>{0, 0, 1}));
  const auto u = cross(s, f);
  Mat m{};
  for (int c = 0; c < 3; ++c) {
    at(m, 0, c) = s[size_t(c)];
    at(m, 1, c) = u[size_t(c)];
    at(m, 2, c) = -f[size_t(c)];
  }
  at(m, 0, 3) = -dot(s, eye);
  at(m, 1, 3) = -dot(u, eye);
  at(m, 2, 3) = dot(f, eye);
  at(m, 3, 3) = 1;
  return m;
}

// Eye -> Vulkan clip (y down, depth 0..1, standard), vertical fov 45 degrees.
inline Mat perspective(float aspect, float near_plane, float far_plane) {
  const float t = 1.0f / std::tan(0.5f * 45.0f * 3.14159265f / 180.0f);
  Mat m{};
  at(m, 0, 0) = t / aspect;
  at(m, 1, 1) = -t;
  at(m, 2, 2) = far_plane / (near_plane - far_plane);
  at(m, 2, 3) = near_plane * far_plane / (near_plane - far_plane);
  at(m, 3, 2) = -1;
  return m;
}

// `error_pixels` > 0: drawn at 1920 x 1080, records whose coarse
// positions lie within that many pixels are read without their fine parts.
inline ViewDemand demand_of(std::array<float, 3> eye, std::array<float, 3> target, float level, bool lod = true,
                            float error_pixels = 0) {
  ViewDemand d;
  d.views.push_back({look_at(eye, target), perspective(16.0f / 9.0f, 0.01f, 100.0f), error_pixels > 0 ? 1920u : 0u,
                     error_pixels > 0 ? 1080u : 0u});
  d.position_error_pixels = error_pixels;
  d.lod = lod;
  d.level = level;
  d.reference_distance = 1.5f;  // about the data's diagonal
  d.particle_radius = 0.005f;
  d.particle_reach = 0.005f;
  return d;
}

// A scattered block (1 x 0.6 x 0.3) with random ids: chunks of 8192 written
// as LOD tiers (scattered data: tiers pay).
// `major`: the container's layout (io::set_format_version); `planes`: how
// the planes are coded (GpuDecodable: every record relays to the GPU).
inline std::filesystem::path write_scattered(const std::filesystem::path& path, uint64_t frames, uint32_t n,
                                             uint16_t major = io::kFormatMajor,
                                             io::PlaneCoding planes = io::PlaneCoding::Packed) {
  io::FileHeader header;
  io::set_format_version(header, major);
  header.particle_spacing = 0.01f;
  header.particle_radius = 0.005f;
  header.frame_rate = 30;
  io::ContainerWriter writer(path, header);
  for (uint64_t f = 0; f < frames; ++f) {
    std::mt19937 rng(uint32_t(f) + 11);
    std::uniform_real_distribution<float> u(0, 1);
    std::vector<float> xyz;
    std::vector<uint16_t> lod;
    for (uint32_t i = 0; i < n; ++i) {
      xyz.insert(xyz.end(), {u(rng), 0.6f * u(rng), 0.3f * u(rng) + 0.01f * float(f)});
      lod.push_back(io::lod_value_from_id(i));
    }
    io::FrameInput in;
    in.positions = xyz;
    in.lod = lod;
    in.time = double(f) / 30;
    io::EncodeOptions o;
    o.chunk_particles = 8192;
    o.planes = planes;
    writer.append(io::encode_frame(in, header, o));
  }
  writer.finish();
  return path;
}

}  // namespace sluice::test
