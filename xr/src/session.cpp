// The session's life: instance to session, events and states, loss and
// restart, exit (the frames are in frames.cpp).
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "session_impl.h"
#include "sluice/error.h"

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

void detail::SessionImpl::create_session() {
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

void detail::SessionImpl::destroy_session() {
  if (device) vkDeviceWaitIdle(device);  // the swapchain images' last use
  destroy_action_spaces();
  destroy_swapchains();
  if (space) xrDestroySpace(space);
  space = XR_NULL_HANDLE;
  if (session) xrDestroySession(session);
  session = XR_NULL_HANDLE;
  running = false;
}

void detail::SessionImpl::handle_state(XrSessionState next) {
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
        throw Error("after the session was lost, the OpenXR runtime picked another GPU: start sluice again");
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

}  // namespace sluice::xr
