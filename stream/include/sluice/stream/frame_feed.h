// sluice/stream/frame_feed.h: the one path from the streaming runtime to the
// renderer. Once per displayed frame, update() asks the runtime::Player which
// frame is due and, when it changed, commits it to the render::Renderer: a copy
// (on the transfer queue, the graphics queue without one) and, for frames
// the GPU decodes, a compute pass on the graphics queue; overlapped with
// rendering, record() shows the frame once they are done.
//
// The player gives a frame's buffers back at its next update(); the copy out
// of them must be finished by then, so update() first waits for the previous
// commit's copy: the transfer queue only, and in a display loop that copy
// finished a refresh ago, so the wait returns at once.
//
// Ownership: borrows the renderer, the player and the allocator (the one the
// player decodes into, or nullptr for plain host memory), which outlive it.
// Threads: the thread that calls the renderer.
#pragma once

#include <cstdint>

#include "sluice/render/renderer.h"
#include "sluice/render/staging_allocator.h"
#include "sluice/runtime/player.h"

namespace sluice::stream {

// Where frames are decoded: Auto is the GPU where the file allows it.
enum class DecodeSite { Auto, Cpu, Gpu };

struct FeedUpdate {
  bool changed = false;      // a new frame was committed by this update()
  bool has_frame = false;    // some frame has been committed
  uint64_t frame = 0;        // the newest committed frame
  uint64_t ticket = 0;       // its upload ticket (render::Renderer::upload_complete, wait_upload)
  double commit_wall_ms = 0; // CPU time of the commit (chunk table, submission)
};

class FrameFeed {
 public:
  // What a player that feeds a renderer decodes: only the colour attribute
  // (`color_attribute` < 0: none), into `staging` within its device budget.
  // Frames of a file the GPU decodes (io::gpu_decodable: 16-bit positions)
  // stay encoded and are decoded by the GPU (render::Renderer::commit),
  // unless `decode` says Cpu.
  static void configure(runtime::PlayerOptions& options, const render::StagingAllocator& staging, int color_attribute,
                        const io::FileHeader& file, DecodeSite decode = DecodeSite::Auto);
  // The staging for such a player, made before configure(): frames the GPU
  // decodes are relayed into a window in device memory as they are read
  // (render::StagingOptions::resident; docs/gpu_decode.md measures both ways),
  // unless the relay would share a queue the host
  // submits to without render::Context::queue_lock() (`host_takes_queue_lock`
  // false and render::Context::relay_queue_shared()).
  static render::StagingOptions staging_options(const render::Context& context, const io::FileHeader& file,
                                                DecodeSite decode, bool host_takes_queue_lock);

  // `color_attribute`: the attribute's index in the file header (-1: none);
  // the player must decode only that attribute (PipelineOptions::attributes).
  FrameFeed(render::Renderer& renderer, runtime::Player& player, const render::StagingAllocator* staging,
            int color_attribute);
  // Waits for the last commit's copy: the player may free the buffers it
  // copies from as soon as the feed is gone.
  ~FrameFeed();
  FrameFeed(const FrameFeed&) = delete;
  FrameFeed& operator=(const FrameFeed&) = delete;

  // The views and options the next frames are drawn with, as the player's
  // demand (runtime::Player::set_demand): frames are read with
  // only the LOD tiers of the cells these views can keep, and a paused
  // frame is read again with the tiers it lacks when the views need more.
  // `margin`: world units the views may move before a frame read now is
  // drawn (the players use a twentieth of the scene's diagonal at least,
  // more for a view moving fast). Call it when the views or options change (once
  // per displayed frame is fine), before update(). Never called: every
  // tier is read.
  void set_views(std::span<const render::View> views, const render::FluidOptions& fluid, const render::LodOptions& lod,
                 float margin);

  FeedUpdate update();
  const FeedUpdate& last() const { return last_; }

 private:
  render::Renderer& renderer_;
  runtime::Player& player_;
  const render::StagingAllocator* staging_;
  int color_attribute_;
  uint64_t pending_ = 0;  // ticket of the last commit's copy
  FeedUpdate last_;
};

}  // namespace sluice::stream
