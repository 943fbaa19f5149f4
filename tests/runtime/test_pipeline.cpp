// The pipeline on its own: order, completeness, restarts (no stale frame),
// tiny budgets, peak memory, frames kept for reversal, direct I/O, window
// re-evaluation. Frames identify themselves (runtime_test_util.h), so every
// delivered buffer is checked against the frame it claims to be.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <memory>
#include <random>
#include <thread>

#include "runtime_test_util.h"
#include "sluice/error.h"
#include "sluice/io/gpu_decode_plan.h"
#include "sluice/io/gpu_decode_reference.h"
#include "sluice/io/lod.h"
#include "sluice/io/writer.h"
#include "sluice/runtime/pipeline.h"

using namespace sluice;
using namespace sluice::runtime;

namespace {

class PipelineTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TempDir;
    path_ = new std::filesystem::path(test::write_tiny_file(*dir_ / "tiny.sluice", spec_));
  }
  static void TearDownTestSuite() {
    delete path_;
    delete dir_;
  }
  static PipelineOptions options() {
    PipelineOptions o;
    o.decode.threads = 2;
    o.window.budget.memory_cap = 64u << 20;
    return o;
  }
  // Options whose window is planned from `fake`/meminfo alone (no cap, no
  // cgroup), re-read before every frame.
  static PipelineOptions budget_from_fake_meminfo(const test::TempDir& fake) {
    PipelineOptions o = options();
    o.window.budget.memory_cap = 0;
    o.window.budget.max_frames = 0;
    o.window.budget.ring_capacity = 64;
    o.window.budget.host_paths = {(fake / "meminfo").string(), (fake / "none").string(), (fake / "none").string()};
    o.window.reevaluate_every = 1;
    return o;
  }
  // Takes `count` entries (or until the schedule ends) checking each one.
  static std::vector<uint64_t> take_all(Pipeline& p, uint64_t count) {
    std::vector<uint64_t> frames;
    for (uint64_t i = 0; i < count; ++i) {
      const NextEntry next = p.wait_next();
      if (next.end) break;
      EXPECT_EQ(next.status, EntryStatus::Ready);
      FrameHandle h = p.take();
      EXPECT_TRUE(test::holds_frame(h, next.frame, spec_));
      EXPECT_EQ(h.generation(), p.generation());
      EXPECT_EQ(p.schedule().frame_at(h.sequence()), h.frame());
      frames.push_back(h.frame());
    }
    return frames;
  }

  static inline test::TinySpec spec_{};
  static inline test::TempDir* dir_ = nullptr;
  static inline std::filesystem::path* path_ = nullptr;
};

std::vector<uint64_t> expected(const PlaybackSchedule& s, uint64_t count) {
  std::vector<uint64_t> out;
  for (uint64_t k = 0; k < count && s.frame_at(k); ++k) out.push_back(*s.frame_at(k));
  return out;
}

}  // namespace

TEST_F(PipelineTest, DeliversEveryFrameInOrderThenEnds) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  Pipeline p(reader, allocator, options());
  const PlaybackSchedule s{reader.frame_count(), 0, 1, 1, EndMode::Stop};
  p.restart(s);
  EXPECT_EQ(take_all(p, 1000), expected(s, 1000));
  EXPECT_TRUE(p.wait_next().end);
  const PipelineStats st = p.stats();
  EXPECT_EQ(st.frames_delivered, reader.frame_count());
  EXPECT_EQ(st.frames_failed, 0u);
  EXPECT_GT(st.bytes_read, 0u);
  uint64_t worker_bytes = 0;
  for (const WorkerStats& w : st.workers) worker_bytes += w.output_bytes;
  EXPECT_EQ(worker_bytes, st.decoded_bytes);
}

