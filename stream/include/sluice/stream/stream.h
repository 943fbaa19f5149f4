// sluice/stream/stream.h: one object that streams a sequence into a host's
// frames. It owns what playing takes: the file's reader, the renderer, the
// staging the runtime decodes into, the runtime::Player and the FrameFeed
// between them (or, for frames a host computes, a LiveSource). A host makes
// one, then per displayed frame:
//
//   stream.set_views(views);          // what the next frames are drawn with
//   stream.update();                  // commits the frame due, if it changed
//   render::FrameSync s = stream.record(cmd, target, views);
//   submit cmd, waiting on s          // as render::Renderer::record says
//
// A batch client (a frame at a time, each drawn once) calls show(frame)
// instead of update(): it returns once that frame is the one record() draws.
//
// Reading by the view: a file with layers is read with only the LOD tiers
// of the cells the views can keep (stream/src/demand.cpp); set the look and the
// first views before the first update() (or player()) so that even the
// first frames are read for them. Files without layers, LayerSet
// particles() and LOD off are read whole.
//
// Queues: with StreamOptions::queue_lock HostTakesIt the host submits to
// the context's queues under render::Context::queue_lock() (desktop::Window does),
// and frames the GPU decodes are relayed to device memory as they are read
// (runtime/frame_allocator.h); with HostDoesNot they are relayed only where the relay
// has a queue of its own. Each update() that commits a frame submits a copy
// (the transfer queue, the graphics queue without one) and, for frames the
// GPU decodes, a compute pass on the graphics queue: call update() on the
// thread that submits the host's frames, or between its submissions.
//
// Ownership: borrows the context, which outlives the stream. Threads: one
// thread calls the members (the player's readers and decoders run on
// their own). Units: world units, seconds.
#pragma once

#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "sluice/io/codec.h"
#include "sluice/io/reader.h"
#include "sluice/render/context.h"
#include "sluice/render/options.h"
#include "sluice/render/renderer.h"
#include "sluice/render/staging_allocator.h"
#include "sluice/runtime/clock.h"
#include "sluice/runtime/player.h"
#include "sluice/stream/frame_feed.h"

namespace sluice::stream {

// A frame a host computed (Stream::push): positions and optional stable ids
// and attributes, turned into exactly what a file frame is (LOD values from
// the ids, chunks in Morton order, positions quantized per chunk, as `sluice
// convert` does) and drawn with the same cLOD. Borrowed for the call.
struct LiveFrame {
  std::span<const float> positions;                // x,y,z interleaved, finite
  std::span<const uint64_t> ids;                   // one stable id per particle (LiveOptions::ids), else empty
  std::vector<std::span<const float>> attributes;  // one per scene attribute (or none), one value per particle
  double time = 0;                                 // simulation time in seconds
};

struct LiveOptions {
  // Written into the recording's header: rest spacing and render radius
  // (0: unknown), nominal frame rate, and the attributes' names.
  float particle_spacing = 0, particle_radius = 0, frame_rate = 0;
  // Which world direction points up (the scene's up and the recording's;
  // a host drawing its own ground passes render::FluidOptions::ground = false).
  io::UpAxis up = io::UpAxis::PosZ;
  std::vector<std::string> attributes;
  int color_attribute = -1;      // which attribute the renderer colours by (-1: none)
  bool ids = true;               // frames carry stable ids; false: LOD values follow the particle index
  std::filesystem::path record;  // empty: not recorded
  // Chunk size; zstd level and plane packing of the recording (frames not
  // recorded are not compressed: only decoded at once).
  io::EncodeOptions encode{.chunk_particles = 65536, .zstd_level = 1};
};

class LiveSource;  // frames pushed: stream/src

// Whether the host submits to the context's queues under render::Context::queue_lock().
enum class QueueLock { HostTakesIt, HostDoesNot };
// Whether the views may move before a frame read now is drawn (a window, a
// headset) or stay where they are (a fixed camera: no margin is read).
enum class ViewMotion { Moving, Fixed };

struct StreamOptions {
  // Rate, start frame, end and error policies, memory and threads. The
  // stream sets what the renderer needs of the pipeline: layers (below),
  // the attribute decoded, the decode site, the device budget, the demand.
  runtime::PlayerOptions player;
  // frames_in_flight; classify_unlayered is set from `layers`.
  render::RendererOptions renderer;
  // Which layers are read and drawn: the narrow band and blobs (frames of
  // a file without layers are classified on the GPU), or every particle.
  io::LayerSet layers = io::LayerSet::surface();
  DecodeSite decode = DecodeSite::Auto;
  QueueLock queue_lock = QueueLock::HostTakesIt;
  ViewMotion motion = ViewMotion::Moving;
  // The scene's up direction instead of the file's (an --up the user gave).
  std::optional<render::Vec3> up;
  // Whose time the player follows (XR: the predicted display time);
  // nullptr: a steady clock of the stream's own. Borrowed; outlives the stream.
  const runtime::Clock* clock = nullptr;
};

class Stream {
 public:
  // Opens `file` and makes the renderer and staging; the player starts at
  // the first update() or player(), paused at options.player.start_frame.
  // Throws io::Error for a file that cannot be read, render::Error
  // for a file without frames or options it cannot honour (DecodeSite::Gpu
  // for float32 positions).
  Stream(render::Context& context, const std::filesystem::path& file, StreamOptions options = {});
  // Frames the host pushes (push()) inside `bounds`, optionally recorded
  // (LiveOptions::record). Throws as LiveSource does.
  Stream(render::Context& context, const render::Bounds& bounds, const LiveOptions& live, StreamOptions options = {});
  ~Stream();
  Stream(const Stream&) = delete;
  Stream& operator=(const Stream&) = delete;

