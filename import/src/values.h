// Private: numeric arrays of any stored type into what a io::ParticleFrame holds
// (float values, float magnitudes of vectors, uint64 ids). Shared by the
// readers, so every format converts the same way.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <vector>

namespace sluice::import::detail {

template <class T>
void convert_values(const T* in, size_t count, float* out) {
  for (size_t k = 0; k < count; ++k) out[k] = static_cast<float>(in[k]);
}

// One float per tuple: the length of its `comps` components.
template <class T>
void magnitudes(const T* in, size_t tuples, size_t comps, float* out) {
  for (size_t t = 0; t < tuples; ++t) {
    double sum = 0.0;
    for (size_t c = 0; c < comps; ++c) {
      const auto v = static_cast<double>(in[t * comps + c]);
      sum += v * v;
    }
    out[t] = static_cast<float>(std::sqrt(sum));
  }
}

// Converts ids; returns the index of the first id that is negative,
// fractional or out of range, or `count` when all are valid.
template <class T>
size_t convert_ids(const T* in, size_t count, uint64_t* out) {
  for (size_t k = 0; k < count; ++k) {
    const T v = in[k];
    if constexpr (std::is_floating_point_v<T>) {
      if (!(v >= 0) || std::floor(v) != v || static_cast<double>(v) >= 18446744073709551616.0) return k;
    } else if constexpr (std::is_signed_v<T>) {
      if (v < 0) return k;
    }
    out[k] = static_cast<uint64_t>(v);
  }
  return count;
}

// The values as floats, into `out` (replacing it, without zero-filling it
// first: for float input this is a plain copy).
template <class T>
void assign_values(const T* in, size_t count, std::vector<float>& out) {
  out.assign(in, in + count);
}

// The ids into `out`; returns the index of the first invalid one (see
// convert_ids), or `count`. Unsigned ids are all valid and copied as they
// are; signed ones are copied, then checked for a negative one.
template <class T>
size_t assign_ids(const T* in, size_t count, std::vector<uint64_t>& out) {
  if constexpr (std::is_floating_point_v<T>) {
    out.resize(count);
    return convert_ids(in, count, out.data());
  } else {
    out.assign(in, in + count);
    if constexpr (std::is_signed_v<T>) {
      for (size_t k = 0; k < count; ++k) {
        if (in[k] < 0) return k;
      }
    }
    return count;
  }
}

}  // namespace sluice::import::detail