TEST_F(PipelineTest, FollowsReverseLoopBounceAndStride) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  Pipeline p(reader, allocator, options());
  const uint64_t n = reader.frame_count();
  for (const PlaybackSchedule& s : {PlaybackSchedule{n, int64_t(n) - 1, -1, 1, EndMode::Stop},
                                    PlaybackSchedule{n, 50, 1, 1, EndMode::Loop},
                                    PlaybackSchedule{n, 3, -1, 1, EndMode::Bounce},
                                    PlaybackSchedule{n, 10, 1, 7, EndMode::Bounce},
                                    PlaybackSchedule{n, 60, -1, 3, EndMode::Loop}}) {
    p.restart(s);
    EXPECT_EQ(take_all(p, 150), expected(s, 150)) << end_mode_name(s.end) << " from " << s.start;
  }
}

TEST_F(PipelineTest, NoStaleFrameAfterRestart) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  PipelineOptions o = options();
  o.window.budget.max_frames = 12;
  Pipeline p(reader, allocator, o);
  std::mt19937 rng(2024);
  const uint64_t n = reader.frame_count();
  std::vector<FrameHandle> held;  // frames the consumer keeps across restarts
  for (int round = 0; round < 1500; ++round) {
    const PlaybackSchedule s{n, int64_t(rng() % n), rng() % 2 ? 1 : -1, 1 + uint32_t(rng() % 3),
                             static_cast<EndMode>(rng() % 3)};
    const uint64_t g = p.restart(s);
    const int takes = int(rng() % 4);  // often restart again before anything arrives
    for (int t = 0; t < takes; ++t) {
      const NextEntry next = p.wait_next();
      if (next.end) break;
      FrameHandle h = p.take();
      ASSERT_EQ(h.generation(), g) << "a frame of an older schedule was delivered";
      ASSERT_EQ(h.sequence(), uint64_t(t));
      ASSERT_EQ(s.frame_at(h.sequence()), h.frame());
      ASSERT_TRUE(test::holds_frame(h, h.frame(), spec_));
      if (held.size() < 3 && rng() % 4 == 0) held.push_back(std::move(h));
    }
    if (!held.empty() && rng() % 3 == 0) held.erase(held.begin());
  }
  held.clear();
  const PipelineStats st = p.stats();
  EXPECT_EQ(st.frames_failed, 0u);
  EXPECT_GT(st.generation, 1000u);
}

TEST_F(PipelineTest, TwoFrameBudgetStillPlays) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  PipelineOptions o = options();
  const FrameFootprint f = largest_frame(reader, 1, &allocator);
  o.window.budget.memory_cap = 2 * f.decoded_bytes + f.record_bytes;
  std::vector<WindowChange> changes;
  o.window.on_change = [&](const WindowChange& c) { changes.push_back(c); };
  Pipeline p(reader, allocator, o);
  ASSERT_EQ(changes.size(), 1u);
  EXPECT_EQ(changes[0].plan.frames, 2u);
  EXPECT_EQ(changes[0].plan.record_buffers, 1u);
  EXPECT_EQ(p.window(), 2u);
  for (int dir : {1, -1}) {
    const PlaybackSchedule s{reader.frame_count(), dir > 0 ? 0 : int64_t(reader.frame_count()) - 1, dir, 1, EndMode::Stop};
    p.restart(s);
    EXPECT_EQ(take_all(p, 1000), expected(s, 1000));
  }
  EXPECT_LE(allocator.peak_held_bytes() + p.stats().peak_record_bytes, o.window.budget.memory_cap);
}

// A consumer holding every frame the reader may keep ahead gets an error
// from wait_next(), not a wait that never ends; one release and it plays on.
TEST_F(PipelineTest, WaitingWithTheWindowHeldThrows) {
  const io::ContainerReader reader(*path_);
  for (uint32_t window : {2u, 3u, 8u}) {
    HostFrameAllocator allocator;
    PipelineOptions o = options();
    o.window.budget.max_frames = window;
    Pipeline p(reader, allocator, o);
    ASSERT_EQ(p.window(), window);
    p.restart({reader.frame_count(), 0, 1, 1, EndMode::Loop});
    const uint32_t ahead = window - window / 4;
    EXPECT_EQ(p.most_ahead(), ahead);
    std::vector<FrameHandle> held;
    for (uint32_t i = 0; i < ahead; ++i) {
      ASSERT_FALSE(p.wait_next().end);
      held.push_back(p.take());
      ASSERT_TRUE(test::holds_frame(held.back(), i, spec_));
    }
    EXPECT_THROW(p.wait_next(), sluice::runtime::Error) << "window " << window;
    held.erase(held.begin());
    const NextEntry next = p.wait_next();
    ASSERT_EQ(next.status, EntryStatus::Ready) << "window " << window;
    EXPECT_EQ(next.frame, ahead % reader.frame_count());
    held.push_back(p.take());
    EXPECT_THROW(p.wait_next(), sluice::runtime::Error) << "window " << window;
    held.clear();
  }
}

