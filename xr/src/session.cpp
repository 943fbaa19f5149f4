// The session's life (events and states, loss and restart) and the frame
// loop: wait, begin, locate the eyes, acquire, hand a command buffer out;
// submit, release, end with the projection (and depth) layer.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "session_impl.h"

namespace sluice::xr {
namespace {

State to_state(XrSessionState s) {
  switch (s) {
    case XR_SESSION_STATE_IDLE: return State::Idle;
    case XR_SESSION_STATE_READY: return State::Ready;
    case XR_SESSION_STATE_SYNCHRONIZED: return State::Synchronized;
    case XR_SESSION_STATE_VISIBLE: return State::Visible;
    case XR_SESSION_STATE_FOCUSED: return State::Focused;
    case XR_SESSION_STATE_STOPPING: return State::Stopping;
    case XR_SESSION_STATE_LOSS_PENDING: return State::LossPending;
    case XR_SESSION_STATE_EXITING: return State::Exiting;
    default: return State::Unknown;
  }
}

XrPosef to_xr(const Pose& p) {
  XrPosef x;
  x.orientation = {p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w};
  x.position = {p.position.x, p.position.y, p.position.z};
  return x;
}

}  // namespace

const char* to_string(State s) {
  switch (s) {
    case State::Unknown: return "unknown";
    case State::Idle: return "idle";
    case State::Ready: return "ready";
    case State::Synchronized: return "synchronized";
    case State::Visible: return "visible";
    case State::Focused: return "focused";
    case State::Stopping: return "stopping";
    case State::LossPending: return "loss pending";
    case State::Exiting: return "exiting";
  }
  return "?";
}

Session::Session(const SessionOptions& options) : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  s.options = options;
  try {
    s.create_instance();
    s.create_vulkan();
    s.create_actions();
    s.create_session();
  } catch (...) {
    s.destroy_session();
    s.destroy_vulkan();
    if (s.instance) xrDestroyInstance(s.instance);
    throw;
  }
}

Session::~Session() {
  Impl& s = *impl_;
  s.destroy_session();
  s.destroy_vulkan();
  if (s.instance) xrDestroyInstance(s.instance);  // also destroys the action set
}

void Session::Impl::create_session() {
  XrGraphicsBindingVulkan2KHR binding{XR_TYPE_GRAPHICS_BINDING_VULKAN2_KHR};
  binding.instance = vk_instance;
  binding.physicalDevice = physical_device;
  binding.device = device;
  binding.queueFamilyIndex = graphics_family;
  binding.queueIndex = 0;
  XrSessionCreateInfo create{XR_TYPE_SESSION_CREATE_INFO};
  create.next = &binding;
  create.systemId = system_id;
  check(xrCreateSession(instance, &create, &session), instance, "xrCreateSession");
  ++counters.sessions;
  state = State::Unknown;
  lost = false;

  // STAGE where the runtime has it (the floor at y = 0), else LOCAL.
  uint32_t n = 0;
  check(xrEnumerateReferenceSpaces(session, 0, &n, nullptr), instance, "xrEnumerateReferenceSpaces");
  std::vector<XrReferenceSpaceType> spaces(n);
  check(xrEnumerateReferenceSpaces(session, n, &n, spaces.data()), instance, "xrEnumerateReferenceSpaces");
  const bool stage = options.floor == Floor::Stage &&
                     std::find(spaces.begin(), spaces.end(), XR_REFERENCE_SPACE_TYPE_STAGE) != spaces.end();
  info.floor = stage ? Floor::Stage : Floor::Local;
  XrReferenceSpaceCreateInfo space_info{XR_TYPE_REFERENCE_SPACE_CREATE_INFO};
  space_info.referenceSpaceType = stage ? XR_REFERENCE_SPACE_TYPE_STAGE : XR_REFERENCE_SPACE_TYPE_LOCAL;
  space_info.poseInReferenceSpace.orientation.w = 1;
  check(xrCreateReferenceSpace(session, &space_info, &space), instance, "xrCreateReferenceSpace");
  create_swapchains();
  attach_actions();
}

void Session::Impl::destroy_session() {
  if (device) vkDeviceWaitIdle(device);  // the swapchain images' last use
  destroy_action_spaces();
  destroy_swapchains();
  if (space) xrDestroySpace(space);
  space = XR_NULL_HANDLE;
  if (session) xrDestroySession(session);
  session = XR_NULL_HANDLE;
  running = false;
}

