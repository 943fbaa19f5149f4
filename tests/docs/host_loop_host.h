// What a host owns in docs/embedding.md's minimal host loop: its Vulkan
// handles, images, per-frame slots and helpers. Declared only: the loop is
// compiled (tests/docs/CMakeLists.txt) so that it cannot drift from the
// headers it calls; examples/host_vulkan runs the same loop.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstdint>
#include <initializer_list>
#include <vector>

#include "sluice/render/context.h"
#include "sluice/render/stream.h"

namespace host {

struct Slot {
  VkCommandBuffer cmd;
  VkFence fence;
};

extern VkInstance instance;
extern VkPhysicalDevice pd;
extern VkDevice device;
extern uint32_t graphics_family, transfer_family;
extern VkQueue graphics_queue, transfer_queue;
extern void* host_features_pnext;
extern VkDeviceCreateInfo device_info;
constexpr uint32_t kFramesInFlight = 3;
extern std::vector<Slot> slots;
extern bool running;
extern uint32_t w, h;
extern sluice::render::Mat4 view_matrix, projection_matrix;
extern VkCommandBufferBeginInfo begin;
extern VkImage color, depth;
extern VkImageView color_view, depth_view;
extern VkSemaphoreSubmitInfo acquire_semaphore;

void draw_host_geometry(VkCommandBuffer cmd);
void submit2(VkQueue queue, std::initializer_list<VkSemaphoreSubmitInfo> waits, VkCommandBuffer cmd, VkFence fence);

}  // namespace host
