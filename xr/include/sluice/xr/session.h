// sluice/xr/session.h: an OpenXR session that sluice renders into, built the
// way hello_xr is: the runtime picks the GPU and approves the Vulkan instance
// and device (XR_KHR_vulkan_enable2), which then become the renderer's host
// handles (render::Context(HostVulkan)); the frame loop is poll() ->
// begin_frame() -> record each eye -> end_frame().
//
//   xr::Session session(options);
//   render::Renderer renderer(session.context(), scene, {.frames_in_flight = xr::Session::kRecordsInFlight});
//   while (session.poll()) {
//     if (!session.running()) { wait a little; continue; }
//     xr::Frame frame = session.begin_frame();
//     render::FrameSync sync;
//     if (frame.render && frame.stereo) sync = renderer.record(frame.command_buffer, frame.stereo_target, {left, right}, ...);
//     else if (frame.render) for (eye : frame.eyes) sync = renderer.record(frame.command_buffer, eye.target, {view}, ...);
//     session.end_frame(frame, sync);
//   }
//
// Swapchains: one colour array swapchain of two layers (layer = eye) where
// both eyes ask for the same size, else one per eye; a depth swapchain beside
// it, submitted through XR_KHR_composition_layer_depth where the runtime
// offers it. Depth is reversed (1 at `near`, 0 at `far`): the projection of
// placement.h's eye_view(), with the planes reported to the compositor.
//
// States: every XrSessionState is handled. READY begins the session,
// STOPPING ends it, EXITING and instance loss make poll() return false, LOSS
// PENDING destroys the session and poll() creates a new one once the runtime
// has the system again (the Vulkan device is kept when the runtime still
// picks the same GPU; otherwise poll() throws).
//
// Ownership: the Session owns the XrInstance, the Vulkan instance and device
// and the render::Context; renderers made from context() must be destroyed
// before it. Threads: one thread makes every call (OpenXR's frame calls and
// the graphics queue are used from it).
#pragma once

#include <vulkan/vulkan_core.h>

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "sluice/render/context.h"
#include "sluice/render/renderer.h"
#include "sluice/xr/controls.h"
#include "sluice/xr/placement.h"

namespace sluice::xr {

struct SessionOptions {
  std::string application_name = "sluice";
  // Vulkan validation layer on the instance the runtime creates, with a
  // messenger that counts (and prints, unless quiet_validation) errors.
  bool validation = false;
  bool quiet_validation = false;
  bool depth = true;            // submit depth where XR_KHR_composition_layer_depth is offered
  Floor floor = Floor::Stage;   // STAGE where the runtime has it, else LOCAL
  float near = 0.05f;           // metres; the depth planes of the eyes' projections
  float far = 1000.0f;
  // The eye images may also be copied from (transfer source usage): a
  // desktop mirror, screenshots, tests.
  bool readable_images = false;
};

// XrSessionState, as sluice names it.
enum class State { Unknown, Idle, Ready, Synchronized, Visible, Focused, Stopping, LossPending, Exiting };
const char* to_string(State s);

struct SystemInfo {
  std::string runtime;            // "Monado(XRT) by Collabora et al ..." and version
  std::string system;             // the HMD's name
  std::array<uint32_t, 2> eye_width{}, eye_height{};  // recommended image size per eye
  bool depth_layer = false;       // XR_KHR_composition_layer_depth offered (and used when asked)
  bool array_swapchain = false;   // one colour swapchain of two layers
  Floor floor = Floor::Stage;     // the reference space in use
  VkFormat color_format = VK_FORMAT_UNDEFINED, depth_format = VK_FORMAT_UNDEFINED;
};

struct Eye {
  Pose pose;                  // in the room (the reference space), at the frame's display time
  Fov fov;
  render::RenderTarget target;  // this eye's colour (and depth) layer, acquired for this frame
  render::Viewport viewport;    // the whole image
};

struct Frame {
  int64_t display_time = 0;     // XrTime (ns) the frame will be shown at
  double display_seconds = 0;   // the same, in seconds (for runtime::Clock)
  int64_t period = 0;           // predicted display period, ns
  bool render = false;          // the runtime wants pictures: record both eyes
  VkCommandBuffer command_buffer = VK_NULL_HANDLE;  // begun; graphics family (only when render)
  std::array<Eye, 2> eyes;
  // Both eyes in one record() (array swapchains, SystemInfo::array_swapchain):
  // the two layers as one 2-layer target, views = {left, right}. Otherwise
  // each eye's target is recorded on its own.
  bool stereo = false;
  render::RenderTarget stereo_target;
  ActionState actions;          // sampled this frame (all idle unless FOCUSED)
};

struct SessionCounters {
  uint64_t frames = 0;           // ended frames
  uint64_t projection_layers = 0;  // ended with a 2-view projection layer
  uint64_t depth_layers = 0;     // ... that carried depth
  uint64_t sessions = 0;         // sessions created (restarts after loss add one)
  uint32_t states_seen = 0;      // bit (1 << State) for each state reached
};

namespace detail {
struct SessionImpl;  // defined in xr/src, seen by no caller
}  // namespace detail

class Session {
 public:
  // Record() calls per frame in flight: renderers drawing both eyes with one
  // record() each need RendererOptions::frames_in_flight = kRecordsInFlight.
  static constexpr uint32_t kFramesInFlight = 2;
  static constexpr uint32_t kRecordsInFlight = 2 * kFramesInFlight;

  // Throws xr::Error naming what is missing (no runtime, no HMD,
  // no XR_KHR_vulkan_enable2, a GPU sluice cannot use).
  explicit Session(const SessionOptions& options = {});
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  render::Context& context();
  const SystemInfo& system() const;

  // Handles the runtime's events; false once the app should exit (EXITING,
  // instance loss, or after request_exit() when the session has ended).
  bool poll();
  State state() const;
  bool running() const;  // between xrBeginSession and xrEndSession: frames may be begun
  void request_exit();   // ends the session through STOPPING and EXITING

  // xrWaitFrame (blocks until the runtime paces the next frame), xrBeginFrame,
  // and when the runtime wants pictures: the eyes located, the images
  // acquired, a command buffer begun. Only while running().
  Frame begin_frame();
  // Submits the command buffer (waiting on `sync`), releases the images and
  // ends the frame with the projection layer (and depth). Every begun frame
  // must be ended.
  void end_frame(Frame& frame, const render::FrameSync& sync);

  SessionCounters counters() const;
  uint64_t validation_errors() const;
  std::vector<std::string> validation_messages() const;  // the first 32


 private:
  using Impl = detail::SessionImpl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sluice::xr
