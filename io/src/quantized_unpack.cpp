// Three kernels, one result. The portable one gathers each particle's 8
// bytes and decodes its Morton code through a table. The x86 ones work on
// blocks of 32 particles: an 8 x 32 byte transpose (unpack instructions)
// turns the 8 planes into 32 words `delta | lod << 48` at about one shuffle
// per particle, into a block that stays in L1; a scalar pass then runs the
// prefix sum and splits each code with three PEXTs (or the table, on CPUs
// whose PEXT is slow). One pass over the planes, no 64-bit delta array in
// between.
//
// The kernel is picked by a flag read once rather than an ifunc
// (target_clones): ifunc resolvers run before TSan initialises and crash it.
#include "quantized_unpack.h"

#include <algorithm>
#include <cstring>
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#define SLUICE_X86_KERNELS 1
#endif

#include "morton.h"

namespace sluice::io {
namespace {

constexpr uint64_t kDeltaMask = (uint64_t{1} << 48) - 1;
constexpr uint64_t kFineMask = 0xffff;

// One particle's code from its word and the code before it. Whole: the word
// holds the code's delta in bytes 0-5. Split (format 3.0): bytes 0-1 are
// the code's low 16 bits and bytes 2-5 the delta of its high 32.
template <bool Split>
inline uint64_t next_code(uint64_t code, uint64_t word) {
  if constexpr (Split) {
    const uint64_t high = (code >> 16) + ((word & kDeltaMask) >> 16);
    return (high << 16 | (word & kFineMask)) & kDeltaMask;
  } else {
    return code + (word & kDeltaMask);
  }
}

inline uint64_t gather_word(const uint8_t* const* p, size_t i) {
  return uint64_t(p[0][i]) | uint64_t(p[1][i]) << 8 | uint64_t(p[2][i]) << 16 | uint64_t(p[3][i]) << 24 |
         uint64_t(p[4][i]) << 32 | uint64_t(p[5][i]) << 40 | uint64_t(p[6][i]) << 48 | uint64_t(p[7][i]) << 56;
}

// Particles [begin, n) given the code before `begin`; returns the last code.
template <bool Split>
uint64_t unpack_portable_from(const uint8_t* const* p, size_t begin, size_t n, uint64_t code, std::byte* dst) {
  for (size_t i = begin; i < n; ++i) {
    const uint64_t word = gather_word(p, i);
    code = next_code<Split>(code, word);
    const uint64_t packed = morton_to_packed16(code) | (word & ~kDeltaMask);
    std::memcpy(dst + 8 * i, &packed, 8);
  }
  return code;
}

#if SLUICE_X86_KERNELS
constexpr size_t kBlock = 32;

// 8 planes x 32 bytes -> 32 words, word i = byte i of each plane, plane k at
// bits 8k. AVX2 unpacks work within 128-bit lanes, so the three unpack
// levels leave particles {0,1,16,17}, {2,3,18,19}, ... in the registers;
// the last step puts the lanes in order.
__attribute__((target("avx2"))) inline void transpose_block(const uint8_t* const* p, size_t i, uint64_t* words) {
  __m256i a[8];
  for (int k = 0; k < 8; ++k) a[k] = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p[k] + i));
  __m256i b[8], c[8], d[8];
  for (int k = 0; k < 4; ++k) {  // 16-bit elements: planes (2k, 2k+1)
    b[2 * k] = _mm256_unpacklo_epi8(a[2 * k], a[2 * k + 1]);      // particles 0-7 | 16-23
    b[2 * k + 1] = _mm256_unpackhi_epi8(a[2 * k], a[2 * k + 1]);  // 8-15 | 24-31
  }
  for (int h = 0; h < 2; ++h) {  // 32-bit elements: planes 0-3 and 4-7
    c[4 * h + 0] = _mm256_unpacklo_epi16(b[0 + h], b[2 + h]);
    c[4 * h + 1] = _mm256_unpackhi_epi16(b[0 + h], b[2 + h]);
    c[4 * h + 2] = _mm256_unpacklo_epi16(b[4 + h], b[6 + h]);
    c[4 * h + 3] = _mm256_unpackhi_epi16(b[4 + h], b[6 + h]);
  }
  // c[4h+0]: planes 0-3 of particles 8h+{0..3} | 16+8h+{0..3}; c[4h+1]: +4..7;
  // c[4h+2], c[4h+3]: planes 4-7 of the same particles.
  for (int q = 0; q < 4; ++q) {  // 64-bit elements
    const int lo = 4 * (q / 2) + (q % 2), hi = lo + 2;
    d[2 * q] = _mm256_unpacklo_epi32(c[lo], c[hi]);
    d[2 * q + 1] = _mm256_unpackhi_epi32(c[lo], c[hi]);
  }
  // d[j] holds particles 2j, 2j+1 (low lane) and 16+2j, 17+2j (high lane).
  auto* out = reinterpret_cast<__m256i*>(words);
  for (int j = 0; j < 4; ++j) {
    _mm256_storeu_si256(out + j, _mm256_permute2x128_si256(d[2 * j], d[2 * j + 1], 0x20));
    _mm256_storeu_si256(out + 4 + j, _mm256_permute2x128_si256(d[2 * j], d[2 * j + 1], 0x31));
  }
}

// Blocks of packed particles are written with streaming stores when the
// chunk is large (kStreamFrom particles, 128 KiB decoded) and the
// destination 32-byte aligned: decoded frames go to the GPU, not back
// through this core, and streaming stores spare the memory bus the
// read-for-ownership of every destination line (2.8 against 3.4-4.6 ns per
// particle on a 2M-particle frame, one core). Small chunks may well be read
// again from cache, so they are stored normally.
constexpr size_t kStreamFrom = 16384;

