#include "sluice/stream/stream.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>
#include <thread>

#include "sluice/stream/demand.h"
#include "sluice/stream/live_source.h"
#include "sluice/error.h"

namespace sluice::stream {
namespace {

int decoded_attribute(const render::FluidOptions& fluid) {
  return fluid.scalar_visibility ? fluid.color_attribute : -1;
}

double steady_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// The eye of `view` in world space.
render::Vec3 eye_of(const render::View& view) {
  const render::Vec4 eye = inverse(view.view) * render::Vec4{0, 0, 0, 1};
  return {eye.x, eye.y, eye.z};
}

}  // namespace

Stream::Stream(render::Context& context, const std::filesystem::path& file, StreamOptions options)
    : context_(context), options_(std::move(options)) {
  reader_ = std::make_unique<io::ContainerReader>(file);
  if (reader_->frame_count() == 0) throw render::Error(file.string() + ": the file has no frames to play");
  render::SceneInfo scene = render::scene_info(*reader_);
  if (options_.up) scene.up = *options_.up;
  render::RendererOptions ro = options_.renderer;
  ro.classify_unlayered = options_.layers == io::LayerSet::surface();
  renderer_ = std::make_unique<render::Renderer>(context_, scene, ro);
  fluid_.up = scene.up;
  const io::FileHeader& header = reader_->header();
  const bool host_locks = options_.queue_lock == QueueLock::HostTakesIt;
  staging_ = std::make_unique<render::StagingAllocator>(
      context_, FrameFeed::staging_options(context_, header, options_.decode, host_locks));
  const bool layered = reader_->frame_count() > 0 && reader_->index().frames[0].layered();
  by_view_ = layered && options_.layers == io::LayerSet::surface();
  if (options_.decode == DecodeSite::Gpu && !io::gpu_decodable(header)) {
    throw render::Error(file.string() + ": frames with float32 positions are decoded on the CPU only");
  }
  gpu_decode_ = options_.decode != DecodeSite::Cpu && io::gpu_decodable(header);
}

Stream::Stream(render::Context& context, const render::Bounds& bounds, const LiveOptions& live, StreamOptions options)
    : context_(context), options_(std::move(options)) {
  render::SceneInfo scene = live_scene(bounds, live);
  if (options_.up) scene.up = *options_.up;
  render::RendererOptions ro = options_.renderer;
  ro.classify_unlayered = options_.layers == io::LayerSet::surface();
  renderer_ = std::make_unique<render::Renderer>(context_, scene, ro);
  fluid_.up = scene.up;
  fluid_.color_attribute = live.color_attribute;
  fluid_.scalar_visibility = live.color_attribute >= 0;
  live_ = std::make_unique<LiveSource>(*renderer_, live);
}

Stream::~Stream() = default;

const render::SceneInfo& Stream::scene() const { return renderer_->scene(); }

void Stream::require_file(const char* what) const {
  if (!reader_) throw render::Error(std::string("Stream::") + what + ": a live stream has no file");
}

const io::ContainerReader& Stream::reader() const {
  require_file("reader");
  return *reader_;
}

const render::StagingAllocator& Stream::staging() const {
  require_file("staging");
  return *staging_;
}

runtime::Player& Stream::player() {
  require_file("player");
  if (!player_) start_player();
  return *player_;
}

void Stream::set_look(const render::FluidOptions& fluid, const render::LodOptions& lod) {
  if (player_ && decoded_attribute(fluid) != decoded_attribute(fluid_)) {
    throw render::Error("Stream::set_look: the colour attribute is fixed once the player started");
  }
  fluid_ = fluid;
  lod_ = lod;
  demand_stale_ = true;
}

void Stream::set_views(std::span<const render::View> views) {
  views_.assign(views.begin(), views.end());
  if (views_.empty()) return;
  // The fastest recent move of the (first) eye, decaying by half every 0.25 s.
  const double now = steady_seconds();
  const render::Vec3 eye = eye_of(views_.front());
  if (eye_seconds_ >= 0 && now > eye_seconds_) {
    const float moved = length(eye - eye_) / float(now - eye_seconds_);
    speed_ = std::max(moved, speed_ * float(std::exp2(-(now - eye_seconds_) / 0.25)));
  }
  eye_ = eye;
  eye_seconds_ = now;
  demand_stale_ = true;
}

runtime::ViewDemand Stream::demand() const {
  if (!reads_by_view() || views_.empty()) return {};
  float margin = 0;
  if (options_.motion == ViewMotion::Moving) {
    // How far the views may move while frames read now wait in the window.
    const double rate = player_ ? std::max(player_->frame_rate(), 1.0) : 30.0;
    const float horizon = player_ ? float(double(player_->pipeline().most_ahead()) / rate) : 0.0f;
    margin = view_margin(scene().bounds.diagonal(), speed_, horizon);
  }
  return view_demand(views_, scene(), fluid_, lod_, margin);
}

void Stream::start_player() {
  runtime::PlayerOptions po = options_.player;
  po.pipeline.layers = options_.layers;
  const int color = decoded_attribute(fluid_);
  FrameFeed::configure(po, *staging_, color, reader_->header(), options_.decode);
  po.pipeline.demand = demand();
  demand_stale_ = false;
  const runtime::Clock* clock = options_.clock;
  if (!clock) {
    own_clock_ = std::make_unique<runtime::SteadyClock>();
    clock = own_clock_.get();
  }
  player_ = std::make_unique<runtime::Player>(*reader_, *staging_, *clock, po);
  feed_ = std::make_unique<FrameFeed>(*renderer_, *player_, staging_.get(), color);
}

FeedUpdate Stream::show(uint64_t frame, std::chrono::milliseconds timeout) {
  require_file("show");
  if (frame >= reader_->frame_count()) {
    throw render::Error("Stream::show: no frame " + std::to_string(frame) + " (the file has " +
                        std::to_string(reader_->frame_count()) + ")");
  }
  runtime::Player& p = player();
  p.pause();
  p.seek(frame);
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (true) {
    p.wait_for_due();
    const FeedUpdate u = update();
    if (const auto error = p.pop_error()) throw io::Error(error->where, error->message);
    if (u.has_frame && u.frame == frame) {
      renderer_->wait_upload(u.ticket);
      return u;
    }
    if (std::chrono::steady_clock::now() > deadline) {
      throw render::Error("Stream::show: frame " + std::to_string(frame) + " was not ready within " +
                          std::to_string(timeout.count()) + " ms");
    }
    std::this_thread::yield();
  }
}

FeedUpdate Stream::update() {
  if (live_) {
    const FeedUpdate now = last_push_;
    last_push_.changed = false;
    return now;
  }
  if (!player_) start_player();
  // The look and views set since the last update(), as one demand.
  if (demand_stale_) player_->set_demand(demand());
  demand_stale_ = false;
  return feed_->update();
}

render::FrameSync Stream::record(VkCommandBuffer cmd, const render::RenderTarget& target,
                                 std::span<const render::View> views) {
  return renderer_->record(cmd, target, views, fluid_, lod_);
}

uint64_t Stream::push(const LiveFrame& frame) {
  if (!live_) throw render::Error("Stream::push: a file stream takes no pushed frames");
  const uint64_t ticket = live_->push(frame);
  last_push_.changed = true;
  last_push_.has_frame = true;
  last_push_.frame = live_->frames_pushed() - 1;
  last_push_.ticket = ticket;
  last_push_.commit_wall_ms = live_->last_encode_ms() + live_->last_decode_ms();
  return ticket;
}

void Stream::finish() {
  if (live_) live_->finish();
}

}  // namespace sluice::stream