  // How the frames are drawn: the attribute coloured by (decoded only if
  // fluid.scalar_visibility; fixed once the player started: a change
  // throws render::Error), the splat reach and cLOD the view's
  // demand assumes (taken at the next update()). Defaults: render::FluidOptions{}
  // with the scene's up, render::LodOptions{}.
  void set_look(const render::FluidOptions& fluid, const render::LodOptions& lod);
  // The views (1..4) the next frames are drawn with: frames are read for
  // them (with a margin for their motion, ViewMotion::Moving), and a paused
  // frame is read again when they need more. Once per displayed frame is
  // fine: the player takes the look and views as one demand at update().
  void set_views(std::span<const render::View> views);

  // Once per displayed frame, before record(): commits the frame due when
  // it changed (a file), or reports the last push (live).
  FeedUpdate update();
  // Batch rendering (screenshots, a movie, tests), a file's frames one by
  // one: pauses on `frame` and blocks until it is read (for the views set),
  // committed and its upload done, so that the next record() draws exactly
  // it. Returns the update that committed it (.frame == frame). The last
  // frame is reader().frame_count() - 1. Throws io::Error when the frame
  // cannot be read (naming file, frame and chunk), render::Error on a live
  // stream, for a frame past the end, or when `timeout` passes first.
  FeedUpdate show(uint64_t frame, std::chrono::milliseconds timeout = std::chrono::seconds(60));
  // Records the newest committed frame for `views` with the look
  // (render::Renderer::record: the caller submits `cmd`, waiting on the result).
  render::FrameSync record(VkCommandBuffer cmd, const render::RenderTarget& target,
                           std::span<const render::View> views);
  // A frame the host computed (live streams only; render::Error otherwise).
  uint64_t push(const LiveFrame& frame);
  // Closes a live recording (index and footer written); no-op otherwise.
  void finish();

  bool live() const { return live_ != nullptr; }
  const render::SceneInfo& scene() const;
  const render::FluidOptions& fluid() const { return fluid_; }
  const render::LodOptions& lod() const { return lod_; }
  render::Renderer& renderer() { return *renderer_; }
  // A file's reader, player and staging (render::Error on a live stream).
  const io::ContainerReader& reader() const;
  runtime::Player& player();
  const render::StagingAllocator& staging() const;
  // Whether frames are read by the view (a file with layers, layers
  // surface(), LOD on); otherwise every tier.
  bool reads_by_view() const { return by_view_ && lod_.mode != render::LodMode::Off; }
  // Whether a file's frames stay encoded until the GPU decodes them
  // (DecodeSite::Auto and 16-bit positions, or DecodeSite::Gpu).
  bool decodes_on_gpu() const { return gpu_decode_; }

 private:
  void start_player();
  runtime::ViewDemand demand() const;
  void require_file(const char* what) const;

  render::Context& context_;
  StreamOptions options_;
  std::unique_ptr<io::ContainerReader> reader_;
  std::unique_ptr<render::Renderer> renderer_;
  std::unique_ptr<render::StagingAllocator> staging_;
  std::unique_ptr<runtime::Clock> own_clock_;
  std::unique_ptr<runtime::Player> player_;
  std::unique_ptr<FrameFeed> feed_;
  std::unique_ptr<LiveSource> live_;
  render::FluidOptions fluid_;
  render::LodOptions lod_;
  std::vector<render::View> views_;
  bool by_view_ = false;
  bool gpu_decode_ = false;
  // The views' speed (world units per second) for the margin of a moving view.
  float speed_ = 0;
  bool demand_stale_ = false;  // the look or views changed since the player last took the demand
  render::Vec3 eye_{};
  double eye_seconds_ = -1;
  FeedUpdate last_push_;
};

}  // namespace sluice::stream