TEST_F(PipelineTest, PeakMemoryStaysWithinTheBudget) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  PipelineOptions o = options();
  const FrameFootprint f = largest_frame(reader, 1, &allocator);
  o.window.budget.memory_cap = 7 * f.decoded_bytes + 3 * f.record_bytes;
  Pipeline p(reader, allocator, o);
  EXPECT_EQ(p.window(), 7u);
  std::mt19937 rng(99);
  const uint64_t n = reader.frame_count();
  for (int round = 0; round < 200; ++round) {
    const PlaybackSchedule s{n, int64_t(rng() % n), rng() % 2 ? 1 : -1, 1, EndMode::Loop};
    p.restart(s);
    const auto got = take_all(p, rng() % 20);
    ASSERT_EQ(got, expected(s, got.size()));
    ASSERT_LE(allocator.held_bytes() + p.stats().peak_record_bytes, o.window.budget.memory_cap);
  }
  EXPECT_LE(allocator.peak_held_bytes() + p.stats().peak_record_bytes, o.window.budget.memory_cap)
      << "decoded buffers peaked at " << allocator.peak_held_bytes() << ", records at " << p.stats().peak_record_bytes;
  EXPECT_GT(allocator.peak_held_bytes(), 3 * f.decoded_bytes) << "the window was used, not just the minimum";
}

TEST_F(PipelineTest, FramesBehindThePlayheadServeAReversal) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  PipelineOptions o = options();
  o.window.budget.max_frames = 16;  // 4 kept behind
  o.window.slow_start = false;      // the whole window at once (this consumer never lets decoding idle)
  Pipeline p(reader, allocator, o);
  const uint64_t n = reader.frame_count();
  p.restart({n, 0, 1, 1, EndMode::Stop});
  EXPECT_EQ(take_all(p, 20).back(), 19u);
  const uint64_t before = p.stats().cache_hits;
  const PlaybackSchedule back{n, 18, -1, 1, EndMode::Stop};
  p.restart(back);
  EXPECT_EQ(take_all(p, 6), expected(back, 6));
  EXPECT_GE(p.stats().cache_hits - before, 3u) << "frames just shown should come from memory, not from disk";
}

TEST_F(PipelineTest, SlowStartUsesAFewSlotsFirst) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  PipelineOptions o = options();
  o.window.budget.max_frames = 16;
  Pipeline slow(reader, allocator, o);
  EXPECT_EQ(slow.stats().window_frames, 16u);
  EXPECT_EQ(slow.stats().active_frames, 4u) << "two decode workers + 2";
  o.window.slow_start = false;
  Pipeline eager(reader, allocator, o);
  EXPECT_EQ(eager.stats().active_frames, 16u);
}

TEST_F(PipelineTest, DecodesOnlyTheAttributesAskedFor) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  PipelineOptions o = options();
  o.decode.attributes = std::vector<uint32_t>{};
  Pipeline p(reader, allocator, o);
  p.restart({reader.frame_count(), 5, 1, 1, EndMode::Stop});
  ASSERT_EQ(p.wait_next().status, EntryStatus::Ready);
  const FrameHandle h = p.take();
  EXPECT_EQ(h.layout().attribute_streams, 0u);
  EXPECT_TRUE(h.buffers().attributes.empty());
  EXPECT_TRUE(test::holds_frame(h, 5, spec_));

  o.decode.attributes = std::vector<uint32_t>{1};
  EXPECT_THROW(Pipeline(reader, allocator, o), io::Error);
}

