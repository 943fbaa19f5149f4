// The pipeline's relayed reads (runtime/frame_allocator.h) with the relay in host
// memory: areas that stand where device memory would, filled by memcpy from
// a ring of slots, several read threads at once. What the pipeline hands
// over (the areas as filled, the plans made chunk by chunk as read) must
// decode to the particles the CPU decoder writes, bit for bit. Runs under
// ThreadSanitizer with the rest of the runtime's tests; the GPU's ring is
// tested by the renderer's StreamedUpload.Relayed* tests.
#include <gtest/gtest.h>

#include <condition_variable>
#include <cstring>
#include <deque>
#include <map>
#include <mutex>
#include <random>

#include "demand_test_util.h"
#include "runtime_test_util.h"
#include "sluice/io/gpu_decode_plan.h"
#include "sluice/io/gpu_decode_reference.h"
#include "sluice/runtime/pipeline.h"
#include "sluice/runtime/frame_allocator.h"

namespace sluice::runtime {
namespace {

class HostRelay final : public FrameAllocator, public PieceRelay {
 public:
  HostRelay(uint32_t slots, uint64_t piece) : piece_(piece), ring_(size_t(slots) * piece) {
    for (uint32_t s = 0; s < slots; ++s) free_.push_back(s);
  }

  // FrameAllocator: resident frames only (the pipeline never asks for others
  // of a GPU-decodable file read in place).
  FrameBuffers allocate(const FrameLayout& layout) override {
    EXPECT_TRUE(layout.resident);
    const std::lock_guard lock(mutex_);
    const uint64_t tag = ++next_tag_;
    areas_[tag].assign(layout.encoded_bytes, std::byte{0});
    FrameBuffers out;
    out.tag = tag;
    return out;
  }
  void release(FrameBuffers& buffers) override {
    const std::lock_guard lock(mutex_);
    areas_.erase(buffers.tag);
    buffers = {};
  }
  PieceRelay* relay() override { return this; }

  // PieceRelay.
  uint64_t piece_bytes() const override { return piece_; }
  std::span<std::byte> claim(uint64_t bytes) override {
    EXPECT_LE(bytes, piece_);
    std::unique_lock lock(mutex_);
    freed_.wait(lock, [&] { return !free_.empty(); });
    const uint32_t s = free_.front();
    free_.pop_front();
    ++claimed_;
    return {ring_.data() + s * piece_, bytes};
  }
  void send(std::span<std::byte> piece, const FrameBuffers& frame, std::span<const Range> ranges) override {
    const std::lock_guard lock(mutex_);
    std::vector<std::byte>& area = areas_.at(frame.tag);
    for (const Range& r : ranges) {
      EXPECT_LE(r.from + r.bytes, piece.size());
      EXPECT_LE(r.to + r.bytes, area.size());
      std::memcpy(area.data() + r.to, piece.data() + r.from, r.bytes);
    }
    ++sent_;
    put_back(piece);
  }
  void give_back(std::span<std::byte> piece) override {
    const std::lock_guard lock(mutex_);
    put_back(piece);
  }

  std::vector<std::byte> area(uint64_t tag) {
    const std::lock_guard lock(mutex_);
    return areas_.at(tag);
  }
  uint64_t sent() {
    const std::lock_guard lock(mutex_);
    return sent_;
  }

 private:
  void put_back(std::span<std::byte> piece) {  // mutex_ held
    free_.push_back(uint32_t((piece.data() - ring_.data()) / ptrdiff_t(piece_)));
    freed_.notify_one();
  }

