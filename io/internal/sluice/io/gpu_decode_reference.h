// sluice/io/gpu_decode_reference.h (internal to io: its tests and the fuzz
// targets): the CPU's reference for what the GPU decodes from a plan.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "sluice/io/gpu_decode_plan.h"

namespace sluice::io {

// The CPU's reference for what the GPU decodes from a plan: particles
// (8 bytes each) and the colour attribute, bit for bit what decode_chunk
// writes. For tests of the plan and the kernels.
void decode_plan_on_cpu(std::span<const std::byte> encoded, const GpuDecodePlan& plan, std::span<uint64_t> particles,
                        std::span<uint16_t> attribute);

}  // namespace sluice::io