// Read time counts a read still in flight: taken while a read waits at a
// gate, stats() already shows the time since it began. (It used to count a
// stretch only once every read had ended, so with reads always in flight it
// showed next to nothing.)
TEST_F(PipelineTest, ReadTimeCountsAReadStillInFlight) {
  const io::ContainerReader reader(*path_);
  auto gate = std::make_shared<test::GatedSource>(
      std::make_shared<FileRecordSource>(reader.path(), reader.descriptor(), false), 0);  // nothing passes
  const test::OpenAtExit open_gate{*gate};
  HostFrameAllocator allocator;
  PipelineOptions o = options();
  o.read.source = gate;
  Pipeline p(reader, allocator, o);
  p.restart({reader.frame_count(), 0, 1, 1, EndMode::Stop});
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (gate->waiting() == 0 && std::chrono::steady_clock::now() < deadline) std::this_thread::yield();
  ASSERT_GT(gate->waiting(), 0u) << "no read reached the gate in 30 s";
  const auto waited = std::chrono::milliseconds(50);
  std::this_thread::sleep_for(waited);  // at least this long; the read began before it
  EXPECT_GE(p.stats().read_seconds, 0.05);
  gate->open();
  EXPECT_EQ(p.wait_next().status, EntryStatus::Ready);
}

// Kept encoded for a GPU decoder: the staged area, decoded from its plan
// (io::decode_plan_on_cpu, the kernels' reference), is the frame the
// workers decode otherwise, bit for bit. Returns the pipeline's stats.
PipelineStats expect_kept_encoded_frames_decode_the_same(const std::filesystem::path& path) {
  const io::ContainerReader reader(path);
  EXPECT_TRUE(io::gpu_decodable(reader.header()));
  HostFrameAllocator decoded_memory, encoded_memory;
  PipelineOptions o;
  o.decode.threads = 2;
  o.decode.attributes = std::vector<uint32_t>{0};
  Pipeline decoded(reader, decoded_memory, o);
  o.decode.mode = sluice::runtime::DecodeMode::KeepEncoded;
  o.decode.color_attribute = 0;
  Pipeline encoded(reader, encoded_memory, o);
  const PlaybackSchedule s{reader.frame_count(), 0, 1, 1, EndMode::Stop};
  decoded.restart(s);
  encoded.restart(s);
  for (uint64_t f = 0; f < reader.frame_count(); ++f) {
    EXPECT_EQ(decoded.wait_next().status, EntryStatus::Ready);
    EXPECT_EQ(encoded.wait_next().status, EntryStatus::Ready);
    const FrameHandle d = decoded.take(), e = encoded.take();
    EXPECT_EQ(d.gpu_plan(), nullptr);
    EXPECT_EQ(d.content(), FrameContent::Decoded);
    EXPECT_EQ(e.content(), FrameContent::Encoded);
    const io::GpuDecodePlan* plan = e.gpu_plan();
    if (!plan) {
      ADD_FAILURE() << "frame " << f << " has no plan";
      break;
    }
    EXPECT_TRUE(e.buffers().attributes.empty());
    if (e.buffers().particles.size() < plan->staged_bytes()) {
      ADD_FAILURE() << "frame " << f << ": the staged area is smaller than its plan";
      break;
    }
    const uint64_t n = d.layout().particles;
    std::vector<uint64_t> particles(n);
    std::vector<uint16_t> attribute(n);
    io::decode_plan_on_cpu(e.buffers().particles.first(plan->staged_bytes()), *plan, particles, attribute);
    EXPECT_EQ(std::memcmp(particles.data(), d.buffers().particles.data(), n * 8), 0) << "frame " << f;
    EXPECT_EQ(std::memcmp(attribute.data(), d.buffers().attributes[0].data(), n * 2), 0) << "frame " << f;
  }
  EXPECT_TRUE(encoded.wait_next().end);
  EXPECT_EQ(encoded.stats().frames_failed, 0u);
  return encoded.stats();
}

