// Internal: IEEE half-precision floats read back from the GPU (thickness
// targets without 32-bit float blending, the ellipsoids' shape matrices).
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>

namespace sluice::render {

inline float half_to_float(uint16_t h) {
  const uint32_t sign = uint32_t(h >> 15) << 31, exponent = (h >> 10) & 31, mantissa = h & 1023;
  if (exponent == 0) return (sign ? -1.f : 1.f) * std::ldexp(float(mantissa), -24);
  uint32_t bits = sign | ((exponent == 31 ? 255u : exponent + 112u) << 23) | (mantissa << 13);
  float f;
  std::memcpy(&f, &bits, 4);
  return f;
}

}  // namespace sluice::render