void Session::Impl::handle_state(XrSessionState next) {
  state = to_state(next);
  counters.states_seen |= 1u << unsigned(state);
  switch (next) {
    case XR_SESSION_STATE_READY: {
      XrSessionBeginInfo begin{XR_TYPE_SESSION_BEGIN_INFO};
      begin.primaryViewConfigurationType = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
      check(xrBeginSession(session, &begin), instance, "xrBeginSession");
      running = true;
      if (exit_requested) check(xrRequestExitSession(session), instance, "xrRequestExitSession");
      break;
    }
    case XR_SESSION_STATE_STOPPING:
      check(xrEndSession(session), instance, "xrEndSession");
      running = false;
      break;
    case XR_SESSION_STATE_EXITING:
      exit = true;
      break;
    case XR_SESSION_STATE_LOSS_PENDING:
      // The runtime lost the device; a new session once it has it again.
      destroy_session();
      lost = true;
      break;
    default:
      break;
  }
}

bool Session::poll() {
  Impl& s = *impl_;
  XrEventDataBuffer event{XR_TYPE_EVENT_DATA_BUFFER};
  while (true) {
    event = {XR_TYPE_EVENT_DATA_BUFFER};
    const XrResult r = xrPollEvent(s.instance, &event);
    if (r == XR_EVENT_UNAVAILABLE) break;
    check(r, s.instance, "xrPollEvent");
    switch (event.type) {
      case XR_TYPE_EVENT_DATA_INSTANCE_LOSS_PENDING:
        s.exit = true;
        break;
      case XR_TYPE_EVENT_DATA_SESSION_STATE_CHANGED: {
        const auto& changed = reinterpret_cast<const XrEventDataSessionStateChanged&>(event);
        if (changed.session == s.session) s.handle_state(changed.state);
        break;
      }
      default:
        break;  // space changes, interaction profile changes: nothing to do
    }
  }
  if (s.lost && !s.exit && !s.exit_requested) {
    XrSystemGetInfo get{XR_TYPE_SYSTEM_GET_INFO};
    get.formFactor = XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY;
    XrSystemId system = XR_NULL_SYSTEM_ID;
    if (xrGetSystem(s.instance, &get, &system) == XR_SUCCESS) {
      s.system_id = system;
      auto requirements_of =
          instance_function<PFN_xrGetVulkanGraphicsRequirements2KHR>(s.instance, "xrGetVulkanGraphicsRequirements2KHR");
      auto device_of = instance_function<PFN_xrGetVulkanGraphicsDevice2KHR>(s.instance, "xrGetVulkanGraphicsDevice2KHR");
      XrGraphicsRequirementsVulkan2KHR requirements{XR_TYPE_GRAPHICS_REQUIREMENTS_VULKAN2_KHR};
      check(requirements_of(s.instance, system, &requirements), s.instance, "xrGetVulkanGraphicsRequirements2KHR");
      XrVulkanGraphicsDeviceGetInfoKHR device_get{XR_TYPE_VULKAN_GRAPHICS_DEVICE_GET_INFO_KHR};
      device_get.systemId = system;
      device_get.vulkanInstance = s.vk_instance;
      VkPhysicalDevice physical = VK_NULL_HANDLE;
      check(device_of(s.instance, &device_get, &physical), s.instance, "xrGetVulkanGraphicsDevice2KHR");
      if (physical != s.physical_device) {
        throw std::runtime_error("after the session was lost, the OpenXR runtime picked another GPU: start sluice again");
      }
      s.create_session();
    }
  }
  // Asked to exit before the session ever ran: nothing to end.
  if (s.exit_requested && !s.running && (s.state == State::Unknown || s.lost)) s.exit = true;
  return !s.exit;
}

void Session::request_exit() {
  Impl& s = *impl_;
  s.exit_requested = true;
  if (s.running) check(xrRequestExitSession(s.session), s.instance, "xrRequestExitSession");
}

render::Context& Session::context() { return *impl_->context; }
const SystemInfo& Session::system() const { return impl_->info; }
State Session::state() const { return impl_->state; }
bool Session::running() const { return impl_->running; }
SessionCounters Session::counters() const { return impl_->counters; }

uint64_t Session::validation_errors() const { return impl_->validation ? impl_->validation->errors.load() : 0; }

std::vector<std::string> Session::validation_messages() const {
  if (!impl_->validation) return {};
  const std::lock_guard lock(impl_->validation->mutex);
  return impl_->validation->messages;
}

