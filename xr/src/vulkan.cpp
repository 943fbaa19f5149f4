// The OpenXR instance and system, and the Vulkan instance and device the
// runtime approves (XR_KHR_vulkan_enable2), handed to the renderer as host
// handles.
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "session_impl.h"
#include "sluice/error.h"

namespace sluice::xr {
namespace {

bool has_extension(const std::vector<XrExtensionProperties>& list, const char* name) {
  return std::any_of(list.begin(), list.end(), [&](const XrExtensionProperties& e) { return std::strcmp(e.extensionName, name) == 0; });
}

VKAPI_ATTR VkBool32 VKAPI_CALL count_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity, VkDebugUtilsMessageTypeFlagsEXT,
                                             const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
  if (!(severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT)) return VK_FALSE;
  auto* v = static_cast<Validation*>(user);
  v->errors.fetch_add(1);
  const std::string text = data && data->pMessage ? data->pMessage : "(no message)";
  if (!v->quiet) std::fprintf(stderr, "vulkan validation: %s\n", text.c_str());
  const std::lock_guard lock(v->mutex);
  if (v->messages.size() < 32) v->messages.push_back(text);
  return VK_FALSE;
}

// The Vulkan 1.2 features sluice needs, as the structs of the extensions
// that became 1.2 (see create_vulkan). Throws std::logic_error when sluice
// asks for a 1.2 feature this does not carry over.
class Vulkan12Structs {
 public:
  explicit Vulkan12Structs(VkPhysicalDeviceVulkan12Features f) {
    address_.bufferDeviceAddress = f.bufferDeviceAddress;
    timeline_.timelineSemaphore = f.timelineSemaphore;
    reset_.hostQueryReset = f.hostQueryReset;
    f.bufferDeviceAddress = f.timelineSemaphore = f.hostQueryReset = VK_FALSE;
    f.pNext = nullptr;
    VkPhysicalDeviceVulkan12Features none{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
    if (std::memcmp(&f, &none, sizeof f) != 0) {
      throw Error("xr: render::required_device_features() asks for a Vulkan 1.2 feature the XR device setup does not pass on");
    }
    address_.pNext = &timeline_;
    timeline_.pNext = &reset_;
  }
  Vulkan12Structs(const Vulkan12Structs&) = delete;
  Vulkan12Structs& operator=(const Vulkan12Structs&) = delete;
  void* first() { return &address_; }

 private:
  VkPhysicalDeviceBufferDeviceAddressFeatures address_{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_BUFFER_DEVICE_ADDRESS_FEATURES};
  VkPhysicalDeviceTimelineSemaphoreFeatures timeline_{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_TIMELINE_SEMAPHORE_FEATURES};
  VkPhysicalDeviceHostQueryResetFeatures reset_{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_HOST_QUERY_RESET_FEATURES};
};

bool layer_available(const char* name) {
  uint32_t n = 0;
  vkEnumerateInstanceLayerProperties(&n, nullptr);
  std::vector<VkLayerProperties> layers(n);
  vkEnumerateInstanceLayerProperties(&n, layers.data());
  return std::any_of(layers.begin(), layers.end(), [&](const VkLayerProperties& l) { return std::strcmp(l.layerName, name) == 0; });
}

}  // namespace

void check(XrResult result, XrInstance instance, const char* what) {
  if (XR_SUCCEEDED(result)) return;
  throw Error(std::string(what) + " failed: " + result_name(result, instance));
}

std::string result_name(XrResult result, XrInstance instance) {
  char name[XR_MAX_RESULT_STRING_SIZE] = {};
  if (instance == XR_NULL_HANDLE || XR_FAILED(xrResultToString(instance, result, name))) {
    return "XrResult " + std::to_string(int(result));
  }
  return name;
}

void detail::SessionImpl::create_instance() {
  uint32_t n = 0;
  const XrResult listed = xrEnumerateInstanceExtensionProperties(nullptr, 0, &n, nullptr);
  if (XR_FAILED(listed)) {
    throw Error("no OpenXR runtime (" + result_name(listed, XR_NULL_HANDLE) +
                             "): install one (Monado, SteamVR) or point XR_RUNTIME_JSON at its manifest");
  }
  std::vector<XrExtensionProperties> extensions(n, {XR_TYPE_EXTENSION_PROPERTIES});
  check(xrEnumerateInstanceExtensionProperties(nullptr, n, &n, extensions.data()), XR_NULL_HANDLE,
        "xrEnumerateInstanceExtensionProperties");
  if (!has_extension(extensions, XR_KHR_VULKAN_ENABLE2_EXTENSION_NAME)) {
    throw Error("the OpenXR runtime does not offer " XR_KHR_VULKAN_ENABLE2_EXTENSION_NAME
                             ", which sluice needs to share its Vulkan device");
  }
  std::vector<const char*> enabled{XR_KHR_VULKAN_ENABLE2_EXTENSION_NAME};
  info.depth_layer = options.depth && has_extension(extensions, XR_KHR_COMPOSITION_LAYER_DEPTH_EXTENSION_NAME);
  if (info.depth_layer) enabled.push_back(XR_KHR_COMPOSITION_LAYER_DEPTH_EXTENSION_NAME);

  XrInstanceCreateInfo create{XR_TYPE_INSTANCE_CREATE_INFO};
  std::snprintf(create.applicationInfo.applicationName, XR_MAX_APPLICATION_NAME_SIZE, "%s", options.application_name.c_str());
  create.applicationInfo.applicationVersion = 1;
  std::snprintf(create.applicationInfo.engineName, XR_MAX_ENGINE_NAME_SIZE, "sluice");
  create.applicationInfo.engineVersion = 1;
  // 1.0: the loader's headers are 1.0.20; newer 1.0 runtimes accept it.
  create.applicationInfo.apiVersion = XR_MAKE_VERSION(1, 0, XR_VERSION_PATCH(XR_CURRENT_API_VERSION));
  create.enabledExtensionCount = uint32_t(enabled.size());
  create.enabledExtensionNames = enabled.data();
  check(xrCreateInstance(&create, &instance), XR_NULL_HANDLE, "xrCreateInstance");

  XrInstanceProperties props{XR_TYPE_INSTANCE_PROPERTIES};
  check(xrGetInstanceProperties(instance, &props), instance, "xrGetInstanceProperties");
  info.runtime = std::string(props.runtimeName) + " " + std::to_string(XR_VERSION_MAJOR(props.runtimeVersion)) + "." +
                 std::to_string(XR_VERSION_MINOR(props.runtimeVersion)) + "." +
                 std::to_string(XR_VERSION_PATCH(props.runtimeVersion));

  XrSystemGetInfo get{XR_TYPE_SYSTEM_GET_INFO};
  get.formFactor = XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY;
  const XrResult got = xrGetSystem(instance, &get, &system_id);
  if (got == XR_ERROR_FORM_FACTOR_UNAVAILABLE) {
    throw Error("the OpenXR runtime has no headset right now (connect it, start its service)");
  }
  check(got, instance, "xrGetSystem");
  XrSystemProperties system{XR_TYPE_SYSTEM_PROPERTIES};
  check(xrGetSystemProperties(instance, system_id, &system), instance, "xrGetSystemProperties");
  info.system = system.systemName;

  uint32_t views = 0;
  check(xrEnumerateViewConfigurationViews(instance, system_id, XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO, 0, &views, nullptr),
        instance, "xrEnumerateViewConfigurationViews");
  if (views != 2) throw Error("the headset's stereo configuration has " + std::to_string(views) + " views, not 2");
  std::vector<XrViewConfigurationView> config(views, {XR_TYPE_VIEW_CONFIGURATION_VIEW});
  check(xrEnumerateViewConfigurationViews(instance, system_id, XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO, views, &views,
                                          config.data()),
        instance, "xrEnumerateViewConfigurationViews");
  uint32_t modes = 0;
  check(xrEnumerateEnvironmentBlendModes(instance, system_id, XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO, 0, &modes, nullptr),
        instance, "xrEnumerateEnvironmentBlendModes");
  std::vector<XrEnvironmentBlendMode> blend(modes);
  check(xrEnumerateEnvironmentBlendModes(instance, system_id, XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO, modes, &modes,
                                         blend.data()),
        instance, "xrEnumerateEnvironmentBlendModes");
  if (!blend.empty()) blend_mode = blend[0];
  for (size_t e = 0; e < 2; ++e) {
    info.eye_width[e] = config[e].recommendedImageRectWidth;
    info.eye_height[e] = config[e].recommendedImageRectHeight;
  }
}

// The order OpenXR's Vulkan enable2 asks for: the runtime's Vulkan
// instance, then the device it picks, then sluice's context on them.
void detail::SessionImpl::create_vulkan() {
  create_vulkan_instance();
  create_vulkan_device();
  create_frame_resources();
}

// Vulkan 1.3 through the runtime (xrCreateVulkanInstanceKHR), with the
// validation layer and its messenger where asked and installed.
void detail::SessionImpl::create_vulkan_instance() {
  auto requirements_of = instance_function<PFN_xrGetVulkanGraphicsRequirements2KHR>(instance, "xrGetVulkanGraphicsRequirements2KHR");
  auto create_instance_of = instance_function<PFN_xrCreateVulkanInstanceKHR>(instance, "xrCreateVulkanInstanceKHR");

  XrGraphicsRequirementsVulkan2KHR requirements{XR_TYPE_GRAPHICS_REQUIREMENTS_VULKAN2_KHR};
  check(requirements_of(instance, system_id, &requirements), instance, "xrGetVulkanGraphicsRequirements2KHR");
  // sluice needs Vulkan 1.3 whatever the runtime has tested up to.
  if (XR_VERSION_MAJOR(requirements.minApiVersionSupported) > 1 || XR_VERSION_MINOR(requirements.minApiVersionSupported) > 3) {
    throw Error("the OpenXR runtime needs a Vulkan newer than 1.3");
  }

  std::vector<const char*> instance_extensions = render::required_instance_extensions();
  std::vector<const char*> layers;
  VkDebugUtilsMessengerCreateInfoEXT messenger_info{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
  if (options.validation && layer_available("VK_LAYER_KHRONOS_validation")) {
    validation = std::make_unique<Validation>();
    validation->quiet = options.quiet_validation;
    layers.push_back("VK_LAYER_KHRONOS_validation");
    instance_extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
    messenger_info.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT;
    messenger_info.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT;
    messenger_info.pfnUserCallback = count_message;
    messenger_info.pUserData = validation.get();
  }
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = options.application_name.c_str();
  app.pEngineName = "sluice";
  app.apiVersion = VK_API_VERSION_1_3;
  VkInstanceCreateInfo vk_create{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  vk_create.pNext = validation ? &messenger_info : nullptr;  // also reports on instance creation
  vk_create.pApplicationInfo = &app;
  vk_create.enabledExtensionCount = uint32_t(instance_extensions.size());
  vk_create.ppEnabledExtensionNames = instance_extensions.data();
  vk_create.enabledLayerCount = uint32_t(layers.size());
  vk_create.ppEnabledLayerNames = layers.data();
  XrVulkanInstanceCreateInfoKHR xr_create{XR_TYPE_VULKAN_INSTANCE_CREATE_INFO_KHR};
  xr_create.systemId = system_id;
  xr_create.pfnGetInstanceProcAddr = &vkGetInstanceProcAddr;
  xr_create.vulkanCreateInfo = &vk_create;
  VkResult vk_result = VK_SUCCESS;
  check(create_instance_of(instance, &xr_create, &vk_instance, &vk_result), instance, "xrCreateVulkanInstanceKHR");
  if (vk_result != VK_SUCCESS) {
    throw Error("vkCreateInstance through the OpenXR runtime failed (VkResult " + std::to_string(int(vk_result)) + ")");
  }
  if (validation) {
    auto create_messenger = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(vk_instance, "vkCreateDebugUtilsMessengerEXT"));
    if (create_messenger) create_messenger(vk_instance, &messenger_info, nullptr, &messenger);
  }
}

// The GPU the runtime picked, checked for sluice, and a device on it
// through the runtime (xrCreateVulkanDeviceKHR) with sluice's extensions and
// features and a graphics+compute queue (a transfer one where there is one).
void detail::SessionImpl::create_vulkan_device() {
  auto device_of = instance_function<PFN_xrGetVulkanGraphicsDevice2KHR>(instance, "xrGetVulkanGraphicsDevice2KHR");
  auto create_device_of = instance_function<PFN_xrCreateVulkanDeviceKHR>(instance, "xrCreateVulkanDeviceKHR");
  VkResult vk_result = VK_SUCCESS;
  XrVulkanGraphicsDeviceGetInfoKHR device_get{XR_TYPE_VULKAN_GRAPHICS_DEVICE_GET_INFO_KHR};
  device_get.systemId = system_id;
  device_get.vulkanInstance = vk_instance;
  check(device_of(instance, &device_get, &physical_device), instance, "xrGetVulkanGraphicsDevice2KHR");
  const std::string unusable = render::device_unusable_reason(vk_instance, physical_device);
  if (!unusable.empty()) throw Error("the GPU the OpenXR runtime picked cannot run sluice: " + unusable);

  // Queues: a graphics+compute family; a transfer-only family for uploads where there is one.
  uint32_t n = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(physical_device, &n, nullptr);
  std::vector<VkQueueFamilyProperties> families(n);
  vkGetPhysicalDeviceQueueFamilyProperties(physical_device, &n, families.data());
  graphics_family = UINT32_MAX;
  for (uint32_t i = 0; i < n; ++i) {
    const VkQueueFlags f = families[i].queueFlags;
    if ((f & VK_QUEUE_GRAPHICS_BIT) && (f & VK_QUEUE_COMPUTE_BIT) && graphics_family == UINT32_MAX) graphics_family = i;
    if ((f & VK_QUEUE_TRANSFER_BIT) && !(f & (VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT)) && transfer_family == UINT32_MAX) {
      transfer_family = i;
    }
  }
  if (graphics_family == UINT32_MAX) throw Error("the OpenXR runtime's GPU has no graphics+compute queue");
  const float priority = 1.0f;
  std::vector<VkDeviceQueueCreateInfo> queues;
  for (uint32_t family : {graphics_family, transfer_family}) {
    if (family == UINT32_MAX) continue;
    VkDeviceQueueCreateInfo q{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    q.queueFamilyIndex = family;
    q.queueCount = 1;
    q.pQueuePriorities = &priority;
    queues.push_back(q);
  }
  const std::vector<const char*> device_extensions = render::required_device_extensions(physical_device);
  memory_budget = std::any_of(device_extensions.begin(), device_extensions.end(),
                              [](const char* e) { return std::strcmp(e, VK_EXT_MEMORY_BUDGET_EXTENSION_NAME) == 0; });
  // sluice's features, with the Vulkan 1.2 ones as their own structs: the
  // runtime adds VkPhysicalDeviceTimelineSemaphoreFeatures to the chain
  // unless it finds one there (Monado 25 looks for that struct only), and a
  // chain must not hold both it and VkPhysicalDeviceVulkan12Features.
  render::DeviceFeatures features = render::required_device_features();
  Vulkan12Structs v12(features.vulkan12);
  features.features2.pNext = &features.vulkan11;
  features.vulkan11.pNext = &features.vulkan13;
  features.vulkan13.pNext = v12.first();
  VkDeviceCreateInfo device_create{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  device_create.pNext = &features.features2;
  device_create.queueCreateInfoCount = uint32_t(queues.size());
  device_create.pQueueCreateInfos = queues.data();
  device_create.enabledExtensionCount = uint32_t(device_extensions.size());
  device_create.ppEnabledExtensionNames = device_extensions.data();
  XrVulkanDeviceCreateInfoKHR xr_device{XR_TYPE_VULKAN_DEVICE_CREATE_INFO_KHR};
  xr_device.systemId = system_id;
  xr_device.pfnGetInstanceProcAddr = &vkGetInstanceProcAddr;
  xr_device.vulkanPhysicalDevice = physical_device;
  xr_device.vulkanCreateInfo = &device_create;
  check(create_device_of(instance, &xr_device, &device, &vk_result), instance, "xrCreateVulkanDeviceKHR");
  if (vk_result != VK_SUCCESS) {
    throw Error("vkCreateDevice through the OpenXR runtime failed (VkResult " + std::to_string(int(vk_result)) + ")");
  }
  vkGetDeviceQueue(device, graphics_family, 0, &graphics_queue);
}

// sluice's context on the runtime's handles, and the session's command
// pool, command buffers and fences.
void detail::SessionImpl::create_frame_resources() {
  render::HostVulkan host;
  host.handles.instance = vk_instance;
  host.handles.physical_device = physical_device;
  host.handles.device = device;
  host.handles.graphics_family = graphics_family;
  host.handles.graphics_queue = graphics_queue;
  if (transfer_family != UINT32_MAX) {
    host.handles.transfer_family = transfer_family;
    vkGetDeviceQueue(device, transfer_family, 0, &host.handles.transfer_queue);
  }
  host.memory_budget_enabled = memory_budget;
  context = std::make_unique<render::Context>(host);

  VkCommandPoolCreateInfo pool{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pool.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pool.queueFamilyIndex = graphics_family;
  if (vkCreateCommandPool(device, &pool, nullptr, &command_pool) != VK_SUCCESS) throw Error("vkCreateCommandPool failed");
  VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  alloc.commandPool = command_pool;
  alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  alloc.commandBufferCount = uint32_t(command_buffers.size());
  if (vkAllocateCommandBuffers(device, &alloc, command_buffers.data()) != VK_SUCCESS) {
    throw Error("vkAllocateCommandBuffers failed");
  }
  for (VkFence& f : fences) {
    VkFenceCreateInfo fence{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    fence.flags = VK_FENCE_CREATE_SIGNALED_BIT;
    if (vkCreateFence(device, &fence, nullptr, &f) != VK_SUCCESS) throw Error("vkCreateFence failed");
  }
}

void detail::SessionImpl::destroy_vulkan() {
  if (device) {
    vkDeviceWaitIdle(device);
    for (VkFence f : fences) {
      if (f) vkDestroyFence(device, f, nullptr);
    }
    if (command_pool) vkDestroyCommandPool(device, command_pool, nullptr);
  }
  context.reset();
  if (device) vkDestroyDevice(device, nullptr);
  if (messenger) {
    auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(vkGetInstanceProcAddr(vk_instance, "vkDestroyDebugUtilsMessengerEXT"));
    if (destroy) destroy(vk_instance, messenger, nullptr);
  }
  if (vk_instance) vkDestroyInstance(vk_instance, nullptr);
  device = VK_NULL_HANDLE;
  vk_instance = VK_NULL_HANDLE;
}

}  // namespace sluice::xr
