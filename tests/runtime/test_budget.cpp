// Memory budgets: /proc/meminfo and cgroup files (fake trees), user sizes,
// and the window planned from them.
#include <gtest/gtest.h>

#include "runtime_test_util.h"
#include "sluice/runtime/budget.h"
#include "sluice/runtime/window.h"

using namespace sluice;
using namespace sluice::runtime;

namespace {

constexpr uint64_t kMiB = uint64_t(1) << 20;
constexpr uint64_t kGiB = uint64_t(1) << 30;

struct FakeHost {
  test::TempDir dir;
  HostMemoryPaths paths{(dir / "meminfo").string(), (dir / "self_cgroup").string(), (dir / "cgroup").string()};

  void meminfo(uint64_t available_kb) {
    test::write_text_file(paths.meminfo, "MemTotal:       32000000 kB\nMemFree:         1000000 kB\nMemAvailable:   " +
                                             std::to_string(available_kb) + " kB\nBuffers:          20000 kB\n");
  }
  void membership(const std::string& text) { test::write_text_file(paths.self_cgroup, text); }
  void file(const std::string& relative, const std::string& text) { test::write_text_file(dir / ("cgroup/" + relative), text); }
};

}  // namespace

TEST(ParseByteSize, UnderstandsWhatUsersType) {
  EXPECT_EQ(parse_byte_size("8G"), 8 * kGiB);
  EXPECT_EQ(parse_byte_size("512M"), 512 * kMiB);
  EXPECT_EQ(parse_byte_size("512MiB"), 512 * kMiB);
  EXPECT_EQ(parse_byte_size("1.5GB"), 3 * kGiB / 2);
  EXPECT_EQ(parse_byte_size("64k"), 64u * 1024);
  EXPECT_EQ(parse_byte_size("1000000"), 1000000u);
  EXPECT_EQ(parse_byte_size("2 T"), 2 * 1024 * kGiB);
  EXPECT_FALSE(parse_byte_size(""));
  EXPECT_FALSE(parse_byte_size("G"));
  EXPECT_FALSE(parse_byte_size("12Q"));
  EXPECT_FALSE(parse_byte_size("1..5G"));
  EXPECT_FALSE(parse_byte_size("-3G"));
}

TEST(HostMemory, ReadsMemAvailableWithoutCgroup) {
  FakeHost h;
  h.meminfo(4000000);
  const HostMemory m = read_host_memory(h.paths);
  EXPECT_EQ(m.mem_available, 4000000ull * 1024);
  EXPECT_FALSE(m.cgroup_headroom);
  EXPECT_EQ(m.available(), 4000000ull * 1024);
}

TEST(HostMemory, CgroupV2TightestLevelWins) {
  FakeHost h;
  h.meminfo(8000000);
  h.membership("0::/app/job\n");
  h.file("cgroup.controllers", "cpu memory\n");
  h.file("app/memory.max", std::to_string(6 * kGiB) + "\n");
  h.file("app/memory.current", std::to_string(1 * kGiB) + "\n");  // 5 GiB headroom
  h.file("app/job/memory.max", "max\n");                            // no limit of its own
  h.file("app/job/memory.current", std::to_string(kGiB / 2) + "\n");
  HostMemory m = read_host_memory(h.paths);
  ASSERT_TRUE(m.cgroup_headroom);
  EXPECT_EQ(*m.cgroup_headroom, 5 * kGiB);
  EXPECT_NE(m.cgroup_source.find("app/memory.max"), std::string::npos);
  EXPECT_EQ(m.available(), 5 * kGiB) << "the cgroup headroom is tighter than MemAvailable";

  h.file("app/job/memory.max", std::to_string(2 * kGiB) + "\n");  // now the job is tighter
  m = read_host_memory(h.paths);
  EXPECT_EQ(*m.cgroup_headroom, 2 * kGiB - kGiB / 2);
}

TEST(HostMemory, CgroupV1MemoryControllerAndHybridLayout) {
  FakeHost h;
  h.meminfo(8000000);
  h.membership("9:name=systemd:/\n4:cpu,memory:/batch/task\n0::/\n");
  h.file("memory/batch/task/memory.limit_in_bytes", std::to_string(3 * kGiB) + "\n");
  h.file("memory/batch/task/memory.usage_in_bytes", std::to_string(1 * kGiB) + "\n");
  h.file("memory/memory.limit_in_bytes", "9223372036854771712\n");  // v1's "no limit"
  h.file("memory/memory.usage_in_bytes", "123\n");
  h.file("unified/cgroup.controllers", "\n");  // hybrid: v2 under unified/, without memory files
  const HostMemory m = read_host_memory(h.paths);
  ASSERT_TRUE(m.cgroup_headroom);
  EXPECT_EQ(*m.cgroup_headroom, 2 * kGiB);
  EXPECT_EQ(m.available(), 2 * kGiB);
}

TEST(HostMemory, MissingFilesMeanNoInformation) {
  FakeHost h;  // nothing written
  const HostMemory m = read_host_memory(h.paths);
  EXPECT_EQ(m.mem_available, 0u);
  EXPECT_FALSE(m.cgroup_headroom);
  EXPECT_EQ(m.available(), 0u);
}

TEST(HostMemory, UsageAboveLimitLeavesNoHeadroom) {
  FakeHost h;
  h.meminfo(8000000);
  h.membership("0::/\n");
  h.file("cgroup.controllers", "memory\n");
  h.file("memory.max", "1000\n");
  h.file("memory.current", "5000\n");
  EXPECT_EQ(read_host_memory(h.paths).available(), 0u);
}

