// Playback on a virtual clock: frames at their time, reverse, stride, end
// modes, and seeded property tests with thousands of random operations
// (seek, rate, pause, step, scrub, end mode) checking that delivery stays in
// order, complete and never stale; a 10k-frame looping soak.
#include <gtest/gtest.h>

#include <random>

#include "runtime_test_util.h"
#include "sluice/runtime/player.h"

using namespace sluice;
using namespace sluice::runtime;

namespace {

constexpr double kFps = 30.0;  // the tiny files' frame rate

PlayerOptions small_options(RealTimePolicy policy = RealTimePolicy::HoldLastFrame) {
  PlayerOptions o;
  o.policy = policy;
  o.pipeline.decode.threads = 2;
  o.pipeline.window.budget.memory_cap = 64u << 20;
  o.pipeline.window.budget.max_frames = 12;
  return o;
}

// Advances the clock, waits for the due frame (no stall by construction),
// and returns what update() shows.
Tick advance(VirtualClock& clock, Player& player, double seconds) {
  clock.advance(seconds);
  player.wait_for_due();
  return player.update();
}

// Plays `ticks` frame intervals of a 30 fps file and returns the frames
// that came on screen, in order.
std::vector<uint64_t> frames_shown(VirtualClock& clock, Player& player, int ticks) {
  std::vector<uint64_t> shown;
  for (int i = 0; i < ticks; ++i) {
    const Tick t = advance(clock, player, 1 / kFps);
    if (t.changed) shown.push_back(t.frame->frame());
  }
  return shown;
}

uint64_t step_target(uint64_t from, int64_t n, EndMode mode, uint64_t frames) {
  const auto count = static_cast<int64_t>(frames);
  const int64_t to = static_cast<int64_t>(from) + n;
  if (mode == EndMode::Loop) return static_cast<uint64_t>(((to % count) + count) % count);
  return static_cast<uint64_t>(std::clamp<int64_t>(to, 0, count - 1));
}

class PlayerTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TempDir;
    path_ = new std::filesystem::path(test::write_tiny_file(*dir_ / "tiny.sluice", spec_));
  }
  static void TearDownTestSuite() {
    delete path_;
    delete dir_;
  }
  static inline test::TinySpec spec_{40, 60, 24, true};
  static inline test::TempDir* dir_ = nullptr;
  static inline std::filesystem::path* path_ = nullptr;
};

}  // namespace

TEST_F(PlayerTest, ShowsTheFirstFrameWhilePausedThenEachFrameAtItsTime) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  VirtualClock clock;
  Player player(reader, allocator, clock, small_options());
  EXPECT_EQ(player.state(), PlayerState::Paused);
  Tick t = advance(clock, player, 0);
  ASSERT_TRUE(t.changed);
  EXPECT_TRUE(test::holds_frame(*t.frame, 0, spec_));

  player.play();
  // A 60 Hz display: each frame of a 30 fps file stays up for two refreshes,
  // the nearest frame to the media position showing (frame k from time
  // (k - 1/2) / 30 on).
  for (int i = 1; i <= 40; ++i) {
    t = advance(clock, player, 1.0 / 60);
    const uint64_t due = std::min<uint64_t>(uint64_t(i + 1) / 2, 39);
    ASSERT_EQ(t.frame->frame(), due) << "at refresh " << i;
    EXPECT_EQ(t.changed, i % 2 == 1) << "at refresh " << i;
  }
  EXPECT_EQ(player.stats().stalls, 0u);
}

TEST_F(PlayerTest, ReversePlaysBackwardsAndEndsAtFrameZero) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  VirtualClock clock;
  PlayerOptions o = small_options();
  o.start_frame = 10;
  o.rate = -1;
  Player player(reader, allocator, clock, o);
  advance(clock, player, 0);
  player.play();
  EXPECT_EQ(frames_shown(clock, player, 15), (std::vector<uint64_t>{9, 8, 7, 6, 5, 4, 3, 2, 1, 0}));
  EXPECT_EQ(player.state(), PlayerState::Ended);
  player.play();  // from the end, play starts over (in the direction of the rate)
  const Tick t = advance(clock, player, 0);
  EXPECT_TRUE(t.changed);
  EXPECT_EQ(t.frame->frame(), 39u);
}

