// `sluice bench view`: the players' path (Player -> FrameFeed -> Renderer)
// on a scripted camera path, reading by the view's demand against the full
// read of the surface and blobs (view_bench.h).
#include "sluice/bench/view_bench.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <filesystem>
#include <stdexcept>
#include <thread>

#include "bounds.h"
#include "machine.h"
#include "sluice/io/particles.h"
#include "sluice/io/reader.h"
#include "sluice/stream/demand.h"
#include "sluice/stream/frame_feed.h"
#include "sluice/render/image_io.h"
#include "sluice/render/offscreen.h"
#include "sluice/render/renderer.h"
#include "sluice/render/staging_allocator.h"
#include "sluice/render/load.h"
#include "sluice/runtime/player.h"
#include "sluice/bench/table.h"

namespace sluice::bench {
namespace {

using Clock = std::chrono::steady_clock;

enum class Segment { Orbit, FlyIn, Pause };
const char* segment_name(Segment s) {
  switch (s) {
    case Segment::Orbit: return "overview orbit";
    case Segment::FlyIn: return "fly-in to a close-up";
    case Segment::Pause: return "pause on the overview, level to 1";
  }
  return "?";
}

struct Step {
  std::vector<render::View> views;
};

// One camera, or two eyes 6.4 cm apart at human scale (the scene's extent
// taken as 1.5 m), as in `bench render --stereo`.
std::vector<render::View> views_of(const render::Camera& cam, const ViewBenchOptions& o, float extent) {
  if (!o.stereo) return {render::camera_view(cam, {0, 0, o.width, o.height})};
  const render::Vec3 forward = render::normalize(cam.target - cam.eye);
  const render::Vec3 right = render::normalize(render::cross(forward, cam.up));
  std::vector<render::View> v;
  for (int e = 0; e < 2; ++e) {
    render::Camera c = cam;
    const render::Vec3 shift = right * ((e == 0 ? -0.5f : 0.5f) * extent * 0.064f / 1.5f);
    c.eye = c.eye + shift;
    c.target = c.target + shift;
    v.push_back(render::camera_view(c, {0, 0, o.width, o.height}));
  }
  return v;
}

render::Vec3 lerp(render::Vec3 a, render::Vec3 b, float t) { return a + (b - a) * t; }

// The orbit turns the overview a quarter around the up axis; the fly-in goes
// from where it ends to a close-up: an eye a fifth of the diagonal from a
// point a quarter of the way along the pool, near its surface, looking
// along the pool so that much of it lies outside the view.
struct Path {
  std::vector<Step> orbit, fly_in;
};

Path make_path(const render::SceneInfo& scene, const ViewBenchOptions& o, uint32_t steps) {
  const render::Bounds& b = scene.bounds;
  const render::Vec3 up = scene.up;
  const float extent = std::max({b.max.x - b.min.x, b.max.y - b.min.y, b.max.z - b.min.z});
  const render::Camera overview = render::Camera::framing(b, up, float(o.width) / float(o.height));
  Path p;
  const render::Vec3 axis = render::normalize(up);
  const auto turned = [&](render::Vec3 v, float angle) {  // Rodrigues about the up axis
    return v * std::cos(angle) + render::cross(axis, v) * std::sin(angle) + axis * (render::dot(axis, v) * (1 - std::cos(angle)));
  };
  render::Camera last = overview;
  for (uint32_t k = 0; k < steps; ++k) {
    render::Camera c = overview;
    c.eye = overview.target + turned(overview.eye - overview.target, 1.5707963f * float(k) / float(steps));
    p.orbit.push_back({views_of(c, o, extent)});
    last = c;
  }
  // The close-up: a quarter of the way along the longest horizontal axis.
  const render::Vec3 size = b.max - b.min;
  render::Vec3 along{0, 0, 0};
  if (std::abs(axis.x) < 0.5f && size.x >= size.y && size.x >= size.z) along = {1, 0, 0};
  else if (std::abs(axis.y) < 0.5f && size.y >= size.z) along = {0, 1, 0};
  else along = {0, 0, 1};
  if (std::abs(render::dot(along, axis)) > 0.5f) along = std::abs(axis.x) < 0.5f ? render::Vec3{1, 0, 0} : render::Vec3{0, 1, 0};
  const render::Vec3 centre = b.center();
  const float length = std::abs(render::dot(size, along));
  const float height = std::abs(render::dot(size, axis));
  render::Camera close = overview;
  close.target = centre - along * (0.25f * length) + axis * (0.1f * height);
  close.eye = close.target - along * (0.2f * b.diagonal()) + axis * (0.12f * b.diagonal());
  for (uint32_t k = 0; k < steps; ++k) {
    const float t = float(k + 1) / float(steps);
    const float s = t * t * (3 - 2 * t);
    render::Camera c = last;
    c.eye = lerp(last.eye, close.eye, s);
    c.target = lerp(last.target, close.target, s);
    p.fly_in.push_back({views_of(c, o, extent)});
  }
  return p;
}

render::LodOptions lod_options(const ViewBenchOptions& o, float level) {
  render::LodOptions lod;
  lod.mode = o.lod == "density" ? render::LodMode::DensityPreserving : render::LodMode::Clod;
  lod.level = level;
  lod.position_error_pixels = o.position_error;
  return lod;
}

stream::DecodeSite decode_site(const std::string& s) {
  if (s == "cpu") return stream::DecodeSite::Cpu;
  if (s == "gpu") return stream::DecodeSite::Gpu;
  return stream::DecodeSite::Auto;
}

struct StepTimes {
  double wait_ms = 0, commit_ms = 0, upload_ms = 0;
};

struct Run {
  uint64_t frames_shown = 0, frames_read = 0, bytes_read = 0, record_bytes = 0, refinements = 0;
  uint64_t device_bytes = 0;  // what storage delivered meanwhile (process_read_bytes)
  uint64_t runs = 0;          // the runs reads by demand took (PipelineStats::runs_read)
  // Records the workers checked and decoded (or staged for the GPU), and
  // their time on them: the per-record cost a layout of fewer records saves.
  uint64_t records = 0;
  double worker_seconds = 0;
  double seconds = 0;
  // From the start to the first frame fed (the player's start, its window,
  // the first read): paid once a playback, not once a frame.
  double first_seconds = 0;
  double start_seconds = 0;  // of which making the player (staging, window, threads)
  double worst_psnr = std::numeric_limits<double>::infinity();
  double median_psnr = std::numeric_limits<double>::infinity();
  // Once playing (the steps after the first), each step's wall time in
  // parts (ms): waiting for the player's next frame, committing it to the
  // renderer, waiting for its upload (the GPU's copy and decode), and
  // recording and submitting the frame's render.
  std::vector<double> wait_ms, commit_ms, upload_ms, render_ms;
  // Frames decoded and waiting after each such step: 0 most of the time
  // means the reader keeps the consumer waiting, more means the consumer
  // is the slower side.
  std::vector<double> ready;
  double read_seconds = 0;  // the reader's time with a read in flight
  runtime::PipelineStats::RelayTimes relay;  // the read threads' time on relayed frames, by part
};

// The full read's picture of `frame` for `views` (quality pass only).
struct Reference {
  render::Renderer renderer;
  render::OffscreenTarget target;
  const io::ContainerReader& reader;
  Reference(render::Context& c, const render::SceneInfo& scene, const io::ContainerReader& r, const ViewBenchOptions& o)
      : renderer(c, scene), target(c, o.width, o.height, {.layers = o.stereo ? 2u : 1u}), reader(r) {}
  render::Image picture(uint64_t frame, const std::vector<render::View>& views, const render::FluidOptions& fluid,
                        const render::LodOptions& lod) {
    sluice::render::load_frame(renderer, reader, frame, -1, io::LayerSet::surface());
    target.render(renderer, views, fluid, lod);
    return {target.width(), target.height(), target.read_rgba8()};
  }
};

class Bench {
 public:
  // One renderer and its targets for every run: its first use (pipelines,
  // device buffers) is paid once, in run_view_bench's warm-up.
  Bench(const ViewBenchOptions& o, render::Context& context, const io::ContainerReader& reader)
      : o_(o),
        context_(context),
        reader_(reader),
        scene_(render::scene_info(reader)),
        path_(make_path(scene_, o, o.steps)),
        cache_path_(make_path(scene_, o, o.cache_steps > 0 ? o.cache_steps : o.steps)),
        renderer_(context, scene_, {.frames_in_flight = 2}),
        timed_(context, o.width, o.height, {.frames_in_flight = 2, .read_back = false, .layers = o.stereo ? 2u : 1u}),
        checked_(context, o.width, o.height, {.frames_in_flight = 1, .read_back = true, .layers = o.stereo ? 2u : 1u}) {
    fluid_.scalar_visibility = false;
  }

