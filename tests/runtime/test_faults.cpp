// Faults mid-play: a read that fails, a file that ends early, short reads, a
// corrupt chunk, no memory for a frame. Each gives an error naming the file
// and frame (and chunk), and playback carries on or stops cleanly by policy.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <thread>
#include <new>

#include "failing_allocation.h"
#include "runtime_test_util.h"
#include "sluice/io/reader.h"
#include "sluice/runtime/player.h"

using namespace sluice;
using namespace sluice::runtime;

namespace {

constexpr uint64_t kBad = 12;  // the frame that goes wrong

class FaultTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TempDir;
    path_ = new std::filesystem::path(test::write_tiny_file(*dir_ / "tiny.sluice", spec_));
  }
  static void TearDownTestSuite() {
    delete path_;
    delete dir_;
  }

  static std::shared_ptr<RecordSource> faulty(const io::ContainerReader& reader, test::FaultySource::Fault fault) {
    const io::FrameIndexEntry& e = reader.index().frames[kBad];
    return std::make_shared<test::FaultySource>(
        std::make_shared<FileRecordSource>(reader.path(), reader.descriptor(), false), reader.path(), fault, e.offset,
        e.offset + e.bytes);
  }

  static PlayerOptions options(ErrorPolicy policy, std::shared_ptr<RecordSource> source = nullptr) {
    PlayerOptions o;
    o.on_error = policy;
    o.pipeline.decode.threads = 2;
    o.pipeline.window.budget.max_frames = 8;
    o.pipeline.read.source = std::move(source);
    return o;
  }

  // Plays until the player leaves Playing (or `ticks` refreshes); returns the frames shown.
  static std::vector<uint64_t> play_through(Player& player, VirtualClock& clock, int ticks = 200) {
    std::vector<uint64_t> shown;
    auto record = [&](const Tick& t) {
      if (!t.changed) return;
      EXPECT_TRUE(test::holds_frame(*t.frame, t.frame->frame(), spec_));
      shown.push_back(t.frame->frame());
    };
    player.wait_for_due();
    record(player.update());
    player.play();
    for (int i = 0; i < ticks && player.state() == PlayerState::Playing; ++i) {
      clock.advance(1 / 30.0);
      player.wait_for_due();
      record(player.update());
    }
    return shown;
  }

  // Frames kBad to the end each failed with a short read, in order, and nothing else.
  static void expect_short_reads_from_bad(Player& player) {
    for (uint64_t f = kBad; f < 30; ++f) {
      const auto error = player.pop_error();
      ASSERT_TRUE(error) << "frame " << f;
      EXPECT_EQ(error->where.frame, f);
      EXPECT_NE(error->message.find("short read"), std::string::npos) << error->text();
    }
    EXPECT_FALSE(player.pop_error());
  }

  static std::vector<uint64_t> all_but(uint64_t from, uint64_t to, std::vector<uint64_t> skipped) {
    std::vector<uint64_t> out;
    for (uint64_t f = from; f < to; ++f) {
      if (std::find(skipped.begin(), skipped.end(), f) == skipped.end()) out.push_back(f);
    }
    return out;
  }

  static inline test::TinySpec spec_{30, 80, 24, true};
  static inline test::TempDir* dir_ = nullptr;
  static inline std::filesystem::path* path_ = nullptr;
};

}  // namespace

TEST_F(FaultTest, ReadErrorMidPlayIsReportedAndSkipped) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  VirtualClock clock;
  Player player(reader, allocator, clock, options(ErrorPolicy::SkipFrame, faulty(reader, test::FaultySource::Fault::Fail)));
  EXPECT_EQ(play_through(player, clock), all_but(0, 30, {kBad}));
  EXPECT_EQ(player.state(), PlayerState::Ended);
  const auto error = player.pop_error();
  ASSERT_TRUE(error);
  EXPECT_EQ(error->where.file, reader.path());
  EXPECT_EQ(error->where.frame, kBad);
  EXPECT_NE(error->message.find("Input/output error"), std::string::npos) << error->text();
  EXPECT_NE(error->text().find("frame 12"), std::string::npos) << error->text();
  EXPECT_FALSE(player.pop_error());
  EXPECT_EQ(player.stats().errors, 1u);
  EXPECT_EQ(player.stats().pipeline.frames_failed, 1u);
}