// PlayerOptions::frames: the file ends early for this player: frames 3..5
// are shown, it ends at 5, and nothing past 5 is read (a window of 12).
TEST_F(PlayerTest, APlayerOfTheFirstFramesReadsNothingPastThem) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  VirtualClock clock;
  PlayerOptions o = small_options();
  o.start_frame = 3;
  o.frames = 6;
  Player player(reader, allocator, clock, o);
  EXPECT_EQ(player.frame_count(), 6u);
  advance(clock, player, 0);
  player.play();
  EXPECT_EQ(frames_shown(clock, player, 10), (std::vector<uint64_t>{4, 5}));
  EXPECT_EQ(player.state(), PlayerState::Ended);
  EXPECT_LE(player.stats().pipeline.frames_read, 3u) << "frames 3, 4 and 5 only";
}

TEST_F(PlayerTest, FastRatesFetchEveryNthFrameForTheDisplay) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  VirtualClock clock;
  PlayerOptions o = small_options();
  o.display_rate = 30;  // the display shows 30 frames a second
  o.rate = 4;           // 120 frames of media a second: every 4th frame
  o.end = EndMode::Loop;
  Player player(reader, allocator, clock, o);
  EXPECT_EQ(player.schedule().stride, 4u);
  advance(clock, player, 0);
  player.play();
  std::vector<uint64_t> shown;
  for (int i = 0; i < 12; ++i) shown.push_back(advance(clock, player, 1 / 30.0).frame->frame());
  EXPECT_EQ(shown, (std::vector<uint64_t>{4, 8, 12, 16, 20, 24, 28, 32, 36, 0, 4, 8}));
}

TEST_F(PlayerTest, BounceTurnsAround) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  VirtualClock clock;
  PlayerOptions o = small_options();
  o.end = EndMode::Bounce;
  o.start_frame = 36;
  Player player(reader, allocator, clock, o);
  advance(clock, player, 0);
  player.play();
  std::vector<uint64_t> shown;
  for (int i = 0; i < 8; ++i) shown.push_back(advance(clock, player, 1 / kFps).frame->frame());
  EXPECT_EQ(shown, (std::vector<uint64_t>{37, 38, 39, 38, 37, 36, 35, 34}));
}

TEST_F(PlayerTest, HoldNeverSkipsALateFrame) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  VirtualClock clock;
  Player player(reader, allocator, clock, small_options());
  advance(clock, player, 0);
  player.play();
  EXPECT_EQ(advance(clock, player, 1 / kFps).frame->frame(), 1u);
  // The display comes back ten frame-times late: hold shows the next frame,
  // not the one the clock says, and media time resumes from it.
  std::vector<uint64_t> shown;
  shown.push_back(advance(clock, player, 10 / kFps).frame->frame());
  for (int i = 0; i < 4; ++i) shown.push_back(advance(clock, player, 1 / kFps).frame->frame());
  EXPECT_EQ(shown, (std::vector<uint64_t>{2, 3, 4, 5, 6}));
  EXPECT_EQ(player.stats().drops, 0u);
}