// The block loop, shared by both x86 kernels; `Split` turns a Morton code
// into x | y << 16 | z << 32.
template <bool Split, class Decode>
__attribute__((target("avx2,bmi2"), always_inline)) inline void unpack_blocks(const uint8_t* const* p, size_t n, std::byte* dst, Decode split) {
  alignas(32) uint64_t words[kBlock];
  alignas(32) uint64_t packed[kBlock];
  // Particles before the first 32-byte boundary of dst go the portable way.
  const size_t misaligned = reinterpret_cast<uintptr_t>(dst) % 32;
  size_t i = misaligned % 8 != 0 ? n : std::min(n, ((32 - misaligned) % 32) / 8);
  uint64_t code = unpack_portable_from<Split>(p, 0, i, 0, dst);
  const bool stream = n >= kStreamFrom;
  for (; i + kBlock <= n; i += kBlock) {
    transpose_block(p, i, words);
    for (size_t j = 0; j < kBlock; ++j) {
      const uint64_t word = words[j];
      code = next_code<Split>(code, word);
      packed[j] = split(code) | (word & ~kDeltaMask);
    }
    auto* out = reinterpret_cast<__m256i*>(dst + 8 * i);
    const auto* block = reinterpret_cast<const __m256i*>(packed);
    if (stream) {
      for (size_t j = 0; j < kBlock / 4; ++j) _mm256_stream_si256(out + j, _mm256_load_si256(block + j));
    } else {
      for (size_t j = 0; j < kBlock / 4; ++j) _mm256_storeu_si256(out + j, _mm256_load_si256(block + j));
    }
  }
  if (stream) _mm_sfence();  // streaming stores are weakly ordered: publish them before the caller does
  unpack_portable_from<Split>(p, i, n, code, dst);
}

template <bool Split>
__attribute__((target("avx2,bmi2"))) void unpack_avx2_pext(const uint8_t* const* p, size_t n, std::byte* dst) {
  unpack_blocks<Split>(p, n, dst, [](uint64_t code) __attribute__((target("avx2,bmi2"), always_inline)) {
    return _pext_u64(code, 0x249249249249ull) | _pext_u64(code, 0x492492492492ull) << 16 |
           _pext_u64(code, 0x924924924924ull) << 32;
  });
}

// Compiled for BMI2 too (the compiler's own shifts, never PEXT), so that one
// block loop serves both kernels.
template <bool Split>
__attribute__((target("avx2,bmi2"))) void unpack_avx2_table(const uint8_t* const* p, size_t n, std::byte* dst) {
  unpack_blocks<Split>(p, n, dst, [](uint64_t code) __attribute__((target("avx2,bmi2"), always_inline)) {
    return morton_to_packed16(code);
  });
}

const bool kHaveAvx2Bmi2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("bmi2");
#endif

}  // namespace

bool fast_pext() {
#if SLUICE_X86_KERNELS
  // AMD before Zen 3 runs PDEP/PEXT in microcode, at tens to hundreds of
  // cycles each (one per mask bit): there the table is far faster.
  static const bool fast = __builtin_cpu_supports("bmi2") && !__builtin_cpu_is("znver1") && !__builtin_cpu_is("znver2");
  return fast;
#else
  return false;
#endif
}

bool unpack_kernel_runs_here(UnpackKernel kernel) {
  switch (kernel) {
    case UnpackKernel::Portable: return true;
#if SLUICE_X86_KERNELS
    case UnpackKernel::Avx2Table:
    case UnpackKernel::Avx2Pext: return kHaveAvx2Bmi2;
#else
    default: return false;
#endif
  }
  return false;
}

UnpackKernel chosen_unpack_kernel() {
  if (unpack_kernel_runs_here(UnpackKernel::Avx2Pext) && fast_pext()) return UnpackKernel::Avx2Pext;
  if (unpack_kernel_runs_here(UnpackKernel::Avx2Table)) return UnpackKernel::Avx2Table;
  return UnpackKernel::Portable;
}

namespace {

template <bool Split>
void unpack_with(UnpackKernel kernel, const uint8_t* const* planes, size_t n, std::byte* dst) {
  switch (kernel) {
#if SLUICE_X86_KERNELS
    case UnpackKernel::Avx2Pext: return unpack_avx2_pext<Split>(planes, n, dst);
    case UnpackKernel::Avx2Table: return unpack_avx2_table<Split>(planes, n, dst);
#endif
    default: unpack_portable_from<Split>(planes, 0, n, 0, dst);
  }
}

}  // namespace

void unpack_quantized16_with(UnpackKernel kernel, const uint8_t* const* planes, size_t n, std::byte* dst) {
  unpack_with<false>(kernel, planes, n, dst);
}

void unpack_split16_with(UnpackKernel kernel, const uint8_t* const* planes, size_t n, std::byte* dst) {
  unpack_with<true>(kernel, planes, n, dst);
}

void unpack_quantized16(const uint8_t* const* planes, size_t n, std::byte* dst) {
  static const UnpackKernel kernel = chosen_unpack_kernel();
  unpack_with<false>(kernel, planes, n, dst);
}

void unpack_split16(const uint8_t* const* planes, size_t n, std::byte* dst) {
  static const UnpackKernel kernel = chosen_unpack_kernel();
  unpack_with<true>(kernel, planes, n, dst);
}

}  // namespace sluice::io
