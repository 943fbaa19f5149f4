#include "sluice/stream/frame_feed.h"
#include "sluice/error.h"
#include "sluice/stream/demand.h"

#include <chrono>
#include <stdexcept>

namespace sluice::stream {

FrameFeed::FrameFeed(render::Renderer& renderer, runtime::Player& player, const render::StagingAllocator* staging,
                     int color_attribute)
    : renderer_(renderer), player_(player), staging_(staging), color_attribute_(color_attribute) {}

// Without this wait, a stream torn down mid-copy freed the staging memory
// lavapipe's queue thread was still copying from (ASan, 1 run of 12 under load).
FrameFeed::~FrameFeed() { renderer_.wait_upload(pending_); }

void FrameFeed::configure(runtime::PlayerOptions& options, const render::StagingAllocator& staging, int color_attribute,
                          const io::FileHeader& file, DecodeSite decode) {
  options.pipeline.decode.attributes = color_attribute >= 0 ? std::vector<uint32_t>{uint32_t(color_attribute)} : std::vector<uint32_t>{};
  options.pipeline.window.device_budget = staging.device_budget();
  if (decode == DecodeSite::Gpu && !io::gpu_decodable(file)) {
    throw render::Error("frames with float32 positions are decoded on the CPU only");
  }
  options.pipeline.decode.mode = decode != DecodeSite::Cpu && io::gpu_decodable(file) ? runtime::DecodeMode::KeepEncoded
                                                                                     : runtime::DecodeMode::Cpu;
  options.pipeline.decode.color_attribute = color_attribute;
}

render::StagingOptions FrameFeed::staging_options(const render::Context& context, const io::FileHeader& file,
                                                  DecodeSite decode, bool host_takes_queue_lock) {
  render::StagingOptions o;
  o.resident = decode != DecodeSite::Cpu && io::gpu_decodable(file) && (host_takes_queue_lock || !context.relay_queue_shared());
  return o;
}

void FrameFeed::set_views(std::span<const render::View> views, const render::FluidOptions& fluid,
                          const render::LodOptions& lod, float margin) {
  player_.set_demand(view_demand(views, renderer_.scene(), fluid, lod, margin));
}

FeedUpdate FrameFeed::update() {
  renderer_.wait_upload(pending_);  // the player may now take those buffers back
  const runtime::Tick tick = player_.update();
  last_.changed = false;
  if (tick.changed && tick.frame) {
    const runtime::FrameHandle& f = *tick.frame;
    const auto t0 = std::chrono::steady_clock::now();
    pending_ = renderer_.commit(render::frame_upload(f, color_attribute_, staging_));
    last_.commit_wall_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    last_.changed = true;
    last_.has_frame = true;
    last_.frame = f.frame();
    last_.ticket = pending_;
  }
  return last_;
}

}  // namespace sluice::stream