TEST_F(FaultTest, ReadErrorStopsPlaybackCleanlyUnderTheStopPolicy) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  VirtualClock clock;
  Player player(reader, allocator, clock, options(ErrorPolicy::Stop, faulty(reader, test::FaultySource::Fault::Fail)));
  EXPECT_EQ(play_through(player, clock), all_but(0, kBad, {}));
  EXPECT_EQ(player.state(), PlayerState::Stopped);
  const auto error = player.pop_error();
  ASSERT_TRUE(error);
  EXPECT_EQ(error->where.frame, kBad);
  for (int i = 0; i < 10; ++i) {  // stays stopped on the last good frame
    clock.advance(1 / 30.0);
    player.wait_for_due();
    const Tick t = player.update();
    EXPECT_FALSE(t.changed);
    EXPECT_EQ(t.frame->frame(), kBad - 1);
  }
  // A seek past the bad frame resumes.
  player.seek(kBad + 1);
  player.play();
  std::vector<uint64_t> shown;
  for (int i = 0; i < 40 && player.state() == PlayerState::Playing; ++i) {
    player.wait_for_due();
    const Tick t = player.update();
    if (t.changed) shown.push_back(t.frame->frame());
    clock.advance(1 / 30.0);
  }
  EXPECT_EQ(shown, all_but(kBad + 1, 30, {}));
}

TEST_F(FaultTest, FileEndingMidPlayNamesEachMissingFrame) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  VirtualClock clock;
  Player player(reader, allocator, clock,
                options(ErrorPolicy::SkipFrame, faulty(reader, test::FaultySource::Fault::EndEarly)));
  EXPECT_EQ(play_through(player, clock), all_but(0, kBad, {}));
  EXPECT_EQ(player.state(), PlayerState::Ended);
  expect_short_reads_from_bad(player);
}

// The default source copies out of a mapping of the file (MappedSource
// below): the file really cut after it was opened, no fault injection.
TEST_F(FaultTest, FileCutAfterOpeningNamesEachMissingFrame) {
  const auto copy = *dir_ / "cut.sluice";
  std::filesystem::copy_file(*path_, copy, std::filesystem::copy_options::overwrite_existing);
  const io::ContainerReader reader(copy);
  std::filesystem::resize_file(copy, reader.index().frames[kBad].offset + 10);  // after the index was read
  HostFrameAllocator allocator;
  VirtualClock clock;
  Player player(reader, allocator, clock, options(ErrorPolicy::SkipFrame));
  EXPECT_EQ(play_through(player, clock), all_but(0, kBad, {}));
  EXPECT_EQ(player.state(), PlayerState::Ended);
  expect_short_reads_from_bad(player);
}

TEST_F(FaultTest, FaultsInParallelPiecesNameTheFrame) {
  const io::ContainerReader reader(*path_);
  for (const auto fault : {test::FaultySource::Fault::Fail, test::FaultySource::Fault::Dribble}) {
    HostFrameAllocator allocator;
    VirtualClock clock;
    PlayerOptions o = options(ErrorPolicy::SkipFrame, faulty(reader, fault));
    o.pipeline.read.threads = 3;
    o.pipeline.read.piece_bytes = 300;
    Player player(reader, allocator, clock, o);
    const bool fails = fault == test::FaultySource::Fault::Fail;
    EXPECT_EQ(play_through(player, clock), all_but(0, 30, fails ? std::vector<uint64_t>{kBad} : std::vector<uint64_t>{}));
    const auto error = player.pop_error();
    EXPECT_EQ(error.has_value(), fails);
    if (error) {
      EXPECT_EQ(error->where.frame, kBad);
    }
  }
}