  uint64_t piece_;
  std::vector<std::byte> ring_;
  std::mutex mutex_;
  std::condition_variable freed_;
  std::deque<uint32_t> free_;
  std::map<uint64_t, std::vector<std::byte>> areas_;
  uint64_t next_tag_ = 0, claimed_ = 0, sent_ = 0;
};

// Frames relayed through `relay` by `read_threads`, against the CPU
// decoder's frames, bit for bit (particles and the colour attribute), both
// read under `demand`.
PipelineStats expect_relayed_frames_decode_the_same(const std::filesystem::path& path, HostRelay& relay, int read_threads,
                                                    const ViewDemand& demand = {}, int rounds = 2) {
  const io::ContainerReader reader(path);
  HostFrameAllocator decoded_memory;
  PipelineOptions o;
  o.decode.threads = 2;
  o.read.threads = read_threads;
  o.read.rounds = rounds;
  o.demand = demand;
  const bool coloured = !reader.header().attributes.empty();
  if (coloured) o.decode.attributes = std::vector<uint32_t>{0};
  Pipeline decoded(reader, decoded_memory, o);
  o.decode.mode = sluice::runtime::DecodeMode::KeepEncoded;
  if (coloured) o.decode.color_attribute = 0;
  Pipeline relayed(reader, relay, o);
  const PlaybackSchedule s{reader.frame_count(), 0, 1, 1, EndMode::Stop};
  decoded.restart(s);
  relayed.restart(s);
  for (uint64_t f = 0; f < reader.frame_count(); ++f) {
    EXPECT_EQ(decoded.wait_next().status, EntryStatus::Ready);
    relayed.wait_next();
    const FrameHandle d = decoded.take(), e = relayed.take();
    if (e.failed()) {
      ADD_FAILURE() << e.error()->text();
      break;
    }
    const io::GpuDecodePlan* plan = e.gpu_plan();
    EXPECT_TRUE(e.layout().resident);
    EXPECT_EQ(e.content(), FrameContent::Relayed);
    EXPECT_TRUE(e.buffers().particles.empty());
    const std::vector<std::byte> area = relay.area(e.buffers().tag);
    if (!plan || area.size() < plan->encoded_bytes()) {
      ADD_FAILURE() << "frame " << f << ": no plan, or an area smaller than it";
      break;
    }
    const uint64_t n = d.layout().particles;
    std::vector<uint64_t> particles(n);
    std::vector<uint16_t> attribute(n);
    io::decode_plan_on_cpu(area, *plan, particles, attribute);
    EXPECT_EQ(std::memcmp(particles.data(), d.buffers().particles.data(), n * 8), 0) << "frame " << f;
    if (coloured) {
      EXPECT_EQ(std::memcmp(attribute.data(), d.buffers().attributes[0].data(), n * 2), 0) << "frame " << f;
    }
  }
  EXPECT_TRUE(relayed.wait_next().end);
  return relayed.stats();
}

class RelayTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TempDir;
    test::TinySpec spec{.frames = 12, .particles = 3000, .chunk = 256};
    spec.planes = io::PlaneCoding::GpuDecodable;
    path_ = new std::filesystem::path(test::write_tiny_file(*dir_ / "gpu.sluice", spec));
  }
  static void TearDownTestSuite() {
    delete path_;
    delete dir_;
  }
  static test::TempDir* dir_;
  static std::filesystem::path* path_;
};
test::TempDir* RelayTest::dir_ = nullptr;
std::filesystem::path* RelayTest::path_ = nullptr;

TEST_F(RelayTest, RelayedFramesDecodeToTheSameParticles) {
  HostRelay relay(8, 64 << 10);
  const PipelineStats stats = expect_relayed_frames_decode_the_same(*path_, relay, 3);
  EXPECT_EQ(stats.frames_relayed, 12u);
  EXPECT_EQ(stats.frames_failed, 0u);
  EXPECT_GE(relay.sent(), 12u);
  // The read threads' time on them is accounted by part: every relayed
  // record is copied (checked as copied here: whole frames) and planned.
  EXPECT_GT(stats.relay.copy_seconds, 0.0);
  EXPECT_GT(stats.relay.plan_seconds, 0.0);
  EXPECT_GT(stats.relay.send_seconds, 0.0);
  EXPECT_EQ(stats.relay.check_seconds, 0.0) << "whole frames are checked as they are copied, not apart";
}

// Four frames read at once (ReadSettings::rounds), whole and by a view's
// demand: the same particles as the CPU decoder's.
TEST_F(RelayTest, FourFramesReadAtOnceDecodeToTheSameParticles) {
  HostRelay whole(8, 64 << 10);
  EXPECT_EQ(expect_relayed_frames_decode_the_same(*path_, whole, 3, {}, 4).frames_relayed, 12u);
  const auto path = test::write_scattered(*dir_ / "scattered4.sluice", 6, 200000, io::kFormatMajor, io::PlaneCoding::GpuDecodable);
  HostRelay by_view(8, 4 << 20);
  const ViewDemand close = test::demand_of({0.3f, 0.2f, 0.15f}, {-1.0f, -0.5f, 0.15f}, 1.0f);
  const PipelineStats stats = expect_relayed_frames_decode_the_same(path, by_view, 2, close, 4);
  EXPECT_EQ(stats.frames_by_demand, 6u);
  EXPECT_EQ(stats.frames_failed, 0u);
}