Frame Session::begin_frame() {
  Impl& s = *impl_;
  if (!s.running) throw std::logic_error("begin_frame: the session is not running (call poll() until running())");
  XrFrameWaitInfo wait_info{XR_TYPE_FRAME_WAIT_INFO};
  XrFrameState frame_state{XR_TYPE_FRAME_STATE};
  check(xrWaitFrame(s.session, &wait_info, &frame_state), s.instance, "xrWaitFrame");
  XrFrameBeginInfo begin_info{XR_TYPE_FRAME_BEGIN_INFO};
  check(xrBeginFrame(s.session, &begin_info), s.instance, "xrBeginFrame");
  Frame f;
  f.display_time = frame_state.predictedDisplayTime;
  f.display_seconds = double(frame_state.predictedDisplayTime) * 1e-9;
  f.period = frame_state.predictedDisplayPeriod;
  f.actions = s.sample_actions(frame_state.predictedDisplayTime);
  if (!frame_state.shouldRender) return f;

  XrViewLocateInfo locate{XR_TYPE_VIEW_LOCATE_INFO};
  locate.viewConfigurationType = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
  locate.displayTime = frame_state.predictedDisplayTime;
  locate.space = s.space;
  XrViewState view_state{XR_TYPE_VIEW_STATE};
  std::array<XrView, 2> views{{{XR_TYPE_VIEW}, {XR_TYPE_VIEW}}};
  uint32_t count = 0;
  check(xrLocateViews(s.session, &locate, &view_state, 2, &count, views.data()), s.instance, "xrLocateViews");
  const XrViewStateFlags needed = XR_VIEW_STATE_POSITION_VALID_BIT | XR_VIEW_STATE_ORIENTATION_VALID_BIT;
  if ((view_state.viewStateFlags & needed) != needed) return f;  // no tracking: nothing sensible to draw

  for (SwapchainImages& c : s.color) s.acquire(c);
  for (SwapchainImages& d : s.depth) s.acquire(d);
  for (size_t e = 0; e < 2; ++e) {
    const XrView& v = views[e];
    Eye& eye = f.eyes[e];
    eye.pose = {{v.pose.orientation.x, v.pose.orientation.y, v.pose.orientation.z, v.pose.orientation.w},
                {v.pose.position.x, v.pose.position.y, v.pose.position.z}};
    eye.fov = {v.fov.angleLeft, v.fov.angleRight, v.fov.angleUp, v.fov.angleDown};
    const SwapchainImages& c = s.color[s.info.array_swapchain ? 0 : e];
    const uint32_t layer = s.info.array_swapchain ? uint32_t(e) : 0;
    render::RenderTarget& t = eye.target;
    t.width = c.width;
    t.height = c.height;
    t.color_image = c.images[c.acquired];
    t.color_view = c.views[c.acquired][layer];
    t.color_format = c.format;
    t.color_layout_before = VK_IMAGE_LAYOUT_UNDEFINED;  // drawn whole every frame
    t.color_layout_after = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;  // as OpenXR's Vulkan binding wants it back
    t.base_layer = layer;
    if (!s.depth.empty()) {
      const SwapchainImages& d = s.depth[s.info.array_swapchain ? 0 : e];
      t.depth_image = d.images[d.acquired];
      t.depth_view = d.views[d.acquired][layer];
      t.depth_format = d.format;
      t.depth_layout_before = VK_IMAGE_LAYOUT_UNDEFINED;
      t.depth_layout_after = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
    }
    eye.viewport = {0, 0, c.width, c.height};
  }
  if (s.info.array_swapchain) {
    // Both layers at once: the renderer draws the two eyes in one pass.
    const SwapchainImages& c = s.color[0];
    f.stereo = true;
    f.stereo_target = f.eyes[0].target;
    f.stereo_target.color_view = c.array_views[c.acquired];
    f.stereo_target.base_layer = 0;
    f.stereo_target.layer_count = 2;
    if (!s.depth.empty()) f.stereo_target.depth_view = s.depth[0].array_views[s.depth[0].acquired];
  }

  const size_t slot = s.frame_index % s.fences.size();
  vkWaitForFences(s.device, 1, &s.fences[slot], VK_TRUE, UINT64_MAX);
  vkResetFences(s.device, 1, &s.fences[slot]);
  f.command_buffer = s.command_buffers[slot];
  vkResetCommandBuffer(f.command_buffer, 0);
  VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  vkBeginCommandBuffer(f.command_buffer, &begin);
  f.render = true;
  return f;
}

