// `sluice bench stream --gpu`: frames from the page cache into the
// renderer's device buffers, decoded by the GPU (the pipeline keeps them
// encoded) and, beside it, by the CPU's workers; the bounds measured in the
// same run: reading the file from the page cache, copying host memory to
// the device, and the GPU decoding a resident frame.
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <deque>
#include <exception>
#include <stdexcept>
#include <thread>

#include "bounds.h"
#include "machine.h"
#include "sluice/bench/stream_bench.h"
#include "sluice/render/gpu_decoder.h"
#include "sluice/render/renderer.h"
#include "sluice/render/staging_allocator.h"
#include "sluice/render/transfer_bound.h"
#include "sluice/runtime/pipeline.h"
#include "stream_slice.h"
#include "sluice/bench/table.h"

namespace sluice::bench {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// What is being measured, on stderr (the tables go to stdout).
void step(const char* what) { std::fprintf(stderr, "  measuring %s ...\n", what); }

// User + system CPU time of this process.
double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

struct DevicePass {
  double seconds = 0, cpu = 0;
  uint64_t frames = 0;
  uint64_t staged_bytes = 0;  // bytes copied to the device over the timed frames
  std::string window;
  double in_place = 0;  // share of the frames read straight into their staged area
  double relayed = 0;   // share of the frames relayed to device memory as read
  double reading = 0;   // share of the timed run with a read in progress
  double read_busy = 0; // share of the read threads' time spent copying
  double waiting_frames = 0;  // share of the timed run the consumer waited for the pipeline
  double waiting_gpu = 0;     // share it waited for the GPU (a copy and decode two frames back)
  uint64_t fresh_blocks = 0;  // staging blocks allocated anew during the timed run
};

struct DeviceSetup {
  int decode_threads = 1, read_threads = 1;
  uint64_t memory = 0;
  int color = -1;  // attribute decoded with the positions (-1: none)
  render::StagingOptions staging;  // .resident: the relayed row
};

// Streams the slice round and round through a pipeline into a renderer's
// device frame buffers for `min_seconds` (after a window of warm-up). Two
// frames in flight on the GPU: a frame goes back to the pipeline once its
// copy (and decode) is done.
constexpr size_t kInFlight = 2;  // frames handed to the renderer and not yet waited for

DevicePass stream_to_device(const io::ContainerReader& reader, const Slice& slice, render::Context& context,
                            const DeviceSetup& setup, bool gpu_decode, bool mapped, double min_seconds) {
  render::StagingAllocator staging(context, setup.staging);
  if (staging.resident()) {
    std::fprintf(stderr, "  the relayed row's ring: %u slots of %.1f MiB in %s, %s\n", staging.ring_slots(),
                 double(staging.ring_piece_bytes()) / (1 << 20),
                 staging.ring_imported() ? "imported anonymous memory" : "the driver's memory",
                 context.relay_queue_shared() ? "sharing the transfer queue (Context::queue_lock)" : "on a queue of its own");
  }
  render::Renderer renderer(context, render::scene_info(reader));
  runtime::PipelineOptions o;
  o.decode.threads = setup.decode_threads;
  o.read.threads = setup.read_threads;
  o.window.budget.memory_cap = setup.memory;
  // Every frame comes through again; at least one more than the frames in
  // flight, or the pipeline has no slot left for the frame awaited.
  o.window.budget.max_frames = static_cast<uint32_t>(std::max<uint64_t>(kInFlight + 1, slice.frames / 2));
  o.window.device_budget = staging.device_budget();
  o.layers = slice.layers;
  o.decode.attributes = setup.color >= 0 ? std::vector<uint32_t>{uint32_t(setup.color)} : std::vector<uint32_t>{};
  o.decode.mode = (gpu_decode) ? sluice::runtime::DecodeMode::KeepEncoded : sluice::runtime::DecodeMode::Cpu;
  o.read.mapped = mapped;
  o.decode.color_attribute = setup.color;
  runtime::Pipeline pipeline(reader, staging, o);
  pipeline.restart({slice.frames, 0, 1, 1, runtime::EndMode::Loop});

  // A small memory cap plans a small window: frames held in flight stay
  // below what the reader may keep ahead, or the next would never come.
  const size_t in_flight = std::clamp<size_t>(pipeline.most_ahead() - 1, 1, kInFlight);
  std::deque<std::pair<runtime::FrameHandle, uint64_t>> flight;
  uint64_t staged = 0;
  double waited_frames = 0, waited_gpu = 0;
  auto consume = [&](uint64_t most, double seconds) {
    const auto start = Clock::now();
    uint64_t n = 0;
    for (; n < most && (seconds <= 0 || seconds_since(start) < seconds); ++n) {
      const auto asked = Clock::now();
      const bool end = pipeline.wait_next().end;
      waited_frames += seconds_since(asked);
      if (end) break;
      runtime::FrameHandle h = pipeline.take();
      if (h.failed()) throw io::Error(h.error()->where, h.error()->message);
      const uint64_t ticket = renderer.commit(render::frame_upload(h, setup.color, &staging));
      const io::GpuDecodePlan* plan = h.gpu_plan();
      staged += plan ? plan->staged_bytes() : h.header().particle_count * (8 + (setup.color >= 0 ? 2 : 0));
      flight.emplace_back(std::move(h), ticket);
      const auto before = Clock::now();
      while (flight.size() > in_flight) {
        renderer.wait_upload(flight.front().second);
        flight.pop_front();
      }
      waited_gpu += seconds_since(before);
    }
    return n;
  };
  consume(pipeline.window(), 0);
  DevicePass p;
  staged = 0;
  waited_frames = waited_gpu = 0;
  const double cpu0 = cpu_seconds();
  const runtime::PipelineStats stats0 = pipeline.stats();
  const uint64_t blocks0 = staging.fresh_allocations();
  const auto start = Clock::now();
  p.frames = consume(UINT64_MAX, min_seconds);
  for (auto& [handle, ticket] : flight) renderer.wait_upload(ticket);  // the last frames arrive too
  p.seconds = seconds_since(start);
  p.cpu = cpu_seconds() - cpu0;
  p.staged_bytes = staged;
  const runtime::PipelineStats stats = pipeline.stats();
  p.window = std::to_string(stats.active_frames) + "/" + std::to_string(stats.window_frames);
  p.in_place = double(stats.frames_in_place) / double(std::max<uint64_t>(stats.frames_read, 1));
  p.relayed = double(stats.frames_relayed) / double(std::max<uint64_t>(stats.frames_read, 1));
  p.reading = (stats.read_seconds - stats0.read_seconds) / p.seconds;
  p.read_busy = (stats.read_thread_seconds - stats0.read_thread_seconds) / (std::max(1u, stats.read_threads) * p.seconds);
  p.fresh_blocks = staging.fresh_allocations() - blocks0;
  p.waiting_frames = waited_frames / p.seconds;
  p.waiting_gpu = waited_gpu / p.seconds;
  if (stats.frames_relayed > stats0.frames_relayed) {
    // The read threads' time on relayed frames by part (runtime::PipelineStats::relay).
    const double read = double(std::max<uint64_t>(stats.frames_read - stats0.frames_read, 1));
    const auto ms = [&](double a, double b) { return 1e3 * (a - b) / read; };
    const runtime::PipelineStats::RelayTimes &t = stats.relay, &t0 = stats0.relay;
    std::fprintf(stderr, "  the relayed row's read threads, ms a frame read: claim %.2f, copy %.2f, check %.2f, plan %.2f, send %.2f\n",
                 ms(t.claim_seconds, t0.claim_seconds), ms(t.copy_seconds, t0.copy_seconds), ms(t.check_seconds, t0.check_seconds),
                 ms(t.plan_seconds, t0.plan_seconds), ms(t.send_seconds, t0.send_seconds));
  }
  flight.clear();
  return p;
}

// The GPU decoding frame 0 of the slice, already resident: median ms of 7.
struct DecodeAlone {
  double ms = 0;
  std::vector<double> pass_ms;
  uint64_t particles = 0;
  io::GpuDecodePlan plan;
};
DecodeAlone gpu_decode_alone(render::Context& context, const io::ContainerReader& reader, const Slice& slice, int color) {
  const std::vector<std::byte> record = reader.read_record(0);
  io::FrameHeader header = reader.parse_record(0, record);
  io::keep_layers(header, slice.layers);
  render::GpuDecoder decoder(context);
  decoder.load(record, header, reader.header(), {.color_attribute = color}, true, reader.location(0));
  // Warm-up: a second of decoding, so the GPU's clocks have risen (after 3
  // warm-up runs the H200 measured 3.81 ms a frame where playback of the
  // same file measured 0.99 ms).
  const auto warm = Clock::now();
  while (seconds_since(warm) < 1.0) (void)decoder.run(10);
  std::vector<double> ms = decoder.run(7);
  if (ms.empty()) throw std::runtime_error("the device has no timestamps: GPU decode alone cannot be timed");
  std::sort(ms.begin(), ms.end());
  return {ms[ms.size() / 2], decoder.last_pass_ms(), header.particle_count, decoder.plan()};
}

// The host -> device copy straight from the file's page-cache pages: a
// read-only mapping of its first `bytes` imported as device-readable memory.
render::ImportedCopy copy_from_mapping(render::Context& context, const std::string& path, uint64_t bytes) {
  const uint64_t alignment = render::import_alignment(context);
  if (alignment == 0) return {false, "the device has no VK_EXT_external_memory_host", 0};
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return {false, "cannot open the file", 0};
  const off_t size = ::lseek(fd, 0, SEEK_END);
  bytes = std::min<uint64_t>(bytes, uint64_t(std::max<off_t>(size, 0))) / alignment * alignment;
  render::ImportedCopy out{false, "the file is smaller than one import granule", 0};
  if (bytes > 0) {
    void* mapped = ::mmap(nullptr, bytes, PROT_READ, MAP_SHARED | MAP_POPULATE, fd, 0);
    if (mapped == MAP_FAILED) {
      out.refusal = "mmap failed";
    } else {
      out = render::imported_host_copy_gbps(context, mapped, bytes, {});
      ::munmap(mapped, bytes);
    }
  }
  ::close(fd);
  return out;
}

// The host -> device copy in every shape the renderer could make it: from
// either kind of staging memory, 1, 2 (the pipeline's two frames in flight)
// or 4 copies queued at once. The bound is the best of them: a single
// copy's figure alone under-reads what the copy engines sustain.
struct CopyGrid {
  static constexpr std::array<int, 3> kDepths{1, 2, 4};
  std::array<double, 3> plain{}, cached{};  // GB/s
  double best = 0;
};

CopyGrid copy_grid(render::Context& context, uint64_t bytes) {
  CopyGrid grid;
  for (size_t k = 0; k < CopyGrid::kDepths.size(); ++k) {
    grid.plain[k] = render::host_to_device_gbps(context, bytes, {CopyGrid::kDepths[k], render::StagingMemory::Plain, 0.3});
    grid.cached[k] = render::host_to_device_gbps(context, bytes, {CopyGrid::kDepths[k], render::StagingMemory::Cached, 0.3});
    grid.best = std::max({grid.best, grid.plain[k], grid.cached[k]});
  }
  return grid;
}

// The pipeline's two streams measured together: the mapped read into a
// window of frame areas on the read threads, and frame-sized host -> device
// copies two in flight, over the same stretch. Each alone reads the host's
// memory; together they share it, which neither bound alone shows.
struct AtOnce {
  double read_gbps = 0, copy_gbps = 0;
};

AtOnce read_and_copy_at_once(render::Context& context, const std::string& path, const Slice& slice, uint64_t frame_bytes,
                             uint64_t copy_bytes, int read_threads, double seconds) {
  AtOnce out;
  std::exception_ptr read_error;  // rethrown here: an exception may not leave a std::thread
  std::thread reader([&] {
    try {
      out.read_gbps = window_read_gbps(path, slice.offset, slice.bytes, frame_bytes, read_threads, true, seconds);
    } catch (...) {
      read_error = std::current_exception();
    }
  });
  try {
    out.copy_gbps = render::host_to_device_gbps(context, copy_bytes, {2, render::StagingMemory::Cached, seconds});
  } catch (...) {
    reader.join();
    throw;
  }
  reader.join();
  if (read_error) std::rethrow_exception(read_error);
  return out;
}

std::string percent(double share) { return fixed(100 * share, 0) + "%"; }

}  // namespace

