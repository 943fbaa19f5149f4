// sluice/render/offscreen.h: an RGBA8 image of sluice's own that a Renderer
// records into and that is read back: the target of `sluice render`, the
// benches and the tests. It is a client of Renderer::record() like any host;
// unlike a host's loop it submits and waits for every frame (a synchronous
// path for batch work, not for a display loop).
//
// Ownership: borrows the Context, which must outlive it. Threads: one thread.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "sluice/render/renderer.h"

namespace sluice::render {

class OffscreenTarget {
 public:
  // `depth`: also a D32 depth image (cleared to the far plane each frame).
  OffscreenTarget(Context& context, uint32_t width, uint32_t height, bool depth = false);
  ~OffscreenTarget();
  OffscreenTarget(const OffscreenTarget&) = delete;
  OffscreenTarget& operator=(const OffscreenTarget&) = delete;

  // Waits for the last frame, then recreates the images.
  void resize(uint32_t width, uint32_t height);
  uint32_t width() const;
  uint32_t height() const;

  // Records `renderer` for one camera over the whole image (or for `views`),
  // submits on the graphics queue and waits; returns that frame's figures.
  FrameStats render(Renderer& renderer, const Camera& camera, const FluidOptions& options, const LodOptions& lod);
  FrameStats render(Renderer& renderer, std::span<const View> views, const FluidOptions& options, const LodOptions& lod,
                    bool background = true);

  // The last rendered image: width*height RGBA8, top row first.
  std::vector<uint8_t> read_rgba8();

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace sluice::render
