// sluice/io/types.h: plain data shared by the importers, the writer and the
// reader. No behaviour beyond small helpers.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace sluice::io {

// Axis-aligned box in world units. An empty box has min > max.
struct Aabb {
  std::array<float, 3> min{std::numeric_limits<float>::max(), std::numeric_limits<float>::max(),
                           std::numeric_limits<float>::max()};
  std::array<float, 3> max{std::numeric_limits<float>::lowest(), std::numeric_limits<float>::lowest(),
                           std::numeric_limits<float>::lowest()};

  bool empty() const { return min[0] > max[0] || min[1] > max[1] || min[2] > max[2]; }
  void extend(float x, float y, float z);
  void extend(const Aabb& other);
  bool contains(float x, float y, float z) const;
  bool operator==(const Aabb&) const = default;
};

// One frame of particles as an importer hands it over, before encoding.
// Arrays are structure-of-arrays; every per-particle array has `count()` entries.
struct ParticleFrame {
  std::vector<float> positions;               // x,y,z interleaved, world units
  std::vector<uint64_t> ids;                  // stable particle ids; empty if the source has none
  std::vector<std::vector<float>> attributes; // one array per requested attribute, same order as requested
  double time = 0.0;                          // simulation time in seconds (or the frame number if unknown)
  bool time_given = false;                    // the input stated `time` (.pvd, a time field); else it is the frame number
  std::vector<std::string> repairs;           // human-readable notes of what the importer repaired

  uint64_t count() const { return positions.size() / 3; }
};

// A declared attribute stream: a scalar per particle (vectors are stored as
// their magnitude), quantized to 16 bits against a range.
struct AttributeInfo {
  std::string name;
  float declared_min = std::numeric_limits<float>::quiet_NaN();  // NaN: not declared
  float declared_max = std::numeric_limits<float>::quiet_NaN();
};

}  // namespace sluice::io
