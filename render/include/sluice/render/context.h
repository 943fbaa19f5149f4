// sluice/render/context.h: the Vulkan 1.3 instance, device and queues sluice
// renders with. Two ways to get one:
//
//  - Owning (the CLI, tests): Context(ContextOptions) creates its own
//    instance and device and destroys them with itself.
//  - Host handles (an embedding app, an OpenXR session): the host creates
//    its instance and device itself, having asked sluice first what to enable
//    (required_instance_extensions(), required_device_extensions(),
//    required_device_features()), then builds Context(HostVulkan). Nothing is
//    created or destroyed but sluice's own objects; the host's handles must
//    outlive the Context.
//
// Everything the renderer makes belongs to one Context and must be destroyed
// before it. Threads: create and destroy on one thread. validation_*() may be
// called from any thread (the debug callback counts atomically).
// Queues: sluice submits to the graphics queue only for setup work
// (set_environment, the first use of a target size never does) and to the
// transfer queue for frame uploads, always from the thread that calls the
// Renderer; Vulkan requires queue access to be externally synchronized, so
// the host must not submit to the same VkQueue from another thread at the
// same time. One exception: a StagingAllocator with a resident window
// (staging_allocator.h) relays frames' pieces to the device from the
// pipeline's read threads, on a queue of its own where the device has a
// second queue in the transfer family (contexts sluice creates), else on
// the transfer queue (the graphics queue where there is no transfer
// family): then relay_queue_shared() is true, and every submission or
// present on that queue, the host's too, must hold queue_lock() while such
// a pipeline runs.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace sluice::render {

struct ContextOptions {
  // Enable VK_LAYER_KHRONOS_validation and a debug messenger that counts (and
  // prints, unless quiet_validation) errors and warnings. If the layer is not
  // installed the context still works and validation_active() is false.
  bool validation = false;
  bool quiet_validation = false;
  // Device choice: "" picks the first discrete GPU, then integrated, then
  // anything (lavapipe); a number is an index into list_devices(); anything
  // else is matched case-insensitively against device names.
  std::string device;
  // Extra instance extensions (a window system's, e.g. from GLFW) and whether
  // the device must be able to present (enables VK_KHR_swapchain).
  std::vector<std::string> instance_extensions;
  bool presentation = false;
  std::string application_name = "sluice";
};

struct DeviceInfo {
  uint32_t index = 0;
  std::string name;
  std::string type;    // "discrete", "integrated", "virtual", "cpu", "other"
  std::string driver;  // driver name and info
  uint32_t api_version = 0;
  uint64_t device_local_bytes = 0;
  // Largest point sprite, pixels: the largest splat drawn (LodOptions::
  // max_splat_pixels lowers it); nearer particles are culled (thesis 3.4).
  float max_point_size = 0;
  bool usable = false;  // Vulkan 1.3 with what the renderer needs
  std::string why_not;  // when !usable
};

// Raw Vulkan handles. In HostVulkan they are the host's and stay the host's;
// Context::vulkan() hands out the ones a Context uses (owned by the Context
// when it created them).
struct VulkanHandles {
  VkInstance instance = VK_NULL_HANDLE;
  VkPhysicalDevice physical_device = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
  uint32_t graphics_family = 0;        // a family with graphics and compute
  VkQueue graphics_queue = VK_NULL_HANDLE;
  uint32_t transfer_family = UINT32_MAX;  // UINT32_MAX: none; uploads go to the graphics queue
  VkQueue transfer_queue = VK_NULL_HANDLE;
};

struct HostVulkan {
  // The instance must come from the system Vulkan loader (libvulkan.so.1),
  // which sluice also calls through.
  VulkanHandles handles;
  // The instance was created with apiVersion >= 1.3 and the device with
  // required_device_extensions() and required_device_features() enabled.
  // Set when the host enabled VK_EXT_memory_budget (recommended).
  bool memory_budget_enabled = false;
};

// What a host must enable for sluice. Instance extensions: none beyond
// Vulkan 1.3 today (the list is the contract; it may grow).
std::vector<const char*> required_instance_extensions();
// Device extensions to enable on `physical_device`: every required one and
// every recommended one the device offers (VK_EXT_memory_budget).
std::vector<const char*> required_device_extensions(VkPhysicalDevice physical_device);
// The features sluice needs, as a pNext chain the host merges into its own
// VkDeviceCreateInfo (copying the struct keeps the chain valid). Fields sluice
// does not need are VK_FALSE.
struct DeviceFeatures {
  VkPhysicalDeviceFeatures2 features2{};  // .features: largePoints, shaderStorageImageWriteWithoutFormat
  VkPhysicalDeviceVulkan11Features vulkan11{};  // multiview
  VkPhysicalDeviceVulkan12Features vulkan12{};  // bufferDeviceAddress, timelineSemaphore, hostQueryReset
  VkPhysicalDeviceVulkan13Features vulkan13{};  // synchronization2, dynamicRendering, maintenance4
  DeviceFeatures();
  DeviceFeatures(const DeviceFeatures& other);
  DeviceFeatures& operator=(const DeviceFeatures& other);
  // features2 -> vulkan11 -> vulkan12 -> vulkan13 -> `next`.
  void chain(void* next = nullptr);
};
DeviceFeatures required_device_features();
// Empty when `physical_device` (of `instance`) can run sluice, else why not.
std::string device_unusable_reason(VkInstance instance, VkPhysicalDevice physical_device);

namespace detail {
struct ContextImpl;  // defined in render/src, seen by no caller
}  // namespace detail

class Context {
 public:
  // Owning: creates an instance and device. Throws render::Error when
  // Vulkan is missing or no device fits.
  explicit Context(const ContextOptions& options = {});
  // Non-owning: works on the host's handles (see HostVulkan). Throws
  // render::Error naming what is missing when the device cannot run
  // sluice. Validation messages are the host's (its own messenger).
  explicit Context(const HostVulkan& host);
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  // Every physical device with what sluice thinks of it. Creates a temporary
  // instance; does not need a Context.
  static std::vector<DeviceInfo> list_devices();

  const DeviceInfo& device() const;
  // The handles in use (a host's own, or the ones this Context created).
  const VulkanHandles& vulkan() const;
  bool owns_device() const;
  // See "Queues" above. Any thread.
  bool relay_queue_shared() const;
  std::mutex& queue_lock() const;
  // Blocks the calling thread until `fence` (made on this context's device)
  // is signalled; no timeout (a lost device throws vk::SystemError). Any thread.
  void wait(VkFence fence) const;
  // Bytes still free in one memory heap (budget - usage from
  // VK_EXT_memory_budget where present, else the heap size). Any thread.
  uint64_t heap_available_bytes(uint32_t heap) const;

  bool validation_active() const;
  uint64_t validation_errors() const;
  std::vector<std::string> validation_messages() const;  // the first 32 errors and warnings


 private:
  using Impl = detail::ContextImpl;  // render/src/vk_common.h; only sluice_render's sources see it
  friend Impl& context_impl(Context&);
  friend const Impl& context_impl(const Context&);
  std::unique_ptr<Impl> impl_;
};

std::string format_api_version(uint32_t v);

}  // namespace sluice::render
