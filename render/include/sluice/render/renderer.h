// sluice/render/renderer.h: frames of particles in, the fluid recorded into
// the caller's command buffer and images.
//
// Passes (docs/render.md), per view: chunk frustum cull -> per-particle
// cull/cLOD and compaction into a draw list (compute, indirect args) ->
// sphere depth and additive thickness (compute splatting or point sprites)
// -> depth filter (narrow-range or bilateral) -> thickness filter ->
// normals, shading and background (compute) -> present: the shaded fluid
// drawn into the caller's colour image, depth-tested against and written to
// the caller's depth image. Every pass has a GPU timestamp.
//
// The frame loop (docs/embedding.md has the whole host loop; stream::Stream
// does all of it for a file or pushed frames):
//   a frame in, two ways, when a new one is due:
//     stage_frame() + commit_frame()   particles the caller writes (live frames)
//     commit(FrameUpload)              a frame read from a file (render/frame.h;
//                                      frame_upload() makes one of a frame the
//                                      streaming runtime delivered)
//   record(cmd, target, views, ...)                       once per displayed frame
//   the caller submits cmd, waiting on record()'s FrameSync semaphore
//
// Frames in flight: the renderer keeps `frames_in_flight` sets of per-frame
// resources. Contract: when record() is called for the n-th time, the
// command buffer of the (n - frames_in_flight)-th call has finished
// executing on the GPU (or was never submitted); a host that waits on its
// per-frame fence before reusing a frame slot gives this for free. Nothing on
// the per-frame path waits for the GPU: no fence, no queue or device idle.
//
// Uploads: commit_frame() and commit() copy a frame on the transfer queue (the graphics queue
// where the device has none) into one of frames_in_flight + 1 device frame
// buffers and return at once. record() draws the newest committed frame
// whose copy has finished (checked without waiting), so a frame is shown
// only once it is complete, and the next frame's copy overlaps the current
// frame's rendering.
//
// Ownership: a Renderer belongs to one Context, which must outlive it.
// Threads: one thread calls the members; FrameStaging spans may be filled
// from any threads between stage_frame() and commit_frame().
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "sluice/render/camera.h"
#include "sluice/render/context.h"
#include "sluice/render/draw.h"
#include "sluice/render/frame.h"
#include "sluice/render/image_io.h"
#include "sluice/render/options.h"

namespace sluice::render {

namespace detail {
struct RendererImpl;  // defined in render/src, seen by no caller
}  // namespace detail

class Renderer {
 public:
  Renderer(Context& context, const SceneInfo& scene, const RendererOptions& options = {});
  // Waits for the renderer's own uploads, then for the queues it uploaded
  // on (the transfer queue; the graphics queue too once it decoded a frame)
  // to go idle: no other thread may use those queues meanwhile. Frames the
  // host submitted are the host's to finish first.
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // The environment reflected and seen behind the fluid: an equirectangular
  // image (sRGB; u = azimuth around the scene's up axis, v = 0 straight up),
  // or an empty Image for the procedural sky. A setting, not a per-frame
  // call: submits the image's upload to the graphics queue and waits for
  // that submission (not for the device).
  void set_environment(const Image& equirect);
  const SceneInfo& scene() const;
  const RendererOptions& options() const;

  // Staging memory for a frame of `particles` in `chunks` chunks. Fill it,
  // then commit_frame(). May wait for this renderer's own earlier copy out of
  // the same buffer (never for rendering).
  FrameStaging stage_frame(uint64_t particles, uint32_t chunks);
  // Submits the copy of the staged frame to device memory; returns its
  // upload ticket (see upload_complete()).
  uint64_t commit_frame();
  // Submits a frame read from a file (FrameUpload: borrowed for the call;
  // its bytes stay untouched until upload_complete() of the ticket). A
  // decoded frame: its copy, and its colour when it has one. An encoded
  // frame (FrameUpload::plan): its copy and its decode on the GPU
  // (shaders/decode.comp), a compute submission to the graphics queue that
  // waits for the copy; a resident one (FrameUpload::Resident) is already in
  // device memory: only its tables are copied, and the decode waits for its
  // semaphore too. That is the one queue submission the renderer makes per
  // frame on its own: the host must not use the graphics queue from another
  // thread meanwhile. Bytes in one of the Context's Vulkan buffers
  // (UploadBytes::buffer) are copied by the GPU from there; others through
  // the renderer's staging. Returns the ticket (the decode's, for an
  // encoded frame). Throws render::Error for a frame the scene cannot take.
  uint64_t commit(const FrameUpload& frame);
  // Whether the copy with this ticket has finished (no wait).
  bool upload_complete(uint64_t ticket) const;
  // Waits for the copy with this ticket (the transfer queue only).
  void wait_upload(uint64_t ticket) const;

  // Records the fluid for `views` (1..4, all the same size; 2 for a 2-layer
  // target, see RenderTarget::layer_count) into `cmd`, a
  // primary command buffer in the recording state, outside a render pass, of
  // the graphics family. The caller submits it (with FrameSync's wait).
  // Particles get the radius options.particle_radius (0: scene spacing).
  FrameSync record(VkCommandBuffer cmd, const RenderTarget& target, std::span<const View> views,
                   const FluidOptions& options, const LodOptions& lod);
  // The figures of the newest recorded frame whose GPU results are back
  // (frames_in_flight frames behind in a running loop, the last one after
  // the host waited for it). Never waits and never calls into the driver:
  // the GPU copies each frame's timestamps and counters into mapped memory
  // at its end, and this reads them there.
  FrameStats last_stats();

 private:
  using Impl = detail::RendererImpl;      // render/src/renderer_state.h
  friend Impl& renderer_impl(Renderer&);  // for render/src only (inspection.cpp)
  std::unique_ptr<Impl> impl_;
};

}  // namespace sluice::render
