// sluice/render/offscreen.h: an RGBA8 image of sluice's own that a Renderer
// records into and that is read back: the target of `sluice render`, headless
// GPU playback, the benches and the tests. It is a client of
// Renderer::record() like any host. With one frame in flight (the default)
// render() submits and waits, so the image and the figures it returns are
// that frame's; with more, it waits only for the frame that used the same
// slot (the renderer's contract) and returns the newest figures that are back.
//
// Ownership: borrows the Context, which must outlive it. Threads: one thread.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "sluice/render/renderer.h"

namespace sluice::render {

struct OffscreenOptions {
  uint32_t frames_in_flight = 1;  // at most the renderer's
  bool depth = false;             // also a D32 depth image, cleared to the far plane each frame
  // The depth image allows transfers and sampling (RenderTarget::
  // depth_transfer, depth_sampled): the shading pass tests and writes it.
  // Off: the present pass does (the path of hosts whose depth images allow
  // neither).
  bool depth_transfer = true;
  // Each frame starts from the depth the last one left (as a host's depth
  // image holds its own geometry), instead of UNDEFINED: the shading pass
  // then reads the host's depth in place before writing it back.
  bool keep_depth = false;
  bool read_back = true;          // copy each frame out for read_rgba8() (layer 0)
  // 2: an image of two layers drawn as a stereo pair in one pass
  // (RenderTarget::layer_count); render() then takes two views.
  uint32_t layers = 1;
};

namespace detail {
struct OffscreenTargetImpl;  // defined in render/src, seen by no caller
}  // namespace detail

class OffscreenTarget {
 public:
  OffscreenTarget(Context& context, uint32_t width, uint32_t height, const OffscreenOptions& options = {});
  ~OffscreenTarget();
  OffscreenTarget(const OffscreenTarget&) = delete;
  OffscreenTarget& operator=(const OffscreenTarget&) = delete;

  // Waits for the frames in flight, then recreates the images.
  void resize(uint32_t width, uint32_t height);
  uint32_t width() const;
  uint32_t height() const;

  // Records `renderer` for one camera over the whole image (or for `views`),
  // submits on the graphics queue and waits; returns that frame's figures.
  FrameStats render(Renderer& renderer, const Camera& camera, const FluidOptions& options, const LodOptions& lod);
  FrameStats render(Renderer& renderer, std::span<const View> views, const FluidOptions& options, const LodOptions& lod,
                    bool background = true);

  // Waits for the frames in flight.
  void finish();
  // The last rendered image (waits for it): width*height RGBA8, top row first.
  std::vector<uint8_t> read_rgba8();


 private:
  using Impl = detail::OffscreenTargetImpl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sluice::render