  // Plays `steps` from `first`; by_view: the views' demand (the first
  // step's from the pipeline's start), else every tier. Timed from the
  // player's start to the last step drawn: timed runs render with two frames
  // in flight and read nothing back, as `play --headless --gpu` does.
  Run play(const std::vector<Step>& steps, uint64_t first, bool by_view, bool quality) {
    const render::LodOptions lod = lod_options(o_, o_.level);
    std::unique_ptr<Reference> ref;
    if (quality) ref = std::make_unique<Reference>(context_, scene_, reader_, o_);
    render::OffscreenTarget& target = quality ? checked_ : timed_;
    std::vector<double> db;
    const uint64_t device_before = process_read_bytes();
    const auto t0 = Clock::now();
    Player p(*this, first, demand(steps.front().views, lod, by_view));
    const double start_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    p.player.play();
    double first_seconds = 0;
    Run r;
    for (const Step& step : steps) {
      p.player.set_demand(demand(step.views, lod, by_view));
      StepTimes times;
      const stream::FeedUpdate fed = p.next_frame(times);
      const auto rendering = Clock::now();
      if (&step == &steps.front()) first_seconds = std::chrono::duration<double>(rendering - t0).count();
      target.render(renderer_, step.views, fluid_, lod);
      if (&step != &steps.front()) {
        r.wait_ms.push_back(times.wait_ms);
        r.commit_ms.push_back(times.commit_ms);
        r.upload_ms.push_back(times.upload_ms);
        r.render_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - rendering).count());
        r.ready.push_back(double(p.player.pipeline().ready_count()));  // this thread is the consumer: no stats() snapshot a step
      }
      if (ref) {
        const render::Image shown{target.width(), target.height(), target.read_rgba8()};
        db.push_back(render::psnr(shown, ref->picture(fed.frame, step.views, fluid_, lod)));
      }
    }
    target.finish();
    const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    finish(r, p, {}, seconds, uint64_t(steps.size()), db);
    r.first_seconds = first_seconds;
    r.start_seconds = start_seconds;
    r.device_bytes = process_read_bytes() - device_before;
    return r;
  }