TEST_F(FaultTest, ShortReadsAreNotErrors) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  VirtualClock clock;
  Player player(reader, allocator, clock,
                options(ErrorPolicy::Stop, faulty(reader, test::FaultySource::Fault::Dribble)));
  EXPECT_EQ(play_through(player, clock), all_but(0, 30, {}));
  EXPECT_FALSE(player.pop_error());
  EXPECT_EQ(player.state(), PlayerState::Ended);
}

TEST_F(FaultTest, CorruptChunkNamesFileFrameAndChunk) {
  const io::ContainerReader clean(*path_);
  const io::FrameHeader h = clean.parse_record(kBad, clean.read_record(kBad));
  ASSERT_GE(h.chunks.size(), 3u);
  std::vector<char> bytes;
  {
    std::ifstream in(*path_, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  const uint64_t at = clean.index().frames[kBad].offset + h.chunks[1].offset + h.chunks[1].compressed_size / 2;
  bytes[at] = char(bytes[at] ^ 0x21);
  const auto bad = *dir_ / "corrupt.sluice";
  std::ofstream(bad, std::ios::binary | std::ios::trunc).write(bytes.data(), std::streamsize(bytes.size()));

  const io::ContainerReader reader(bad);
  HostFrameAllocator allocator;
  VirtualClock clock;
  Player player(reader, allocator, clock, options(ErrorPolicy::SkipFrame));
  EXPECT_EQ(play_through(player, clock), all_but(0, 30, {kBad}));
  const auto error = player.pop_error();
  ASSERT_TRUE(error);
  EXPECT_EQ(error->where.file, bad.string());
  EXPECT_EQ(error->where.frame, kBad);
  EXPECT_EQ(error->where.chunk, 1u);
  EXPECT_NE(error->message.find("checksum"), std::string::npos) << error->text();

  // Kept encoded for the GPU, the chunk is checked as the read copies it:
  // out of the mapping or by pread, on the reader thread alone or with
  // helpers. The same error, in its place; every other frame arrives.
  ASSERT_TRUE(io::gpu_decodable(reader.header()));
  struct Way {
    bool mapped;
    int read_threads;
  };
  for (const Way way : {Way{true, 1}, Way{true, 3}, Way{false, 3}}) {
    SCOPED_TRACE(testing::Message() << (way.mapped ? "mapped" : "pread") << ", " << way.read_threads << " read threads");
    HostFrameAllocator memory;
    PipelineOptions o;
    o.decode.threads = 2;
    o.decode.mode = sluice::runtime::DecodeMode::KeepEncoded;
    o.read.mapped = way.mapped;
    o.read.threads = way.read_threads;
    Pipeline p(reader, memory, o);
    p.restart({reader.frame_count(), 0, 1, 1, EndMode::Stop});
    for (uint64_t f = 0; f < reader.frame_count(); ++f) {
      const NextEntry next = p.wait_next();
      ASSERT_EQ(next.frame, f);
      ASSERT_EQ(next.status, f == kBad ? EntryStatus::Failed : EntryStatus::Ready);
      const FrameHandle taken = p.take();
      if (f != kBad) continue;
      ASSERT_TRUE(taken.error());
      EXPECT_EQ(taken.error()->where.file, bad.string());
      EXPECT_EQ(taken.error()->where.frame, kBad);
      EXPECT_EQ(taken.error()->where.chunk, 1u);
      EXPECT_NE(taken.error()->message.find("checksum"), std::string::npos) << taken.error()->text();
    }
    EXPECT_TRUE(p.wait_next().end);
    EXPECT_EQ(p.stats().frames_failed, 1u);
  }
}

TEST_F(FaultTest, PipelineHandsFailuresToTheConsumerInOrder) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  PipelineOptions o;
  o.decode.threads = 2;
  o.read.source = faulty(reader, test::FaultySource::Fault::Fail);
  Pipeline p(reader, allocator, o);
  p.restart({reader.frame_count(), 0, 1, 1, EndMode::Stop});
  for (uint64_t f = 0; f < reader.frame_count(); ++f) {
    const NextEntry next = p.wait_next();
    ASSERT_FALSE(next.end);
    ASSERT_EQ(next.frame, f);
    ASSERT_EQ(next.status, f == kBad ? EntryStatus::Failed : EntryStatus::Ready);
    const FrameHandle h = p.take();
    EXPECT_EQ(h.failed(), f == kBad);
    if (h.failed()) EXPECT_EQ(h.error()->where.frame, kBad);
    else EXPECT_TRUE(test::holds_frame(h, f, spec_));
  }
  EXPECT_TRUE(p.wait_next().end);
}

namespace {

// The real host allocator, out of memory for one frame.
class FailingAllocator final : public FrameAllocator {
 public:
  FrameBuffers allocate(const FrameLayout& layout) override {
    if (layout.frame == kBad) throw std::bad_alloc();
    return host_.allocate(layout);
  }
  void release(FrameBuffers& buffers) override { host_.release(buffers); }
  uint64_t bytes_for(const FrameLayout& layout) const override { return host_.bytes_for(layout); }

 private:
  HostFrameAllocator host_;
};

}  // namespace

TEST_F(FaultTest, NoMemoryForAFrameIsAnErrorOfThatFrame) {
  const io::ContainerReader reader(*path_);
  FailingAllocator allocator;
  VirtualClock clock;
  Player player(reader, allocator, clock, options(ErrorPolicy::SkipFrame));
  EXPECT_EQ(play_through(player, clock), all_but(0, 30, {kBad}));
  const auto error = player.pop_error();
  ASSERT_TRUE(error);
  EXPECT_EQ(error->where.frame, kBad);
}

// ------------------------------------------------ failures inside the decoders
namespace {

// What a decode worker throws when a test says so; its message needs no
// allocation, so the allocation that fails is the pipeline's own.
struct InjectedFailure : std::exception {
  const char* what() const noexcept override { return "injected decode failure"; }
};

// Plays every frame once through the pipeline; returns each frame's outcome
// ("" for a good frame, else its error text).
std::map<uint64_t, std::string> play_once(Pipeline& p, uint64_t frames) {
  std::map<uint64_t, std::string> out;
  p.restart({frames, 0, 1, 1, EndMode::Stop});
  while (true) {
    const NextEntry next = p.wait_next();
    if (next.end) break;
    FrameHandle h = p.take();
    out[h.frame()] = h.failed() ? h.error()->text() : "";
  }
  return out;
}

PipelineOptions decode_options() {
  PipelineOptions o;
  o.decode.threads = 2;
  o.window.budget.max_frames = 8;
  return o;
}

}  // namespace

// The error a decode worker reports needs memory (the file name, the
// message); when even that fails, the frame still arrives, failed, in its
// place, and everything after it plays.
TEST_F(FaultTest, NoMemoryToDescribeADecodeErrorIsStillAnErrorFrame) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  PipelineOptions o = decode_options();
  o.faults.before_decode_chunk = [](uint64_t frame, size_t chunk) {
    if (frame != kBad || chunk != 0) return;
    test::fail_next_allocations(1);  // the copy of the file name in the error
    throw InjectedFailure{};
  };
  std::map<uint64_t, std::string> outcome;
  {
    Pipeline p(reader, allocator, o);
    outcome = play_once(p, reader.frame_count());
  }  // and it is destroyed cleanly
  ASSERT_EQ(outcome.size(), reader.frame_count());
  for (const auto& [frame, error] : outcome) {
    if (frame == kBad) {
      EXPECT_NE(error.find("frame 12"), std::string::npos) << error;
      EXPECT_NE(error.find("no memory left to say why"), std::string::npos) << error;
    } else {
      EXPECT_EQ(error, "") << "frame " << frame;
    }
  }
}