TEST_F(PlayerTest, StallsAreCountedWhileTheDueFrameIsNotReady) {
  const io::ContainerReader reader(*path_);
  auto gate = std::make_shared<test::GatedSource>(
      std::make_shared<FileRecordSource>(reader.path(), reader.descriptor(), false), 2);  // frames 0 and 1 only
  HostFrameAllocator allocator;
  VirtualClock clock;
  PlayerOptions o = small_options();
  o.pipeline.read.source = gate;
  Player player(reader, allocator, clock, o);
  const test::OpenAtExit open_gate{*gate};
  advance(clock, player, 0);
  player.play();
  EXPECT_EQ(advance(clock, player, 1 / kFps).frame->frame(), 1u);
  clock.advance(1 / kFps);  // frame 2 is due and cannot have been read
  EXPECT_FALSE(player.update().changed);
  EXPECT_FALSE(player.update().changed);
  EXPECT_EQ(player.stats().stalls, 2u) << "one stall per refresh without the due frame";
  ASSERT_NE(player.shown(), nullptr) << "the last frame stays on screen";
  EXPECT_EQ(player.shown()->frame(), 1u) << "the last frame stays on screen";
  gate->allow(1);
  EXPECT_EQ(advance(clock, player, 0).frame->frame(), 2u);
  gate->open();
  EXPECT_EQ(advance(clock, player, 1 / kFps).frame->frame(), 3u) << "and playback goes on";
  EXPECT_EQ(player.stats().stalls, 2u);
}

TEST_F(PlayerTest, SkipDropsFramesWhoseTimeHasPassed) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  VirtualClock clock;
  Player player(reader, allocator, clock, small_options(RealTimePolicy::SkipToNewest));
  advance(clock, player, 0);
  player.play();
  advance(clock, player, 0);  // the clock starts with frame 0
  clock.advance(5 / kFps);    // frames 1..5 are all due
  player.wait_for_due();
  const Tick t = player.update();
  ASSERT_TRUE(t.changed);
  const uint64_t f = t.frame->frame();
  EXPECT_GE(f, 1u);
  EXPECT_LE(f, 5u);
  const PlaybackStats s = player.stats();
  EXPECT_EQ(s.drops, f - 1) << "every frame passed over is a drop";
  EXPECT_EQ(s.frames_shown, 2u);
}

TEST_F(PlayerTest, ADisplayKeepingPaceShowsEveryFrameDespiteJitter) {
  // Refreshes at the media rate, each up to 0.4 of a frame early or late:
  // the nearest frame is shown, so nothing is dropped or repeated.
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  VirtualClock clock;
  PlayerOptions o = small_options(RealTimePolicy::SkipToNewest);
  o.end = EndMode::Loop;
  Player player(reader, allocator, clock, o);
  advance(clock, player, 0);
  player.play();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> jitter(-0.4 / kFps, 0.4 / kFps);
  double previous = 0;
  for (int i = 1; i <= 100; ++i) {
    const double refresh = i / kFps + jitter(rng);
    const Tick t = advance(clock, player, refresh - previous);
    previous = refresh;
    ASSERT_TRUE(t.changed) << "refresh " << i;
    ASSERT_EQ(t.frame->frame(), uint64_t(i) % 40) << "refresh " << i;
  }
  EXPECT_EQ(player.stats().drops, 0u);
  EXPECT_EQ(player.stats().stalls, 0u);
}

TEST_F(PlayerTest, StepAndScrubWhilePaused) {
  const io::ContainerReader reader(*path_);
  HostFrameAllocator allocator;
  VirtualClock clock;
  Player player(reader, allocator, clock, small_options());
  advance(clock, player, 0);
  const auto shows = [&](uint64_t frame) {
    const Tick t = advance(clock, player, 0);
    return t.frame && t.frame->frame() == frame && test::holds_frame(*t.frame, frame, spec_);
  };
  player.step(1);
  EXPECT_TRUE(shows(1));
  player.step(3);
  EXPECT_TRUE(shows(4));
  player.step(-2);
  EXPECT_TRUE(shows(2));
  player.step(-5);
  EXPECT_TRUE(shows(0)) << "steps clamp at the first frame";
  for (uint64_t f : {10u, 11u, 13u, 12u, 5u, 39u, 38u}) {
    player.scrub(f);
    EXPECT_TRUE(shows(f)) << "scrub to " << f;
  }
  EXPECT_EQ(player.state(), PlayerState::Paused);
  player.set_end_mode(EndMode::Loop);
  player.step(2);
  EXPECT_TRUE(shows(0)) << "steps wrap when looping";
}