  // Paused on the overview at the bench's level, then the level raised to
  // 1: the frame on screen is read again with the tiers it lacks.
  Run pause(uint64_t frame, bool by_view, bool quality) {
    const std::vector<render::View>& views = path_.orbit.front().views;
    Player p(*this, frame, demand(views, lod_options(o_, o_.level), by_view));
    StepTimes ignored;
    p.next_frame(ignored);  // paused: the start frame is shown once read
    const render::LodOptions full = lod_options(o_, 1.0f);
    const runtime::PlaybackStats before = p.player.stats();
    const uint64_t device_before = process_read_bytes();
    const auto t0 = Clock::now();
    p.player.set_demand(demand(views, full, by_view));
    // Until the frame on screen holds what the view needs (its new read is
    // shown; the full read never falls short).
    const auto deadline = Clock::now() + std::chrono::seconds(60);
    while (true) {
      p.feed.update();
      if (const auto error = p.player.pop_error()) throw std::runtime_error(error->text());
      const runtime::FrameHandle* shown = p.player.shown();
      if (shown && !p.player.pipeline().short_of(*shown, p.player.demand())) break;
      if (Clock::now() > deadline) throw std::runtime_error("bench view: the paused frame was not refined within 60 s");
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    renderer_.wait_upload(p.feed.last().ticket);
    checked_.render(renderer_, views, fluid_, full);
    std::vector<double> db;
    if (quality) {
      Reference ref(context_, scene_, reader_, o_);
      const render::Image shown{checked_.width(), checked_.height(), checked_.read_rgba8()};
      db.push_back(render::psnr(shown, ref.picture(frame, views, fluid_, full)));
    }
    checked_.finish();
    const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    Run r;
    finish(r, p, before, seconds, 1, db);
    r.device_bytes = process_read_bytes() - device_before;
    return r;
  }

  const Path& path() const { return path_; }
  const Path& cache_path() const { return cache_path_; }

 private:
  // A player over the file as the players make it (FrameFeed::configure,
  // staging_options), every frame due at once, looping, reading by
  // `demand` from its start.
  struct Player {
    render::StagingAllocator staging;
    runtime::SteadyClock clock;
    runtime::Player player;
    stream::FrameFeed feed;
    render::Renderer& renderer;

    Player(Bench& b, uint64_t first, const runtime::ViewDemand& demand)
        : staging(b.context_,
                  stream::FrameFeed::staging_options(b.context_, b.reader_.header(), decode_site(b.o_.decode), true)),
          player(b.reader_, staging, clock, b.player_options(first, staging, demand)),
          feed(b.renderer_, player, &staging, -1),
          renderer(b.renderer_) {}

    stream::FeedUpdate next_frame(StepTimes& times) {
      const auto t0 = Clock::now();
      const auto deadline = t0 + std::chrono::seconds(120);
      while (true) {
        player.wait_for_due();
        const stream::FeedUpdate fed = feed.update();
        if (const auto error = player.pop_error()) throw std::runtime_error(error->text());
        if (fed.changed) {
          const auto committed = Clock::now();
          renderer.wait_upload(fed.ticket);
          times.commit_ms = fed.commit_wall_ms;
          times.wait_ms = std::chrono::duration<double, std::milli>(committed - t0).count() - fed.commit_wall_ms;
          times.upload_ms = std::chrono::duration<double, std::milli>(Clock::now() - committed).count();
          return fed;
        }
        if (Clock::now() > deadline) throw std::runtime_error("bench view: no frame arrived within 120 s");
      }
    }
  };

  runtime::PlayerOptions player_options(uint64_t first, const render::StagingAllocator& staging,
                                       const runtime::ViewDemand& demand) const {
    runtime::PlayerOptions po;
    po.frame_rate = 1e9;  // every frame due at once: as fast as frames arrive
    po.start_frame = first;
    po.end = runtime::EndMode::Loop;
    po.policy = runtime::RealTimePolicy::HoldLastFrame;
    po.on_error = runtime::ErrorPolicy::Stop;
    po.pipeline.layers = io::LayerSet::surface();
    po.pipeline.window.budget.memory_cap = o_.memory > 0 ? o_.memory : (uint64_t(4) << 30);
    stream::FrameFeed::configure(po, staging, -1, reader_.header(), decode_site(o_.decode));
    po.pipeline.demand = demand;
    if (o_.read_threads > 0) po.pipeline.read.threads = o_.read_threads;
    if (o_.read_rounds > 0) po.pipeline.read.rounds = o_.read_rounds;
    po.pipeline.read.mapped = o_.mapped_reads;
    po.pipeline.read.direct_io = o_.direct_io;
    return po;
  }

  runtime::ViewDemand demand(const std::vector<render::View>& views, const render::LodOptions& lod, bool by_view) const {
    if (!by_view) return {};
    return stream::view_demand(views, scene_, fluid_, lod, stream::view_margin(scene_.bounds.diagonal(), 0, 0));
  }

  float extent() const {
    const render::Bounds& b = scene_.bounds;
    return std::max({b.max.x - b.min.x, b.max.y - b.min.y, b.max.z - b.min.z});
  }

  static void finish(Run& r, Player& p, const runtime::PlaybackStats& before, double seconds, uint64_t shown,
                     std::vector<double>& db) {
    const runtime::PlaybackStats after = p.player.stats();
    r.seconds = seconds;
    r.frames_shown = shown;
    r.frames_read = after.pipeline.frames_read - before.pipeline.frames_read;
    r.bytes_read = after.pipeline.bytes_read - before.pipeline.bytes_read;
    r.record_bytes = after.pipeline.record_bytes - before.pipeline.record_bytes;
    r.refinements = after.refinements - before.refinements;
    r.runs = after.pipeline.runs_read - before.pipeline.runs_read;
    r.read_seconds = after.pipeline.read_seconds - before.pipeline.read_seconds;
    const auto& a = after.pipeline.relay;
    const auto& b = before.pipeline.relay;
    r.relay = {a.claim_seconds - b.claim_seconds, a.copy_seconds - b.copy_seconds, a.check_seconds - b.check_seconds,
               a.plan_seconds - b.plan_seconds, a.send_seconds - b.send_seconds};
    const auto records = [](const runtime::PlaybackStats& s) {
      uint64_t n = 0;
      for (const runtime::WorkerStats& w : s.pipeline.workers) n += w.chunks;
      return n;
    };
    const auto busy = [](const runtime::PlaybackStats& s) {
      double t = 0;
      for (const runtime::WorkerStats& w : s.pipeline.workers) t += w.busy_seconds;
      return t;
    };
    r.records = records(after) - records(before);
    r.worker_seconds = busy(after) - busy(before);
    if (!db.empty()) {
      r.worst_psnr = *std::min_element(db.begin(), db.end());
      r.median_psnr = median(db);
    }
  }

  const ViewBenchOptions& o_;
  render::Context& context_;
  const io::ContainerReader& reader_;
  render::SceneInfo scene_;
  Path path_, cache_path_;
  render::Renderer renderer_;
  render::OffscreenTarget timed_, checked_;
  render::FluidOptions fluid_;
};

// The share of frame `frame`'s surface particles and blobs whose centre
// lies inside any of `views`' frusta: what any layout must read of it at
// full detail, against which reading by the view is judged.
double share_in_view(const io::ContainerReader& reader, uint64_t frame, const std::vector<render::View>& views) {
  io::ParticleQuery q;
  q.layers = io::LayerSet::surface();
  const io::ParticleArrays p = io::read_particles(reader, frame, q);
  std::vector<render::Mat4> clip;
  for (const render::View& v : views) clip.push_back(v.projection * v.view);
  uint64_t inside = 0;
  for (uint64_t i = 0; i < p.count(); ++i) {
    const render::Vec4 x{p.positions[3 * i], p.positions[3 * i + 1], p.positions[3 * i + 2], 1};
    for (const render::Mat4& m : clip) {
      const render::Vec4 c = m * x;
      if (c.w > 0 && std::abs(c.x) <= c.w && std::abs(c.y) <= c.w && c.z >= 0 && c.z <= c.w) {
        ++inside;
        break;
      }
    }
  }
  return p.count() ? double(inside) / double(p.count()) : 0;
}

std::string mb(double bytes) { return fixed(bytes / 1e6, 1) + " MB"; }

// The read threads' time on relayed frames by part, ms a frame read summed
// over the threads ("-" where no frame was relayed).
std::string relay_parts(const Run& r) {
  const runtime::PipelineStats::RelayTimes& t = r.relay;
  const double total = t.claim_seconds + t.copy_seconds + t.check_seconds + t.plan_seconds + t.send_seconds;
  if (r.frames_read == 0 || total <= 0) return "-";
  const auto ms = [&](double seconds) { return fixed(1e3 * seconds / double(r.frames_read), 2); };
  return ms(t.claim_seconds) + "/" + ms(t.copy_seconds) + "/" + ms(t.check_seconds) + "/" + ms(t.plan_seconds) + "/" +
         ms(t.send_seconds);
}
std::string db_text(double v) { return std::isinf(v) ? "identical" : fixed(v, 1) + " dB"; }

// The fly-in's last frame alone, from the page cache, read by its view and
// whole: the share of the full read's bytes the view read, beside the share
// of the particles that lie in the view (any layout's floor at level 1; at a
// lower level the view needs less of the far ones).
void print_close_up(Bench& bench, const io::ContainerReader& reader, const ViewBenchOptions& o) {
  const uint64_t frames = reader.frame_count();
  const uint64_t fly_first = o.steps % frames;
  const std::vector<Step> close{bench.path().fly_in.back()};
  const uint64_t frame = (fly_first + o.steps - 1) % frames;
  const Run view = bench.play(close, frame, true, false), whole = bench.play(close, frame, false, false);
  // Per frame read: the player reads ahead of the one frame shown, more
  // frames the smaller they are.
  const auto per_frame = [](const Run& r) { return r.frames_read ? double(r.bytes_read) / double(r.frames_read) : 0.0; };
  const double in_view = share_in_view(reader, frame, close.front().views);
  std::printf("\nThe close-up (the fly-in's last view), frame %llu: reading by the view read %s of the full read "
              "(%s of %s a frame read); %s of the frame's surface particles and blobs lie in the view\n",
              (unsigned long long)frame,
              per_frame(whole) > 0 ? (fixed(100.0 * per_frame(view) / per_frame(whole), 1) + "%").c_str() : "-",
              mb(per_frame(view)).c_str(), mb(per_frame(whole)).c_str(),
              (fixed(100.0 * in_view, 1) + "%").c_str());
}

}  // namespace

