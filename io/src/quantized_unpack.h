// Unfiltering a quantized chunk: 8 byte planes (bytes 0..5 of the Morton-code
// deltas, then the LOD value's low and high byte) -> packed particles
// (x | y << 16 | z << 32 | lod << 48), the decoded layout of format.h.
#pragma once

#include <cstddef>
#include <cstdint>

namespace sluice::io {

// `planes[0..7]` hold n bytes each; `dst` receives n uint64 (any alignment:
// it may be mapped staging memory). Runs chosen_unpack_kernel(); every
// kernel gives the same bytes.
void unpack_quantized16(const uint8_t* const* planes, size_t n, std::byte* dst);
// Format 3.0's split positions: `planes[0..1]` the low 16 bits of each code
// (the fine part, or kCoarseFill's bytes), `planes[2..5]` bytes 0..3 of the
// deltas of the codes' high 32 bits, `planes[6..7]` the LOD value.
void unpack_split16(const uint8_t* const* planes, size_t n, std::byte* dst);

enum class UnpackKernel {
  Portable,   // any CPU
  Avx2Table,  // AVX2 transpose, table Morton decode (needs BMI2 present, not fast)
  Avx2Pext,   // AVX2 transpose, BMI2 PEXT Morton decode
};
// Avx2Pext where PEXT is fast (not AMD Zen 1/2, which run it in microcode),
// else Avx2Table where there is AVX2, else Portable.
UnpackKernel chosen_unpack_kernel();
bool unpack_kernel_runs_here(UnpackKernel kernel);
// One kernel by name, for tests that compare kernels; it must run here.
void unpack_quantized16_with(UnpackKernel kernel, const uint8_t* const* planes, size_t n, std::byte* dst);
void unpack_split16_with(UnpackKernel kernel, const uint8_t* const* planes, size_t n, std::byte* dst);

// Whether BMI2's PDEP/PEXT are there and fast on this CPU.
bool fast_pext();

}  // namespace sluice::io
