#include <fstream>
#include "bounds.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <thread>
#include <vector>

#include "sluice/error.h"
#include "sluice/runtime/record_source.h"

namespace sluice::bench {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

struct Fd {
  int fd;
  ~Fd() {
    if (fd >= 0) ::close(fd);
  }
};

constexpr uint64_t kPiece = 8u << 20;
constexpr uint64_t kAlign = 4096;

}  // namespace

double parallel_memcpy_gbps(int threads, double min_seconds) {
  const size_t bytes = size_t(64) << 20;
  std::vector<std::vector<char>> src(size_t(threads), std::vector<char>(bytes, 1)), dst(size_t(threads), std::vector<char>(bytes, 0));
  std::vector<double> rates(static_cast<size_t>(threads), 0.0);
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t) {
    pool.emplace_back([&, t] {
      auto& a = src[size_t(t)];
      auto& b = dst[size_t(t)];
      std::memcpy(b.data(), a.data(), bytes);  // fault the pages in first
      const auto start = Clock::now();
      size_t copies = 0;
      do {
        std::memcpy(b.data(), a.data(), bytes);
        ++copies;
      } while (seconds_since(start) < min_seconds);
      rates[size_t(t)] = double(bytes) * double(copies) / seconds_since(start) / 1e9;
    });
  }
  for (auto& t : pool) t.join();
  double total = 0;
  for (double r : rates) total += r;
  return total;
}

void drop_from_page_cache(const std::string& path, uint64_t offset, uint64_t bytes) {
  const Fd f{::open(path.c_str(), O_RDONLY | O_CLOEXEC)};
  if (f.fd < 0) throw io::Error({path}, std::string("cannot open: ") + std::strerror(errno));
  ::fdatasync(f.fd);  // dirty pages cannot be dropped
  ::posix_fadvise(f.fd, static_cast<off_t>(offset), static_cast<off_t>(bytes), POSIX_FADV_DONTNEED);
}

double page_cache_share(const std::string& path, uint64_t offset, uint64_t bytes) {
  const Fd f{::open(path.c_str(), O_RDONLY | O_CLOEXEC)};
  if (f.fd < 0 || bytes == 0) return 0;
  const auto page = static_cast<uint64_t>(::sysconf(_SC_PAGESIZE));
  const uint64_t begin = offset / page * page;
  const uint64_t length = offset + bytes - begin;
  void* map = ::mmap(nullptr, length, PROT_READ, MAP_SHARED, f.fd, static_cast<off_t>(begin));
  if (map == MAP_FAILED) return 0;
  std::vector<unsigned char> resident((length + page - 1) / page);
  double share = 0;
  if (::mincore(map, length, resident.data()) == 0) {
    size_t in = 0;
    for (unsigned char r : resident) in += r & 1;
    share = double(in) / double(resident.size());
  }
  ::munmap(map, length);
  return share;
}

std::optional<double> sequential_read_gbps(const std::string& path, uint64_t offset, uint64_t bytes, ReadMode mode,
                                           double min_seconds, int threads) {
  if (mode == ReadMode::BufferedCold) drop_from_page_cache(path, offset, bytes);
  const int flags = O_RDONLY | O_CLOEXEC | (mode == ReadMode::Direct ? O_DIRECT : 0);
  const Fd f{::open(path.c_str(), flags)};
  if (f.fd < 0) {
    if (mode == ReadMode::Direct) return std::nullopt;
    throw io::Error({path}, std::string("cannot open: ") + std::strerror(errno));
  }
  if (mode != ReadMode::Direct) ::posix_fadvise(f.fd, 0, 0, POSIX_FADV_SEQUENTIAL);
  const uint64_t begin = offset / kAlign * kAlign, end = offset + bytes;
  const uint64_t pieces = (end - begin + kPiece - 1) / kPiece;
  std::atomic<uint64_t> total{0};
  std::atomic<bool> refused{false};
  const auto start = Clock::now();
  do {
    std::atomic<uint64_t> next{0};
    std::vector<std::thread> pool;
    for (int t = 0; t < std::max(1, threads); ++t) {
      pool.emplace_back([&] {
        void* raw = std::aligned_alloc(kAlign, kPiece);
        const std::unique_ptr<void, decltype(&std::free)> buffer(raw, &std::free);
        for (uint64_t p; raw && (p = next.fetch_add(1)) < pieces;) {
          const uint64_t at = begin + p * kPiece;
          const ssize_t n = ::pread(f.fd, raw, std::min(kPiece, end - at + kAlign - 1) / kAlign * kAlign,
                                    static_cast<off_t>(at));
          if (n < 0 && mode == ReadMode::Direct && errno == EINVAL) refused = true;
          if (n <= 0) break;
          total += static_cast<uint64_t>(n);
        }
      });
    }
    for (auto& t : pool) t.join();
  } while (mode == ReadMode::PageCache && seconds_since(start) < min_seconds);
  if (refused) return std::nullopt;
  return double(total.load()) / seconds_since(start) / 1e9;
}

double window_read_gbps(const std::string& path, uint64_t offset, uint64_t bytes, uint64_t frame_bytes, int threads,
                        bool mapped, double min_seconds, uint32_t window) {
  const Fd f{::open(path.c_str(), O_RDONLY | O_CLOEXEC)};
  if (f.fd < 0) throw io::Error({path}, std::string("cannot open: ") + std::strerror(errno));
  runtime::FileRecordSource source(path, f.fd, false, mapped);
  frame_bytes = std::max<uint64_t>(1, std::min(frame_bytes, bytes));
  const uint64_t frames = std::max<uint64_t>(1, bytes / frame_bytes);
  std::vector<std::unique_ptr<std::byte[]>> areas;
  for (uint32_t w = 0; w < window; ++w) {
    areas.emplace_back(new std::byte[frame_bytes]);
    std::memset(areas.back().get(), 0, frame_bytes);  // faulted in: only the copy is timed
  }
  const uint64_t per_frame = (frame_bytes + kPiece - 1) / kPiece;
  std::atomic<uint64_t> total{0};
  uint64_t rounds = 0;
  const auto start = Clock::now();
  do {
    std::atomic<uint64_t> next{0};
    std::vector<std::thread> pool;
    for (int t = 0; t < std::max(1, threads); ++t) {
      pool.emplace_back([&] {
        for (uint64_t p; (p = next.fetch_add(1)) < frames * per_frame;) {
          const uint64_t frame = p / per_frame, at = (p % per_frame) * kPiece;
          const uint64_t n = std::min(kPiece, frame_bytes - at);
          std::byte* dst = areas[(rounds * frames + frame) % window].get() + at;
          uint64_t got = 0;
          while (got < n) {
            const size_t r = source.read_at({dst + got, n - got}, offset + frame * frame_bytes + at + got);
            if (r == 0) break;
            got += r;
          }
          total += got;
        }
      });
    }
    for (auto& t : pool) t.join();
    ++rounds;
  } while (seconds_since(start) < min_seconds);
  return double(total.load()) / seconds_since(start) / 1e9;
}

uint64_t process_read_bytes() {
  std::ifstream io("/proc/self/io");
  std::string key;
  uint64_t value = 0;
  while (io >> key >> value) {
    if (key == "read_bytes:") return value;
  }
  return 0;
}

}  // namespace sluice::bench
