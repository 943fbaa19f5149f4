// Memory budgets: /proc/meminfo and cgroup files (fake trees), user sizes,
// and the window planned from them.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "runtime_test_util.h"
#include "sluice/runtime/budget.h"

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

// memory.stat as this machine's cgroup v1 wrote it (the test machine, while
// building): page cache counts as available, less the dirty pages.
constexpr const char* kRealV1Stat =
    "cache 706551808\nrss 728047616\nrss_huge 0\nshmem 0\nmapped_file 26726400\ndirty 5275648\nwriteback 0\n"
    "workingset_refault_anon 0\nworkingset_refault_file 225513\nswap 0\nswapcached 0\npgpgin 41945456\n"
    "pgpgout 41638512\npgfault 43948877\npgmajfault 2454\ninactive_anon 727916544\nactive_anon 81920\n"
    "inactive_file 192098304\nactive_file 514453504\nunevictable 0\nhierarchical_memory_limit 9223372036854771712\n"
    "hierarchical_memsw_limit 9223372036854771712\ntotal_cache 706551808\ntotal_rss 728047616\ntotal_rss_huge 0\n"
    "total_shmem 0\ntotal_mapped_file 26726400\ntotal_dirty 5275648\ntotal_writeback 0\n"
    "total_workingset_refault_anon 0\ntotal_workingset_refault_file 225513\ntotal_swap 0\ntotal_swapcached 0\n"
    "total_pgpgin 41945456\ntotal_pgpgout 41638512\ntotal_pgfault 43948877\ntotal_pgmajfault 2454\n"
    "total_inactive_anon 727916544\ntotal_active_anon 81920\ntotal_inactive_file 192098304\n"
    "total_active_file 514453504\ntotal_unevictable 0\n";

// The key set cgroup v2 writes (Linux 6.1), with a player's page cache.
constexpr const char* kV2Stat =
    "anon 1073741824\nfile 2684354560\nkernel 52428800\nkernel_stack 1048576\npagetables 4194304\n"
    "sec_pagetables 0\npercpu 0\nsock 0\nvmalloc 0\nshmem 0\nzswap 0\nzswapped 0\nfile_mapped 8388608\n"
    "file_dirty 104857600\nfile_writeback 0\nswapcached 0\nanon_thp 0\nfile_thp 0\nshmem_thp 0\n"
    "inactive_anon 1073741824\nactive_anon 0\ninactive_file 1610612736\nactive_file 1073741824\nunevictable 0\n"
    "slab_reclaimable 20971520\nslab_unreclaimable 10485760\nslab 31457280\nworkingset_refault_anon 0\n"
    "workingset_refault_file 1000\npgfault 123456\npgmajfault 12\n";

TEST(HostMemory, CgroupPageCacheCountsAsAvailableV1) {
  FakeHost h;
  h.meminfo(8000000);
  h.membership("4:memory:/player\n");
  const uint64_t usage = 706551808ull + 728047616ull;  // cache + rss, as usage_in_bytes counts them
  h.file("memory/player/memory.limit_in_bytes", std::to_string(2 * kGiB) + "\n");
  h.file("memory/player/memory.usage_in_bytes", std::to_string(usage) + "\n");
  h.file("memory/player/memory.stat", kRealV1Stat);
  const HostMemory m = read_host_memory(h.paths);
  ASSERT_TRUE(m.cgroup_headroom);
  const uint64_t cache = 192098304ull + 514453504ull - 5275648ull;  // file LRU pages less dirty
  EXPECT_EQ(m.cgroup_file_cache, cache);
  EXPECT_EQ(*m.cgroup_headroom, 2 * kGiB - (usage - cache));
}

TEST(HostMemory, CgroupPageCacheCountsAsAvailableV2) {
  FakeHost h;
  h.meminfo(16000000);
  h.membership("0::/player\n");
  h.file("cgroup.controllers", "memory\n");
  h.file("player/memory.max", std::to_string(4 * kGiB) + "\n");
  h.file("player/memory.current", std::to_string(3 * kGiB + kGiB / 2) + "\n");  // mostly page cache
  h.file("player/memory.stat", kV2Stat);
  const HostMemory m = read_host_memory(h.paths);
  ASSERT_TRUE(m.cgroup_headroom);
  EXPECT_EQ(m.cgroup_file_cache, 1610612736ull + 1073741824ull - 104857600ull);
  EXPECT_EQ(*m.cgroup_headroom, 4 * kGiB - (3 * kGiB + kGiB / 2 - m.cgroup_file_cache));
  // Without memory.stat (or with a cache larger than the usage) nothing is invented.
  h.file("player/memory.stat", "inactive_file 99999999999\n");
  EXPECT_EQ(*read_host_memory(h.paths).cgroup_headroom, 4 * kGiB);
}