// The default file: small planes are bit-packed, so its frames are read in
// place too.
TEST_F(PipelineTest, KeptEncodedFramesDecodeToTheSameParticles) {
  const PipelineStats stats = expect_kept_encoded_frames_decode_the_same(*path_);
  EXPECT_EQ(stats.frames_read, spec_.frames);
}

// Planes in zstd wherever it is smaller: frames read into an area sized for
// the record alone move to a larger one for the planes inflated there.
TEST_F(PipelineTest, KeptEncodedFramesWithZstdPlanesMoveToALargerArea) {
  test::TinySpec spec{.frames = 4, .particles = 20000, .chunk = 4096};  // planes larger than the area's rounding
  spec.planes = io::PlaneCoding::Zstd;
  const auto path = test::write_tiny_file(*dir_ / "zstd.sluice", spec);
  const PipelineStats stats = expect_kept_encoded_frames_decode_the_same(path);
  EXPECT_EQ(stats.frames_read, spec.frames);
  EXPECT_LT(stats.frames_in_place, spec.frames);
}

// A GPU-decodable file: every record is read straight into its staged area
// and staged there.
TEST_F(PipelineTest, GpuDecodableFramesAreReadInPlace) {
  test::TinySpec spec = spec_;
  spec.planes = io::PlaneCoding::GpuDecodable;
  const auto path = test::write_tiny_file(*dir_ / "gpu.sluice", spec);
  const PipelineStats stats = expect_kept_encoded_frames_decode_the_same(path);
  EXPECT_EQ(stats.frames_in_place, spec.frames);
}

TEST_F(PipelineTest, ReadsPiecesOfARecordInParallel) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  PipelineOptions o = options();
  o.read.threads = 3;
  o.read.piece_bytes = 256;  // several pieces per (tiny) record
  Pipeline p(reader, allocator, o);
  EXPECT_NE(p.io_mode().find("3 read threads"), std::string::npos) << p.io_mode();
  std::mt19937 rng(5);
  for (int round = 0; round < 50; ++round) {
    const PlaybackSchedule s{reader.frame_count(), int64_t(rng() % reader.frame_count()), rng() % 2 ? 1 : -1, 1,
                             EndMode::Loop};
    p.restart(s);
    EXPECT_EQ(take_all(p, 40), expected(s, 40));
  }
}

TEST_F(PipelineTest, DirectIoReadsTheSameFrames) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  PipelineOptions o = options();
  o.read.direct_io = true;
  Pipeline p(reader, allocator, o);
  const PlaybackSchedule s{reader.frame_count(), 0, 1, 1, EndMode::Stop};
  p.restart(s);
  EXPECT_EQ(take_all(p, 1000), expected(s, 1000));
  const std::string mode = p.io_mode();
  EXPECT_TRUE(mode == "pread, O_DIRECT" || mode.find("O_DIRECT refused") != std::string::npos) << mode;
}

TEST_F(PipelineTest, FallsBackWhenTheFilesystemRefusesDirectIo) {
  // tmpfs refuses O_DIRECT at open; use it where there is one.
  const std::filesystem::path shm = "/dev/shm";
  std::error_code ec;
  if (!std::filesystem::is_directory(shm, ec)) GTEST_SKIP() << "no /dev/shm";
  const auto copy = shm / ("sluice-rt-" + std::to_string(::getpid()) + ".sluice");
  std::filesystem::copy_file(*path_, copy, std::filesystem::copy_options::overwrite_existing, ec);
  if (ec) GTEST_SKIP() << "cannot write /dev/shm: " << ec.message();
  {
    const io::ContainerReader reader(copy);
    FileRecordSource probe(reader.path(), reader.descriptor(), true);
    if (probe.direct()) {
      std::filesystem::remove(copy);
      GTEST_SKIP() << "/dev/shm accepts O_DIRECT here";
    }
    HostFrameAllocator allocator;
    PipelineOptions o = options();
    o.read.direct_io = true;
    Pipeline p(reader, allocator, o);
    const PlaybackSchedule s{reader.frame_count(), 0, 1, 1, EndMode::Stop};
    p.restart(s);
    EXPECT_EQ(take_all(p, 1000), expected(s, 1000));
    EXPECT_NE(p.io_mode().find("O_DIRECT refused"), std::string::npos) << p.io_mode();
  }
  std::filesystem::remove(copy);
}

