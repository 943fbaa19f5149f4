// sluice/render/transfer_bound.h: the host-to-device copy bandwidth, the
// bound a benchmark of frames arriving in GPU memory prints beside its
// figure (the other being how fast the file is read).
//
// Threads: submits to the context's transfer queue and waits; must not
// overlap another thread's use of that queue.
#pragma once

#include <cstdint>

#include "sluice/render/context.h"

namespace sluice::render {

// `bytes` of persistently mapped staging memory (the kind the renderer's
// uploads copy from) copied into device-local memory on the transfer
// queue, `repeats` times after one warm-up copy; GB/s of the median copy
// (wall clock from submission to the fence).
double host_to_device_gbps(Context& context, uint64_t bytes, int repeats);

}  // namespace sluice::render