// Fewer slots than read threads, and slots smaller than a chunk: threads
// wait for slots, and chunks go whole through a thread's own buffer in parts.
TEST_F(RelayTest, FewSmallSlotsStillDeliverEveryFrame) {
  HostRelay relay(2, 512);
  const PipelineStats stats = expect_relayed_frames_decode_the_same(*path_, relay, 4);
  EXPECT_EQ(stats.frames_relayed, 12u);
  EXPECT_GT(relay.sent(), 12u * 4);
}

// A close view's demand reads runs that lie apart in the frame (its cells'
// tiers, format 2.0): a ring slot takes as many of them as fit, each read
// on its own, and goes in one send.
TEST_F(RelayTest, AViewsRunsShareRingSlots) {
  const auto path = test::write_scattered(*dir_ / "scattered.sluice", 4, 200000, io::kFormatMajor, io::PlaneCoding::GpuDecodable);
  HostRelay relay(8, 4 << 20);
  // From inside the block, looking out at one corner: the cells behind are left out.
  const ViewDemand close = test::demand_of({0.3f, 0.2f, 0.15f}, {-1.0f, -0.5f, 0.15f}, 1.0f);
  const PipelineStats stats = expect_relayed_frames_decode_the_same(path, relay, 2, close);
  EXPECT_EQ(stats.frames_relayed, 4u);
  EXPECT_EQ(stats.frames_by_demand, 4u);
  EXPECT_LT(stats.bytes_read, stats.record_bytes) << "the view leaves cells out";
  EXPECT_GT(stats.runs_read, 4u * 2) << "the runs lie apart";
  EXPECT_LT(relay.sent(), stats.runs_read) << "several runs go in one send";
  EXPECT_GT(stats.relay.check_seconds, 0.0) << "by demand, records are checked after their run is read";
}

// A relay whose allocator also hands out host areas (what a frame read
// again on the host needs), as the renderer's StagingAllocator does.
class HostRelayWithHostAreas final : public FrameAllocator {
 public:
  explicit HostRelayWithHostAreas(HostRelay& relay) : relay_(relay) {}
  FrameBuffers allocate(const FrameLayout& layout) override {
    if (layout.resident) return relay_.allocate(layout);
    FrameBuffers b = host_.allocate(layout);
    b.tag |= uint64_t(1) << 63;  // host, not an area
    return b;
  }
  void release(FrameBuffers& buffers) override {
    if (buffers.tag >> 63) {
      buffers.tag &= ~(uint64_t(1) << 63);
      host_.release(buffers);
    } else {
      relay_.release(buffers);
    }
  }
  PieceRelay* relay() override { return &relay_; }

 private:
  HostRelay& relay_;
  HostFrameAllocator host_;
};

// Zstd planes: the first frame relayed meets one and is read again into a
// host area, and no later frame is relayed.
TEST_F(RelayTest, ZstdPlanesFallBackToHostAreas) {
  test::TinySpec spec{.frames = 6, .particles = 3000, .chunk = 256};
  spec.planes = io::PlaneCoding::Zstd;
  const auto path = test::write_tiny_file(*dir_ / "zstd.sluice", spec);
  const io::ContainerReader reader(path);
  HostRelay relay(8, 64 << 10);
  HostRelayWithHostAreas allocator(relay);
  PipelineOptions o;
  o.decode.threads = 2;
  o.read.threads = 3;
  o.decode.mode = sluice::runtime::DecodeMode::KeepEncoded;
  o.decode.color_attribute = 0;
  Pipeline p(reader, allocator, o);
  p.restart({reader.frame_count(), 0, 1, 1, EndMode::Stop});
  for (uint64_t f = 0; f < reader.frame_count(); ++f) {
    p.wait_next();
    const FrameHandle h = p.take();
    ASSERT_FALSE(h.failed()) << h.error()->text();
    EXPECT_FALSE(h.layout().resident) << "frame " << f;
    ASSERT_NE(h.gpu_plan(), nullptr);
    EXPECT_EQ(h.content(), FrameContent::Encoded) << "zstd planes: a host area, not relayed";
    EXPECT_GE(h.buffers().particles.size(), h.gpu_plan()->staged_bytes());
  }
  EXPECT_EQ(p.stats().frames_relayed, 0u);
}

}  // namespace
}  // namespace sluice::runtime