TEST_F(FaultTest, DecodeErrorsOfEveryKindAreErrorFrames) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  PipelineOptions o = decode_options();
  o.faults.before_decode_chunk = [](uint64_t frame, size_t chunk) {
    if (frame == kBad && chunk == 1) throw std::bad_alloc();
    if (frame == kBad + 1 && chunk == 0) throw 42;  // not even an exception
  };
  Pipeline p(reader, allocator, o);
  const auto outcome = play_once(p, reader.frame_count());
  EXPECT_NE(outcome.at(kBad).find("frame 12, chunk 1"), std::string::npos) << outcome.at(kBad);
  EXPECT_NE(outcome.at(kBad + 1).find("unknown exception"), std::string::npos) << outcome.at(kBad + 1);
  EXPECT_EQ(outcome.at(kBad + 2), "");
}

// Handing a frame to the decode workers allocates a task; when that fails
// the frame fails in its place instead of staying "decoding" forever.
TEST_F(FaultTest, NoMemoryToHandAFrameToTheDecodersIsAnErrorFrame) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  PipelineOptions o = decode_options();
  o.faults.before_decode_handoff = [](uint64_t frame) {
    if (frame == kBad) throw std::bad_alloc();
  };
  std::map<uint64_t, std::string> outcome;
  {
    Pipeline p(reader, allocator, o);
    outcome = play_once(p, reader.frame_count());
  }
  ASSERT_EQ(outcome.size(), reader.frame_count());
  EXPECT_NE(outcome.at(kBad).find("no memory to hand the frame to the decoders"), std::string::npos) << outcome.at(kBad);
  for (const auto& [frame, error] : outcome) {
    if (frame != kBad) {
      EXPECT_EQ(error, "") << "frame " << frame;
    }
  }
}