void Session::end_frame(Frame& f, const render::FrameSync& sync) {
  Impl& s = *impl_;
  XrCompositionLayerProjection layer{XR_TYPE_COMPOSITION_LAYER_PROJECTION};
  std::array<XrCompositionLayerProjectionView, 2> views{{{XR_TYPE_COMPOSITION_LAYER_PROJECTION_VIEW},
                                                          {XR_TYPE_COMPOSITION_LAYER_PROJECTION_VIEW}}};
  std::array<XrCompositionLayerDepthInfoKHR, 2> depth{{{XR_TYPE_COMPOSITION_LAYER_DEPTH_INFO_KHR},
                                                        {XR_TYPE_COMPOSITION_LAYER_DEPTH_INFO_KHR}}};
  const bool submitted = f.render && f.command_buffer;
  if (submitted) {
    vkEndCommandBuffer(f.command_buffer);
    VkCommandBufferSubmitInfo cmd{VK_STRUCTURE_TYPE_COMMAND_BUFFER_SUBMIT_INFO};
    cmd.commandBuffer = f.command_buffer;
    VkSemaphoreSubmitInfo wait{VK_STRUCTURE_TYPE_SEMAPHORE_SUBMIT_INFO};
    wait.semaphore = sync.upload_semaphore;
    wait.value = sync.upload_value;
    wait.stageMask = sync.wait_stages;
    VkSubmitInfo2 submit{VK_STRUCTURE_TYPE_SUBMIT_INFO_2};
    submit.commandBufferInfoCount = 1;
    submit.pCommandBufferInfos = &cmd;
    if (sync.upload_semaphore && sync.upload_value > 0) {
      submit.waitSemaphoreInfoCount = 1;
      submit.pWaitSemaphoreInfos = &wait;
    }
    const size_t slot = s.frame_index % s.fences.size();
    if (vkQueueSubmit2(s.graphics_queue, 1, &submit, s.fences[slot]) != VK_SUCCESS) throw std::runtime_error("vkQueueSubmit2 failed");
    ++s.frame_index;
    for (SwapchainImages& c : s.color) s.release(c);
    for (SwapchainImages& d : s.depth) s.release(d);

    for (size_t e = 0; e < 2; ++e) {
      const Eye& eye = f.eyes[e];
      XrCompositionLayerProjectionView& v = views[e];
      v.pose = to_xr(eye.pose);
      v.fov = {eye.fov.left, eye.fov.right, eye.fov.up, eye.fov.down};
      const SwapchainImages& c = s.color[s.info.array_swapchain ? 0 : e];
      v.subImage.swapchain = c.handle;
      v.subImage.imageRect = {{0, 0}, {int32_t(c.width), int32_t(c.height)}};
      v.subImage.imageArrayIndex = s.info.array_swapchain ? uint32_t(e) : 0;
      if (!s.depth.empty()) {
        const SwapchainImages& d = s.depth[s.info.array_swapchain ? 0 : e];
        XrCompositionLayerDepthInfoKHR& di = depth[e];
        di.subImage.swapchain = d.handle;
        di.subImage.imageRect = v.subImage.imageRect;
        di.subImage.imageArrayIndex = v.subImage.imageArrayIndex;
        // Reversed depth: the value 0 (minDepth) lies at the far plane.
        di.minDepth = 0;
        di.maxDepth = 1;
        di.nearZ = s.options.far;
        di.farZ = s.options.near;
        v.next = &di;
      }
    }
    layer.space = s.space;
    layer.viewCount = 2;
    layer.views = views.data();
  }
  const XrCompositionLayerBaseHeader* layers[] = {reinterpret_cast<const XrCompositionLayerBaseHeader*>(&layer)};
  XrFrameEndInfo end{XR_TYPE_FRAME_END_INFO};
  end.displayTime = f.display_time;
  end.environmentBlendMode = s.blend_mode;
  end.layerCount = submitted ? 1 : 0;
  end.layers = layers;
  check(xrEndFrame(s.session, &end), s.instance, "xrEndFrame");
  ++s.counters.frames;
  if (submitted) {
    ++s.counters.projection_layers;
    if (!s.depth.empty()) ++s.counters.depth_layers;
  }
  f.command_buffer = VK_NULL_HANDLE;  // submitted: no more recording into it
}

}  // namespace sluice::xr
