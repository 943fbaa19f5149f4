// Internal: one function per pass of a frame, recorded into the caller's
// command buffer. record() (renderer.cpp) calls them in order for each view:
// cull -> splat | raster_spheres -> filters -> shade -> present.
#pragma once

#include <vector>

#include "renderer_state.h"

namespace sluice::render {

// How the shaded fluid reaches the caller's images.
enum class Output {
  Direct,          // the shading pass writes the colour image (storage, no depth image)
  DepthInShading,  // the shading pass also tests and writes the host's depth, copied out and back (RenderTarget::depth_transfer)
  Present,         // into sluice's image, then a full-viewport raster pass with the depth test
};
// The cheapest of the three `target` allows.
Output output_path(const RenderTarget& target);
// Output::DepthInShading with a sampled depth image that holds the host's
// depth: the shading pass reads it in place instead of a copy out.
bool reads_host_depth_in_place(const RenderTarget& target, Output output);

class PassRecorder {
 public:
  PassRecorder(detail::RendererImpl& r, vk::CommandBuffer cmd, FrameSlot& slot, uint32_t slot_index);

  // Orders the frame after everything before it on the queue, initializes
  // new targets, moves the caller's images to attachment layouts.
  // Direct and DepthInShading: shading writes the caller's colour image
  // (GENERAL layout); DepthInShading: the depth image is in GENERAL too.
  void begin_frame(const RenderTarget& target, Output output);
  // Binds the view's uniforms (dynamic offset: a Globals per eye) and the
  // frame's buffers; `layers` eyes are drawn by the passes that follow.
  void begin_view(uint32_t globals_offset, const FrameSet* frame, uint32_t layers);
  // A frame first drawn: its narrow band on the GPU if it came without
  // layers, its particles' ellipsoids if anisotropic (frame_band.h), once;
  // the views then draw its surface and blobs, and the ellipsoids.
  void prepare(FrameSet& frame);
  void cull();                          // chunks -> blocks -> particles -> draw list
  void splat();                         // compute splatting of depth and thickness, then resolve
  void raster_spheres();                // point sprites: exact depth, additive thickness
  void filters(const FluidOptions& o);  // depth, then thickness (separable, ping-pong)
  // Normals, shading, background (compute), into binding 9 at `origin`;
  // `fluid_only`: pixels without fluid are left alone.
  void shade(const Viewport& origin, bool fluid_only);
  // Output::DepthInShading: the view's region of the host's depth copied
  // out (an UNDEFINED depth image: the far plane; `first`, where the views
  // do not tile the image, it is cleared), shading that tests the fluid
  // against it as the present pass would and writes colour and depth, and
  // the depth copied back.
  void shade_with_host_depth(const RenderTarget& target, const View& view, bool first, bool views_tile);
  // The shaded view into the caller's images; `first` view of the frame
  // clears what the target's UNDEFINED layouts discard.
  void present(const RenderTarget& target, const View& view, bool first);
  // Counters back to the host; the caller's images to their after layouts.
  void end_frame(const RenderTarget& target, Output output);

 private:
  void present_layer(const RenderTarget& target, VkImageView color, VkImageView depth, const View& view, bool first,
                     uint32_t eye);
  void stamp(const char* name);
  void push(uint32_t p0 = 0, uint32_t p1 = 0, uint32_t p2 = 0);
  void compute_to_compute();
  void separable(const vk::raii::Pipeline& pipeline, vk::Extent2D size, int iterations);

  detail::RendererImpl& r_;
  vk::CommandBuffer cmd_;
  FrameSlot& slot_;
  uint32_t first_stamp_;
  PushConstants pc_{};
  bool have_frame_ = false;
  uint32_t layers_ = 1;  // eyes drawn at once: the screen-space passes' dispatch z, the raster passes' views
};

}  // namespace sluice::render