// A gate on the decoder: frame kBad's first chunk waits until the test opens
// it, so a seek, a restart and the pipeline's destruction happen while that
// frame is decoding, on purpose.
class DecodeGate {
 public:
  // Waits here at most 30 s: a test that fails before opening the gate
  // ends instead of hanging.
  void wait_here(uint64_t frame, size_t chunk) {
    if (frame != kBad || chunk != 0) return;
    std::unique_lock lock(mutex_);
    held_ = true;
    changed_.notify_all();
    changed_.wait_for(lock, std::chrono::seconds(30), [&] { return open_; });
  }
  // Whether the decode reached the gate within 30 s.
  [[nodiscard]] bool wait_until_held() {
    std::unique_lock lock(mutex_);
    return changed_.wait_for(lock, std::chrono::seconds(30), [&] { return held_; });
  }
  void open() {
    const std::lock_guard lock(mutex_);
    open_ = true;
    changed_.notify_all();
  }

 private:
  std::mutex mutex_;
  std::condition_variable changed_;
  bool held_ = false, open_ = false;
};

TEST_F(FaultTest, SeekWhileAFrameIsDecodingDeliversTheNewScheduleOnly) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  auto gate = std::make_shared<DecodeGate>();
  PipelineOptions o = decode_options();
  o.faults.before_decode_chunk = [gate](uint64_t frame, size_t chunk) { gate->wait_here(frame, chunk); };
  Pipeline p(reader, allocator, o);
  p.restart({reader.frame_count(), int64_t(kBad), 1, 1, EndMode::Stop});
  ASSERT_TRUE(gate->wait_until_held()) << "frame kBad never reached the decoder";
  p.restart({reader.frame_count(), 2, 1, 1, EndMode::Stop});  // seek back while kBad decodes
  // The new schedule's first frame arrives while kBad is still held (the
  // other decode worker takes it); then kBad's decode may finish.
  std::vector<uint64_t> shown;
  for (int i = 0; i < 5; ++i) {
    ASSERT_FALSE(p.wait_next().end);
    FrameHandle h = p.take();
    EXPECT_FALSE(h.failed());
    EXPECT_TRUE(test::holds_frame(h, h.frame(), spec_));
    shown.push_back(h.frame());
    if (i == 0) gate->open();
  }
  EXPECT_EQ(shown, (std::vector<uint64_t>{2, 3, 4, 5, 6}));
}

