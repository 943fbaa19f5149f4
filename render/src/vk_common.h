// Internal to sluice_render: the Vulkan-Hpp RAII objects behind the public
// pimpls, and small helpers for buffers and images.
//
// This is the only header of sluice_render that includes vulkan_raii.hpp (a
// large header); only the sources that talk to Vulkan include it, so the
// plain C++ parts (globals, camera, options, lod, ...) compile fast.
#pragma once

#include <vulkan/vulkan_raii.hpp>

#include <atomic>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "sluice/render/context.h"

// Vulkan-Hpp compiled in sluice's own namespace (cmake/vulkan_hpp.cmake: a
// host's vk:: of another build type must not share its inline code).
namespace vk = ::sluice_vk;

namespace sluice::render {

struct detail::ContextImpl {
  ContextOptions options;
  bool owning = true;     // false: the handles are a host's; released, not destroyed
  VulkanHandles handles;  // raw copies of the handles below
  vk::raii::Context context;
  vk::raii::Instance instance{nullptr};
  vk::raii::DebugUtilsMessengerEXT messenger{nullptr};
  vk::raii::PhysicalDevice physical{nullptr};
  vk::raii::Device device{nullptr};
  uint32_t graphics_family = 0;  // graphics + compute (+ present when asked)
  uint32_t transfer_family = 0;  // == graphics_family when there is no separate one
  vk::raii::Queue graphics_queue{nullptr};
  vk::raii::Queue transfer_queue{nullptr};  // the graphics queue when there is no separate one
  // Where a StagingAllocator's relay copies frames' pieces from the
  // pipeline's read threads (runtime/frame_allocator.h): a second queue of the
  // transfer family where the device has one (devices sluice creates),
  // else the transfer queue, shared: then every submission to it holds
  // queue_mutex (sluice's own through submit(); the host's by
  // Context::queue_lock()).
  vk::raii::Queue relay_queue{nullptr};
  bool relay_shared = true;
  mutable std::mutex queue_mutex;
  vk::PhysicalDeviceProperties properties;
  vk::PhysicalDeviceMemoryProperties memory;
  bool memory_budget = false;  // VK_EXT_memory_budget enabled
  bool external_memory_host = false;  // VK_EXT_external_memory_host enabled (devices sluice creates, where offered)
  DeviceInfo info;
  bool validation = false;

  // Debug messenger state (written from the driver's threads).
  std::atomic<uint64_t> errors{0};
  mutable std::mutex messages_mutex;
  std::vector<std::string> messages;

  ContextImpl() = default;
  ~ContextImpl();

  uint32_t memory_type(uint32_t type_bits, vk::MemoryPropertyFlags wanted) const;
  // Submits to `queue` (one of the above), holding queue_mutex while the
  // relay shares it: sluice's submissions go through here.
  void submit(const vk::raii::Queue& queue, const vk::SubmitInfo2& submission, vk::Fence fence = {}) const;
  void wait_idle(const vk::raii::Queue& queue) const;
  void wait(vk::Fence fence) const;  // Context::wait
  // Records `record` into a fresh command buffer on the graphics queue, submits
  // it and waits. For setup work only.
  void run_once(const std::function<void(vk::CommandBuffer)>& record) const;
};

inline detail::ContextImpl& context_impl(Context& c) { return *c.impl_; }
inline const detail::ContextImpl& context_impl(const Context& c) { return *c.impl_; }

// A buffer with its own memory. Host-visible buffers are persistently mapped.
struct Buffer {
  vk::raii::Buffer buffer{nullptr};
  vk::raii::DeviceMemory memory{nullptr};
  vk::DeviceSize size = 0;
  void* mapped = nullptr;
  vk::DeviceAddress address = 0;  // when created with eShaderDeviceAddress
};

// UploadRead: staging the CPU also reads (encoded frames whose checksums
// are checked where they were read): cached where the driver offers it, as
// Readback; plain Upload memory may be write-combined, slow to read.
enum class MemoryKind { DeviceLocal, Upload, UploadRead, Readback };
Buffer create_buffer(const detail::ContextImpl& ctx, vk::DeviceSize size, vk::BufferUsageFlags usage, MemoryKind kind);
// VK_EXT_external_memory_host: the alignment an imported host pointer and
// size need; 0 when the device cannot import.
uint64_t host_import_alignment(const detail::ContextImpl& ctx);
// A buffer over `bytes` of caller-owned host memory at `host` (both aligned
// as host_import_alignment() says; the memory must outlive the buffer),
// `mapped` at it. An empty Buffer when no memory type takes the pointer;
// vk::SystemError when the driver refuses it.
Buffer import_host_buffer(const detail::ContextImpl& ctx, void* host, vk::DeviceSize bytes, vk::BufferUsageFlags usage);
// Makes `b` at least `size` bytes (contents lost when it grows). The old
// buffer goes to `retire` when given (recorded work may still use it), else
// it is freed before the new one is allocated.
void grow_buffer(const detail::ContextImpl& ctx, Buffer& b, vk::DeviceSize size, vk::BufferUsageFlags usage, MemoryKind kind,
                 const std::function<void(Buffer&&)>& retire = {});

// A 2D image (array of `layers`: one per eye for multiview stereo) with a
// view; an array view (2D_ARRAY) when `array_view` or layers > 1.
struct Texture {
  vk::raii::Image image{nullptr};
  vk::raii::DeviceMemory memory{nullptr};
  vk::raii::ImageView view{nullptr};
  vk::Format format = vk::Format::eUndefined;
  vk::Extent2D extent;
  uint32_t layers = 1;
  vk::ImageAspectFlags aspect = vk::ImageAspectFlagBits::eColor;
};
Texture create_texture(const detail::ContextImpl& ctx, vk::Extent2D extent, vk::Format format, vk::ImageUsageFlags usage,
                       uint32_t layers = 1, bool array_view = false);

// An image layout transition with synchronization2 scopes.
vk::ImageMemoryBarrier2 image_barrier(const Texture& t, vk::ImageLayout from, vk::ImageLayout to,
                                      vk::PipelineStageFlags2 src_stage, vk::AccessFlags2 src_access,
                                      vk::PipelineStageFlags2 dst_stage, vk::AccessFlags2 dst_access);
void memory_barrier(vk::CommandBuffer cmd, vk::PipelineStageFlags2 src_stage, vk::AccessFlags2 src_access,
                    vk::PipelineStageFlags2 dst_stage, vk::AccessFlags2 dst_access);

}  // namespace sluice::render