namespace {

// Beneath the bounds table: the copy by depth, the decode's passes, frame 0's planes.
void print_bound_details(uint64_t copy_bytes, const CopyGrid& copies, const DecodeAlone& alone) {
  std::printf("  host -> device copies of %.1f MB, GB/s by copies queued at once:", double(copy_bytes) / 1e6);
  for (size_t k = 0; k < CopyGrid::kDepths.size(); ++k) {
    std::printf(" %d: %.2f plain, %.2f cached%s", CopyGrid::kDepths[k], copies.plain[k], copies.cached[k],
                k + 1 < CopyGrid::kDepths.size() ? ";" : "\n");
  }
  if (alone.pass_ms.size() == 2) {
    std::printf("  GPU decode passes: tile sums %.3f ms, decode %.3f ms; %zu chunks, %zu tiles\n", alone.pass_ms[0],
                alone.pass_ms[1], alone.plan.chunks.size(), alone.plan.tile_chunk.size());
  }
  std::printf("  frame 0's planes: %llu stored, %llu bit-packed, %llu zstd (inflated on the CPU)\n",
              (unsigned long long)alone.plan.stored_planes, (unsigned long long)alone.plan.packed_planes,
              (unsigned long long)alone.plan.zstd_planes);
}

// The pipeline rows: GPU decoding relayed, mapped, pread; CPU decoding.
struct Way {
  bool gpu, mapped, relayed;
};
constexpr std::array<Way, 4> kWays{Way{true, true, true}, Way{true, true, false}, Way{true, false, false},
                                   Way{false, true, false}};

void print_imported_copy(const render::ImportedCopy& imported, double staged) {
  if (imported.imported) {
    std::printf("  host -> device copy from the file's mapping (page-cache pages imported, no CPU copy): %.2f GB/s, "
                "%.1f frames/s encoded\n", imported.gbps, imported.gbps * 1e9 / staged);
  } else {
    std::printf("  host -> device copy from the file's mapping: not imported: %s\n", imported.refusal.c_str());
  }
}

}  // namespace