TEST_F(FaultTest, DestroyingWhileAFrameIsDecodingWaitsForItAndEnds) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  auto gate = std::make_shared<DecodeGate>();
  PipelineOptions o = decode_options();
  o.faults.before_decode_chunk = [gate](uint64_t frame, size_t chunk) { gate->wait_here(frame, chunk); };
  auto p = std::make_unique<Pipeline>(reader, allocator, o);
  p->restart({reader.frame_count(), int64_t(kBad), 1, 1, EndMode::Stop});
  ASSERT_TRUE(gate->wait_until_held()) << "frame kBad never reached the decoder";
  // The gate opens once the destruction has begun (no sleep: a flag set
  // just before it), so the destructor meets the decode still running.
  std::atomic<bool> destroying{false};
  std::thread opener([&] {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (!destroying.load() && std::chrono::steady_clock::now() < deadline) std::this_thread::yield();
    gate->open();
  });
  destroying.store(true);
  p.reset();
  opener.join();
  EXPECT_EQ(allocator.in_use_buffers(), 0u) << "every buffer went back";
}

// Once the window is warm, delivering a frame allocates nothing: not the
// reader (record, chunk table, locations), not the decode workers, not the
// hand-off to the consumer.
TEST_F(FaultTest, SteadyPlaybackAllocatesNothingPerFrame) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  PipelineOptions o = decode_options();
  o.window.reevaluate_every = 1u << 30;  // re-reading /proc for the budget allocates; not per frame
  o.window.slow_start = false;           // the window stands: no new buffer blocks while it grows
  // One decode worker: a worker's scratch grows to the largest chunk it has
  // decoded (once), and with several, which worker meets which chunk first is
  // TBB's choice; with one, the warm-up has shown it every chunk.
  o.decode.threads = 1;
  Pipeline p(reader, allocator, o);
  p.restart({reader.frame_count(), 0, 1, 1, EndMode::Loop});
  const auto take = [&](uint64_t n) {
    for (uint64_t i = 0; i < n; ++i) {
      ASSERT_FALSE(p.wait_next().end);
      FrameHandle h = p.take();
      ASSERT_FALSE(h.failed());
    }
  };
  take(3 * reader.frame_count());  // warm: every slot, record buffer and worker scratch has been used
  const unsigned long long before = test::allocations_so_far();
  const uint64_t blocks_before = allocator.allocations();
  take(2 * reader.frame_count());
  // How full the window gets depends on timing (the reader finishes a frame
  // while it reads the next), so the buffer pool may still grow toward the
  // window: a new block costs its own bookkeeping (the block, and the pool's
  // two lists growing), and nothing else may allocate.
  const uint64_t grew = allocator.allocations() - blocks_before;
  EXPECT_LE(test::allocations_so_far() - before, 3 * grew) << "allocations while delivering " << 2 * reader.frame_count()
                                                           << " frames, " << grew << " new buffer blocks";
}

