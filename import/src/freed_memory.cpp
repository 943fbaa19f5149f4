// glibc's malloc thresholds, raised for the life of a KeepFreedMemory.
#include "sluice/import/freed_memory.h"

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace sluice::import {


KeepFreedMemory::KeepFreedMemory(size_t bytes) {
#if defined(__GLIBC__)
  const int most = bytes > (size_t(1) << 30) ? (1 << 30) : static_cast<int>(bytes);
  // Blocks below the mmap threshold (glibc allows 32 MiB at most) come from
  // the heap, which is trimmed only above the trim threshold.
  mallopt(M_MMAP_THRESHOLD, most / 4 < (32 << 20) ? most / 4 : (32 << 20));
  mallopt(M_TRIM_THRESHOLD, most);
#else
  (void)bytes;
#endif
}

KeepFreedMemory::~KeepFreedMemory() {
#if defined(__GLIBC__)
  mallopt(M_MMAP_THRESHOLD, 128 * 1024);  // glibc's defaults
  mallopt(M_TRIM_THRESHOLD, 128 * 1024);
  malloc_trim(0);
#endif
}

}  // namespace sluice::import
