// The kernels of dequantize.h. Picked by a flag read once rather than an
// ifunc (as quantized_unpack.cpp: ifunc resolvers run before TSan starts).
#include "dequantize.h"

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#define SLUICE_X86_KERNELS 1
#endif

namespace sluice::io {
namespace {

#if SLUICE_X86_KERNELS
size_t streaming_sse2(const uint16_t* q, size_t i, size_t n, const ChunkScale& s, float* xyz, uint16_t* lod) {
  const __m128 scale = _mm_setr_ps(s.step[0], s.step[1], s.step[2], 0.0f);
  const __m128 base = _mm_setr_ps(s.lo[0], s.lo[1], s.lo[2], 0.0f);
  const __m128i zero = _mm_setzero_si128();
  for (; i + 4 <= n; i += 4) {
    const __m128i a = _mm_loadu_si128(reinterpret_cast<const __m128i*>(q + 4 * i));
    const __m128i b = _mm_loadu_si128(reinterpret_cast<const __m128i*>(q + 4 * i + 8));
    const __m128 v0 = _mm_add_ps(_mm_mul_ps(_mm_cvtepi32_ps(_mm_unpacklo_epi16(a, zero)), scale), base);
    const __m128 v1 = _mm_add_ps(_mm_mul_ps(_mm_cvtepi32_ps(_mm_unpackhi_epi16(a, zero)), scale), base);
    const __m128 v2 = _mm_add_ps(_mm_mul_ps(_mm_cvtepi32_ps(_mm_unpacklo_epi16(b, zero)), scale), base);
    const __m128 v3 = _mm_add_ps(_mm_mul_ps(_mm_cvtepi32_ps(_mm_unpackhi_epi16(b, zero)), scale), base);
    // Four (x, y, z, 0) into three registers of x0 y0 z0 x1 | y1 z1 x2 y2 | z2 x3 y3 z3.
    const __m128 zx = _mm_shuffle_ps(v0, v1, _MM_SHUFFLE(0, 0, 2, 2));   // z0 z0 x1 x1
    const __m128 zx2 = _mm_shuffle_ps(v2, v3, _MM_SHUFFLE(0, 0, 2, 2));  // z2 z2 x3 x3
    _mm_stream_ps(xyz + 3 * i, _mm_shuffle_ps(v0, zx, _MM_SHUFFLE(2, 0, 1, 0)));
    _mm_stream_ps(xyz + 3 * i + 4, _mm_shuffle_ps(v1, v2, _MM_SHUFFLE(1, 0, 2, 1)));
    _mm_stream_ps(xyz + 3 * i + 8, _mm_shuffle_ps(zx2, v3, _MM_SHUFFLE(2, 1, 2, 0)));
    const uint64_t lods = uint64_t(_mm_extract_epi16(a, 3)) | uint64_t(_mm_extract_epi16(a, 7)) << 16 |
                          uint64_t(_mm_extract_epi16(b, 3)) << 32 | uint64_t(_mm_extract_epi16(b, 7)) << 48;
    _mm_stream_si64(reinterpret_cast<long long*>(lod + i), static_cast<long long>(lods));
  }
  _mm_sfence();
  return i;
}

// Each load holds two particles; widened to 32 bits they fill a register
// (x y z lod x y z lod), converted as one; permutes and blends then pack
// eight particles' x,y,z into three registers.
__attribute__((target("avx2"))) size_t streaming_avx2(const uint16_t* q, size_t i, size_t n, const ChunkScale& s, float* xyz,
                                                      uint16_t* lod) {
  const __m256 scale = _mm256_setr_ps(s.step[0], s.step[1], s.step[2], 0, s.step[0], s.step[1], s.step[2], 0);
  const __m256 base = _mm256_setr_ps(s.lo[0], s.lo[1], s.lo[2], 0, s.lo[0], s.lo[1], s.lo[2], 0);
  const __m256i pack0 = _mm256_setr_epi32(0, 1, 2, 4, 5, 6, 0, 0);  // out0 lanes 0-5 from v0
  const __m256i tail1 = _mm256_setr_epi32(0, 0, 0, 0, 0, 0, 0, 1);  // out0 lanes 6-7 from v1
  const __m256i head1 = _mm256_setr_epi32(2, 4, 5, 6, 0, 0, 0, 0);  // out1 lanes 0-3 from v1
  const __m256i tail2 = _mm256_setr_epi32(0, 0, 0, 0, 0, 1, 2, 4);  // out1 lanes 4-7 from v2
  const __m256i head2 = _mm256_setr_epi32(5, 6, 0, 0, 0, 0, 0, 0);  // out2 lanes 0-1 from v2
  const __m256i tail3 = _mm256_setr_epi32(0, 0, 0, 1, 2, 4, 5, 6);  // out2 lanes 2-7 from v3
  const __m128i lod_bytes = _mm_setr_epi8(6, 7, 14, 15, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1);
  for (; i + 8 <= n; i += 8) {
    __m128i r[4];
    __m256 v[4];
    for (int k = 0; k < 4; ++k) {
      r[k] = _mm_loadu_si128(reinterpret_cast<const __m128i*>(q + 4 * i + 8 * k));
      v[k] = _mm256_add_ps(_mm256_mul_ps(_mm256_cvtepi32_ps(_mm256_cvtepu16_epi32(r[k])), scale), base);
    }
    const __m256 out0 = _mm256_blend_ps(_mm256_permutevar8x32_ps(v[0], pack0), _mm256_permutevar8x32_ps(v[1], tail1), 0xC0);
    const __m256 out1 = _mm256_blend_ps(_mm256_permutevar8x32_ps(v[1], head1), _mm256_permutevar8x32_ps(v[2], tail2), 0xF0);
    const __m256 out2 = _mm256_blend_ps(_mm256_permutevar8x32_ps(v[2], head2), _mm256_permutevar8x32_ps(v[3], tail3), 0xFC);
    float* at = xyz + 3 * i;
    _mm_stream_ps(at, _mm256_castps256_ps128(out0));
    _mm_stream_ps(at + 4, _mm256_extractf128_ps(out0, 1));
    _mm_stream_ps(at + 8, _mm256_castps256_ps128(out1));
    _mm_stream_ps(at + 12, _mm256_extractf128_ps(out1, 1));
    _mm_stream_ps(at + 16, _mm256_castps256_ps128(out2));
    _mm_stream_ps(at + 20, _mm256_extractf128_ps(out2, 1));
    // The LOD words (the fourth of each particle) of the four loads, side by side.
    const __m128i lods = _mm_or_si128(
        _mm_or_si128(_mm_shuffle_epi8(r[0], lod_bytes), _mm_slli_si128(_mm_shuffle_epi8(r[1], lod_bytes), 4)),
        _mm_or_si128(_mm_slli_si128(_mm_shuffle_epi8(r[2], lod_bytes), 8), _mm_slli_si128(_mm_shuffle_epi8(r[3], lod_bytes), 12)));
    _mm_stream_si64(reinterpret_cast<long long*>(lod + i), _mm_cvtsi128_si64(lods));
    _mm_stream_si64(reinterpret_cast<long long*>(lod + i + 4), _mm_extract_epi64(lods, 1));
  }
  _mm_sfence();
  return i;
}
#endif

}  // namespace

void dequantize_plain(const uint16_t* q, size_t i, size_t n, const ChunkScale& s, float* xyz, uint16_t* lod) {
  for (; i < n; ++i) {
    xyz[3 * i + 0] = s.lo[0] + float(q[4 * i + 0]) * s.step[0];
    xyz[3 * i + 1] = s.lo[1] + float(q[4 * i + 1]) * s.step[1];
    xyz[3 * i + 2] = s.lo[2] + float(q[4 * i + 2]) * s.step[2];
    lod[i] = q[4 * i + 3];
  }
}

bool streaming_kernel_runs_here(StreamingKernel kernel) {
#if SLUICE_X86_KERNELS
  if (kernel == StreamingKernel::Avx2) return __builtin_cpu_supports("avx2");
  return true;
#else
  (void)kernel;
  return false;
#endif
}

StreamingKernel chosen_streaming_kernel() {
  static const StreamingKernel kernel =
      streaming_kernel_runs_here(StreamingKernel::Avx2) ? StreamingKernel::Avx2 : StreamingKernel::Sse2;
  return kernel;
}

size_t dequantize_streaming(StreamingKernel kernel, const uint16_t* q, size_t i, size_t n, const ChunkScale& s, float* xyz,
                            uint16_t* lod) {
#if SLUICE_X86_KERNELS
  if (kernel == StreamingKernel::Avx2 && streaming_kernel_runs_here(kernel)) i = streaming_avx2(q, i, n, s, xyz, lod);
  return streaming_sse2(q, i, n, s, xyz, lod);  // the last groups of four
#else
  (void)kernel, (void)q, (void)n, (void)s, (void)xyz, (void)lod;
  return i;
#endif
}

size_t dequantize_cached(const uint16_t* q, size_t n, const ChunkScale& s, float* xyz, uint16_t* lod) {
#if SLUICE_X86_KERNELS
  const __m128 scale = _mm_setr_ps(s.step[0], s.step[1], s.step[2], 0.0f);
  const __m128 base = _mm_setr_ps(s.lo[0], s.lo[1], s.lo[2], 0.0f);
  const __m128i zero = _mm_setzero_si128();
  size_t i = 0;
  for (; i + 4 < n; i += 4) {
    const __m128i a = _mm_loadu_si128(reinterpret_cast<const __m128i*>(q + 4 * i));      // particles i, i+1
    const __m128i b = _mm_loadu_si128(reinterpret_cast<const __m128i*>(q + 4 * i + 8));  // particles i+2, i+3
    const __m128i words[4] = {_mm_unpacklo_epi16(a, zero), _mm_unpackhi_epi16(a, zero), _mm_unpacklo_epi16(b, zero),
                              _mm_unpackhi_epi16(b, zero)};
    for (size_t k = 0; k < 4; ++k) {
      const __m128 v = _mm_add_ps(_mm_mul_ps(_mm_cvtepi32_ps(words[k]), scale), base);
      _mm_storeu_ps(xyz + 3 * (i + k), v);  // x, y, z and one float into the next particle's x
      lod[i + k] = q[4 * (i + k) + 3];
    }
  }
  return i;
#else
  (void)q, (void)n, (void)s, (void)xyz, (void)lod;
  return 0;
#endif
}

}  // namespace sluice::io
