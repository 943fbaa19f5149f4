// Internal: what upload.cpp and load.cpp share of a frame's way in.
#pragma once

#include <cstdint>
#include <span>

#include "frame_set.h"
#include "sluice/error.h"
#include "sluice/io/format.h"
#include "sluice/render/frame.h"

namespace sluice::render {

// Whether the frame's chunks carry layers (for RendererOptions::classify_unlayered).
void mark_layers(FrameSet& set, const io::FrameHeader& header);

// The chunk table rows of a frame: AABBs, first particle, count and the
// colour attribute's range (`color_attribute` < 0: none). `first`, when given
// (the runtime's chunk_first), must agree with the running sum of the counts.
void fill_chunk_table(const io::FrameHeader& header, std::span<const uint64_t> first, int color_attribute,
                      std::span<GpuChunk> out, const io::ErrorLocation& where);

}  // namespace sluice::render
