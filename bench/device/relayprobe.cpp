// A probe, not part of the build: the smallest pipeline of the GPU path's
// bytes, to see what the host's memory lets through when the CPU copies a
// file's frames out of the page cache into staging and the GPU copies the
// staging to device memory at the same time. The file is read as a stream
// of units (a whole frame, or a piece of one); each unit is copied into a
// ring of `slots` staging slots by `threads` threads (streaming stores, or
// plain stores that leave the slot in the CPU's cache), then handed to the
// GPU on its copy-only queue, whose copy frees the slot again. Small rings
// of plain stores test whether staging the GPU reads soon after from the
// last-level cache spares the host's memory a write and a read per byte.
// Figures in docs/measurements.md ("A small ring the GPU reads from the
// cache"); run.sh's relayprobe stage runs a grid of shapes.
//   g++ -O2 -mavx2 -std=c++20 bench/device/relayprobe.cpp -o .gpu/relayprobe -lvulkan -pthread
//   relayprobe FILE FRAME_BYTES UNIT_BYTES SLOTS THREADS nt|plain SECONDS
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <string>
#include <thread>

#include "probe.h"

namespace {

// Threads that copy their share of the unit the caller names, all at once.
class Crew {
 public:
  Crew(int threads, size_t unit, bool streaming) : threads_(threads), unit_(unit), streaming_(streaming) {
    share_ = (unit / size_t(threads) + 4095) / 4096 * 4096;
    for (int t = 0; t < threads; ++t) workers_.emplace_back([this, t] { work(t); });
  }
  ~Crew() {
    stop_ = true;
    for (auto& w : workers_) w.join();
  }
  // Copies the unit at src to dst on every thread; returns when all are done.
  void copy(char* dst, const char* src) {
    dst_ = dst;
    src_ = src;
    done_.store(0, std::memory_order_relaxed);
    go_.fetch_add(1, std::memory_order_release);
    while (done_.load(std::memory_order_acquire) < threads_) _mm_pause();
  }

 private:
  void work(int t) {
    uint64_t seen = 0;
    for (;;) {
      uint64_t g;
      while ((g = go_.load(std::memory_order_acquire)) == seen) {
        if (stop_.load(std::memory_order_relaxed)) return;
        _mm_pause();
      }
      seen = g;
      const size_t begin = std::min(unit_, size_t(t) * share_), end = std::min(unit_, begin + share_);
      if (end > begin) {
        if (streaming_) probe::nt_copy(dst_ + begin, src_ + begin, end - begin);
        else std::memcpy(dst_ + begin, src_ + begin, end - begin);
      }
      done_.fetch_add(1, std::memory_order_acq_rel);
    }
  }

  const int threads_;
  const size_t unit_;
  const bool streaming_;
  size_t share_ = 0;
  std::atomic<uint64_t> go_{0};
  std::atomic<int> done_{0};
  std::atomic<bool> stop_{false};
  char* dst_ = nullptr;        // written before go_ (release), read after it (acquire)
  const char* src_ = nullptr;
  std::vector<std::thread> workers_;
};

}  // namespace

int main(int argc, char** argv) {
  if (argc < 8) return std::fprintf(stderr, "relayprobe FILE FRAME_BYTES UNIT_BYTES SLOTS THREADS nt|plain SECONDS\n"), 1;
  const char* path = argv[1];
  const size_t frame = std::strtoull(argv[2], nullptr, 10);
  const size_t unit = (std::strtoull(argv[3], nullptr, 10) + 4095) / 4096 * 4096;
  const int slots = std::atoi(argv[4]), threads = std::atoi(argv[5]);
  const bool streaming = std::string(argv[6]) == "nt";
  const double seconds = std::atof(argv[7]);

  const int fd = open(path, O_RDONLY);
  struct stat st {};
  if (fd < 0 || fstat(fd, &st) != 0) return std::printf("cannot open %s\n", path), 2;
  const size_t file = size_t(st.st_size) / unit * unit;
  const auto* map = static_cast<const char*>(mmap(nullptr, file, PROT_READ, MAP_SHARED | MAP_POPULATE, fd, 0));
  if (map == MAP_FAILED) return std::puts("mmap failed"), 2;
  const size_t units = file / unit;

  const probe::Device d = probe::make_device(true);
  const size_t ring_bytes = size_t(slots) * unit;
  auto* ring = static_cast<char*>(mmap(nullptr, ring_bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_POPULATE, -1, 0));
  std::memset(ring, 1, ring_bytes);
  probe::Buffer staging;
  PROBE_CHECK(probe::import_host(d, ring, ring_bytes, staging));
  const probe::Buffer dest = probe::device_buffer(d, 2 * frame + unit);  // two frames' places, alternated
  const std::vector<VkCommandBuffer> cmds = probe::command_buffers(d, uint32_t(slots));
  std::vector<VkFence> fences(static_cast<size_t>(slots));
  for (VkFence& f : fences) f = probe::make_fence(d);
  std::vector<bool> pending(static_cast<size_t>(slots), false);

  Crew crew(threads, unit, streaming);
  uint64_t copied = 0, waits = 0;
  double cpu_s = 0;
  const size_t units_per_frame = std::max<size_t>(1, frame / unit);
  const auto start = probe::Clock::now();
  for (uint64_t u = 0;; ++u) {
    const size_t s = size_t(u % uint64_t(slots));
    if (pending[s]) {  // the slot's last unit is still on its way to the GPU
      if (vkGetFenceStatus(d.device, fences[s]) != VK_SUCCESS) ++waits;
      PROBE_CHECK(vkWaitForFences(d.device, 1, &fences[s], VK_TRUE, UINT64_MAX));
      PROBE_CHECK(vkResetFences(d.device, 1, &fences[s]));
      pending[s] = false;
    }
    if (probe::since(start) >= seconds) break;
    const auto copying = probe::Clock::now();
    const size_t at = size_t(u % units) * unit;
    crew.copy(ring + s * unit, map + at);
    cpu_s += probe::since(copying);
    const size_t into = (u / units_per_frame) % 2 * frame + at % frame;
    probe::record_copy(cmds[s], staging.buffer, s * unit, dest.buffer, into, unit);
    probe::submit(d, cmds[s], fences[s]);
    pending[s] = true;
    copied += unit;
  }
  for (size_t s = 0; s < size_t(slots); ++s) {
    if (pending[s]) PROBE_CHECK(vkWaitForFences(d.device, 1, &fences[s], VK_TRUE, UINT64_MAX));
  }
  const double wall = probe::since(start);
  std::printf("family %u: unit %6.1f MB x %2d slots (%6.1f MB ring), %2d threads, %-5s stores: %6.2f GB/s = %6.1f frames/s; "
              "CPU copying %3.0f%% of the time, %llu waits for a slot\n",
              d.family, double(unit) / 1e6, slots, double(ring_bytes) / 1e6, threads, streaming ? "nt" : "plain",
              double(copied) / wall / 1e9, double(copied) / wall / double(frame), 100 * cpu_s / wall,
              static_cast<unsigned long long>(waits));
  return 0;
}
