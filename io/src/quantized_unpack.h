// Unfiltering a quantized chunk: 8 byte planes (bytes 0..5 of the Morton-code
// deltas, then the LOD value's low and high byte) -> packed particles
// (x | y << 16 | z << 32 | lod << 48), the decoded layout of format.h.
#pragma once

#include <cstddef>
#include <cstdint>

namespace sluice::io {

// `planes[0..7]` hold n bytes each; `dst` receives n uint64 (any alignment:
// it may be mapped staging memory). Picks the fastest kernel this CPU runs
// (AVX2 + BMI2, else portable); every kernel gives the same bytes.
void unpack_quantized16(const uint8_t* const* planes, size_t n, std::byte* dst);

// The portable kernel alone, for tests that compare kernels.
void unpack_quantized16_portable(const uint8_t* const* planes, size_t n, std::byte* dst);

// Whether unpack_quantized16 runs the AVX2 + BMI2 kernel on this CPU.
bool quantized_unpack_is_vectorized();

}  // namespace sluice::io
