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

#include "sluice/io/error.h"
#include "sluice/io/gpu_decode_plan.h"
#include "sluice/render/camera.h"
#include "sluice/render/context.h"
#include "sluice/render/frame.h"
#include "sluice/render/image_io.h"
#include "sluice/render/options.h"


namespace sluice::render {

struct PassTime {
  std::string name;  // "cull", "splat", "resolve", "filter", "shade", "present", ...
  double ms = 0;     // GPU time from timestamps, summed over the frame's views
};

struct FrameStats {
  uint64_t record_index = 0;   // which record() call (0-based) these figures are of (not a frame number)
  uint64_t particles = 0;      // in the frame drawn
  uint64_t drawn = 0;          // after frustum, near and LOD culling (the last view)
  uint64_t visible_chunks = 0; // the last view
  std::vector<PassTime> passes;
  double gpu_ms = 0;           // first to last timestamp of the frame
  double upload_ms = 0;        // GPU time of the copy of the frame drawn
  bool decoded_on_gpu = false; // the frame drawn was committed encoded (Renderer::commit of a frame kept encoded)
  double decode_ms = 0;        // GPU time of its decode (0 when not decoded on the GPU, or no timestamps)
  uint32_t decode_errors = 0;  // its chunks whose packed planes the GPU found inconsistent
  // RendererOptions::classify_unlayered: what the classification this frame
  // ran (if it ran one: the first draw of a frame without layers) made of it.
  struct Classification {
    bool ran = false;
    bool narrowed = false;       // drawn from surface + blobs; false: drawn whole
    uint64_t surface = 0;        // particles kept (L1 + L2 + isolated)
    uint64_t blobs = 0;          // voxel blobs (drawn only when narrowed: at most blob_room)
    uint64_t blob_room = 0;      // blobs the frame had room for
    uint32_t cells[3] = {};      // the voxel grid; 2^32 cells or more cannot be classified
    bool grid_fits = false;
  } classification;
};

// For logs and the HUD: "classified on the GPU: 5,012 surface + 1,190 blobs"
// or why the frame was drawn whole; "" when no classification ran.
std::string describe(const FrameStats::Classification& c);

// A rectangle of the target in pixels (origin top left).
struct Viewport {
  uint32_t x = 0, y = 0;
  uint32_t width = 0, height = 0;
};

// One eye or camera. Matrices are column-major (math.h).
//  - view: world -> eye space (right-handed, looking down -z, +y up).
//  - projection: eye -> Vulkan clip space (x right, y down, depth 0..1) as
//    the host's own rasterizer uses it; asymmetric frusta (OpenXR's per-eye
//    fov) and reversed or standard depth, finite or infinite far plane, are
//    all accepted. The fluid's depth is written with this projection, and the
//    depth test follows its direction (greater-or-equal for reversed depth).
struct View {
  Mat4 view = Mat4::identity();
  Mat4 projection = Mat4::identity();
  Viewport viewport;
};
// The view of `camera` over `viewport` (aspect from the viewport).
View camera_view(const Camera& camera, const Viewport& viewport);

// The caller's images. Layouts: the images are in `*_layout_before` when the
// recorded commands start and in `*_layout_after` when they end (sluice
// records the transitions, synchronized with everything before and after on
// the queue). A `before` layout of UNDEFINED discards the contents: colour is
// cleared to transparent black, depth to the far plane.
struct RenderTarget {
  uint32_t width = 0, height = 0;  // extent of the images (every view's viewport lies inside)
  VkImage color_image = VK_NULL_HANDLE;
  // A 2D view of layer base_layer (layer_count 1), or a 2D_ARRAY view of
  // layers base_layer.. base_layer + 1 (layer_count 2); colour attachment usage.
  VkImageView color_view = VK_NULL_HANDLE;
  VkFormat color_format = VK_FORMAT_UNDEFINED;  // *_SRGB formats get linear values (the hardware encodes)
  VkImageLayout color_layout_before = VK_IMAGE_LAYOUT_UNDEFINED;
  VkImageLayout color_layout_after = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
  // The colour image was created with VK_IMAGE_USAGE_STORAGE_BIT and its
  // (non-sRGB) format allows storage. Then, without a depth image, the
  // shading pass writes it directly and the present pass (a full-viewport
  // raster pass, slow on compute-first GPUs) is skipped.
  bool color_storage = false;
  // Optional: the host's depth (its opaque geometry). The fluid is hidden
  // behind it and writes its own depth into it.
  VkImage depth_image = VK_NULL_HANDLE;
  VkImageView depth_view = VK_NULL_HANDLE;  // as color_view: 2D, or 2D_ARRAY of layer_count layers
  VkFormat depth_format = VK_FORMAT_UNDEFINED;  // D16, D32, D24S8, D32S8
  // The depth image was created with VK_IMAGE_USAGE_TRANSFER_SRC_BIT and
  // TRANSFER_DST_BIT, and its format is D32, D32S8 or D24S8. Then, with
  // color_storage, the shading pass tests the fluid against the host's depth
  // and writes colour and depth itself, the depth going back by one copy of
  // the viewport (and out by one first, unless depth_layout_before is
  // UNDEFINED or depth_sampled), and the present pass is skipped: both eyes
  // of 2064x2208 took 0.48 ms this way on the H100 against 2.61 ms through
  // the present pass (docs/measurements.md). The depth image is in GENERAL
  // layout while the recorded commands run; the stencil is left alone.
  bool depth_transfer = false;
  // With depth_transfer, the depth image was also created with
  // VK_IMAGE_USAGE_SAMPLED_BIT: the shading pass reads a D32 or D32S8 depth
  // in place instead of copying it out (0.40 ms of 0.83 for both eyes of
  // 2064x2208 on the H100).
  bool depth_sampled = false;
  VkImageLayout depth_layout_before = VK_IMAGE_LAYOUT_UNDEFINED;
  VkImageLayout depth_layout_after = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
  uint32_t base_layer = 0;   // the first array layer drawn
  // 1: every view into layer base_layer (side by side, each its own pass).
  // 2: stereo in one pass: views[0] into base_layer, views[1] into the next
  // (same viewport), with one cull for both eyes (a particle is kept for
  // both or neither: the larger LOD importance of the two eyes decides),
  // the point-sprite passes through multiview, and every screen-space pass
  // over both layers at once.
  uint32_t layer_count = 1;
  // Draw sluice's sky and ground where the host's depth is still at the far
  // plane (everywhere without a host depth); off: only the fluid is drawn.
  bool background = true;
  // Optional: the host's scene behind the fluid, refracted through it
  // instead of sluice's environment (as engines hand a scene-colour texture
  // to their transparent passes). A copy of the host's opaque colour, not
  // color_image (which sluice writes): the target's size and layers
  // (base_layer.., layer_count), VK_IMAGE_USAGE_SAMPLED_BIT, in
  // scene_color_layout (SHADER_READ_ONLY_OPTIMAL or GENERAL) while the
  // recorded commands run; the host makes its writes visible to compute
  // shader sampled reads before record() (a barrier in its command buffer).
  // *_SRGB formats are read as linear light, others as display
  // (sRGB-encoded) values, as sluice writes UNORM targets.
  VkImage scene_color_image = VK_NULL_HANDLE;
  VkFormat scene_color_format = VK_FORMAT_UNDEFINED;
  VkImageLayout scene_color_layout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
};

// One attachment of a host's target: the image, a view of it, its format
// and its layouts before and after sluice's commands (see RenderTarget).
struct TargetImage {
  VkImage image = VK_NULL_HANDLE;
  VkImageView view = VK_NULL_HANDLE;
  VkFormat format = VK_FORMAT_UNDEFINED;
  VkImageLayout before = VK_IMAGE_LAYOUT_UNDEFINED, after = VK_IMAGE_LAYOUT_UNDEFINED;
};

// A mono target (layer 0) over a host's colour image and, when `depth.image`
// is set, its depth image; every other field as RenderTarget's defaults.
RenderTarget render_target(uint32_t width, uint32_t height, const TargetImage& color, const TargetImage& depth = {});

// What the caller's submission of the recorded command buffer must wait on:
// the timeline semaphore of the uploads, at the value of the copy of the
// frame drawn. It is already signalled when record() returns (only finished
// copies are drawn); the wait orders the transfer queue's writes before the
// reads, as Vulkan's memory model requires. Value 0: nothing to wait for.
struct FrameSync {
  VkSemaphore upload_semaphore = VK_NULL_HANDLE;
  uint64_t upload_value = 0;
  VkPipelineStageFlags2 wait_stages = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT;
};

// The largest frame the apps' `--particles auto` (their default) draws as
// ellipsoids (RendererOptions::anisotropic_limit): their once-a-frame pass
// takes about 3 ms per million particles on an H100 (docs/render.md), so a
// new frame of this size costs one stereo frame's time at 90 Hz at most.
inline constexpr uint64_t kAutoAnisotropicLimit = 2'000'000;

struct RendererOptions {
  uint32_t frames_in_flight = 2;  // see the contract above; 1..8
  // Keep each view's eye normals and depth for read_surface() (render/internal: inspection.h; costs
  // 16 bytes per pixel per frame).
  bool debug_surfaces = false;
  // Frames that arrive without layers (files converted with --no-layers,
  // frames a host pushes live: every chunk io::Layer::All, or staged rows
  // with no blob chunk) are classified on the GPU when first drawn (the
  // narrow band of io/narrow_band.h, voxel 2h, h = the scene's particle
  // spacing, else twice its radius) and drawn from their surface and voxel
  // blobs, as a layered file's surface set is. Costs the classification once
  // per uploaded frame (a pass "classify" in FrameStats), a bit per particle,
  // and room for n/4 blobs after the particles; a frame with more blobs, or
  // whose grid is too large, is drawn whole.
  bool classify_unlayered = false;
  // Anisotropic particles (Yu & Turk 2013): each particle drawn as an
  // ellipsoid from the covariance of its neighbours within 2h (h = the
  // scene's particle spacing, else twice its radius), flat where the fluid
  // is flat, so a resting surface shades smooth instead of showing the
  // particles' lattice. Computed on the GPU when a frame is first drawn (a
  // pass "ellipsoids" in FrameStats, or part of "classify"), 12 bytes per
  // particle and the classifier's scratch; each radius at most 4 times
  // another, volume kept; a particle with fewer than 6 others near it stays
  // a sphere, as do blobs. Needs a known particle size; otherwise, and for
  // a frame of more than 2^28 particles, particles stay spheres.
  bool anisotropic = false;
  // With `anisotropic`: a frame of more particles than this is drawn as
  // spheres, so the once-a-frame pass stays short (0: no limit but 2^28).
  // The apps' `--particles auto` sets kAutoAnisotropicLimit.
  uint64_t anisotropic_limit = 0;
};

// The particle look by name, as `--particles` and the Python module take
// it, into `options`' anisotropic and anisotropic_limit: "spheres",
// "ellipsoids", or "auto" (ellipsoids up to kAutoAnisotropicLimit particles
// a frame). Throws render::Error listing the choices.
void apply_particles(const std::string& name, RendererOptions& options);

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
  using Impl = detail::RendererImpl;  // render/src/renderer_impl.h
  friend Impl& renderer_impl(Renderer&);  // for render/src only (inspection.cpp)
  std::unique_ptr<Impl> impl_;
};

// Effective sphere radius for `options` in `scene`.
float effective_radius(const FluidOptions& options, const SceneInfo& scene);

}  // namespace sluice::render
