// A host application's Vulkan setup, for the embedding tests: its own
// instance (validation layer and a messenger counting its warnings and errors, when present),
// device made with what sluice asks for, a graphics queue, and images of its
// own. sluice only ever sees the handles (Context(HostVulkan)).
#pragma once

#include <vulkan/vulkan_raii.hpp>

#include <atomic>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "sluice/render/context.h"

namespace sluice::render::testing {

class TestHost {
 public:
  TestHost() {
    const char* layer = "VK_LAYER_KHRONOS_validation";
    bool have_layer = false;
    for (const auto& l : context_.enumerateInstanceLayerProperties()) have_layer |= std::strcmp(l.layerName, layer) == 0;
    std::vector<const char*> layers, extensions = required_instance_extensions();
    if (have_layer) {
      layers.push_back(layer);
      extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
    }
    vk::ApplicationInfo app("sluice host test", 1, nullptr, 0, VK_API_VERSION_1_3);
    instance_ = vk::raii::Instance(context_, vk::InstanceCreateInfo({}, &app, layers, extensions));
    if (have_layer) {
      using S = vk::DebugUtilsMessageSeverityFlagBitsEXT;
      using T = vk::DebugUtilsMessageTypeFlagBitsEXT;
      messenger_ = vk::raii::DebugUtilsMessengerEXT(
          instance_, vk::DebugUtilsMessengerCreateInfoEXT({}, S::eWarning | S::eError, T::eValidation | T::eGeneral | T::ePerformance, &on_message, this));
      validation = true;
    }
    for (auto& pd : vk::raii::PhysicalDevices(instance_)) {
      if (device_unusable_reason(*instance_, *pd).empty()) {
        physical_ = std::move(pd);
        break;
      }
    }
    if (!*physical_) throw std::runtime_error("no Vulkan device can run sluice");
    const auto families = physical_.getQueueFamilyProperties();
    for (uint32_t i = 0; i < families.size(); ++i) {
      const auto f = families[i].queueFlags;
      if ((f & vk::QueueFlagBits::eGraphics) && (f & vk::QueueFlagBits::eCompute)) {
        family = i;
        break;
      }
    }
    const float priority = 1;
    vk::DeviceQueueCreateInfo queue({}, family, 1, &priority);
    const std::vector<const char*> device_extensions = required_device_extensions(*physical_);
    DeviceFeatures features = required_device_features();
    vk::DeviceCreateInfo info({}, queue, {}, device_extensions);
    info.pNext = &features.features2;
    device_ = vk::raii::Device(physical_, info);
    queue_ = vk::raii::Queue(device_, family, 0);
    pool_ = vk::raii::CommandPool(device_, vk::CommandPoolCreateInfo(vk::CommandPoolCreateFlagBits::eResetCommandBuffer, family));
    memory_budget = false;
    for (const char* e : device_extensions) memory_budget |= std::strcmp(e, VK_EXT_MEMORY_BUDGET_EXTENSION_NAME) == 0;
  }
  ~TestHost() {
    if (*device_) device_.waitIdle();
  }

  HostVulkan handles() const {
    HostVulkan h;
    h.handles.instance = *instance_;
    h.handles.physical_device = *physical_;
    h.handles.device = *device_;
    h.handles.graphics_family = family;
    h.handles.graphics_queue = *queue_;
    h.memory_budget_enabled = memory_budget;
    return h;
  }

  struct Image {
    vk::raii::Image image{nullptr};
    vk::raii::DeviceMemory memory{nullptr};
    vk::raii::ImageView view{nullptr};
    vk::Format format{};
    vk::ImageAspectFlags aspect;
  };
  // `layers` > 1: an array image (one layer per eye) with a 2D_ARRAY view.
  Image image(uint32_t w, uint32_t h, vk::Format format, vk::ImageUsageFlags usage, uint32_t layers = 1) {
    Image i;
    i.format = format;
    const bool depth = format == vk::Format::eD32Sfloat || format == vk::Format::eD24UnormS8Uint;
    i.aspect = depth ? vk::ImageAspectFlagBits::eDepth : vk::ImageAspectFlagBits::eColor;
    i.image = vk::raii::Image(device_, vk::ImageCreateInfo({}, vk::ImageType::e2D, format, vk::Extent3D(w, h, 1), 1, layers,
                                                           vk::SampleCountFlagBits::e1, vk::ImageTiling::eOptimal, usage));
    const auto req = i.image.getMemoryRequirements();
    i.memory = vk::raii::DeviceMemory(device_, vk::MemoryAllocateInfo(req.size, memory_type(req.memoryTypeBits, {})));
    i.image.bindMemory(*i.memory, 0);
    i.view = vk::raii::ImageView(
        device_, vk::ImageViewCreateInfo({}, *i.image, layers > 1 ? vk::ImageViewType::e2DArray : vk::ImageViewType::e2D, format,
                                         {}, vk::ImageSubresourceRange(i.aspect, 0, 1, 0, layers)));
    return i;
  }

