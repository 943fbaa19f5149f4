// A probe, not part of the build: the smallest pipeline of the GPU path's
// bytes, to see what the host's memory lets through when the CPU copies a
// file's frames out of the page cache into staging and the GPU copies the
// staging to device memory at the same time. The file is read as a stream
// of units (a whole frame, or a piece of one); each unit is copied into a
// ring of `slots` staging slots by `threads` threads (streaming stores, or
// plain stores that leave the slot in the CPU's cache), then handed to the
// GPU, whose copy frees the slot again. Small rings of plain stores test
// whether staging the GPU reads soon after from the last-level cache spares
// the host's memory a write and a read per byte.
//   g++ -O2 -mavx2 -std=c++20 bench/device/relayprobe.cpp -o .gpu/relayprobe -lvulkan -pthread
//   relayprobe FILE FRAME_BYTES UNIT_BYTES SLOTS THREADS nt|plain SECONDS
#include <fcntl.h>
#include <immintrin.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#include <vulkan/vulkan.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

using Clock = std::chrono::steady_clock;
static double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }
#define CHECK(x)                                                                    \
  do {                                                                              \
    VkResult r_ = (x);                                                              \
    if (r_ != VK_SUCCESS) {                                                         \
      std::printf("%s failed: VkResult %d\n", #x, int(r_));                         \
      std::exit(2);                                                                 \
    }                                                                               \
  } while (0)

static void nt_copy(char* dst, const char* src, size_t n) {
  size_t i = 0;
  for (; i + 128 <= n; i += 128) {  // dst 32-aligned: slots and shares are
    __m256i a = _mm256_loadu_si256((const __m256i*)(src + i));
    __m256i b = _mm256_loadu_si256((const __m256i*)(src + i + 32));
    __m256i c = _mm256_loadu_si256((const __m256i*)(src + i + 64));
    __m256i d = _mm256_loadu_si256((const __m256i*)(src + i + 96));
    _mm256_stream_si256((__m256i*)(dst + i), a);
    _mm256_stream_si256((__m256i*)(dst + i + 32), b);
    _mm256_stream_si256((__m256i*)(dst + i + 64), c);
    _mm256_stream_si256((__m256i*)(dst + i + 96), d);
  }
  std::memcpy(dst + i, src + i, n - i);
  _mm_sfence();
}

int main(int argc, char** argv) {
  if (argc < 8) return std::fprintf(stderr, "relayprobe FILE FRAME_BYTES UNIT_BYTES SLOTS THREADS nt|plain SECONDS\n"), 1;
  const char* path = argv[1];
  const size_t frame = std::strtoull(argv[2], nullptr, 10);
  size_t unit = std::strtoull(argv[3], nullptr, 10);
  const int slots = std::atoi(argv[4]), threads = std::atoi(argv[5]);
  const bool nt = std::string(argv[6]) == "nt";
  const double seconds = std::atof(argv[7]);
  unit = (unit + 4095) / 4096 * 4096;

  const int fd = open(path, O_RDONLY);
  struct stat st;
  fstat(fd, &st);
  const size_t file = size_t(st.st_size) / unit * unit;
  const char* map = static_cast<const char*>(mmap(nullptr, file, PROT_READ, MAP_SHARED | MAP_POPULATE, fd, 0));
  if (map == MAP_FAILED) return std::puts("mmap failed"), 2;
  const size_t units = file / unit;

  // Vulkan: one queue, staging imported from anonymous memory, two device buffers.
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.apiVersion = VK_API_VERSION_1_2;
  VkInstanceCreateInfo ici{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  ici.pApplicationInfo = &app;
  VkInstance instance;
  CHECK(vkCreateInstance(&ici, nullptr, &instance));
  uint32_t n = 1;
  VkPhysicalDevice physical;
  vkEnumeratePhysicalDevices(instance, &n, &physical);
  // A queue family for copies only (the copy engines, as the renderer's
  // transfer queue), else family 0.
  uint32_t qn = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(physical, &qn, nullptr);
  std::vector<VkQueueFamilyProperties> qf(qn);
  vkGetPhysicalDeviceQueueFamilyProperties(physical, &qn, qf.data());
  uint32_t family = 0;
  for (uint32_t i = 0; i < qn; ++i)
    if ((qf[i].queueFlags & VK_QUEUE_TRANSFER_BIT) && !(qf[i].queueFlags & (VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT))) {
      family = i;
      break;
    }
  float priority = 1;
  VkDeviceQueueCreateInfo qci{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  qci.queueFamilyIndex = family;
  qci.queueCount = 1;
  qci.pQueuePriorities = &priority;
  const char* ext[] = {VK_EXT_EXTERNAL_MEMORY_HOST_EXTENSION_NAME};
  VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  dci.queueCreateInfoCount = 1;
  dci.pQueueCreateInfos = &qci;
  dci.enabledExtensionCount = 1;
  dci.ppEnabledExtensionNames = ext;
  VkDevice device;
  CHECK(vkCreateDevice(physical, &dci, nullptr, &device));
  auto host_props = reinterpret_cast<PFN_vkGetMemoryHostPointerPropertiesEXT>(
      vkGetDeviceProcAddr(device, "vkGetMemoryHostPointerPropertiesEXT"));
  VkQueue queue;
  vkGetDeviceQueue(device, family, 0, &queue);

  const size_t ring_bytes = size_t(slots) * unit;
  char* ring = static_cast<char*>(mmap(nullptr, ring_bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_POPULATE, -1, 0));
  std::memset(ring, 1, ring_bytes);
  VkMemoryHostPointerPropertiesEXT hp{VK_STRUCTURE_TYPE_MEMORY_HOST_POINTER_PROPERTIES_EXT};
  CHECK(host_props(device, VK_EXTERNAL_MEMORY_HANDLE_TYPE_HOST_ALLOCATION_BIT_EXT, ring, &hp));
  VkExternalMemoryBufferCreateInfo ebi{VK_STRUCTURE_TYPE_EXTERNAL_MEMORY_BUFFER_CREATE_INFO};
  ebi.handleTypes = VK_EXTERNAL_MEMORY_HANDLE_TYPE_HOST_ALLOCATION_BIT_EXT;
  VkBufferCreateInfo sbi{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO, &ebi};
  sbi.size = ring_bytes;
  sbi.usage = VK_BUFFER_USAGE_TRANSFER_SRC_BIT;
  VkBuffer staging;
  CHECK(vkCreateBuffer(device, &sbi, nullptr, &staging));
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(device, staging, &req);
  VkImportMemoryHostPointerInfoEXT import{VK_STRUCTURE_TYPE_IMPORT_MEMORY_HOST_POINTER_INFO_EXT};
  import.handleType = VK_EXTERNAL_MEMORY_HANDLE_TYPE_HOST_ALLOCATION_BIT_EXT;
  import.pHostPointer = ring;
  VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, &import};
  mai.allocationSize = ring_bytes;
  mai.memoryTypeIndex = __builtin_ctz(req.memoryTypeBits & hp.memoryTypeBits);
  VkDeviceMemory staging_memory;
  CHECK(vkAllocateMemory(device, &mai, nullptr, &staging_memory));
  CHECK(vkBindBufferMemory(device, staging, staging_memory, 0));

  VkBufferCreateInfo dbi{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  dbi.size = 2 * frame + unit;
  dbi.usage = VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  VkBuffer dest;
  CHECK(vkCreateBuffer(device, &dbi, nullptr, &dest));
  vkGetBufferMemoryRequirements(device, dest, &req);
  VkPhysicalDeviceMemoryProperties mp;
  vkGetPhysicalDeviceMemoryProperties(physical, &mp);
  uint32_t local = 0;
  for (uint32_t i = 0; i < mp.memoryTypeCount; ++i)
    if ((req.memoryTypeBits >> i & 1) && (mp.memoryTypes[i].propertyFlags & VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT)) {
      local = i;
      break;
    }
  VkMemoryAllocateInfo dai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  dai.allocationSize = req.size;
  dai.memoryTypeIndex = local;
  VkDeviceMemory dmem;
  CHECK(vkAllocateMemory(device, &dai, nullptr, &dmem));
  CHECK(vkBindBufferMemory(device, dest, dmem, 0));

  VkCommandPoolCreateInfo cpi{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  cpi.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  cpi.queueFamilyIndex = family;
  VkCommandPool pool;
  CHECK(vkCreateCommandPool(device, &cpi, nullptr, &pool));
  std::vector<VkCommandBuffer> cmds(slots);
  VkCommandBufferAllocateInfo cai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  cai.commandPool = pool;
  cai.commandBufferCount = uint32_t(slots);
  CHECK(vkAllocateCommandBuffers(device, &cai, cmds.data()));
  std::vector<VkFence> fences(slots);
  std::vector<bool> pending(slots, false);
  for (auto& f : fences) {
    VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    CHECK(vkCreateFence(device, &fci, nullptr, &f));
  }

  // Workers: copy their share of the unit the main thread names, then count in.
  std::atomic<uint64_t> go{0};
  std::atomic<int> done{0};
  std::atomic<bool> stop{false};
  const char* volatile src_now = nullptr;
  char* volatile dst_now = nullptr;
  const size_t share = (unit / threads + 4095) / 4096 * 4096;
  std::vector<std::thread> crew;
  for (int t = 0; t < threads; ++t) {
    crew.emplace_back([&, t] {
      uint64_t seen = 0;
      for (;;) {
        uint64_t g;
        while ((g = go.load(std::memory_order_acquire)) == seen) {
          if (stop.load(std::memory_order_relaxed)) return;
          _mm_pause();
        }
        seen = g;
        const size_t begin = std::min(unit, size_t(t) * share), end = std::min(unit, begin + share);
        if (end > begin) {
          if (nt)
            nt_copy(dst_now + begin, src_now + begin, end - begin);
          else
            std::memcpy(dst_now + begin, src_now + begin, end - begin);
        }
        done.fetch_add(1, std::memory_order_acq_rel);
      }
    });
  }

  uint64_t copied = 0, waits = 0;
  double cpu_s = 0;
  const auto start = Clock::now();
  for (uint64_t u = 0;; ++u) {
    const int s = int(u % slots);
    if (pending[s]) {  // the slot's last unit is still on its way to the GPU
      if (vkGetFenceStatus(device, fences[s]) != VK_SUCCESS) ++waits;
      CHECK(vkWaitForFences(device, 1, &fences[s], VK_TRUE, UINT64_MAX));
      CHECK(vkResetFences(device, 1, &fences[s]));
      pending[s] = false;
    }
    if (since(start) >= seconds) break;
    const auto c0 = Clock::now();
    src_now = map + (u % units) * unit;
    dst_now = ring + size_t(s) * unit;
    done.store(0, std::memory_order_relaxed);
    go.fetch_add(1, std::memory_order_release);
    while (done.load(std::memory_order_acquire) < threads) _mm_pause();
    cpu_s += since(c0);
    VkCommandBufferBeginInfo cbi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    cbi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    CHECK(vkBeginCommandBuffer(cmds[s], &cbi));
    const size_t within = ((u % units) * unit) % frame;
    VkBufferCopy region{VkDeviceSize(s) * unit, VkDeviceSize((u / std::max<size_t>(1, frame / unit)) % 2 * frame + within), unit};
    vkCmdCopyBuffer(cmds[s], staging, dest, 1, &region);
    CHECK(vkEndCommandBuffer(cmds[s]));
    VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    si.commandBufferCount = 1;
    si.pCommandBuffers = &cmds[s];
    CHECK(vkQueueSubmit(queue, 1, &si, fences[s]));
    pending[s] = true;
    copied += unit;
  }
  for (int s = 0; s < slots; ++s)
    if (pending[s]) CHECK(vkWaitForFences(device, 1, &fences[s], VK_TRUE, UINT64_MAX));
  const double wall = since(start);
  stop = true;
  for (auto& t : crew) t.join();
  std::printf("family %u: ", family);
  std::printf("unit %6.1f MB x %2d slots (%6.1f MB ring), %2d threads, %-5s stores: %6.2f GB/s = %6.1f frames/s; CPU copying %3.0f%% of the time, %llu waits for a slot\n",
              unit / 1e6, slots, ring_bytes / 1e6, threads, nt ? "nt" : "plain", copied / wall / 1e9,
              copied / wall / double(frame), 100 * cpu_s / wall, (unsigned long long)waits);
  return 0;
}