TEST_F(PipelineTest, WindowFollowsAvailableMemoryWhilePlaying) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  test::TempDir fake;
  PipelineOptions o = budget_from_fake_meminfo(fake);
  const FrameFootprint f = largest_frame(reader, 1, &allocator);
  const uint64_t plenty = 2 * (40 * f.decoded_bytes + 4 * f.record_bytes);  // host fraction 0.5 -> ~40 frames
  test::write_text_file(fake / "meminfo", "MemAvailable: " + std::to_string(plenty / 1024) + " kB\n");
  // The fake MemAvailable does not drop as the pipeline allocates, so the
  // window may first grow a little; what matters is that it follows the drop.
  std::atomic<uint32_t> smallest{~0u};
  o.window.on_change = [&](const WindowChange& c) { smallest = std::min(smallest.load(), c.plan.frames); };
  Pipeline p(reader, allocator, o);
  const uint32_t first = p.window();
  EXPECT_GE(first, 30u);
  p.restart({reader.frame_count(), 0, 1, 1, EndMode::Loop});
  take_all(p, 10);
  test::write_text_file(fake / "meminfo", "MemAvailable: " + std::to_string(plenty / 1024 / 8) + " kB\n");
  for (int i = 0; i < 5000 && smallest.load() >= first; ++i) take_all(p, 1);
  EXPECT_LT(smallest.load(), first) << "the window did not follow available memory while playing";
  EXPECT_LT(p.window(), first);
  take_all(p, 100);  // and it still plays
}

// The buffers the allocator keeps follow the window both ways: a smaller
// window gives its memory back, a larger one takes it again, and blocks the
// allocator keeps count as the pipeline's own when it plans.
TEST_F(PipelineTest, HeldMemoryFollowsTheWindowDownAndUp) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  test::TempDir fake;
  PipelineOptions o = budget_from_fake_meminfo(fake);
  o.window.slow_start = false;  // the whole window at once: held memory is the window
  const FrameFootprint f = largest_frame(reader, 1, &allocator);
  const uint64_t plenty = 2 * (40 * f.decoded_bytes + 4 * f.record_bytes);  // ~40 frames
  const auto set_available = [&](uint64_t bytes) {
    test::write_text_file(fake / "meminfo", "MemAvailable: " + std::to_string(bytes / 1024) + " kB\n");
  };
  // Plays until `done()` or a bound, taking frames (the window re-plans every frame).
  const auto play_until = [&](Pipeline& p, auto done) {
    for (int i = 0; i < 3000 && !done(); ++i) take_all(p, 1);
  };
  // A window as large as the file (one slot per frame), less one in flight.
  const uint64_t many = (std::min<uint64_t>(reader.frame_count(), 40) - 1) * f.decoded_bytes;
  ASSERT_GE(reader.frame_count(), 12u);
  set_available(plenty);
  Pipeline p(reader, allocator, o);
  p.restart({reader.frame_count(), 0, 1, 1, EndMode::Loop});
  play_until(p, [&] { return allocator.held_bytes() >= many; });
  ASSERT_GE(allocator.held_bytes(), many) << "a large window holds many frames; window " << p.window() << ", frames " << reader.frame_count() << ", in use " << allocator.in_use_buffers();

  // A tenth of the memory: the window shrinks and the memory held with it.
  set_available(plenty / 10);
  play_until(p, [&] { return p.window() <= 6 && allocator.held_bytes() <= (p.window() + 1) * f.decoded_bytes; });
  EXPECT_LE(p.window(), 6u);
  EXPECT_LE(allocator.held_bytes(), (p.window() + 1) * f.decoded_bytes)
      << "held " << allocator.held_bytes() << " bytes for a window of " << p.window() << " frames of "
      << f.decoded_bytes;

  // Plenty again: the window grows back and takes memory again.
  set_available(plenty);
  play_until(p, [&] { return allocator.held_bytes() >= many; });
  EXPECT_GE(allocator.held_bytes(), many);
  take_all(p, 50);  // and it still plays
}

