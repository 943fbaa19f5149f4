// Vulkan instance, device selection and queues; buffer and image helpers.
#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "vk_common.h"
#include "sluice/error.h"

namespace sluice::render {
namespace {

constexpr const char* kValidationLayer = "VK_LAYER_KHRONOS_validation";

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

const char* type_name(vk::PhysicalDeviceType t) {
  switch (t) {
    case vk::PhysicalDeviceType::eDiscreteGpu: return "discrete";
    case vk::PhysicalDeviceType::eIntegratedGpu: return "integrated";
    case vk::PhysicalDeviceType::eVirtualGpu: return "virtual";
    case vk::PhysicalDeviceType::eCpu: return "cpu";
    default: return "other";
  }
}

int type_rank(vk::PhysicalDeviceType t) {
  switch (t) {
    case vk::PhysicalDeviceType::eDiscreteGpu: return 0;
    case vk::PhysicalDeviceType::eIntegratedGpu: return 1;
    case vk::PhysicalDeviceType::eVirtualGpu: return 2;
    case vk::PhysicalDeviceType::eCpu: return 3;
    default: return 4;
  }
}

bool has_extension(const std::vector<vk::ExtensionProperties>& list, const char* name) {
  return std::any_of(list.begin(), list.end(), [&](const vk::ExtensionProperties& e) {
    return std::strcmp(e.extensionName.data(), name) == 0;
  });
}

// What the renderer needs from a device; empty string when it has it all.
std::string missing_features(const vk::raii::PhysicalDevice& pd, bool presentation) {
  const auto props = pd.getProperties();
  if (props.apiVersion < VK_API_VERSION_1_3) return "Vulkan " + format_api_version(props.apiVersion) + " < 1.3";
  const auto chain = pd.getFeatures2<vk::PhysicalDeviceFeatures2, vk::PhysicalDeviceVulkan12Features,
                                     vk::PhysicalDeviceVulkan13Features>();
  const auto& f = chain.get<vk::PhysicalDeviceFeatures2>().features;
  const auto& f12 = chain.get<vk::PhysicalDeviceVulkan12Features>();
  const auto& f13 = chain.get<vk::PhysicalDeviceVulkan13Features>();
  const auto f11 = pd.getFeatures2<vk::PhysicalDeviceFeatures2, vk::PhysicalDeviceVulkan11Features>()
                       .get<vk::PhysicalDeviceVulkan11Features>();
  if (!f.largePoints) return "no largePoints";
  if (!f.shaderStorageImageWriteWithoutFormat) return "no shaderStorageImageWriteWithoutFormat";
  if (!f11.multiview) return "no multiview";
  if (!f.shaderInt64) return "no shaderInt64";
  if (!f11.storageBuffer16BitAccess) return "no storageBuffer16BitAccess";
  if (!f12.bufferDeviceAddress) return "no bufferDeviceAddress";
  if (!f12.timelineSemaphore) return "no timelineSemaphore";
  if (!f13.synchronization2) return "no synchronization2";
  if (!f13.dynamicRendering) return "no dynamicRendering";
  if (!f13.maintenance4) return "no maintenance4";
  if (!f12.hostQueryReset) return "no hostQueryReset";
  if (!props.limits.timestampComputeAndGraphics) return "no timestamps on graphics/compute queues";
  {  // the GPU decoder's workgroup sums (decode.comp); Vulkan 1.1 guarantees only basic subgroup operations
    const auto subgroup = pd.getProperties2<vk::PhysicalDeviceProperties2, vk::PhysicalDeviceSubgroupProperties>()
                              .get<vk::PhysicalDeviceSubgroupProperties>();
    if (!(subgroup.supportedStages & vk::ShaderStageFlagBits::eCompute) ||
        !(subgroup.supportedOperations & vk::SubgroupFeatureFlagBits::eArithmetic)) {
      return "no subgroup arithmetic in compute shaders";
    }
    if (subgroup.subgroupSize < 4) return "subgroups narrower than 4 lanes";  // decode.comp's shared sums
  }
  if (presentation && !has_extension(pd.enumerateDeviceExtensionProperties(), VK_KHR_SWAPCHAIN_EXTENSION_NAME)) {
    return "no VK_KHR_swapchain";
  }
  bool graphics = false;
  for (const auto& q : pd.getQueueFamilyProperties()) {
    if ((q.queueFlags & vk::QueueFlagBits::eGraphics) && (q.queueFlags & vk::QueueFlagBits::eCompute)) graphics = true;
  }
  if (!graphics) return "no graphics+compute queue";
  return {};
}

DeviceInfo describe(const vk::raii::PhysicalDevice& pd, uint32_t index, bool presentation) {
  DeviceInfo d;
  const auto chain = pd.getProperties2<vk::PhysicalDeviceProperties2, vk::PhysicalDeviceDriverProperties>();
  const auto& p = chain.get<vk::PhysicalDeviceProperties2>().properties;
  const auto& drv = chain.get<vk::PhysicalDeviceDriverProperties>();
  d.index = index;
  d.name = p.deviceName.data();
  d.type = type_name(p.deviceType);
  d.driver = std::string(drv.driverName.data()) + " " + drv.driverInfo.data();
  d.api_version = p.apiVersion;
  d.max_point_size = p.limits.pointSizeRange[1];
  const auto mem = pd.getMemoryProperties();
  for (uint32_t h = 0; h < mem.memoryHeapCount; ++h) {
    if (mem.memoryHeaps[h].flags & vk::MemoryHeapFlagBits::eDeviceLocal) d.device_local_bytes += mem.memoryHeaps[h].size;
  }
  d.why_not = missing_features(pd, presentation);
  d.usable = d.why_not.empty();
  return d;
}

VKAPI_ATTR VkBool32 VKAPI_CALL debug_callback(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                              VkDebugUtilsMessageTypeFlagsEXT /*types*/,
                                              const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
  auto* impl = static_cast<detail::ContextImpl*>(user);
  const bool error = severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
  if (error) impl->errors.fetch_add(1, std::memory_order_relaxed);  // warnings are only kept as messages
  const std::string text = std::string(error ? "validation error: " : "validation warning: ") +
                           (data && data->pMessage ? data->pMessage : "");
  {
    std::lock_guard lock(impl->messages_mutex);
    if (impl->messages.size() < 32) impl->messages.push_back(text);
  }
  if (!impl->options.quiet_validation) std::fprintf(stderr, "sluice: %s\n", text.c_str());
  return VK_FALSE;
}

vk::raii::Instance make_instance(const vk::raii::Context& context, const ContextOptions& o, bool validation,
                                 bool debug_utils, bool portability) {
  vk::ApplicationInfo app(o.application_name.c_str(), 1, "sluice", 1, VK_API_VERSION_1_3);
  std::vector<const char*> layers;
  if (validation) layers.push_back(kValidationLayer);
  std::vector<const char*> extensions;
  for (const std::string& e : o.instance_extensions) extensions.push_back(e.c_str());
  if (debug_utils) extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
  if (portability) extensions.push_back(VK_KHR_PORTABILITY_ENUMERATION_EXTENSION_NAME);
  vk::InstanceCreateInfo info({}, &app, layers, extensions);
  if (portability) info.flags |= vk::InstanceCreateFlagBits::eEnumeratePortabilityKHR;
  return vk::raii::Instance(context, info);
}

}  // namespace

std::string format_api_version(uint32_t v) {
  return std::to_string(VK_API_VERSION_MAJOR(v)) + "." + std::to_string(VK_API_VERSION_MINOR(v)) + "." +
         std::to_string(VK_API_VERSION_PATCH(v));
}

std::vector<DeviceInfo> Context::list_devices() {
  vk::raii::Context context;
  const bool portability = has_extension(context.enumerateInstanceExtensionProperties(),
                                         VK_KHR_PORTABILITY_ENUMERATION_EXTENSION_NAME);
  vk::raii::Instance instance = make_instance(context, {}, false, false, portability);
  std::vector<DeviceInfo> out;
  uint32_t i = 0;
  for (const auto& pd : vk::raii::PhysicalDevices(instance)) out.push_back(describe(pd, i++, false));
  return out;
}

namespace {

// The loader, the validation layer where asked and installed, the instance
// and its messenger.
void open_instance(detail::ContextImpl& c, const ContextOptions& options) {
  if (c.context.enumerateInstanceVersion() < VK_API_VERSION_1_3) {
    throw Error("the Vulkan loader is older than 1.3 (" +
                             format_api_version(c.context.enumerateInstanceVersion()) + ")");
  }
  const auto instance_extensions = c.context.enumerateInstanceExtensionProperties();
  bool layer_present = false;
  for (const auto& l : c.context.enumerateInstanceLayerProperties()) {
    if (std::strcmp(l.layerName.data(), kValidationLayer) == 0) layer_present = true;
  }
  const bool debug_utils = has_extension(instance_extensions, VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
  c.validation = options.validation && layer_present && debug_utils;
  if (options.validation && !c.validation && !options.quiet_validation) {
    std::fprintf(stderr, "sluice: warning: %s is not installed; running without validation\n", kValidationLayer);
  }
  const bool portability = has_extension(instance_extensions, VK_KHR_PORTABILITY_ENUMERATION_EXTENSION_NAME);
  c.instance = make_instance(c.context, options, c.validation, c.validation, portability);
  if (c.validation) {
    using S = vk::DebugUtilsMessageSeverityFlagBitsEXT;
    using T = vk::DebugUtilsMessageTypeFlagBitsEXT;
    vk::DebugUtilsMessengerCreateInfoEXT info({}, S::eWarning | S::eError,
                                              T::eGeneral | T::eValidation | T::ePerformance, &debug_callback, &c);
    c.messenger = vk::raii::DebugUtilsMessengerEXT(c.instance, info);
  }
}

// The device `want` names (an index or part of a name), else the
// best-ranked usable one. Throws Error listing the devices when none fits.
uint32_t choose_device(const vk::raii::PhysicalDevices& devices, const std::vector<DeviceInfo>& infos,
                       const std::string& want) {
  int chosen = -1;
  if (!want.empty()) {
    const bool numeric = std::all_of(want.begin(), want.end(), [](char ch) { return std::isdigit(static_cast<unsigned char>(ch)); });
    for (const DeviceInfo& d : infos) {
      if (numeric ? d.index == uint32_t(std::stoul(want)) : lower(d.name).find(lower(want)) != std::string::npos) {
        chosen = int(d.index);
        break;
      }
    }
    if (chosen < 0) {
      std::string list;
      for (const DeviceInfo& d : infos) list += "\n  " + std::to_string(d.index) + ": " + d.name;
      throw Error("no Vulkan device matches '" + want + "'; devices:" + list);
    }
    if (!infos[size_t(chosen)].usable) {
      throw Error("device " + infos[size_t(chosen)].name + " cannot run sluice: " + infos[size_t(chosen)].why_not);
    }
  } else {
    for (const DeviceInfo& d : infos) {
      if (!d.usable) continue;
      if (chosen < 0 || type_rank(devices[d.index].getProperties().deviceType) <
                            type_rank(devices[size_t(chosen)].getProperties().deviceType)) {
        chosen = int(d.index);
      }
    }
    if (chosen < 0) {
      std::string list;
      for (const DeviceInfo& d : infos) list += "\n  " + d.name + ": " + d.why_not;
      throw Error("no Vulkan device can run sluice:" + list);
    }
  }
  return uint32_t(chosen);
}

// Queues (one graphics+compute family, a transfer-only family where there
// is one, a second queue of it for the relay), extensions and features; the
// device and the handles it hands out.
void create_device(detail::ContextImpl& c, const ContextOptions& options) {
  // Queues: one graphics+compute family; a transfer-only family if there is one.
  const auto families = c.physical.getQueueFamilyProperties();
  std::optional<uint32_t> graphics, transfer;
  for (uint32_t i = 0; i < families.size(); ++i) {
    const auto f = families[i].queueFlags;
    if (!graphics && (f & vk::QueueFlagBits::eGraphics) && (f & vk::QueueFlagBits::eCompute)) graphics = i;
    if (!transfer && (f & vk::QueueFlagBits::eTransfer) && !(f & vk::QueueFlagBits::eGraphics) &&
        !(f & vk::QueueFlagBits::eCompute) && families[i].timestampValidBits > 0) {
      transfer = i;
    }
  }
  c.graphics_family = *graphics;
  c.transfer_family = transfer.value_or(*graphics);
  const float priority = 1.0f;
  // A second queue of the transfer family, where it has one, for the relay
  // alone (vk_common.h).
  const std::array<float, 2> priorities{1.0f, 1.0f};
  const uint32_t transfer_queues = std::min<uint32_t>(2, families[c.transfer_family].queueCount);
  std::vector<vk::DeviceQueueCreateInfo> queues;
  if (c.transfer_family != c.graphics_family) {
    queues.emplace_back(vk::DeviceQueueCreateInfo({}, c.graphics_family, 1, &priority));
    queues.emplace_back(vk::DeviceQueueCreateInfo({}, c.transfer_family, transfer_queues, priorities.data()));
  } else {
    queues.emplace_back(vk::DeviceQueueCreateInfo({}, c.graphics_family, transfer_queues, priorities.data()));
  }

  const auto device_extensions = c.physical.enumerateDeviceExtensionProperties();
  std::vector<const char*> extensions;
  if (options.presentation) extensions.push_back(VK_KHR_SWAPCHAIN_EXTENSION_NAME);
  c.memory_budget = has_extension(device_extensions, VK_EXT_MEMORY_BUDGET_EXTENSION_NAME);
  if (c.memory_budget) extensions.push_back(VK_EXT_MEMORY_BUDGET_EXTENSION_NAME);
  // Optional: importing a file's mapping as memory the GPU copies from
  // (render/transfer_bound.h measures whether the driver accepts it).
  c.external_memory_host = has_extension(device_extensions, VK_EXT_EXTERNAL_MEMORY_HOST_EXTENSION_NAME);
  if (c.external_memory_host) extensions.push_back(VK_EXT_EXTERNAL_MEMORY_HOST_EXTENSION_NAME);

  // The same features a host is asked to enable (required_device_features).
  DeviceFeatures features = required_device_features();
  vk::DeviceCreateInfo info({}, queues, {}, extensions);
  info.pNext = &features.features2;
  c.device = vk::raii::Device(c.physical, info);
  c.graphics_queue = vk::raii::Queue(c.device, c.graphics_family, 0);
  c.transfer_queue = vk::raii::Queue(c.device, c.transfer_family, 0);
  c.relay_shared = transfer_queues < 2;
  c.relay_queue = vk::raii::Queue(c.device, c.transfer_family, c.relay_shared ? 0 : 1);
  c.handles = {static_cast<VkInstance>(*c.instance), static_cast<VkPhysicalDevice>(*c.physical),
               static_cast<VkDevice>(*c.device),      c.graphics_family,
               static_cast<VkQueue>(*c.graphics_queue), c.transfer_family != c.graphics_family ? c.transfer_family : UINT32_MAX,
               c.transfer_family != c.graphics_family ? static_cast<VkQueue>(*c.transfer_queue) : VK_NULL_HANDLE};
}

}  // namespace

Context::Context(const ContextOptions& options) : impl_(std::make_unique<Impl>()) {
  Impl& c = *impl_;
  c.options = options;
  open_instance(c, options);
  const vk::raii::PhysicalDevices devices(c.instance);
  std::vector<DeviceInfo> infos;
  for (uint32_t i = 0; i < devices.size(); ++i) infos.push_back(describe(devices[i], i, options.presentation));
  if (infos.empty()) throw Error("no Vulkan device found (is mesa-vulkan-drivers or a GPU driver installed?)");
  const uint32_t chosen = choose_device(devices, infos, options.device);
  c.physical = devices[chosen];
  c.info = infos[chosen];
  c.properties = c.physical.getProperties();
  c.memory = c.physical.getMemoryProperties();
  create_device(c, options);
}

Context::Context(const HostVulkan& host) : impl_(std::make_unique<Impl>()) {
  Impl& c = *impl_;
  const VulkanHandles& h = host.handles;
  if (!h.instance || !h.physical_device || !h.device || !h.graphics_queue) {
    throw Error("sluice context: the host's instance, physical device, device and graphics queue are required");
  }
  if (h.transfer_family != UINT32_MAX && !h.transfer_queue) {
    throw Error("sluice context: a transfer family was given without its queue");
  }
  c.owning = false;
  c.handles = h;
  c.instance = vk::raii::Instance(c.context, h.instance);
  c.physical = vk::raii::PhysicalDevice(c.instance, h.physical_device);
  const std::string why = missing_features(c.physical, false);
  if (!why.empty()) {
    throw Error("the host's Vulkan device cannot run sluice: " + why);
  }
  c.info = describe(c.physical, 0, false);
  c.properties = c.physical.getProperties();
  c.memory = c.physical.getMemoryProperties();
  c.memory_budget = host.memory_budget_enabled;
  c.device = vk::raii::Device(c.physical, h.device);
  c.graphics_family = h.graphics_family;
  c.graphics_queue = vk::raii::Queue(c.device, h.graphics_queue);
  const bool transfer = h.transfer_family != UINT32_MAX && h.transfer_family != h.graphics_family;
  c.transfer_family = transfer ? h.transfer_family : h.graphics_family;
  c.transfer_queue = vk::raii::Queue(c.device, transfer ? h.transfer_queue : h.graphics_queue);
  c.relay_queue = vk::raii::Queue(c.device, transfer ? h.transfer_queue : h.graphics_queue);  // shared: queue_lock()
}

detail::ContextImpl::~ContextImpl() {
  if (*device && owning) device.waitIdle();
  if (!owning) {
    // The host's handles: let go of them without destroying anything.
    relay_queue.release();
    transfer_queue.release();
    graphics_queue.release();
    device.release();
    physical.release();
    instance.release();
  }
}

Context::~Context() = default;

const VulkanHandles& Context::vulkan() const { return impl_->handles; }
bool Context::owns_device() const { return impl_->owning; }
bool Context::relay_queue_shared() const { return impl_->relay_shared; }
void Context::wait(VkFence fence) const { impl_->wait(fence); }
std::mutex& Context::queue_lock() const { return impl_->queue_mutex; }

std::vector<const char*> required_instance_extensions() { return {}; }

std::vector<const char*> required_device_extensions(VkPhysicalDevice physical_device) {
  uint32_t count = 0;
  vkEnumerateDeviceExtensionProperties(physical_device, nullptr, &count, nullptr);
  std::vector<VkExtensionProperties> list(count);
  vkEnumerateDeviceExtensionProperties(physical_device, nullptr, &count, list.data());
  std::vector<const char*> out;
  for (const VkExtensionProperties& e : list) {
    if (std::strcmp(e.extensionName, VK_EXT_MEMORY_BUDGET_EXTENSION_NAME) == 0) out.push_back(VK_EXT_MEMORY_BUDGET_EXTENSION_NAME);
  }
  return out;
}

DeviceFeatures::DeviceFeatures() {
  features2.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2;
  vulkan11.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_FEATURES;
  vulkan12.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES;
  vulkan13.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES;
  chain();
}
DeviceFeatures::DeviceFeatures(const DeviceFeatures& other)
    : features2(other.features2), vulkan11(other.vulkan11), vulkan12(other.vulkan12), vulkan13(other.vulkan13) {
  chain(other.vulkan13.pNext);
}
DeviceFeatures& DeviceFeatures::operator=(const DeviceFeatures& other) {
  features2 = other.features2;
  vulkan11 = other.vulkan11;
  vulkan12 = other.vulkan12;
  vulkan13 = other.vulkan13;
  chain(other.vulkan13.pNext);
  return *this;
}
void DeviceFeatures::chain(void* next) {
  features2.pNext = &vulkan11;
  vulkan11.pNext = &vulkan12;
  vulkan12.pNext = &vulkan13;
  vulkan13.pNext = next;
}

DeviceFeatures required_device_features() {
  DeviceFeatures f;
  f.features2.features.largePoints = VK_TRUE;
  f.features2.features.shaderStorageImageWriteWithoutFormat = VK_TRUE;  // shading straight into the caller's image
  f.vulkan11.multiview = VK_TRUE;  // stereo (OpenXR) renders both eyes in one pass
  // The GPU decoder (decode.comp): 64-bit Morton codes, 16-bit attribute values.
  f.features2.features.shaderInt64 = VK_TRUE;
  f.vulkan11.storageBuffer16BitAccess = VK_TRUE;
  f.vulkan12.bufferDeviceAddress = VK_TRUE;
  f.vulkan12.timelineSemaphore = VK_TRUE;
  f.vulkan12.hostQueryReset = VK_TRUE;
  f.vulkan13.synchronization2 = VK_TRUE;
  f.vulkan13.dynamicRendering = VK_TRUE;
  f.vulkan13.maintenance4 = VK_TRUE;  // required by 1.3; SPIR-V 1.6 uses LocalSizeId
  return f;
}

std::string device_unusable_reason(VkInstance instance, VkPhysicalDevice physical_device) {
  vk::raii::Context context;
  vk::raii::Instance borrowed(context, instance);
  vk::raii::PhysicalDevice pd(borrowed, physical_device);
  std::string why = missing_features(pd, false);
  pd.release();
  borrowed.release();
  return why;
}

const DeviceInfo& Context::device() const { return impl_->info; }
bool Context::validation_active() const { return impl_->validation; }
uint64_t Context::validation_errors() const { return impl_->errors.load(); }
std::vector<std::string> Context::validation_messages() const {
  std::lock_guard lock(impl_->messages_mutex);
  return impl_->messages;
}

uint64_t Context::heap_available_bytes(uint32_t heap) const {
  const Impl& c = *impl_;
  if (heap >= c.memory.memoryHeapCount) return 0;
  if (!c.memory_budget) return c.memory.memoryHeaps[heap].size;
  const auto chain = c.physical.getMemoryProperties2<vk::PhysicalDeviceMemoryProperties2,
                                                     vk::PhysicalDeviceMemoryBudgetPropertiesEXT>();
  const auto& budget = chain.get<vk::PhysicalDeviceMemoryBudgetPropertiesEXT>();
  return budget.heapBudget[heap] > budget.heapUsage[heap] ? budget.heapBudget[heap] - budget.heapUsage[heap] : 0;
}

uint32_t detail::ContextImpl::memory_type(uint32_t type_bits, vk::MemoryPropertyFlags wanted) const {
  for (uint32_t i = 0; i < memory.memoryTypeCount; ++i) {
    if ((type_bits & (1u << i)) && (memory.memoryTypes[i].propertyFlags & wanted) == wanted) return i;
  }
  throw Error("no Vulkan memory type with the wanted properties");
}

void detail::ContextImpl::run_once(const std::function<void(vk::CommandBuffer)>& record) const {
  vk::raii::CommandPool pool(device, vk::CommandPoolCreateInfo(vk::CommandPoolCreateFlagBits::eTransient, graphics_family));
  vk::raii::CommandBuffers cmds(device, vk::CommandBufferAllocateInfo(*pool, vk::CommandBufferLevel::ePrimary, 1));
  vk::CommandBuffer cmd = *cmds[0];
  cmd.begin(vk::CommandBufferBeginInfo(vk::CommandBufferUsageFlagBits::eOneTimeSubmit));
  record(cmd);
  cmd.end();
  vk::raii::Fence fence(device, vk::FenceCreateInfo());
  vk::CommandBufferSubmitInfo cb(cmd);
  submit(graphics_queue, vk::SubmitInfo2({}, {}, cb), *fence);
  wait(*fence);
}

void detail::ContextImpl::wait(vk::Fence fence) const {
  while (device.waitForFences(fence, VK_TRUE, UINT64_MAX) == vk::Result::eTimeout) {
  }
}

void detail::ContextImpl::submit(const vk::raii::Queue& queue, const vk::SubmitInfo2& submission, vk::Fence fence) const {
  if (!relay_shared) {
    queue.submit2(submission, fence);
    return;
  }
  const std::lock_guard lock(queue_mutex);
  queue.submit2(submission, fence);
}

void detail::ContextImpl::wait_idle(const vk::raii::Queue& queue) const {
  const std::lock_guard lock(queue_mutex);  // rare: teardown
  queue.waitIdle();
}

uint64_t host_import_alignment(const detail::ContextImpl& ctx) {
  if (!ctx.external_memory_host) return 0;
  return ctx.physical.getProperties2<vk::PhysicalDeviceProperties2, vk::PhysicalDeviceExternalMemoryHostPropertiesEXT>()
      .get<vk::PhysicalDeviceExternalMemoryHostPropertiesEXT>()
      .minImportedHostPointerAlignment;
}

Buffer import_host_buffer(const detail::ContextImpl& ctx, void* host, vk::DeviceSize bytes, vk::BufferUsageFlags usage) {
  constexpr auto kHandle = vk::ExternalMemoryHandleTypeFlagBits::eHostAllocationEXT;
  const vk::MemoryHostPointerPropertiesEXT pointer = ctx.device.getMemoryHostPointerPropertiesEXT(kHandle, host);
  const vk::ExternalMemoryBufferCreateInfo external(kHandle);
  vk::BufferCreateInfo info({}, bytes, usage, vk::SharingMode::eExclusive);
  info.pNext = &external;
  Buffer b;
  b.buffer = vk::raii::Buffer(ctx.device, info);
  const uint32_t types = b.buffer.getMemoryRequirements().memoryTypeBits & pointer.memoryTypeBits;
  if (types == 0) return {};
  const vk::ImportMemoryHostPointerInfoEXT import(kHandle, host);
  vk::MemoryAllocateInfo allocate(bytes, uint32_t(std::countr_zero(types)));
  allocate.pNext = &import;
  b.memory = vk::raii::DeviceMemory(ctx.device, allocate);
  b.buffer.bindMemory(*b.memory, 0);
  b.size = bytes;
  b.mapped = host;
  return b;
}

Buffer create_buffer(const detail::ContextImpl& ctx, vk::DeviceSize size, vk::BufferUsageFlags usage, MemoryKind kind) {
  Buffer b;
  b.size = size;
  const bool address = bool(usage & vk::BufferUsageFlagBits::eShaderDeviceAddress);
  vk::BufferCreateInfo info({}, std::max<vk::DeviceSize>(size, 16), usage, vk::SharingMode::eExclusive);
  // Buffers the transfer queue writes are shared with the graphics queue
  // rather than handed over with ownership transfers.
  const std::array<uint32_t, 2> families{ctx.graphics_family, ctx.transfer_family};
  if (ctx.graphics_family != ctx.transfer_family) {
    info.setSharingMode(vk::SharingMode::eConcurrent).setQueueFamilyIndices(families);
  }
  b.buffer = vk::raii::Buffer(ctx.device, info);
  const vk::MemoryRequirements req = b.buffer.getMemoryRequirements();
  vk::MemoryPropertyFlags props;
  switch (kind) {
    case MemoryKind::DeviceLocal: props = vk::MemoryPropertyFlagBits::eDeviceLocal; break;
    case MemoryKind::Upload:
    case MemoryKind::UploadRead:
      props = vk::MemoryPropertyFlagBits::eHostVisible | vk::MemoryPropertyFlagBits::eHostCoherent;
      break;
    case MemoryKind::Readback:
      props = vk::MemoryPropertyFlagBits::eHostVisible | vk::MemoryPropertyFlagBits::eHostCoherent;
      break;
  }
  uint32_t type = 0;
  if (kind == MemoryKind::Readback || kind == MemoryKind::UploadRead) {
    // Prefer cached memory for reads; fall back to any host-visible type.
    try {
      type = ctx.memory_type(req.memoryTypeBits, props | vk::MemoryPropertyFlagBits::eHostCached);
    } catch (const std::runtime_error&) {
      type = ctx.memory_type(req.memoryTypeBits, props);
    }
  } else {
    type = ctx.memory_type(req.memoryTypeBits, props);
  }
  vk::MemoryAllocateFlagsInfo flags(address ? vk::MemoryAllocateFlagBits::eDeviceAddress : vk::MemoryAllocateFlags{});
  vk::MemoryAllocateInfo alloc(req.size, type);
  alloc.pNext = &flags;
  b.memory = vk::raii::DeviceMemory(ctx.device, alloc);
  b.buffer.bindMemory(*b.memory, 0);
  if (kind != MemoryKind::DeviceLocal) b.mapped = b.memory.mapMemory(0, VK_WHOLE_SIZE);
  if (address) b.address = ctx.device.getBufferAddress(vk::BufferDeviceAddressInfo(*b.buffer));
  return b;
}

void grow_buffer(const detail::ContextImpl& ctx, Buffer& b, vk::DeviceSize size, vk::BufferUsageFlags usage, MemoryKind kind,
                 const std::function<void(Buffer&&)>& retire) {
  if (*b.buffer && b.size >= size) return;
  if (retire && *b.buffer) retire(std::move(b));
  b = Buffer{};
  b = create_buffer(ctx, size, usage, kind);
}

Texture create_texture(const detail::ContextImpl& ctx, vk::Extent2D extent, vk::Format format, vk::ImageUsageFlags usage,
                       uint32_t layers, bool array_view) {
  Texture t;
  t.format = format;
  t.extent = extent;
  t.layers = layers;
  const bool depth = format == vk::Format::eD32Sfloat;
  t.aspect = depth ? vk::ImageAspectFlagBits::eDepth : vk::ImageAspectFlagBits::eColor;
  vk::ImageCreateInfo info({}, vk::ImageType::e2D, format, vk::Extent3D(extent, 1), 1, layers, vk::SampleCountFlagBits::e1,
                           vk::ImageTiling::eOptimal, usage, vk::SharingMode::eExclusive, {}, vk::ImageLayout::eUndefined);
  t.image = vk::raii::Image(ctx.device, info);
  const vk::MemoryRequirements req = t.image.getMemoryRequirements();
  t.memory = vk::raii::DeviceMemory(
      ctx.device, vk::MemoryAllocateInfo(req.size, ctx.memory_type(req.memoryTypeBits, vk::MemoryPropertyFlagBits::eDeviceLocal)));
  t.image.bindMemory(*t.memory, 0);
  t.view = vk::raii::ImageView(
      ctx.device, vk::ImageViewCreateInfo({}, *t.image, layers > 1 || array_view ? vk::ImageViewType::e2DArray : vk::ImageViewType::e2D,
                                          format, {}, vk::ImageSubresourceRange(t.aspect, 0, 1, 0, layers)));
  return t;
}

vk::ImageMemoryBarrier2 image_barrier(const Texture& t, vk::ImageLayout from, vk::ImageLayout to,
                                      vk::PipelineStageFlags2 src_stage, vk::AccessFlags2 src_access,
                                      vk::PipelineStageFlags2 dst_stage, vk::AccessFlags2 dst_access) {
  return vk::ImageMemoryBarrier2(src_stage, src_access, dst_stage, dst_access, from, to, VK_QUEUE_FAMILY_IGNORED,
                                 VK_QUEUE_FAMILY_IGNORED, *t.image, vk::ImageSubresourceRange(t.aspect, 0, 1, 0, t.layers));
}

void memory_barrier(vk::CommandBuffer cmd, vk::PipelineStageFlags2 src_stage, vk::AccessFlags2 src_access,
                    vk::PipelineStageFlags2 dst_stage, vk::AccessFlags2 dst_access) {
  vk::MemoryBarrier2 b(src_stage, src_access, dst_stage, dst_access);
  cmd.pipelineBarrier2(vk::DependencyInfo({}, b));
}

}  // namespace sluice::render
