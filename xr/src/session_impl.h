// Internal: the state behind xr::Session, shared by session.cpp (lifecycle,
// events, frames), vulkan.cpp (instance and device through the runtime),
// swapchains.cpp and actions.cpp.
#pragma once

#include <array>
#include <atomic>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "openxr.h"
#include "sluice/xr/session.h"

namespace sluice::xr {

struct SwapchainImages {
  XrSwapchain handle = XR_NULL_HANDLE;
  uint32_t width = 0, height = 0, layers = 1;
  VkFormat format = VK_FORMAT_UNDEFINED;
  std::vector<VkImage> images;
  std::vector<std::array<VkImageView, 2>> views;  // per image, per layer (one used when layers == 1)
  std::vector<VkImageView> array_views;           // per image, both layers (array swapchains)
  uint32_t acquired = UINT32_MAX;
};

struct Validation {
  std::atomic<uint64_t> errors{0};
  bool quiet = false;
  std::mutex mutex;
  std::vector<std::string> messages;
};

struct detail::SessionImpl {
  SessionOptions options;
  SystemInfo info;
  XrInstance instance = XR_NULL_HANDLE;
  XrSystemId system_id = XR_NULL_SYSTEM_ID;
  XrEnvironmentBlendMode blend_mode = XR_ENVIRONMENT_BLEND_MODE_OPAQUE;  // the runtime's first
  // Vulkan, made through the runtime.
  VkInstance vk_instance = VK_NULL_HANDLE;
  VkPhysicalDevice physical_device = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
  uint32_t graphics_family = 0, transfer_family = UINT32_MAX;
  VkQueue graphics_queue = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger = VK_NULL_HANDLE;
  std::unique_ptr<Validation> validation;
  std::unique_ptr<render::Context> context;
  bool memory_budget = false;
  // Frames in flight: a command buffer and fence each.
  VkCommandPool command_pool = VK_NULL_HANDLE;
  std::array<VkCommandBuffer, Session::kFramesInFlight> command_buffers{};
  std::array<VkFence, Session::kFramesInFlight> fences{};
  uint64_t frame_index = 0;

  // The session and what hangs off it (remade after a loss).
  XrSession session = XR_NULL_HANDLE;
  XrSpace space = XR_NULL_HANDLE;
  std::vector<SwapchainImages> color, depth;  // one array swapchain, or one per eye
  State state = State::Unknown;
  bool running = false;
  bool exit = false;
  bool exit_requested = false;
  bool lost = false;
  SessionCounters counters;

  // Actions (instance objects; attached to each new session).
  XrActionSet action_set = XR_NULL_HANDLE;
  XrAction play_pause = XR_NULL_HANDLE, stick = XR_NULL_HANDLE, grab = XR_NULL_HANDLE, grip = XR_NULL_HANDLE;
  std::array<XrPath, 2> hand_paths{};
  std::array<XrSpace, 2> grip_spaces{XR_NULL_HANDLE, XR_NULL_HANDLE};

  // vulkan.cpp
  void create_instance();
  void create_vulkan();  // the three below, in order
  void create_vulkan_instance();
  void create_vulkan_device();
  void create_frame_resources();
  void destroy_vulkan();
  // session.cpp
  void create_session();
  void destroy_session();
  void handle_state(XrSessionState s);
  // swapchains.cpp
  void create_swapchains();
  void destroy_swapchains();
  void acquire(SwapchainImages& s);
  void release(SwapchainImages& s);
  // actions.cpp
  void create_actions();
  void attach_actions();       // to the current session; creates the grip spaces
  void destroy_action_spaces();
  ActionState sample_actions(XrTime time);
};

}  // namespace sluice::xr
