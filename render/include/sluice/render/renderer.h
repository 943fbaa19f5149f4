// sluice/render/renderer.h: one frame of particles in, one shaded image out.
//
// Pipeline (docs/render.md): chunk frustum cull -> per-particle cull/cLOD and
// compaction into a draw list (compute, indirect args) -> sphere impostors
// with exact per-pixel depth -> additive thickness -> depth filter
// (narrow-range or bilateral) -> thickness filter -> normals, shading and
// background (compute) -> RGBA8 image. Every pass has a GPU timestamp.
//
// Ownership: a Renderer belongs to one Context, which must outlive it.
// Threads: one thread calls the members; FrameStaging spans may be filled
// from any threads between stage_frame() and commit_frame().
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "sluice/render/camera.h"
#include "sluice/render/context.h"
#include "sluice/render/frame.h"
#include "sluice/render/image_io.h"
#include "sluice/render/options.h"
#include "sluice/render/staging_allocator.h"

namespace sluice::render {

struct PassTime {
  std::string name;  // "cull", "depth", "thickness", "filter", "shade", ...
  double ms = 0;     // GPU time from timestamps
};

struct FrameStats {
  uint64_t particles = 0;      // in the frame
  uint64_t drawn = 0;          // after frustum, near and LOD culling
  uint64_t visible_chunks = 0;
  std::vector<PassTime> passes;
  double gpu_ms = 0;           // first to last timestamp of the frame
  double upload_ms = 0;        // GPU time of the last commit_frame() copy
};

// A decoded frame as the runtime hands it over (runtime::FrameHandle has
// every field). Borrowed for the call.
struct DecodedFrameView {
  const io::FrameHeader* header = nullptr;       // chunk table: counts, AABBs, attribute ranges
  std::span<const uint64_t> chunk_first;         // first particle of each chunk
  const runtime::FrameBuffers* buffers = nullptr;
  int color_stream = -1;     // index into buffers->attributes of the colour attribute; -1: none
  int color_attribute = -1;  // that attribute's index in the file header (for the chunk ranges)
};

class Renderer {
 public:
  // `width` x `height` is the output image size in pixels.
  Renderer(Context& context, const SceneInfo& scene, uint32_t width, uint32_t height);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  void resize(uint32_t width, uint32_t height);
  // The environment reflected and seen behind the fluid: an equirectangular
  // image (sRGB; u = azimuth around the scene's up axis, v = 0 straight up),
  // or an empty Image for the procedural sky. Waits for the GPU.
  void set_environment(const Image& equirect);
  uint32_t width() const;
  uint32_t height() const;
  const SceneInfo& scene() const;

  // Staging memory for a frame of `particles` in `chunks` chunks (buffers
  // grow as needed; that waits for the GPU). Fill it, then commit_frame().
  FrameStaging stage_frame(uint64_t particles, uint32_t chunks);
  // Copies the staged frame to device memory (on the transfer queue where the
  // device has one; the next render() waits on a timeline semaphore).
  void commit_frame();
  // Uploads a frame the streaming runtime decoded. With `from` (the
  // StagingAllocator that handed out frame.buffers, of this renderer's
  // Context) the GPU copies straight from those buffers; otherwise they are
  // copied through the renderer's staging. The buffers may be reused once
  // this returns.
  void commit_decoded(const DecodedFrameView& frame, const StagingAllocator* from);
  // Reads and decodes `frame` straight into staging (chunks in parallel) and
  // commits it. `color_attribute` < 0 skips attributes.
  void load_frame(const io::ContainerReader& reader, uint64_t frame, int color_attribute);

  // Renders the committed frame and waits for the GPU. Particles get the
  // radius options.particle_radius (0: scene spacing).
  FrameStats render(const Camera& camera, const FluidOptions& options, const LodOptions& lod);

  // The last rendered image: width*height RGBA8, top row first.
  std::vector<uint8_t> read_rgba8();
  // For tests: per pixel (eye-space normal x,y,z, linear depth) of the last
  // render, after filtering; depth 0 where there is no fluid.
  std::vector<float> read_surface();
  // For tests: the unfiltered linear depth (distance along the view axis).
  std::vector<float> read_raw_depth();

  struct Impl;
  Impl& impl() { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

// Effective sphere radius for `options` in `scene`.
float effective_radius(const FluidOptions& options, const SceneInfo& scene);

}  // namespace sluice::render
