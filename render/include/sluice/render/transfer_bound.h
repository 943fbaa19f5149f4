// sluice/render/transfer_bound.h: the host-to-device copy bandwidth, the
// bound a benchmark of frames arriving in GPU memory prints beside its
// figure (the other being how fast the file is read).
//
// Threads: submits to the context's transfer queue and waits; must not
// overlap another thread's use of that queue.
#pragma once

#include <cstdint>
#include <string>

#include "sluice/render/context.h"

namespace sluice::render {

// `bytes` of persistently mapped staging memory (the kind the renderer's
// uploads copy from) copied into device-local memory on the transfer
// queue, `repeats` times after one warm-up copy; GB/s of the median copy
// (wall clock from submission to the fence).
double host_to_device_gbps(Context& context, uint64_t bytes, int repeats);

// The same copy from `bytes` at `host` imported as memory the device reads
// (VK_EXT_external_memory_host, host allocation): with `host` a read-only
// mmap of a file, the GPU would copy its page-cache pages with no CPU copy.
// `host` and `bytes` must be multiples of the device's
// minImportedHostPointerAlignment (import_alignment()); the memory must stay
// mapped for the call. Whether the driver accepts it is the first answer.
struct ImportedCopy {
  bool imported = false;  // the driver accepted the import
  std::string refusal;    // otherwise why (no extension, alignment, the driver's error)
  double gbps = 0;        // median copy, as host_to_device_gbps
};
ImportedCopy imported_host_copy_gbps(Context& context, const void* host, uint64_t bytes, int repeats);
// minImportedHostPointerAlignment; 0 when the context has no
// VK_EXT_external_memory_host (only contexts sluice creates enable it).
uint64_t import_alignment(Context& context);

}  // namespace sluice::render
