// A probe, not part of the build: which host mappings the device accepts as
// imported memory (VK_EXT_external_memory_host), how long the import takes,
// and how fast the GPU copies out of it. One mode per process: after NVIDIA
// refuses an import, the process's next allocation fails too.
//   g++ -O2 -std=c++20 bench/device/importprobe.cpp -o .gpu/importprobe -lvulkan
//   importprobe MODE FILE BYTES
// MODE: anon | shared_ro | private_ro | private_rw | shared_rw
#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>
#include <vulkan/vulkan.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

using Clock = std::chrono::steady_clock;
static double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }
#define CHECK(x)                                                         \
  do {                                                                   \
    VkResult r_ = (x);                                                   \
    if (r_ != VK_SUCCESS) {                                              \
      std::printf("  %s failed: VkResult %d\n", #x, int(r_));            \
      return 2;                                                          \
    }                                                                    \
  } while (0)

int main(int argc, char** argv) {
  if (argc < 4) return std::fprintf(stderr, "importprobe MODE FILE BYTES\n"), 1;
  const std::string mode = argv[1];
  const char* path = argv[2];
  size_t bytes = std::strtoull(argv[3], nullptr, 10);

  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.apiVersion = VK_API_VERSION_1_2;
  VkInstanceCreateInfo ici{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  ici.pApplicationInfo = &app;
  VkInstance instance;
  CHECK(vkCreateInstance(&ici, nullptr, &instance));
  uint32_t n = 0;
  vkEnumeratePhysicalDevices(instance, &n, nullptr);
  std::vector<VkPhysicalDevice> physicals(n);
  vkEnumeratePhysicalDevices(instance, &n, physicals.data());
  if (n == 0) return std::puts("  no device"), 2;
  VkPhysicalDevice physical = physicals[0];
  VkPhysicalDeviceExternalMemoryHostPropertiesEXT hostProps{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_EXTERNAL_MEMORY_HOST_PROPERTIES_EXT};
  VkPhysicalDeviceProperties2 props{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, &hostProps};
  vkGetPhysicalDeviceProperties2(physical, &props);
  const size_t align = hostProps.minImportedHostPointerAlignment;
  bytes = bytes / align * align;

  uint32_t qn = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(physical, &qn, nullptr);
  std::vector<VkQueueFamilyProperties> qf(qn);
  vkGetPhysicalDeviceQueueFamilyProperties(physical, &qn, qf.data());
  uint32_t family = 0;  // the first family: graphics, copies too
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
  auto getHostProps = reinterpret_cast<PFN_vkGetMemoryHostPointerPropertiesEXT>(
      vkGetDeviceProcAddr(device, "vkGetMemoryHostPointerPropertiesEXT"));
  VkQueue queue;
  vkGetDeviceQueue(device, family, 0, &queue);

  // The host memory, by mode.
  void* host = MAP_FAILED;
  const auto t_map = Clock::now();
  if (mode == "anon") {
    host = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_POPULATE, -1, 0);
  } else {
    const bool rw = mode == "shared_rw";
    const int fd = open(path, (rw ? O_RDWR : O_RDONLY) | O_CLOEXEC);
    if (fd < 0) return std::printf("  cannot open %s\n", path), 2;
    const int prot = (mode == "private_rw" || rw) ? PROT_READ | PROT_WRITE : PROT_READ;
    const int flags = (mode.rfind("private", 0) == 0 ? MAP_PRIVATE : MAP_SHARED) | MAP_POPULATE;
    host = mmap(nullptr, bytes, prot, flags, fd, 0);
    close(fd);
  }
  if (host == MAP_FAILED) return std::printf("  mmap failed: %s\n", std::strerror(errno)), 2;
  std::printf("  %s: %zu bytes mapped in %.1f ms (alignment %zu)\n", mode.c_str(), bytes, 1e3 * since(t_map), align);

  VkMemoryHostPointerPropertiesEXT hp{VK_STRUCTURE_TYPE_MEMORY_HOST_POINTER_PROPERTIES_EXT};
  CHECK(getHostProps(device, VK_EXTERNAL_MEMORY_HANDLE_TYPE_HOST_ALLOCATION_BIT_EXT, host, &hp));
  VkExternalMemoryBufferCreateInfo ext_info{VK_STRUCTURE_TYPE_EXTERNAL_MEMORY_BUFFER_CREATE_INFO};
  ext_info.handleTypes = VK_EXTERNAL_MEMORY_HANDLE_TYPE_HOST_ALLOCATION_BIT_EXT;
  VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO, &ext_info};
  bci.size = bytes;
  bci.usage = VK_BUFFER_USAGE_TRANSFER_SRC_BIT;
  VkBuffer source;
  CHECK(vkCreateBuffer(device, &bci, nullptr, &source));
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(device, source, &req);
  const uint32_t types = req.memoryTypeBits & hp.memoryTypeBits;
  std::printf("  pointer memory types 0x%x, buffer 0x%x\n", hp.memoryTypeBits, req.memoryTypeBits);
  if (!types) return std::puts("  no common memory type"), 2;
  VkImportMemoryHostPointerInfoEXT import{VK_STRUCTURE_TYPE_IMPORT_MEMORY_HOST_POINTER_INFO_EXT};
  import.handleType = VK_EXTERNAL_MEMORY_HANDLE_TYPE_HOST_ALLOCATION_BIT_EXT;
  import.pHostPointer = host;
  VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, &import};
  mai.allocationSize = bytes;
  mai.memoryTypeIndex = __builtin_ctz(types);
  VkDeviceMemory imported;
  const auto t_import = Clock::now();
  const VkResult r = vkAllocateMemory(device, &mai, nullptr, &imported);
  const double import_ms = 1e3 * since(t_import);
  if (r != VK_SUCCESS) return std::printf("  import REFUSED: VkResult %d after %.1f ms\n", int(r), import_ms), 3;
  std::printf("  import accepted in %.1f ms (%.2f GB/s pinned)\n", import_ms, bytes / (import_ms * 1e6));
  CHECK(vkBindBufferMemory(device, source, imported, 0));

  // Destination: device-local.
  VkBufferCreateInfo dbi{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  dbi.size = bytes;
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
  cpi.queueFamilyIndex = family;
  VkCommandPool pool;
  CHECK(vkCreateCommandPool(device, &cpi, nullptr, &pool));
  VkCommandBufferAllocateInfo cai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  cai.commandPool = pool;
  cai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  cai.commandBufferCount = 1;
  VkCommandBuffer cmd;
  CHECK(vkAllocateCommandBuffers(device, &cai, &cmd));
  VkCommandBufferBeginInfo cbi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  CHECK(vkBeginCommandBuffer(cmd, &cbi));
  VkBufferCopy region{0, 0, bytes};
  vkCmdCopyBuffer(cmd, source, dest, 1, &region);
  CHECK(vkEndCommandBuffer(cmd));
  VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  VkFence fence;
  CHECK(vkCreateFence(device, &fci, nullptr, &fence));
  VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  si.commandBufferCount = 1;
  si.pCommandBuffers = &cmd;
  std::vector<double> gbps;
  for (int i = 0; i < 8; ++i) {
    const auto t = Clock::now();
    CHECK(vkQueueSubmit(queue, 1, &si, fence));
    CHECK(vkWaitForFences(device, 1, &fence, VK_TRUE, UINT64_MAX));
    gbps.push_back(bytes / (since(t) * 1e9));
    vkResetFences(device, 1, &fence);
  }
  std::printf("  copy out of it:");
  for (double g : gbps) std::printf(" %.1f", g);
  std::puts(" GB/s");
  const auto t_free = Clock::now();
  vkFreeMemory(device, imported, nullptr);
  std::printf("  released in %.1f ms\n", 1e3 * since(t_free));
  return 0;
}
