// What the probes in bench/device share (they are not part of the build:
// each is one g++ command, which finds this header beside it): a clock, a
// copy with streaming stores, and a bare Vulkan device that imports host
// memory (VK_EXT_external_memory_host) and copies it into device memory.
// A failed Vulkan call prints itself and ends the process.
#pragma once

#include <immintrin.h>
#include <vulkan/vulkan.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

namespace probe {

using Clock = std::chrono::steady_clock;
inline double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

inline void check(VkResult r, const char* what) {
  if (r == VK_SUCCESS) return;
  std::printf("  %s failed: VkResult %d\n", what, int(r));
  std::exit(2);
}
#define PROBE_CHECK(x) ::probe::check((x), #x)

// n bytes with 32-byte streaming stores (dst 32-byte aligned), then a fence.
inline void nt_copy(char* dst, const char* src, size_t n) {
  size_t i = 0;
  for (; i + 128 <= n; i += 128) {
    const __m256i a = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(src + i));
    const __m256i b = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(src + i + 32));
    const __m256i c = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(src + i + 64));
    const __m256i d = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(src + i + 96));
    _mm256_stream_si256(reinterpret_cast<__m256i*>(dst + i), a);
    _mm256_stream_si256(reinterpret_cast<__m256i*>(dst + i + 32), b);
    _mm256_stream_si256(reinterpret_cast<__m256i*>(dst + i + 64), c);
    _mm256_stream_si256(reinterpret_cast<__m256i*>(dst + i + 96), d);
  }
  std::memcpy(dst + i, src + i, n - i);
  _mm_sfence();
}

// The first physical device, one queue of `family`, external host memory on.
struct Device {
  VkInstance instance = VK_NULL_HANDLE;
  VkPhysicalDevice physical = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
  uint32_t family = 0;
  VkQueue queue = VK_NULL_HANDLE;
  size_t import_alignment = 0;  // minImportedHostPointerAlignment
};

// `copy_only`: the first queue family that copies and neither draws nor
// computes (the copy engines, as the renderer's transfer queue), else 0.
inline Device make_device(bool copy_only) {
  Device d;
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.apiVersion = VK_API_VERSION_1_2;
  VkInstanceCreateInfo ici{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  ici.pApplicationInfo = &app;
  PROBE_CHECK(vkCreateInstance(&ici, nullptr, &d.instance));
  uint32_t n = 1;
  if (vkEnumeratePhysicalDevices(d.instance, &n, &d.physical) < 0 || n == 0) {
    std::puts("  no Vulkan device");
    std::exit(2);
  }
  VkPhysicalDeviceExternalMemoryHostPropertiesEXT host{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_EXTERNAL_MEMORY_HOST_PROPERTIES_EXT};
  VkPhysicalDeviceProperties2 props{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, &host};
  vkGetPhysicalDeviceProperties2(d.physical, &props);
  d.import_alignment = host.minImportedHostPointerAlignment;
  uint32_t qn = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(d.physical, &qn, nullptr);
  std::vector<VkQueueFamilyProperties> families(qn);
  vkGetPhysicalDeviceQueueFamilyProperties(d.physical, &qn, families.data());
  for (uint32_t i = 0; copy_only && i < qn; ++i) {
    const VkQueueFlags f = families[i].queueFlags;
    if ((f & VK_QUEUE_TRANSFER_BIT) && !(f & (VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT))) {
      d.family = i;
      break;
    }
  }
  const float priority = 1;
  VkDeviceQueueCreateInfo qci{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  qci.queueFamilyIndex = d.family;
  qci.queueCount = 1;
  qci.pQueuePriorities = &priority;
  const char* extensions[] = {VK_EXT_EXTERNAL_MEMORY_HOST_EXTENSION_NAME};
  VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  dci.queueCreateInfoCount = 1;
  dci.pQueueCreateInfos = &qci;
  dci.enabledExtensionCount = 1;
  dci.ppEnabledExtensionNames = extensions;
  PROBE_CHECK(vkCreateDevice(d.physical, &dci, nullptr, &d.device));
  vkGetDeviceQueue(d.device, d.family, 0, &d.queue);
  return d;
}

struct Buffer {
  VkBuffer buffer = VK_NULL_HANDLE;
  VkDeviceMemory memory = VK_NULL_HANDLE;
};

// A transfer-source buffer over `bytes` of host memory at `host` (aligned
// to import_alignment), imported. Returns the VkResult of the import: the
// driver may refuse a mapping (nothing is created then).
inline VkResult import_host(const Device& d, void* host, size_t bytes, Buffer& out) {
  const auto pointer_properties = reinterpret_cast<PFN_vkGetMemoryHostPointerPropertiesEXT>(
      vkGetDeviceProcAddr(d.device, "vkGetMemoryHostPointerPropertiesEXT"));
  VkMemoryHostPointerPropertiesEXT pointer{VK_STRUCTURE_TYPE_MEMORY_HOST_POINTER_PROPERTIES_EXT};
  PROBE_CHECK(pointer_properties(d.device, VK_EXTERNAL_MEMORY_HANDLE_TYPE_HOST_ALLOCATION_BIT_EXT, host, &pointer));
  VkExternalMemoryBufferCreateInfo external{VK_STRUCTURE_TYPE_EXTERNAL_MEMORY_BUFFER_CREATE_INFO};
  external.handleTypes = VK_EXTERNAL_MEMORY_HANDLE_TYPE_HOST_ALLOCATION_BIT_EXT;
  VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO, &external};
  bci.size = bytes;
  bci.usage = VK_BUFFER_USAGE_TRANSFER_SRC_BIT;
  PROBE_CHECK(vkCreateBuffer(d.device, &bci, nullptr, &out.buffer));
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(d.device, out.buffer, &req);
  const uint32_t types = req.memoryTypeBits & pointer.memoryTypeBits;
  if (types == 0) {
    std::printf("  no memory type both the buffer (0x%x) and the pointer (0x%x) allow\n", req.memoryTypeBits,
                pointer.memoryTypeBits);
    std::exit(2);
  }
  VkImportMemoryHostPointerInfoEXT import{VK_STRUCTURE_TYPE_IMPORT_MEMORY_HOST_POINTER_INFO_EXT};
  import.handleType = VK_EXTERNAL_MEMORY_HANDLE_TYPE_HOST_ALLOCATION_BIT_EXT;
  import.pHostPointer = host;
  VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, &import};
  mai.allocationSize = bytes;
  mai.memoryTypeIndex = static_cast<uint32_t>(__builtin_ctz(types));
  const VkResult r = vkAllocateMemory(d.device, &mai, nullptr, &out.memory);
  if (r != VK_SUCCESS) {
    vkDestroyBuffer(d.device, out.buffer, nullptr);
    out = {};
    return r;
  }
  PROBE_CHECK(vkBindBufferMemory(d.device, out.buffer, out.memory, 0));
  return r;
}

