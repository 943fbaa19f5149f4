// XXH3-64 compiled for one instruction set each (checksum.cpp picks one at
// run time). Call a path only where the CPU has its instructions.
#pragma once

#include <cstddef>
#include <cstdint>

namespace sluice::io::detail {

uint64_t xxh3_baseline(const void* data, size_t n);  // SSE2: every x86-64
uint64_t xxh3_avx2(const void* data, size_t n);      // built with -mavx2
uint64_t xxh3_avx512(const void* data, size_t n);    // built with -mavx512f -mavx512bw

}  // namespace sluice::io::detail