void run_stream_gpu_bench(const StreamBenchOptions& o) {
  const io::ContainerReader reader(o.file);
  if (reader.frame_count() == 0) throw io::Error({o.file}, "has no frames to stream");
  if (!io::gpu_decodable(reader.header())) throw io::Error({o.file}, "has float32 positions: the GPU does not decode them");
  render::ContextOptions co;
  co.device = o.device;
  render::Context context(co);
  // The GPU rows run with the pipeline's split for frames kept encoded;
  // the CPU row with its split for decoding (unless either is given).
  const runtime::ThreadSplit split = runtime::default_thread_split(core_count(), runtime::DecodeMode::KeepEncoded);
  const runtime::ThreadSplit cpu_split = runtime::default_thread_split(core_count());
  DeviceSetup setup;
  setup.decode_threads = o.max_threads > 0 ? o.max_threads : split.decode;
  setup.read_threads = o.read_threads > 0 ? o.read_threads : split.read;
  setup.memory = o.memory ? o.memory : uint64_t(2) << 30;
  setup.color = reader.header().attributes.empty() ? -1 : 0;
  const io::LayerSet layers = o.surface ? io::LayerSet::surface() : io::LayerSet::particles();
  const Slice slice = slice_of(reader, o.frames, static_cast<uint64_t>(0.4 * double(runtime::read_host_memory().available())), layers);
  const double in = slice.in_per_frame();
  const double particles = double(slice.particles) / double(slice.frames);

  std::printf("sluice bench stream --gpu: %s%s\n", o.file.c_str(), o.surface ? " (surface and blobs)" : "");
  std::printf("  %llu of %llu frames, %.2f M particles/frame, %.1f MB/frame read%s\n", (unsigned long long)slice.frames,
              (unsigned long long)reader.frame_count(), particles / 1e6, in / 1e6,
              setup.color >= 0 ? (", colour attribute '" + reader.header().attributes[0].name + "'").c_str() : "");
  DeviceSetup cpu_setup = setup;
  cpu_setup.decode_threads = o.max_threads > 0 ? o.max_threads : cpu_split.decode;
  cpu_setup.read_threads = o.read_threads > 0 ? o.read_threads : cpu_split.read;
  std::printf("machine: %s, %d cores; GPU: %s (%s); pipeline: %d workers + %d reading (GPU decoding), %d + %d (CPU "
              "decoding), memory cap %s GB\n",
              cpu_model().c_str(), core_count(), context.device().name.c_str(), context.device().driver.c_str(),
              setup.decode_threads, setup.read_threads, cpu_setup.decode_threads, cpu_setup.read_threads,
              fixed(double(setup.memory) / (1 << 30), 1).c_str());

  // 1. Bounds.
  std::fflush(stdout);
  step("the page-cache read");
  (void)sequential_read_gbps(o.file, slice.offset, slice.bytes, ReadMode::PageCache, 0, setup.read_threads);  // bring it in
  // The page-cache read on `threads` threads, bytes/s; the CPU row's own
  // readers are measured only when they differ from the GPU rows'.
  const auto page_cache_read = [&](int threads) {
    return *sequential_read_gbps(o.file, slice.offset, slice.bytes, ReadMode::PageCache, o.min_seconds, threads) * 1e9;
  };
  const double cached = page_cache_read(setup.read_threads);
  step("the page-cache read into a window of frames");
  const uint64_t frame_bytes = uint64_t(in);
  const double window_pread =
      window_read_gbps(o.file, slice.offset, slice.bytes, frame_bytes, setup.read_threads, false, o.min_seconds) * 1e9;
  const double window_mapped =
      window_read_gbps(o.file, slice.offset, slice.bytes, frame_bytes, setup.read_threads, true, o.min_seconds) * 1e9;
  step("the host -> device copy");
  const uint64_t copy_bytes = std::clamp<uint64_t>(uint64_t(in), 16 << 20, 1024 << 20);  // a frame's copy
  const CopyGrid copies = copy_grid(context, copy_bytes);
  const double h2d = copies.best * 1e9;
  step("the read into the window and the host -> device copy at once");
  const AtOnce at_once = read_and_copy_at_once(context, o.file, slice, uint64_t(in), copy_bytes, setup.read_threads,
                                               o.min_seconds);
  step("the GPU decoding a resident frame");
  const DecodeAlone alone = gpu_decode_alone(context, reader, slice, setup.color);
  const double staged = double(alone.plan.staged_bytes());  // frame 0's, as the GPU path copies it
  const double decoded = particles * (8 + (setup.color >= 0 ? 2 : 0));
  Table bounds({"bound", "GB/s", "frames/s of this file", "what"});
  bounds.row({"pread, page cache, " + std::to_string(setup.read_threads) + " threads", fixed(cached / 1e9, 2),
              fixed(cached / in, 1), "file bytes read into one hot 8 MiB buffer per thread"});
  // The CPU row's own readers, when they differ: its bound.
  const double cached_cpu = cpu_setup.read_threads == setup.read_threads ? cached : page_cache_read(cpu_setup.read_threads);
  if (cpu_setup.read_threads != setup.read_threads) {
    bounds.row({"pread, page cache, " + std::to_string(cpu_setup.read_threads) + " threads (the CPU row's)",
                fixed(cached_cpu / 1e9, 2), fixed(cached_cpu / in, 1), "file bytes read into one hot 8 MiB buffer per thread"});
  }
  bounds.row({"pread into a window of 12 frame areas", fixed(window_pread / 1e9, 2), fixed(window_pread / in, 1),
              "every destination line cold, as in staging"});
  bounds.row({"copy from the file's mapping into the window (streaming stores)", fixed(window_mapped / 1e9, 2),
              fixed(window_mapped / in, 1), "the pipeline's default read"});
  bounds.row({"the mapped read into the window and the copy (2 in flight), at once", fixed(at_once.read_gbps, 2) + " + " +
              fixed(at_once.copy_gbps, 2), fixed(at_once.read_gbps * 1e9 / in, 1) + " read, " +
              fixed(at_once.copy_gbps * 1e9 / staged, 1) + " copied", "both share the host's memory: what the pipeline does"});
  bounds.row({"host -> device copy (transfer queue, the best shape below)", fixed(h2d / 1e9, 2),
              fixed(h2d / staged, 1) + " encoded, " + fixed(h2d / decoded, 1) + " decoded",
              "bytes copied: encoded area, or decoded particles"});
  bounds.row({"GPU decode alone, frame resident", fixed((staged / (alone.ms * 1e-3)) / 1e9, 1), fixed(1e3 / alone.ms, 1),
              fixed(double(alone.particles) / (alone.ms * 1e-3) / 1e9, 1) + " G particles/s (" + fixed(alone.ms, 3) + " ms a frame)"});
  bounds.print("Bounds, measured now");
  print_bound_details(copy_bytes, copies, alone);
  std::fflush(stdout);

  // 2. The pipeline into device memory, GPU decode and CPU decode.
  // The relayed row: the window in device memory, filled through a ring
  // as read (runtime/frame_allocator.h); the others stage the window on the host.
  DeviceSetup relayed_setup = setup;
  relayed_setup.staging.resident = true;
  if (o.ring_slots > 0) relayed_setup.staging.ring_slots = o.ring_slots;
  if (o.ring_piece_bytes > 0) relayed_setup.staging.ring_piece_bytes = o.ring_piece_bytes;
  if (o.ring_imported) relayed_setup.staging.ring_memory = render::RingMemory::Imported;
  std::array<DevicePass, kWays.size()> runs;
  for (size_t w = 0; w < kWays.size(); ++w) {
    step(kWays[w].relayed ? "the pipeline, GPU decoding, relayed" : kWays[w].gpu ? "the pipeline, GPU decoding" : "the pipeline, CPU decoding");
    const DeviceSetup& used = kWays[w].relayed ? relayed_setup : kWays[w].gpu ? setup : cpu_setup;
    runs[w] = stream_to_device(reader, slice, context, used, kWays[w].gpu, kWays[w].mapped, o.min_seconds);
  }

  // 3. The read and the copy bounds again: the machine's memory speed drifts
  // between runs (the H200's page-cache read bound moved from 561.9 to 661.1
  // frames/s between two runs of one call), so each row is measured against
  // the mean of its bounds before and after the rows.
  step("the page-cache read and the host -> device copy again");
  const double cached_after = page_cache_read(setup.read_threads);
  const double cached_cpu_after =
      cpu_setup.read_threads == setup.read_threads ? cached_after : page_cache_read(cpu_setup.read_threads);
  const double h2d_after = copy_grid(context, copy_bytes).best * 1e9;
  std::printf("  measured again after the pipeline rows: pread, page cache, %d threads %.2f GB/s (before %.2f); host -> "
              "device copy %.2f GB/s (before %.2f)\n",
              setup.read_threads, cached_after / 1e9, cached / 1e9, h2d_after / 1e9, h2d / 1e9);
  std::fflush(stdout);
  const double read_bound = (cached + cached_after) / 2, read_bound_cpu = (cached_cpu + cached_cpu_after) / 2;
  const double copy_bound = (h2d + h2d_after) / 2;

  Table passes({"decoded by", "frames/s", "M particles/s", "MB/frame copied", "window", "bound frames/s", "vs bound",
                "limited by", "vs both at once", "CPU ms/frame", "cores busy", "read in place", "relayed", "reading", "read threads copying",
                "new blocks", "waiting for frames", "waiting for the GPU"});
  for (size_t w = 0; w < kWays.size(); ++w) {
    const bool gpu = kWays[w].gpu;
    const DevicePass& p = runs[w];
    const double read_fps = (gpu ? read_bound : read_bound_cpu) / in;
    const double fps = double(p.frames) / p.seconds;
    const double per_frame = double(p.staged_bytes) / double(std::max<uint64_t>(p.frames, 1));
    const double copy_fps = copy_bound / per_frame;
    const double bound = std::min(read_fps, copy_fps);
    const DeviceSetup& used = gpu ? setup : cpu_setup;
    passes.row({std::string(gpu ? "GPU (kept encoded)" : "CPU workers") + (kWays[w].relayed ? ", relayed" : "") +
                    (kWays[w].mapped ? ", mapped" : ", pread") + ", " +
                    std::to_string(used.decode_threads) + " + " + std::to_string(used.read_threads),
                fixed(fps, 1), fixed(fps * particles / 1e6, 1),
                fixed(per_frame / 1e6, 1), p.window, fixed(bound, 1), percent(fps / bound),
                read_fps < copy_fps ? "page-cache read" : "host -> device copy",
                gpu ? percent(fps / std::min(at_once.read_gbps * 1e9 / in, at_once.copy_gbps * 1e9 / per_frame)) : "-",
                fixed(1e3 * p.cpu / double(p.frames), 2),
                fixed(p.cpu / p.seconds, 1), gpu ? percent(p.in_place) : "-", gpu ? percent(p.relayed) : "-", percent(p.reading),
                percent(p.read_busy), std::to_string(p.fresh_blocks), percent(p.waiting_frames),
                percent(p.waiting_gpu)});
  }
  passes.print("Pipeline -> renderer device buffers, page cache, two frames in flight (bound: the slower of reading the "
               "file and copying it to the device, each the mean of its measures before and after the rows)");

  // Last: after NVIDIA 580 refuses the import (ErrorOutOfDeviceMemory), the
  // next device allocation fails too (measured on the H200, 2026-12-03).
  step("the copy from the file's mapping, imported");
  print_imported_copy(copy_from_mapping(context, o.file, copy_bytes), staged);
}

}  // namespace sluice::bench