  // Records into a fresh command buffer, submits on the host's queue with
  // `wait` (a timeline semaphore and value, or none) and waits for it.
  void submit(const std::function<void(vk::CommandBuffer)>& record, VkSemaphore wait = VK_NULL_HANDLE, uint64_t value = 0) {
    vk::raii::CommandBuffer cmd =
        std::move(vk::raii::CommandBuffers(device_, vk::CommandBufferAllocateInfo(*pool_, vk::CommandBufferLevel::ePrimary, 1))[0]);
    cmd.begin(vk::CommandBufferBeginInfo(vk::CommandBufferUsageFlagBits::eOneTimeSubmit));
    record(*cmd);
    cmd.end();
    vk::raii::Fence fence(device_, vk::FenceCreateInfo());
    const vk::CommandBufferSubmitInfo cb(*cmd);
    const vk::SemaphoreSubmitInfo w(vk::Semaphore(wait), value, vk::PipelineStageFlagBits2::eAllCommands);
    queue_.submit2(vk::SubmitInfo2({}, wait ? 1u : 0u, &w, 1, &cb), *fence);
    while (device_.waitForFences(*fence, VK_TRUE, UINT64_MAX) == vk::Result::eTimeout) {
    }
  }

  // The texels of one layer (4 bytes each: RGBA8 or D32), top row first. The
  // image must be in TRANSFER_SRC_OPTIMAL.
  std::vector<uint32_t> read(const Image& i, uint32_t w, uint32_t h, uint32_t layer = 0) {
    const vk::DeviceSize bytes = vk::DeviceSize(w) * h * 4;
    vk::raii::Buffer buffer(device_, vk::BufferCreateInfo({}, bytes, vk::BufferUsageFlagBits::eTransferDst));
    const auto req = buffer.getMemoryRequirements();
    vk::raii::DeviceMemory memory(
        device_, vk::MemoryAllocateInfo(req.size, memory_type(req.memoryTypeBits, vk::MemoryPropertyFlagBits::eHostVisible |
                                                                                     vk::MemoryPropertyFlagBits::eHostCoherent)));
    buffer.bindMemory(*memory, 0);
    submit([&](vk::CommandBuffer c) {
      c.copyImageToBuffer(*i.image, vk::ImageLayout::eTransferSrcOptimal, *buffer,
                          vk::BufferImageCopy(0, 0, 0, vk::ImageSubresourceLayers(i.aspect, 0, layer, 1), {}, {w, h, 1}));
    });
    std::vector<uint32_t> out(size_t(w) * h);
    std::memcpy(out.data(), memory.mapMemory(0, bytes), bytes);
    return out;
  }

  const vk::raii::Device& device() const { return device_; }
  const vk::raii::Queue& queue() const { return queue_; }
  const vk::raii::CommandPool& pool() const { return pool_; }

  uint32_t family = 0;
  bool validation = false;
  bool memory_budget = false;
  std::atomic<int> reports{0};  // validation warnings and errors, performance ones too
  std::vector<std::string> messages;

 private:
  static VKAPI_ATTR VkBool32 VKAPI_CALL on_message(VkDebugUtilsMessageSeverityFlagBitsEXT, VkDebugUtilsMessageTypeFlagsEXT,
                                                   const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
    auto* self = static_cast<TestHost*>(user);
    if (self->reports.fetch_add(1) < 8) self->messages.emplace_back(data && data->pMessage ? data->pMessage : "");
    return VK_FALSE;
  }
  uint32_t memory_type(uint32_t bits, vk::MemoryPropertyFlags want) const {
    const auto props = physical_.getMemoryProperties();
    for (uint32_t i = 0; i < props.memoryTypeCount; ++i) {
      if ((bits & (1u << i)) && (props.memoryTypes[i].propertyFlags & want) == want) return i;
    }
    throw std::runtime_error("no memory type");
  }

  vk::raii::Context context_;
  vk::raii::Instance instance_{nullptr};
  vk::raii::DebugUtilsMessengerEXT messenger_{nullptr};
  vk::raii::PhysicalDevice physical_{nullptr};
  vk::raii::Device device_{nullptr};
  vk::raii::Queue queue_{nullptr};
  vk::raii::CommandPool pool_{nullptr};
};

}  // namespace sluice::render::testing
