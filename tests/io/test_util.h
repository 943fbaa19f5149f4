// Helpers shared by the io tests: synthetic SPH-like frames and temp files.
#pragma once

#include <cstdint>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "sluice/io/codec.h"
#include "sluice/io/lod.h"
#include "sluice/io/types.h"
#include "sluice/io/writer.h"

namespace sluice::test {

// Scattered particles in a slab (not a lattice: LOD tiers pay there) with
// random ids and one attribute.
inline io::ParticleFrame scattered_frame(uint64_t n, uint32_t seed) {
  io::ParticleFrame f;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  f.attributes.resize(1);
  for (uint64_t i = 0; i < n; ++i) {
    const float x = u(rng), y = u(rng), z = 0.5f * u(rng);
    f.positions.insert(f.positions.end(), {x, y, z});
    f.ids.push_back(rng());
    f.attributes[0].push_back(1000.f + 10.f * std::sin(x * 7.f) + y);
  }
  return f;
}

// A jittered lattice of `n` particles, spacing 0.01, moved by `t`, with a
// stable id per particle and one attribute (a smooth field).
inline io::ParticleFrame lattice_frame(uint64_t n, double t, uint32_t seed = 1) {
  io::ParticleFrame f;
  f.time = t;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> jitter(-0.002f, 0.002f);
  const auto side = static_cast<uint64_t>(std::ceil(std::cbrt(double(n))));
  f.attributes.resize(1);
  for (uint64_t i = 0; i < n; ++i) {
    const float x = float(i % side) * 0.01f + jitter(rng) + float(t) * 0.1f;
    const float y = float((i / side) % side) * 0.01f + jitter(rng);
    const float z = float(i / (side * side)) * 0.01f + jitter(rng) - 0.3f;
    f.positions.insert(f.positions.end(), {x, y, z});
    f.ids.push_back(1000 + i);
    f.attributes[0].push_back(1000.f + 10.f * std::sin(x * 7.f) + y);
  }
  return f;
}

inline io::FileHeader test_header(io::PositionCoding coding, bool with_attribute = true) {
  io::FileHeader h;
  h.position_coding = coding;
  h.particle_spacing = 0.01f;
  h.particle_radius = 0.005f;
  h.frame_rate = 30.f;
  if (with_attribute) h.attributes.push_back({"rho"});
  h.lod_id_array = "id";
  h.source = "synthetic lattice";
  return h;
}

inline io::EncodedFrame encode(const io::ParticleFrame& f, const io::FileHeader& h, uint32_t chunk = 4096,
                               bool layers = false, io::F2Test f2 = io::F2Test::All) {
  const std::vector<uint16_t> lod = io::lod_values(f.ids, f.count());
  io::FrameInput in;
  in.positions = f.positions;
  in.lod = lod;
  for (size_t a = 0; a < h.attributes.size(); ++a) in.attributes.push_back(f.attributes[a]);
  in.time = f.time;
  io::EncodeOptions options;
  options.chunk_particles = chunk;
  options.layers = layers;
  options.band_f2 = f2;
  return io::encode_frame(in, h, options);
}

// Writes frames into a new container and returns its path.
inline std::filesystem::path write_file(const std::filesystem::path& path, const io::FileHeader& h,
                                        const std::vector<io::ParticleFrame>& frames, uint32_t chunk = 4096,
                                        bool layers = false) {
  io::ContainerWriter w(path, h);
  for (const auto& f : frames) w.append(encode(f, h, chunk, layers));
  w.finish();
  return path;
}

// A fresh directory under the system temp dir, removed at destruction.
struct TempDir {
  std::filesystem::path path;
  TempDir() {
    path = std::filesystem::temp_directory_path() /
           ("sluice-test-" + std::to_string(std::random_device{}()) + "-" + std::to_string(::getpid()));
    std::filesystem::create_directories(path);
  }
  ~TempDir() { std::filesystem::remove_all(path); }
  std::filesystem::path operator/(const std::string& name) const { return path / name; }
};

}  // namespace sluice::test