void run_view_bench(const ViewBenchOptions& o) {
  const io::ContainerReader reader(o.file);
  if (reader.frame_count() == 0) throw io::Error({o.file}, "no frames");
  render::ContextOptions co;
  co.device = o.device;
  render::Context context(co);
  Bench bench(o, context, reader);
  const render::DeviceInfo& dev = context.device();
  uint64_t file_bytes = 0;
  for (const io::FrameIndexEntry& e : reader.index().frames) file_bytes += e.bytes;
  std::printf("sluice bench view %s: %llu frames, %s a frame on average, format %u.%u\n", o.file.c_str(),
              (unsigned long long)reader.frame_count(), mb(double(file_bytes) / double(reader.frame_count())).c_str(),
              reader.header().version_major, reader.header().version_minor);
  std::printf("device: %s (%s); host: %s, %d cores\n", dev.name.c_str(), dev.type.c_str(), cpu_model().c_str(), core_count());
  std::printf("view: %ux%u%s, %s %.2f; %u frames per moving segment (%u from the page cache); the surface and blobs "
              "(players' default)\n", o.width, o.height, o.stereo ? " per eye, two eyes" : "", o.lod.c_str(), double(o.level),
              o.steps, o.cache_steps > 0 ? o.cache_steps : o.steps);

  if (o.close_up_only) return print_close_up(bench, reader, o);
  const uint64_t frames = reader.frame_count();
  const uint64_t fly_first = o.steps % frames;
  const uint64_t pause_frame = (2 * uint64_t(o.steps)) % frames;
  // The disk's bound, measured on this file in this run: large sequential
  // O_DIRECT reads (8 MiB, 4 threads) of its first 2 GB, cache dropped.
  std::optional<double> disk_gbps;
  if (o.storage) {
    const uint64_t probe = std::min<uint64_t>(std::filesystem::file_size(o.file), uint64_t(2) << 30);
    disk_gbps = sequential_read_gbps(o.file, 0, probe, ReadMode::Direct, 0, 4);
    if (disk_gbps) {
      std::printf("disk: %s MB/s for sequential O_DIRECT reads of 8 MiB (4 threads, the first %s of this file)\n",
                  fixed(*disk_gbps * 1e3, 0).c_str(), mb(double(probe)).c_str());
    } else {
      std::printf("disk: O_DIRECT refused here; no sequential bound measured\n");
    }
  }
  // Where a step's time goes once playing (medians over the steps after the first).
  Table parts({"segment", "read", "from", "step ms", "waiting for the frame", "commit", "upload (GPU copy, decode)",
               "render (record, submit)", "frames ready after it", "reading a frame read",
               "relay claim/copy/check/plan/send a frame read"});
  const auto add_parts = [&](Segment s, bool by_view, const char* from, const Run& r) {
    if (s == Segment::Pause || r.wait_ms.empty()) return;
    std::vector<double> step(r.wait_ms.size());
    for (size_t k = 0; k < step.size(); ++k) step[k] = r.wait_ms[k] + r.commit_ms[k] + r.upload_ms[k] + r.render_ms[k];
    parts.row({segment_name(s), by_view ? "by view" : "full", from, fixed(median(step), 2), fixed(median(r.wait_ms), 2),
               fixed(median(r.commit_ms), 2), fixed(median(r.upload_ms), 2), fixed(median(r.render_ms), 2), fixed(median(r.ready), 1),
               r.frames_read ? fixed(1e3 * r.read_seconds / double(r.frames_read), 2) : "-", relay_parts(r)});
  };
  Table table({"segment", "read", "from", "frames/s", "first frame (start)", "frames/s after it", "read per frame", "device per frame", "runs per frame",
               "records per frame", "worker us per record", "of the records", "of the disk's bound", "refinements"});
  const auto add = [&](Segment s, bool by_view, const char* from, const Run& r) {
    const double read = r.frames_read ? double(r.frames_read) : 1.0;
    const double per = double(r.bytes_read) / read;
    const double device = double(r.device_bytes) / read;
    const double fps = s == Segment::Pause ? 0 : double(r.frames_shown) / r.seconds;
    // The rate once playing: the frames after the first over their time.
    const double after = r.seconds - r.first_seconds;
    const std::string steady = s == Segment::Pause || r.frames_shown < 2 || after <= 0
                                   ? "-"
                                   : fixed(double(r.frames_shown - 1) / after, 1);
    // The share of the disk's sequential rate the segment drew from it.
    const bool cold = std::string(from).find("storage") != std::string::npos;
    const std::string bound = cold && disk_gbps && r.seconds > 0
                                  ? fixed(100.0 * double(r.device_bytes) / r.seconds / (*disk_gbps * 1e9), 0) + "%"
                                  : "-";
    table.row({segment_name(s), by_view ? "by view" : "full", from,
               s == Segment::Pause ? fixed(r.seconds * 1e3, 1) + " ms to converge" : fixed(fps, 1),
               s == Segment::Pause ? "-" : fixed(r.first_seconds * 1e3, 1) + " ms (" + fixed(r.start_seconds * 1e3, 1) + ")", steady,
               s == Segment::Pause ? mb(double(r.bytes_read)) + " (refinement)" : mb(per),
               s == Segment::Pause ? mb(double(r.device_bytes)) : mb(device) + (per > 0 && cold ? " (" + fixed(device / per, 2) + "x)" : ""),
               // (Relayed frames are checked on the read threads: no worker records.)
               by_view ? fixed(double(r.runs) / read, 1) : "-", r.records ? fixed(double(r.records) / read, 0) : "-",
               r.records ? fixed(1e6 * r.worker_seconds / double(r.records), 1) : "-",
               r.record_bytes ? fixed(100.0 * double(r.bytes_read) / double(r.record_bytes), 1) + "%" : "-", bound,
               std::to_string(r.refinements)});
    add_parts(s, by_view, from, r);
  };
  const auto drop = [&] { drop_from_page_cache(o.file, 0, std::filesystem::file_size(o.file)); };
  const auto segments = [&](const char* from, bool cold) {
    const Path& path = cold ? bench.path() : bench.cache_path();
    for (const bool by_view : {false, true}) {
      if (cold) drop();
      add(Segment::Orbit, by_view, from, bench.play(path.orbit, 0, by_view, false));
      if (cold) drop();
      add(Segment::FlyIn, by_view, from, bench.play(path.fly_in, fly_first, by_view, false));
      if (cold) drop();
      add(Segment::Pause, by_view, from, bench.pause(pause_frame, by_view, false));
    }
  };
  // Warm-up: the renderer's first frames, the GPU's clocks (storage segments
  // drop the file from the page cache first).
  bench.play({bench.path().orbit.begin(), bench.path().orbit.begin() + 2}, 0, true, false);
  if (o.storage) segments("storage, cache dropped", true);
  // Warm: every frame read once, then both reads from the page cache.
  bench.play(bench.path().orbit, 0, false, false);
  segments("page cache", false);
  table.print("Frames through the players' path, full read against reading by the view (the time of a pause is its "
              "refinement's)");
  parts.print("A step's wall time in parts once playing (medians of the steps after the first, ms)");

  print_close_up(bench, reader, o);

  if (o.psnr) {
    Table quality({"segment", "read", "frames", "PSNR worst", "PSNR median", "read per frame"});
    const auto row = [&](Segment s, const Run& r) {
      const double per = r.frames_read ? double(r.bytes_read) / double(r.frames_read) : double(r.bytes_read);
      quality.row({segment_name(s), "by view", std::to_string(r.frames_shown), db_text(r.worst_psnr),
                   db_text(r.median_psnr), mb(per)});
    };
    row(Segment::Orbit, bench.play(bench.path().orbit, 0, true, true));
    row(Segment::FlyIn, bench.play(bench.path().fly_in, fly_first, true, true));
    row(Segment::Pause, bench.pause(pause_frame, true, true));
    quality.print("Quality: each streamed picture against the full read of the same frame and view (not timed)");
  }
}

}  // namespace sluice::bench