// The default source copies out of a mapping of the file: a file cut while
// mapped must read as ending at the cut (as pread does), never crash, and
// bytes past the mapping (a file that grew) still come.
TEST(MappedSource, ReadsTheFileAndSaysItIsMapped) {
  test::TempDir dir;
  const auto path = test::write_tiny_file(dir / "mapped.sluice", {6, 40, 8, true});
  const io::ContainerReader reader(path);
  FileRecordSource mapped(reader.path(), reader.descriptor(), false, true);
  FileRecordSource plain(reader.path(), reader.descriptor(), false, false);
  EXPECT_EQ(mapped.describe(), "mapped");
  EXPECT_EQ(plain.describe(), "pread");
  const uint64_t size = std::filesystem::file_size(path);
  std::vector<std::byte> a(size + 100), b(size + 100);
  for (uint64_t offset : {uint64_t(0), uint64_t(1), size / 3, size - 7}) {  // odd offsets: unaligned copies
    const size_t na = mapped.read_at(a, offset), nb = plain.read_at(b, offset);
    EXPECT_EQ(na, size - offset);
    ASSERT_EQ(na, nb);
    EXPECT_EQ(std::memcmp(a.data(), b.data(), na), 0) << "offset " << offset;
  }
  EXPECT_EQ(mapped.read_at(a, size), 0u);
}

// A checked read hashes what it reads: out of the mapping block by block as
// it copies, or after pread; the bytes and the hash are the same either way,
// and a read past the end is short with the hash of what it got.
TEST(MappedSource, ACheckedReadHashesTheBytesItRead) {
  test::TempDir dir;
  const auto path = test::write_tiny_file(dir / "checked.sluice", {6, 20000, 8, true});
  const io::ContainerReader reader(path);
  FileRecordSource mapped(reader.path(), reader.descriptor(), false, true);
  FileRecordSource plain(reader.path(), reader.descriptor(), false, false);
  const uint64_t size = std::filesystem::file_size(path);
  ASSERT_GT(size, 3 * io::kChecksumBlock);
  for (const auto& [offset, length] : {std::pair<uint64_t, uint64_t>{0, size}, {1, io::kChecksumBlock + 1}, {size / 3, 3 * io::kChecksumBlock - 5},
                                       {size - 7, 7}, {size - 7, 100}}) {
    std::vector<std::byte> a(length), b(length);
    uint64_t ha = 0, hb = 0;
    const size_t na = mapped.read_checked(a, offset, ha), nb = plain.read_checked(b, offset, hb);
    EXPECT_EQ(na, std::min<uint64_t>(length, size - offset)) << "offset " << offset;
    ASSERT_EQ(na, nb);
    EXPECT_EQ(std::memcmp(a.data(), b.data(), na), 0) << "offset " << offset;
    EXPECT_EQ(ha, io::chunk_checksum(std::span(b).first(nb))) << "offset " << offset;
    EXPECT_EQ(ha, hb) << "offset " << offset;
  }
}

TEST(MappedSource, AFileCutWhileMappedReadsAsEndingAtTheCut) {
  test::TempDir dir;
  const auto path = test::write_tiny_file(dir / "cut.sluice", {6, 4000, 8, true});
  const io::ContainerReader reader(path);
  FileRecordSource source(reader.path(), reader.descriptor(), false, true);
  const uint64_t size = std::filesystem::file_size(path);
  ASSERT_GT(size, 3 * 4096u);
  const uint64_t cut = 4096 + 100;  // inside a page: the rest of that page reads as zeros through the mapping
  std::filesystem::resize_file(path, cut);
  std::vector<std::byte> buffer(size);
  EXPECT_EQ(source.read_at(buffer, 0), cut);                      // pages wholly past the cut: SIGBUS, caught
  EXPECT_EQ(source.read_at(std::span(buffer).first(50), 4096 + 200), 0u);  // past the cut, inside its page
  EXPECT_EQ(source.read_at(std::span(buffer).first(50), 3 * 4096), 0u);    // a page wholly past it
  uint64_t checksum = 0;  // a checked read too: short, with the hash of what it got
  EXPECT_EQ(source.read_checked(buffer, 0, checksum), cut);
  EXPECT_EQ(checksum, io::chunk_checksum(std::span(buffer).first(cut)));
  // The file grows back past its old end: bytes beyond the mapping by pread.
  std::filesystem::resize_file(path, size + 10);
  EXPECT_EQ(source.read_at(std::span(buffer).first(20), size), 10u);
}
