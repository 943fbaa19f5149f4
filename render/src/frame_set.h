// Internal: one device copy of a frame (the renderer keeps frames_in_flight
// + 1 of them): its buffers, its copy and decode, what the GPU made of it.
#pragma once

#include <cstdint>

#include "vk_common.h"

namespace sluice::render {

// One device copy of a frame: what the cull and the passes read.
struct FrameSet {
  Buffer particles, chunks, attributes;
  Buffer staging;  // the renderer's own staging for this set
  vk::raii::CommandBuffer copy{nullptr};
  vk::raii::QueryPool stamps{nullptr};  // start and end of the copy
  uint64_t particle_count = 0;
  uint32_t chunk_count = 0;
  bool has_attribute = false;
  uint64_t ticket = 0;               // timeline value its copy signals; 0: never filled
  uint64_t last_drawn = UINT64_MAX;  // record() call that last drew it; UINT64_MAX: never
  double upload_ms = -1;             // read once the copy is done
  // Frames without layers, with RendererOptions::classify_unlayered:
  bool unlayered = false;       // every chunk io::Layer::All (or staged without blob rows)
  bool layering_known = false;  // `unlayered` came from the io headers
  bool band_eligible = false;   // uploaded with room for blobs: to be classified when first drawn
  bool classified = false;      // its classification is recorded: draw surface + blobs
  Buffer surface;               // frame_band.h: validity word, a bit per particle
  // With RendererOptions::anisotropic: each particle's ellipsoid, computed when first drawn.
  bool shape_eligible = false;  // sized for them
  bool shaped = false;          // their computation is recorded
  Buffer shapes;                // frame_band.h (shapes_bytes): validity word, 3 words per particle
  // Frames committed encoded (commit_encoded): the staged area, the decode's
  // error words (host-visible), its command buffer and timestamps.
  Buffer encoded, decode_errors, decode_tiles;
  vk::raii::CommandBuffer decode{nullptr};
  vk::raii::QueryPool decode_stamps{nullptr};
  bool decoded_on_gpu = false;
  double decode_ms = -1;  // read once the decode is done
  uint32_t decode_errors_found = 0;
};

}  // namespace sluice::render
