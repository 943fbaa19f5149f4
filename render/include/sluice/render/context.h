// sluice/render/context.h: the Vulkan 1.3 instance, the chosen device and its
// queues. One per process is the usual case; everything the renderer makes
// belongs to one Context and must be destroyed before it.
//
// Threads: create and destroy on one thread. validation_*() may be called
// from any thread (the debug callback counts atomically).
#pragma once

#include <cstdint>
#include <memory>
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
  bool usable = false;  // Vulkan 1.3 with what the renderer needs
  std::string why_not;  // when !usable
};

class Context {
 public:
  // Throws std::runtime_error when Vulkan is missing or no device fits.
  explicit Context(const ContextOptions& options = {});
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  // Every physical device with what sluice thinks of it. Creates a temporary
  // instance; does not need a Context.
  static std::vector<DeviceInfo> list_devices();

  const DeviceInfo& device() const;
  bool has_transfer_queue() const;  // a separate transfer-only queue family is used for uploads
  // Device-local memory the process may still allocate, from
  // VK_EXT_memory_budget where present (else the heap size): for the runtime's
  // prefetch window.
  uint64_t device_budget_bytes() const;
  // Bytes still free in one memory heap (budget - usage from
  // VK_EXT_memory_budget where present, else the heap size). Any thread.
  uint64_t heap_available_bytes(uint32_t heap) const;

  bool validation_active() const;
  uint64_t validation_errors() const;
  uint64_t validation_warnings() const;
  std::vector<std::string> validation_messages() const;  // the first 32 errors and warnings

  struct Impl;
  Impl& impl() { return *impl_; }
  const Impl& impl() const { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

std::string format_api_version(uint32_t v);

}  // namespace sluice::render