TEST_F(PipelineTest, RejectsSchedulesOutsideTheFile) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  Pipeline p(reader, allocator, options());
  EXPECT_THROW(p.restart({reader.frame_count() + 1, 0, 1, 1, EndMode::Loop}), sluice::runtime::Error);
  EXPECT_THROW(p.restart({reader.frame_count(), 0, 1, 0, EndMode::Loop}), sluice::runtime::Error);
  EXPECT_THROW(p.restart({reader.frame_count(), 0, 2, 1, EndMode::Loop}), sluice::runtime::Error);
  // A loop over the first frames only is fine.
  const PlaybackSchedule prefix{5, 3, 1, 1, EndMode::Loop};
  p.restart(prefix);
  EXPECT_EQ(take_all(p, 7), (std::vector<uint64_t>{3, 4, 0, 1, 2, 3, 4}));
}

TEST(ThreadSplit, OneReaderPerFourCoresFromEightCoresOn) {
  // Below 8 cores every core decodes and one reader comes on top.
  EXPECT_EQ(default_thread_split(1).decode, 1);
  EXPECT_EQ(default_thread_split(2).decode, 2);
  EXPECT_EQ(default_thread_split(2).read, 1);
  EXPECT_EQ(default_thread_split(4).read, 1);
  // From 8 cores the readers come out of the cores: 6 + 2, 12 + 4, at most 4 readers.
  EXPECT_EQ(default_thread_split(8).decode, 6);
  EXPECT_EQ(default_thread_split(8).read, 2);
  EXPECT_EQ(default_thread_split(16).decode, 12);
  EXPECT_EQ(default_thread_split(16).read, 4);
  EXPECT_EQ(default_thread_split(64).decode, 60);
  EXPECT_EQ(default_thread_split(64).read, 4);
}

TEST(ThreadSplit, WorldFramesTakeOneReaderPerEightCores) {
  // Their workers convert every chunk to float arrays as well: half as many readers.
  EXPECT_EQ(default_thread_split(2, DecodeMode::World).read, 1);
  EXPECT_EQ(default_thread_split(2, DecodeMode::World).decode, 2);
  EXPECT_EQ(default_thread_split(8, DecodeMode::World).read, 1);
  EXPECT_EQ(default_thread_split(8, DecodeMode::World).decode, 7);
  EXPECT_EQ(default_thread_split(16, DecodeMode::World).read, 2);
  EXPECT_EQ(default_thread_split(16, DecodeMode::World).decode, 14);
  EXPECT_EQ(default_thread_split(64, DecodeMode::World).read, 4);
  EXPECT_EQ(default_thread_split(64, DecodeMode::World).decode, 60);
}

TEST(ThreadSplit, FramesKeptEncodedReadOnThirteenSixteenthsOfTheCores) {
  // The reads check the chunks; the workers only inflate zstd planes:
  // thirteen sixteenths of the cores read, 1 to 13.
  EXPECT_EQ(default_thread_split(1, DecodeMode::KeepEncoded).read, 1);
  EXPECT_EQ(default_thread_split(1, DecodeMode::KeepEncoded).decode, 1);
  EXPECT_EQ(default_thread_split(2, DecodeMode::KeepEncoded).read, 1);
  EXPECT_EQ(default_thread_split(2, DecodeMode::KeepEncoded).decode, 1);
  EXPECT_EQ(default_thread_split(8, DecodeMode::KeepEncoded).read, 6);
  EXPECT_EQ(default_thread_split(8, DecodeMode::KeepEncoded).decode, 2);
  EXPECT_EQ(default_thread_split(16, DecodeMode::KeepEncoded).read, 13);
  EXPECT_EQ(default_thread_split(16, DecodeMode::KeepEncoded).decode, 3);
  EXPECT_EQ(default_thread_split(64, DecodeMode::KeepEncoded).read, 13);
  EXPECT_EQ(default_thread_split(64, DecodeMode::KeepEncoded).decode, 51);
}

