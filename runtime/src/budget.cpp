#include "sluice/runtime/budget.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

namespace sluice::runtime {
namespace {

namespace fs = std::filesystem;

// v1 reports "no limit" as a huge page-rounded number; anything this large
// is no limit in practice.
constexpr uint64_t kNoLimit = uint64_t(1) << 60;

std::optional<uint64_t> read_number_file(const fs::path& path) {
  std::ifstream in(path);
  std::string word;
  if (!(in >> word) || word == "max") return std::nullopt;
  try {
    size_t used = 0;
    const uint64_t value = std::stoull(word, &used);
    if (used != word.size()) return std::nullopt;
    return value;
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

uint64_t read_mem_available(const std::string& path) {
  std::ifstream in(path);
  std::string key, unit;
  uint64_t value = 0;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    if (!(fields >> key >> value)) continue;
    if (key != "MemAvailable:") continue;
    fields >> unit;
    return unit == "kB" ? value * 1024 : value;
  }
  return 0;
}

// The cgroup paths of this process: the v2 path ("0::/a/b") and the v1 path
// of the memory controller ("4:memory:/a/b"), where present.
struct CgroupMembership {
  std::optional<std::string> v2;
  std::optional<std::string> v1_memory;
};

CgroupMembership read_membership(const std::string& path) {
  CgroupMembership m;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    const size_t a = line.find(':');
    const size_t b = a == std::string::npos ? a : line.find(':', a + 1);
    if (b == std::string::npos) continue;
    const std::string controllers = line.substr(a + 1, b - a - 1);
    const std::string where = line.substr(b + 1);
    if (line.compare(0, a, "0") == 0 && controllers.empty()) m.v2 = where;
    std::istringstream list(controllers);
    for (std::string c; std::getline(list, c, ',');) {
      if (c == "memory") m.v1_memory = where;
    }
  }
  return m;
}

// The values of `keys` in a memory.stat file ("key value" lines); 0 for a
// key that is missing.
std::vector<uint64_t> read_stat_values(const fs::path& path, const std::vector<std::string>& keys) {
  std::vector<uint64_t> values(keys.size(), 0);
  std::ifstream in(path);
  std::string key;
  uint64_t value = 0;
  while (in >> key >> value) {
    for (size_t k = 0; k < keys.size(); ++k) {
      if (key == keys[k]) values[k] = value;
    }
  }
  return values;
}

// Page cache the kernel would reclaim before refusing an allocation in this
// cgroup: file pages on both LRU lists, less those still to be written.
// v2 names them per cgroup (hierarchical already); v1's total_* are the
// hierarchical counts that usage_in_bytes includes.
uint64_t reclaimable_file_cache(const fs::path& dir, bool v2) {
  const std::vector<uint64_t> v =
      v2 ? read_stat_values(dir / "memory.stat", {"inactive_file", "active_file", "file_dirty", "file_writeback"})
         : read_stat_values(dir / "memory.stat",
                            {"total_inactive_file", "total_active_file", "total_dirty", "total_writeback"});
  const uint64_t file = v[0] + v[1], pending = v[2] + v[3];
  return file > pending ? file - pending : 0;
}

// Headroom (limit - usage + reclaimable page cache) at `dir` and each of its
// parents up to `root`; the smallest one wins, as the kernel enforces every
// level. The page cache counts as available: a player streaming a file
// larger than the limit fills the cgroup with cache the kernel takes back.
void tightest_headroom(const fs::path& root, const std::string& cgroup, bool v2, HostMemory& out) {
  const char* limit_name = v2 ? "memory.max" : "memory.limit_in_bytes";
  const char* usage_name = v2 ? "memory.current" : "memory.usage_in_bytes";
  fs::path rel = fs::path(cgroup).relative_path();
  while (true) {
    const fs::path dir = root / rel;
    const auto limit = read_number_file(dir / limit_name);
    const auto usage = read_number_file(dir / usage_name);
    if (limit && usage && *limit < kNoLimit) {
      const uint64_t cache = std::min(reclaimable_file_cache(dir, v2), *usage);
      const uint64_t used = *usage - cache;
      const uint64_t headroom = *limit > used ? *limit - used : 0;
      if (!out.cgroup_headroom || headroom < *out.cgroup_headroom) {
        out.cgroup_headroom = headroom;
        out.cgroup_file_cache = cache;
        out.cgroup_source = (dir / limit_name).string();
      }
    }
    if (rel.empty()) break;
    rel = rel.parent_path();
  }
}

}  // namespace

uint64_t HostMemory::available() const {
  if (cgroup_headroom && mem_available) return std::min(*cgroup_headroom, mem_available);
  return cgroup_headroom ? *cgroup_headroom : mem_available;
}

HostMemory read_host_memory(const HostMemoryPaths& paths) {
  HostMemory out;
  out.mem_available = read_mem_available(paths.meminfo);
  const CgroupMembership m = read_membership(paths.self_cgroup);
  const fs::path root(paths.cgroup_root);
  // v2 is mounted at the root (pure v2) or under "unified" (hybrid systems).
  if (m.v2) {
    for (const fs::path& v2_root : {root, root / "unified"}) {
      std::error_code ec;
      if (fs::exists(v2_root / "cgroup.controllers", ec)) {
        tightest_headroom(v2_root, *m.v2, true, out);
        break;
      }
    }
  }
  if (m.v1_memory) tightest_headroom(root / "memory", *m.v1_memory, false, out);
  return out;
}

std::optional<uint64_t> parse_byte_size(const std::string& text) {
  size_t i = 0;
  while (i < text.size() && (std::isdigit(static_cast<unsigned char>(text[i])) || text[i] == '.')) ++i;
  if (i == 0) return std::nullopt;
  double value = 0;
  try {
    size_t used = 0;
    value = std::stod(text.substr(0, i), &used);
    if (used != i) return std::nullopt;
  } catch (const std::exception&) {
    return std::nullopt;
  }
  std::string unit;
  for (size_t j = i; j < text.size(); ++j) {
    if (!std::isspace(static_cast<unsigned char>(text[j]))) unit += char(std::toupper(static_cast<unsigned char>(text[j])));
  }
  if (unit.size() > 1 && unit.back() == 'B') unit.pop_back();           // "GB" -> "G"
  if (unit.size() > 1 && unit.back() == 'I') unit.pop_back();           // "GIB" -> "GI" -> "G"
  static const std::vector<std::pair<std::string, int>> kShifts = {{"", 0}, {"B", 0}, {"K", 10}, {"M", 20}, {"G", 30}, {"T", 40}};
  for (const auto& [name, shift] : kShifts) {
    if (unit != name) continue;
    const double bytes = value * std::ldexp(1.0, shift);
    if (!std::isfinite(bytes) || bytes >= 1.8e19) return std::nullopt;
    return static_cast<uint64_t>(bytes);
  }
  return std::nullopt;
}

}  // namespace sluice::runtime