namespace {

BudgetReading host_reading(uint64_t available, uint64_t held = 0) {
  BudgetReading r;
  r.host.mem_available = available;
  r.held_bytes = held;
  return r;
}

}  // namespace

TEST(PlanWindow, HostMemoryBoundsTheWindow) {
  const FrameFootprint frame{100 * kMiB, 40 * kMiB};
  BudgetOptions o;  // half of what is available
  const WindowPlan p = plan_window(frame, host_reading(4 * kGiB), o, 3);
  // 2 GiB - 4 records x 40 MiB = 1888 MiB -> 18 frames of 100 MiB
  EXPECT_EQ(p.record_buffers, 4u);
  EXPECT_EQ(p.frames, 18u);
  EXPECT_EQ(p.host_budget, 2 * kGiB);
  EXPECT_EQ(p.limited_by, "host memory");
  EXPECT_FALSE(p.over_budget);
  EXPECT_LE(p.frames * frame.decoded_bytes + p.record_buffers * frame.record_bytes, p.host_budget);
}

TEST(PlanWindow, WhatThePipelineHoldsCountsAsAvailable) {
  const FrameFootprint frame{100 * kMiB, 40 * kMiB};
  const WindowPlan idle = plan_window(frame, host_reading(4 * kGiB), {}, 3);
  // The same machine once the pipeline holds 1 GiB: MemAvailable dropped by it.
  const WindowPlan busy = plan_window(frame, host_reading(3 * kGiB, kGiB), {}, 3);
  EXPECT_EQ(idle.frames, busy.frames) << "the window must not shrink because of its own memory";
}

TEST(PlanWindow, UserCapDeviceAndFrameLimits) {
  const FrameFootprint frame{100 * kMiB, 40 * kMiB};
  BudgetOptions o;
  o.memory_cap = 1 * kGiB;
  WindowPlan p = plan_window(frame, host_reading(64 * kGiB), o, 1);
  EXPECT_EQ(p.limited_by, "--memory");
  EXPECT_EQ(p.frames, (kGiB - 2 * 40 * kMiB) / (100 * kMiB));

  BudgetReading with_device = host_reading(64 * kGiB);
  with_device.device_available = 500 * kMiB;  // 80% -> 400 MiB -> 4 frames
  p = plan_window(frame, with_device, o, 1);
  EXPECT_EQ(p.limited_by, "device memory");
  EXPECT_EQ(p.frames, 4u);
  EXPECT_EQ(p.device_budget, 400 * kMiB);

  o.max_frames = 3;
  p = plan_window(frame, with_device, o, 1);
  EXPECT_EQ(p.limited_by, "--window");
  EXPECT_EQ(p.frames, 3u);

  o = {};
  o.ring_capacity = 16;
  p = plan_window({kMiB, kMiB}, host_reading(64 * kGiB), o, 1);
  EXPECT_EQ(p.frames, 16u);
  EXPECT_EQ(p.limited_by, "ring capacity");
}

TEST(PlanWindow, NeverBelowTwoFramesAndFewerRecordsToFit) {
  const FrameFootprint frame{100 * kMiB, 40 * kMiB};
  BudgetOptions o;
  o.memory_cap = 2 * 100 * kMiB + 40 * kMiB;  // exactly two frames and one record
  WindowPlan p = plan_window(frame, host_reading(64 * kGiB), o, 8);
  EXPECT_EQ(p.frames, 2u);
  EXPECT_EQ(p.record_buffers, 1u) << "records give way so that two frames fit";
  EXPECT_FALSE(p.over_budget);

  o.memory_cap = 150 * kMiB;  // not even two frames
  p = plan_window(frame, host_reading(64 * kGiB), o, 8);
  EXPECT_EQ(p.frames, 2u);
  EXPECT_TRUE(p.over_budget);
}

TEST(PlanWindow, BigFramesNeedFewRecordBuffers) {
  // One frame of 150 chunks keeps 16 workers busy: records for it, the next
  // being read and one to spare; the rest of the budget goes to frames.
  const FrameFootprint frame{100 * kMiB, 40 * kMiB, 150};
  BudgetOptions o;
  o.memory_cap = 2 * kGiB;
  const WindowPlan p = plan_window(frame, host_reading(64 * kGiB), o, 16);
  EXPECT_EQ(p.record_buffers, 3u);
  EXPECT_EQ(p.frames, (2 * kGiB - 3 * 40 * kMiB) / (100 * kMiB));
  const WindowPlan small = plan_window({kMiB, kMiB, 2}, host_reading(64 * kGiB), o, 16);
  EXPECT_EQ(small.record_buffers, 10u) << "two-chunk frames: eight decoding at once, one read, one spare";
}

TEST(PlanWindow, CgroupTighterThanHostIsNamed) {
  BudgetReading r = host_reading(64 * kGiB);
  r.host.cgroup_headroom = 2 * kGiB;
  const WindowPlan p = plan_window({100 * kMiB, 0}, r, {}, 1);
  EXPECT_EQ(p.limited_by, "cgroup limit");
  EXPECT_EQ(p.frames, 10u);
}

TEST(PlanWindow, UnknownHostMemoryStaysModest) {
  const WindowPlan p = plan_window({100 * kMiB, 0}, host_reading(0), {}, 1);
  EXPECT_EQ(p.host_budget, kGiB);
  EXPECT_EQ(p.frames, 10u);
}
