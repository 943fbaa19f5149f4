// Layout of a packed plane of n values at width b (1..7), escape code
// e = 2^b - 1:
//   u8 b;
//   ceil(n / 8) groups of b bytes: values 8g .. 8g+7, value j at bits
//     [j*b, (j+1)*b) of the group read as a little-endian integer; a value
//     below e is itself, e means "the next escape"; padding values are 0;
//   the escapes: one byte per value >= e, in plane order.
// Groups of 8 values fill whole bytes, so a group is one unaligned load and
// one PDEP into 8 bytes.
#include "packed_plane.h"

#include "quantized_unpack.h"

#include <algorithm>
#include <array>
#include <cstring>
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#define SLUICE_X86_KERNELS 1
#endif

namespace sluice::io {
namespace {

size_t groups_of(size_t n) { return (n + 7) / 8; }

// The low `width` bits of every byte.
uint64_t byte_mask(int width) { return 0x0101010101010101ull * ((1u << width) - 1); }

// Spreads the 8 * width low bits of `bits` into 8 bytes of `width` bits each.
inline uint64_t spread_portable(uint64_t bits, int width) {
  uint64_t out = 0;
  const uint64_t mask = (1u << width) - 1;
  for (int j = 0; j < 8; ++j) out |= ((bits >> (j * width)) & mask) << (8 * j);
  return out;
}

// Group g's bits (only the low 8 * width are used); the last groups may end
// within 8 bytes of the packed area's end, so they are copied out rather
// than loaded past it.
inline uint64_t load_group(const uint8_t* packed, size_t packed_bytes, size_t g, int width) {
  uint64_t bits = 0;
  const size_t at = g * size_t(width);
  std::memcpy(&bits, packed + at, std::min<size_t>(8, packed_bytes - at));
  return bits;
}

// The groups whose 8 bytes can be loaded before the packed area ends and
// whose 8 values all lie in dst; the rest go through spread_tail.
size_t direct_groups(size_t n, int width) {
  const size_t packed_bytes = groups_of(n) * size_t(width);
  return packed_bytes >= 8 ? std::min(n / 8, (packed_bytes - 8) / size_t(width) + 1) : 0;
}

void spread_tail(const uint8_t* packed, size_t n, int width, uint8_t* dst, size_t g) {
  const size_t groups = groups_of(n), packed_bytes = groups * size_t(width);
  for (; g < groups; ++g) {
    const uint64_t bytes = spread_portable(load_group(packed, packed_bytes, g, width), width);
    std::memcpy(dst + 8 * g, &bytes, std::min<size_t>(8, n - 8 * g));
  }
}

void spread_groups_portable(const uint8_t* packed, size_t n, int width, uint8_t* dst) {
  const size_t direct = direct_groups(n, width);
  for (size_t g = 0; g < direct; ++g) {
    uint64_t bits;
    std::memcpy(&bits, packed + g * size_t(width), 8);
    const uint64_t bytes = spread_portable(bits, width);  // reads only the low 8 * width bits
    std::memcpy(dst + 8 * g, &bytes, 8);
  }
  spread_tail(packed, n, width, dst, direct);
}

#if SLUICE_X86_KERNELS
__attribute__((target("bmi2"))) void spread_groups_bmi2(const uint8_t* packed, size_t n, int width, uint8_t* dst) {
  const size_t direct = direct_groups(n, width);
  const uint64_t mask = byte_mask(width);  // PDEP ignores the bits above 8 * width
  for (size_t g = 0; g < direct; ++g) {
    uint64_t bits;
    std::memcpy(&bits, packed + g * size_t(width), 8);
    const uint64_t bytes = _pdep_u64(bits, mask);
    std::memcpy(dst + 8 * g, &bytes, 8);
  }
  spread_tail(packed, n, width, dst, direct);
}
const bool kFastPdep = fast_pext();  // PDEP is as fast as PEXT (slow on AMD Zen 1/2)
#endif

// Replaces each escape code in dst[0..n) by the next escape byte. Returns
// how many escape codes there were (the caller checks it against the list),
// never reading more than `count` escape bytes. Branch-free per value:
// escapes are common (a tenth of the values) and unpredictable.
size_t patch_escapes_from(uint8_t* dst, size_t begin, size_t n, uint8_t code, const uint8_t* escapes, size_t count,
                          size_t k) {
  for (size_t i = begin; i < n; ++i) {
    const bool hit = dst[i] == code;
    const uint8_t replacement = k < count ? escapes[k] : code;
    dst[i] = hit ? replacement : dst[i];
    k += hit;
  }
  return k;
}

#if SLUICE_X86_KERNELS
// 32 values at a time: a compare, a mask, and one store per escape found.
__attribute__((target("avx2,bmi"))) size_t patch_escapes_avx2(uint8_t* dst, size_t n, uint8_t code,
                                                              const uint8_t* escapes, size_t count) {
  const __m256i codes = _mm256_set1_epi8(static_cast<char>(code));
  size_t k = 0, i = 0;
  for (; i + 32 <= n; i += 32) {
    const __m256i v = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(dst + i));
    auto hits = static_cast<uint32_t>(_mm256_movemask_epi8(_mm256_cmpeq_epi8(v, codes)));
    const auto found = size_t(__builtin_popcount(hits));
    if (k + found > count) return k + found;  // more escape codes than escapes: corrupt, stop here
    for (; hits != 0; hits = _blsr_u32(hits)) dst[i + _tzcnt_u32(hits)] = escapes[k++];
  }
  return patch_escapes_from(dst, i, n, code, escapes, count, k);
}
const bool kHaveAvx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("bmi");
#endif

}  // namespace

