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

// Which of the renderer's two kinds of staging memory a copy reads: Plain
// (write-combined where the driver offers it) for frames decoded on the
// CPU, Cached for frames kept encoded, whose checksums the CPU computes.
enum class StagingMemory { Plain, Cached };

// How the copies are made: `in_flight` copies queued on the transfer queue
// at a time (the pipeline keeps two frames in flight), kept queued for at
// least `seconds` (and two rounds) after one warm-up round.
struct CopyShape {
  int in_flight = 2;
  StagingMemory staging = StagingMemory::Cached;
  double seconds = 0.3;
};

// Copies of `bytes` each from persistently mapped staging into device-local
// memory (one target per copy in flight: `in_flight` x `bytes` of device
// memory), made as `shape` says; GB/s sustained over the timed stretch
// (first submission to the last fence waited). Blocks for the stretch.
double host_to_device_gbps(Context& context, uint64_t bytes, const CopyShape& shape);

// The same copy from `bytes` at `host` imported as memory the device reads
// (VK_EXT_external_memory_host, host allocation): with `host` a read-only
// mmap of a file, the GPU would copy its page-cache pages with no CPU copy.
// `host` and `bytes` must be multiples of the device's
// minImportedHostPointerAlignment (import_alignment()); the memory must stay
// mapped for the call. Whether the driver accepts it is the first answer.
struct ImportedCopy {
  bool imported = false;  // the driver accepted the import
  std::string refusal;    // otherwise why (no extension, alignment, the driver's error)
  double gbps = 0;        // sustained, as host_to_device_gbps (shape.staging does not apply)
};
ImportedCopy imported_host_copy_gbps(Context& context, const void* host, uint64_t bytes, const CopyShape& shape);
// minImportedHostPointerAlignment; 0 when the context has no
// VK_EXT_external_memory_host (only contexts sluice creates enable it).
uint64_t import_alignment(Context& context);

}  // namespace sluice::render