// A device-local transfer-destination buffer.
inline Buffer device_buffer(const Device& d, size_t bytes) {
  Buffer out;
  VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  bci.size = bytes;
  bci.usage = VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  PROBE_CHECK(vkCreateBuffer(d.device, &bci, nullptr, &out.buffer));
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(d.device, out.buffer, &req);
  VkPhysicalDeviceMemoryProperties memory;
  vkGetPhysicalDeviceMemoryProperties(d.physical, &memory);
  uint32_t type = 0;
  for (uint32_t i = 0; i < memory.memoryTypeCount; ++i) {
    if ((req.memoryTypeBits >> i & 1) && (memory.memoryTypes[i].propertyFlags & VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT)) {
      type = i;
      break;
    }
  }
  VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  mai.allocationSize = req.size;
  mai.memoryTypeIndex = type;
  PROBE_CHECK(vkAllocateMemory(d.device, &mai, nullptr, &out.memory));
  PROBE_CHECK(vkBindBufferMemory(d.device, out.buffer, out.memory, 0));
  return out;
}

// `count` primary command buffers of the device's queue family.
inline std::vector<VkCommandBuffer> command_buffers(const Device& d, uint32_t count) {
  VkCommandPoolCreateInfo cpi{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  cpi.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  cpi.queueFamilyIndex = d.family;
  VkCommandPool pool;
  PROBE_CHECK(vkCreateCommandPool(d.device, &cpi, nullptr, &pool));
  std::vector<VkCommandBuffer> out(count);
  VkCommandBufferAllocateInfo cai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  cai.commandPool = pool;
  cai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  cai.commandBufferCount = count;
  PROBE_CHECK(vkAllocateCommandBuffers(d.device, &cai, out.data()));
  return out;
}

// Records `cmd` anew as one copy of `bytes` from src at `from` to dst at `to`.
inline void record_copy(VkCommandBuffer cmd, VkBuffer src, VkDeviceSize from, VkBuffer dst, VkDeviceSize to,
                        VkDeviceSize bytes) {
  VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  PROBE_CHECK(vkBeginCommandBuffer(cmd, &begin));
  const VkBufferCopy region{from, to, bytes};
  vkCmdCopyBuffer(cmd, src, dst, 1, &region);
  PROBE_CHECK(vkEndCommandBuffer(cmd));
}

inline VkFence make_fence(const Device& d) {
  VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  VkFence fence;
  PROBE_CHECK(vkCreateFence(d.device, &fci, nullptr, &fence));
  return fence;
}

inline void submit(const Device& d, VkCommandBuffer cmd, VkFence fence) {
  VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  si.commandBufferCount = 1;
  si.pCommandBuffers = &cmd;
  PROBE_CHECK(vkQueueSubmit(d.queue, 1, &si, fence));
}

}  // namespace probe