PackedPlan plan_packed_plane(std::span<const uint8_t> plane) {
  std::array<size_t, 256> histogram{};
  for (uint8_t v : plane) ++histogram[v];
  PackedPlan best;
  for (int width = 1; width <= kMaxPackedWidth; ++width) {
    const size_t code = (1u << width) - 1;
    size_t escapes = 0;
    for (size_t v = code; v < 256; ++v) escapes += histogram[v];
    const size_t bytes = 1 + groups_of(plane.size()) * size_t(width) + escapes;
    if (best.width == 0 || bytes < best.bytes) best = {width, bytes};
  }
  return best;
}

void pack_plane(std::span<const uint8_t> plane, int width, std::vector<std::byte>& out) {
  const uint8_t code = uint8_t((1u << width) - 1);
  const size_t n = plane.size(), groups = groups_of(n);
  out.push_back(std::byte(width));
  std::vector<std::byte> escapes;
  for (size_t g = 0; g < groups; ++g) {
    uint64_t bits = 0;
    for (size_t j = 0; j < 8 && 8 * g + j < n; ++j) {
      const uint8_t v = plane[8 * g + j];
      if (v >= code) escapes.push_back(std::byte(v));
      bits |= uint64_t(std::min(v, code)) << (j * size_t(width));
    }
    for (int b = 0; b < width; ++b) out.push_back(std::byte(uint8_t(bits >> (8 * b))));
  }
  out.insert(out.end(), escapes.begin(), escapes.end());
}

namespace {

void unpack_with(std::span<const std::byte> payload, size_t n, uint8_t* dst, const ErrorLocation& where,
                 const std::string& what, bool portable) {
  if (payload.empty()) throw Error(where, what + ": packed plane is empty");
  const int width = int(payload[0]);
  if (width < 1 || width > kMaxPackedWidth) throw Error(where, what + ": packed width " + std::to_string(width) + " is not 1..7");
  const size_t packed_bytes = groups_of(n) * size_t(width);
  if (payload.size() - 1 < packed_bytes) throw Error(where, what + ": packed plane is shorter than its values");
  const auto* packed = reinterpret_cast<const uint8_t*>(payload.data() + 1);
  const size_t count = payload.size() - 1 - packed_bytes;
  const auto code = uint8_t((1u << width) - 1);
  size_t found = 0;
#if SLUICE_X86_KERNELS
  if (!portable && kFastPdep) spread_groups_bmi2(packed, n, width, dst);
  else spread_groups_portable(packed, n, width, dst);
  if (!portable && kHaveAvx2) found = patch_escapes_avx2(dst, n, code, packed + packed_bytes, count);
  else found = patch_escapes_from(dst, 0, n, code, packed + packed_bytes, count, 0);
#else
  spread_groups_portable(packed, n, width, dst);
  found = patch_escapes_from(dst, 0, n, code, packed + packed_bytes, count, 0);
#endif
  if (found != count) {
    throw Error(where, what + ": packed plane has " + std::to_string(found) + " escape codes but stores " +
                           std::to_string(count) + " escapes");
  }
}

}  // namespace

void unpack_plane(std::span<const std::byte> payload, size_t n, uint8_t* dst, const ErrorLocation& where,
                  const std::string& what) {
  unpack_with(payload, n, dst, where, what, false);
}

void unpack_plane_portable(std::span<const std::byte> payload, size_t n, uint8_t* dst, const ErrorLocation& where,
                           const std::string& what) {
  unpack_with(payload, n, dst, where, what, true);
}

}  // namespace sluice::io