// Writes a cgroup control file in place (cgroupfs has no renames).
bool write_control(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  out.flush();
  return bool(out);
}

// In a real memory cgroup, where the machine lets the test make one (root,
// cgroup v1 or v2 with the memory controller): a child writes a file inside
// it, the page cache is charged to the cgroup, and the headroom still counts
// it as available.
TEST(HostMemory, RealCgroupPageCacheCountsAsAvailable) {
  std::ifstream self("/proc/self/cgroup");
  std::string line, v1_path, v2_path;
  while (std::getline(self, line)) {
    const size_t a = line.find(':'), b = line.find(':', a + 1);
    if (b == std::string::npos) continue;
    const std::string controllers = line.substr(a + 1, b - a - 1), where = line.substr(b + 1);
    if (controllers.find("memory") != std::string::npos) v1_path = where;
    if (line.compare(0, 2, "0:") == 0 && controllers.empty()) v2_path = where;
  }
  namespace fs = std::filesystem;
  const std::string name = "sluice-budget-test-" + std::to_string(::getpid());
  fs::path dir;
  std::string membership;
  std::error_code ec;
  if (!v1_path.empty() && fs::create_directory(fs::path("/sys/fs/cgroup/memory") / fs::path(v1_path).relative_path() / name, ec)) {
    dir = fs::path("/sys/fs/cgroup/memory") / fs::path(v1_path).relative_path() / name;
    membership = "4:memory:" + (fs::path(v1_path) / name).string() + "\n";
    write_control(dir / "memory.limit_in_bytes", std::to_string(512 * kMiB));
  } else if (!v2_path.empty() && fs::create_directory(fs::path("/sys/fs/cgroup") / fs::path(v2_path).relative_path() / name, ec)) {
    dir = fs::path("/sys/fs/cgroup") / fs::path(v2_path).relative_path() / name;
    membership = "0::" + (fs::path(v2_path) / name).string() + "\n";
    write_control(dir / "memory.max", std::to_string(512 * kMiB));
  }
  if (dir.empty() || !(fs::exists(dir / "memory.limit_in_bytes") || fs::exists(dir / "memory.max"))) {
    if (!dir.empty()) fs::remove(dir, ec);
    GTEST_SKIP() << "cannot create a memory cgroup here";
  }
  test::TempDir tmp;
  const fs::path data = tmp / "cache.bin";
  const std::string command = "sh -c 'echo $$ > " + (dir / "cgroup.procs").string() + " && dd if=/dev/zero of=" +
                              data.string() + " bs=1M count=128 conv=fsync 2>/dev/null'";
  const int status = std::system(command.c_str());
  HostMemoryPaths paths;
  paths.self_cgroup = (tmp / "self_cgroup").string();
  test::write_text_file(paths.self_cgroup, membership);
  const HostMemory m = read_host_memory(paths);
  fs::remove(data, ec);
  if (fs::exists(dir / "memory.force_empty")) write_control(dir / "memory.force_empty", "0");
  fs::remove(dir, ec);
  ASSERT_EQ(status, 0) << command;
  ASSERT_TRUE(m.cgroup_headroom);
  std::printf("real cgroup, 512 MiB limit: headroom %.1f MiB, reclaimable page cache %.1f MiB\n",
              double(*m.cgroup_headroom) / double(kMiB), double(m.cgroup_file_cache) / double(kMiB));
  EXPECT_GE(m.cgroup_file_cache, 100 * kMiB) << "the 128 MiB written should be cached and charged to the cgroup";
  EXPECT_GE(*m.cgroup_headroom, 512 * kMiB - 28 * kMiB) << "the page cache counts as available";
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
  // 2 GiB - 5 records x 40 MiB = 1848 MiB -> 18 frames of 100 MiB
  EXPECT_EQ(p.record_buffers, 5u);
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
  // two being read and one to spare; the rest of the budget goes to frames.
  const FrameFootprint frame{100 * kMiB, 40 * kMiB, 150};
  BudgetOptions o;
  o.memory_cap = 2 * kGiB;
  const WindowPlan p = plan_window(frame, host_reading(64 * kGiB), o, 16);
  EXPECT_EQ(p.record_buffers, 4u);
  EXPECT_EQ(p.frames, (2 * kGiB - 4 * 40 * kMiB) / (100 * kMiB));
  const WindowPlan small = plan_window({kMiB, kMiB, 2}, host_reading(64 * kGiB), o, 16);
  EXPECT_EQ(small.record_buffers, 11u) << "two-chunk frames: eight decoding at once, two read, one spare";
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