namespace {

// One seeded run of random operations; checks every frame shown.
void random_operations(const std::filesystem::path& path, const test::TinySpec& spec, uint32_t seed, int operations,
                       RealTimePolicy policy) {
  const io::ContainerReader reader(path);
  HostFrameAllocator allocator;
  VirtualClock clock;
  std::mt19937 rng(seed);
  PlayerOptions o = small_options(policy);
  o.pipeline.window.budget.max_frames = 2 + static_cast<uint32_t>(rng() % 15);
  o.end = static_cast<EndMode>(rng() % 3);
  o.display_rate = rng() % 2 ? 60 : 0;
  Player player(reader, allocator, clock, o);
  const uint64_t n = reader.frame_count();
  const bool hold = policy == RealTimePolicy::HoldLastFrame;

  std::optional<uint64_t> expect;  // the frame a seek, step or scrub must show next
  uint64_t last_generation = ~0ull, last_sequence = 0, shown = 0;
  auto check = [&](const Tick& t, const std::string& after) {
    if (!t.changed) return;
    const FrameHandle& h = *t.frame;
    ASSERT_TRUE(test::holds_frame(h, h.frame(), spec)) << after;
    ASSERT_EQ(h.generation(), player.pipeline().generation()) << "stale frame shown after " << after;
    ASSERT_EQ(player.schedule().frame_at(h.sequence()), h.frame()) << after;
    if (expect) {
      ASSERT_EQ(h.frame(), *expect) << "after " << after;
      expect.reset();
    } else if (h.generation() == last_generation) {
      if (hold) ASSERT_EQ(h.sequence(), last_sequence + 1) << "hold skipped a frame after " << after;
      else ASSERT_GT(h.sequence(), last_sequence) << after;
    }
    last_generation = h.generation();
    last_sequence = h.sequence();
    ++shown;
  };

  check(advance(clock, player, 0), "start");
  std::string op;
  for (int i = 0; i < operations; ++i) {
    const uint64_t current = expect ? *expect : (player.shown() ? player.shown()->frame() : 0);
    switch (rng() % 12) {
      case 0: op = "play"; player.play(); break;
      case 1: op = "pause"; player.pause(); break;
      case 2: {
        static constexpr double kRates[] = {-4, -2, -1, -0.5, 0.5, 1, 1, 2, 3, 8};
        const double r = kRates[rng() % std::size(kRates)];
        op = "rate " + std::to_string(r);
        player.set_rate(r);
        break;
      }
      case 3: {
        const uint64_t f = rng() % n;
        op = "seek " + std::to_string(f);
        player.seek(f);
        expect = f;
        break;
      }
      case 4: {
        const int64_t k = int64_t(rng() % 7) - 3;
        op = "step " + std::to_string(k);
        const uint64_t to = step_target(current, k, player.end_mode(), n);
        player.step(k);
        if (k != 0 && (to != current || expect)) expect = to;
        break;
      }
      case 5: {
        const uint64_t f = rng() % 2 ? rng() % n : step_target(current, int64_t(rng() % 5) - 2, EndMode::Stop, n);
        op = "scrub " + std::to_string(f);
        player.scrub(f);
        if (f != current || expect) expect = f;
        break;
      }
      case 6: {
        const auto m = static_cast<EndMode>(rng() % 3);
        op = std::string("end mode ") + end_mode_name(m);
        player.set_end_mode(m);
        break;
      }
      default: op = "tick"; break;
    }
    const int ticks = 1 + int(rng() % 4);
    for (int t = 0; t < ticks; ++t) {
      const double dt = double(rng() % 4) / 2 / kFps;  // 0, 1/2, 1 or 3/2 frames
      if (hold || rng() % 2) {
        check(advance(clock, player, dt), op);
      } else {
        clock.advance(dt);  // real time: decode may or may not have kept up
        check(player.update(), op);
      }
      if (::testing::Test::HasFatalFailure()) return;
    }
  }
  const PlaybackStats s = player.stats();
  EXPECT_EQ(s.frames_shown, shown);
  EXPECT_EQ(s.errors, 0u);
  if (hold) {
    EXPECT_EQ(s.stalls, 0u) << "waiting for the due frame leaves nothing to stall on";
  }
  EXPECT_GT(shown, uint64_t(operations) / 4) << "playback made progress";
}

}  // namespace

