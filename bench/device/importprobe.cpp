// A probe, not part of the build: which host mappings the device accepts as
// imported memory (VK_EXT_external_memory_host), how long the import takes,
// and how fast the GPU copies out of it. One mode per process: after NVIDIA
// refuses an import, the process's next allocation fails too. Figures in
// docs/measurements.md ("Which mappings the driver imports"); run.sh's
// importprobe stage runs every mode.
//   g++ -O2 -mavx2 -std=c++20 bench/device/importprobe.cpp -o .gpu/importprobe -lvulkan
//   importprobe MODE FILE BYTES
// MODE: anon | shared_ro | private_ro | private_rw | shared_rw
#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <string>

#include "probe.h"

namespace {

// The host memory to import, by mode: anonymous, or FILE mapped as the mode says.
void* map_host(const std::string& mode, const char* path, size_t bytes) {
  if (mode == "anon") return mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_POPULATE, -1, 0);
  const bool shared_rw = mode == "shared_rw";
  const int fd = open(path, (shared_rw ? O_RDWR : O_RDONLY) | O_CLOEXEC);
  if (fd < 0) {
    std::printf("  cannot open %s\n", path);
    std::exit(2);
  }
  const int prot = (mode == "private_rw" || shared_rw) ? PROT_READ | PROT_WRITE : PROT_READ;
  const int flags = (mode.rfind("private", 0) == 0 ? MAP_PRIVATE : MAP_SHARED) | MAP_POPULATE;
  void* host = mmap(nullptr, bytes, prot, flags, fd, 0);
  close(fd);
  return host;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4) return std::fprintf(stderr, "importprobe MODE FILE BYTES\n"), 1;
  const std::string mode = argv[1];
  const probe::Device d = probe::make_device(false);
  const size_t bytes = std::strtoull(argv[3], nullptr, 10) / d.import_alignment * d.import_alignment;

  const auto mapping = probe::Clock::now();
  void* host = map_host(mode, argv[2], bytes);
  if (host == MAP_FAILED) return std::printf("  mmap failed: %s\n", std::strerror(errno)), 2;
  std::printf("  %s: %zu bytes mapped in %.1f ms (alignment %zu)\n", mode.c_str(), bytes, 1e3 * probe::since(mapping),
              d.import_alignment);

  probe::Buffer source;
  const auto importing = probe::Clock::now();
  const VkResult r = probe::import_host(d, host, bytes, source);
  const double import_ms = 1e3 * probe::since(importing);
  if (r != VK_SUCCESS) return std::printf("  import REFUSED: VkResult %d after %.1f ms\n", int(r), import_ms), 3;
  std::printf("  import accepted in %.1f ms (%.2f GB/s pinned)\n", import_ms, double(bytes) / (import_ms * 1e6));

  const probe::Buffer dest = probe::device_buffer(d, bytes);
  const VkCommandBuffer cmd = probe::command_buffers(d, 1)[0];
  probe::record_copy(cmd, source.buffer, 0, dest.buffer, 0, bytes);
  const VkFence fence = probe::make_fence(d);
  std::printf("  copy out of it:");
  for (int i = 0; i < 8; ++i) {
    const auto t = probe::Clock::now();
    probe::submit(d, cmd, fence);
    PROBE_CHECK(vkWaitForFences(d.device, 1, &fence, VK_TRUE, UINT64_MAX));
    std::printf(" %.1f", double(bytes) / (probe::since(t) * 1e9));
    PROBE_CHECK(vkResetFences(d.device, 1, &fence));
  }
  std::puts(" GB/s");
  const auto releasing = probe::Clock::now();
  vkFreeMemory(d.device, source.memory, nullptr);
  std::printf("  released in %.1f ms\n", 1e3 * probe::since(releasing));
  return 0;
}