// A file with the narrow band's layers: with the surface set the pipeline
// reads each record only up to its last blob payload, and delivers exactly
// the surface and blob chunks, decoded as decode_frame decodes them.
TEST(PipelineLayers, SurfaceSetReadsThePrefixAndDeliversSurfaceAndBlobs) {
  test::TempDir dir;
  io::FileHeader h;
  h.particle_spacing = 0.01f;
  const auto path = dir / "layered.sluice";
  {
    io::ContainerWriter w(path, h);
    for (int f = 0; f < 6; ++f) {
      std::vector<float> xyz;
      for (int k = 0; k < 16; ++k)
        for (int j = 0; j < 16; ++j)
          for (int i = 0; i < 16 + f; ++i) xyz.insert(xyz.end(), {0.01f * float(i), 0.01f * float(j), 0.01f * float(k)});
      const std::vector<uint16_t> lod = io::lod_values({}, xyz.size() / 3);
      io::FrameInput in;
      in.positions = xyz;
      in.lod = lod;
      io::EncodeOptions o;
      o.chunk_particles = 300;
      o.layers = true;
      w.append(io::encode_frame(in, h, o));
    }
    w.finish();
  }
  const io::ContainerReader reader(path);
  uint64_t prefix_bytes = 0, whole_bytes = 0;
  for (uint64_t f = 0; f < reader.frame_count(); ++f) {
    ASSERT_TRUE(reader.index().frames[f].layered());
    prefix_bytes += io::layers_end(reader.read_table(f), io::LayerSet::surface(), 0);
    whole_bytes += reader.index().frames[f].bytes;
  }
  ASSERT_LT(prefix_bytes, whole_bytes);
  // One read thread reads in order; three read two records at once, a
  // prefix's table on the reader thread while the crew copies the record
  // before it.
  for (const auto& [surface, read_threads] : {std::pair{true, 1}, {false, 1}, {true, 3}, {false, 3}}) {
    SCOPED_TRACE(testing::Message() << (surface ? "surface" : "every particle") << ", " << read_threads << " read threads");
    HostFrameAllocator allocator;
    PipelineOptions o;
    o.decode.threads = 2;
    o.read.threads = read_threads;
    o.window.budget.max_frames = 3;
    o.layers = surface ? io::LayerSet::surface() : io::LayerSet::particles();
    Pipeline p(reader, allocator, o);
    p.restart({reader.frame_count(), 0, 1, 1, EndMode::Stop});
    for (uint64_t f = 0; f < reader.frame_count(); ++f) {
      const NextEntry next = p.wait_next();
      ASSERT_EQ(next.status, EntryStatus::Ready);
      FrameHandle got = p.take();
      const io::DecodedFrame want = io::decode_frame(reader, f, o.layers);
      ASSERT_EQ(got.header().chunks.size(), want.header.chunks.size());
      ASSERT_EQ(got.header().particle_count, want.header.particle_count);
      for (size_t c = 0; c < want.header.chunks.size(); ++c) {
        EXPECT_EQ(got.header().chunks[c].layer, want.header.chunks[c].layer);
        EXPECT_NE(got.header().chunks[c].layer, surface ? io::Layer::Interior : io::Layer::Blobs);
      }
      EXPECT_TRUE(std::equal(want.particles.begin(), want.particles.end(), got.buffers().particles.begin()));
    }
    const PipelineStats st = p.stats();
    EXPECT_EQ(st.frames_failed, 0u);
    // Surface: the prefixes (table included, no alignment: buffered reads). All: every
    // record is read whole (the blobs lie between the surface and the interior).
    EXPECT_EQ(st.bytes_read, surface ? prefix_bytes : whole_bytes);
  }
}