TEST_F(PlayerTest, RandomOperationsHoldPolicyDeliverInOrderCompleteAndFresh) {
  for (uint32_t seed = 1; seed <= 6; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    random_operations(*path_, spec_, seed, 1500, RealTimePolicy::HoldLastFrame);
    if (HasFatalFailure()) return;
  }
}

TEST_F(PlayerTest, RandomOperationsSkipPolicyStayInOrderAndFresh) {
  for (uint32_t seed = 101; seed <= 104; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    random_operations(*path_, spec_, seed, 1500, RealTimePolicy::SkipToNewest);
    if (HasFatalFailure()) return;
  }
}

TEST(PlayerSoak, TenThousandFramesLoopingWithRandomOperations) {
  test::TempDir dir;
  const test::TinySpec spec{10000, 12, 8, false};
  const auto path = test::write_tiny_file(dir / "soak.sluice", spec);
  const io::ContainerReader reader(path);
  HostFrameAllocator allocator;
  VirtualClock clock;
  PlayerOptions o = small_options();
  o.end = EndMode::Loop;
  o.pipeline.window.budget.max_frames = 64;
  o.start_frame = 9900;
  Player player(reader, allocator, clock, o);
  std::mt19937 rng(10000);
  advance(clock, player, 0);
  player.play();
#if defined(__SANITIZE_THREAD__)
  constexpr int kTicks = 6000;  // TSan is 5-20x slower; the same code paths run
#else
  constexpr int kTicks = 30000;
#endif
  uint64_t wraps = 0, previous = 9900, last_generation = 0, last_sequence = 0;
  for (int i = 0; i < kTicks; ++i) {
    const auto dice = i < 200 ? 999u : static_cast<uint32_t>(rng() % 1000);  // first wrap around the end undisturbed
    bool jumped = true;
    if (dice < 3) player.seek(rng() % spec.frames);
    else if (dice < 6) player.set_rate(rng() % 2 ? 1.0 : -1.0);
    else if (dice < 8) player.scrub(rng() % spec.frames);
    else if (dice < 10) player.step(int64_t(rng() % 5) - 2);
    else if (dice < 30) player.play();
    else jumped = false;
    const Tick t = advance(clock, player, 1 / kFps);
    if (!t.changed) continue;
    const FrameHandle& h = *t.frame;
    ASSERT_TRUE(test::holds_frame(h, h.frame(), spec));
    ASSERT_EQ(h.generation(), player.pipeline().generation());
    if (!jumped && h.generation() == last_generation) {
      ASSERT_EQ(h.sequence(), last_sequence + 1);
    }
    if (previous == spec.frames - 1 && h.frame() == 0) ++wraps;
    previous = h.frame();
    last_generation = h.generation();
    last_sequence = h.sequence();
  }
  const PlaybackStats s = player.stats();
  EXPECT_GE(wraps, 1u) << "the loop wrapped around the end";
  EXPECT_GT(s.frames_shown, uint64_t(kTicks) / 2);
  EXPECT_EQ(s.errors, 0u);
  EXPECT_EQ(s.stalls, 0u);
  EXPECT_GT(s.pipeline.frames_read, uint64_t(kTicks) / 4);
}
