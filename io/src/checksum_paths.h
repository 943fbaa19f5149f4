// XXH3-64 compiled for one instruction set each (checksum.cpp picks one at
// run time). Call a path only where the CPU has its instructions.
#pragma once

#include <cstddef>
#include <cstdint>

#include "sluice/io/reader.h"

namespace sluice::io::detail {

uint64_t xxh3_baseline(const void* data, size_t n);  // SSE2: every x86-64
uint64_t xxh3_avx2(const void* data, size_t n);      // built with -mavx2
uint64_t xxh3_avx512(const void* data, size_t n);    // built with -mavx512f -mavx512bw

// copy_and_checksum() (sluice/io/reader.h) on each path: XXH3's streaming
// state fed block by block.
uint64_t xxh3_copy_baseline(std::byte* dst, const std::byte* src, size_t n, BlockCopy copy, void* context);
uint64_t xxh3_copy_avx2(std::byte* dst, const std::byte* src, size_t n, BlockCopy copy, void* context);
uint64_t xxh3_copy_avx512(std::byte* dst, const std::byte* src, size_t n, BlockCopy copy, void* context);

}  // namespace sluice::io::detail
