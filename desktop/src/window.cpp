// GLFW window, Vulkan swapchain, and the Dear ImGui backends (see window.h).
// A frame: the renderer records the fluid into the swapchain image, the UI
// is drawn in a render pass on top, optionally copied out, then presented.
// Vulkan objects are Vulkan-Hpp RAII wrappers around the Context's public
// handles (borrowed: released, never destroyed, at the end).
#include <vulkan/vulkan_raii.hpp>  // first: GLFW declares its Vulkan entry points only after vulkan.h
// Vulkan-Hpp compiled in sluice's own namespace (cmake/vulkan_hpp.cmake).
namespace vk = ::sluice_vk;

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_vulkan.h>
#include <imgui.h>

#include <algorithm>
#include <array>
#include <functional>
#include <mutex>
#include <cstring>
#include <stdexcept>

#include "sluice/desktop/window.h"
#include "sluice/error.h"

namespace sluice::desktop {
namespace {

using Stage = vk::PipelineStageFlagBits2;
using Access = vk::AccessFlagBits2;

void check_vk(VkResult r) {
  if (r != VK_SUCCESS) throw Error("Dear ImGui Vulkan backend: error " + std::to_string(int(r)));
}

void ensure_glfw() {
  static bool ready = [] {
    if (!glfwInit()) {
      const char* why = nullptr;
      glfwGetError(&why);
      throw Error(std::string("cannot open a window: ") + (why ? why : "GLFW failed to start") +
                               " (no display? run it on a desktop, under xvfb-run, or use `sluice play --headless` or `sluice render`)");
    }
    if (!glfwVulkanSupported()) throw Error("cannot open a window: GLFW finds no Vulkan loader");
    std::atexit(glfwTerminate);
    return true;
  }();
  (void)ready;
}

}  // namespace

std::vector<std::string> window_instance_extensions() {
  ensure_glfw();
  uint32_t count = 0;
  const char** names = glfwGetRequiredInstanceExtensions(&count);
  if (!names) throw Error("cannot open a window: Vulkan cannot present to this display");
  return std::vector<std::string>(names, names + count);
}

void poll_window_events() { glfwPollEvents(); }

namespace {

// The Context's handles as Vulkan-Hpp RAII objects that do not own them.
struct Borrowed {
  vk::raii::Context context;
  vk::raii::Instance instance{nullptr};
  vk::raii::PhysicalDevice physical{nullptr};
  vk::raii::Device device{nullptr};
  vk::raii::Queue queue{nullptr};
  uint32_t family = 0;
  explicit Borrowed(const render::VulkanHandles& h) {
    instance = vk::raii::Instance(context, h.instance);
    physical = vk::raii::PhysicalDevice(instance, h.physical_device);
    device = vk::raii::Device(physical, h.device);
    queue = vk::raii::Queue(device, h.graphics_queue);
    family = h.graphics_family;
  }
  ~Borrowed() {
    queue.release();
    device.release();
    physical.release();
    instance.release();
  }
};

// A host-visible buffer the presented image is copied into.
struct Readback {
  vk::raii::Buffer buffer{nullptr};
  vk::raii::DeviceMemory memory{nullptr};
  void* mapped = nullptr;
  vk::DeviceSize size = 0;
};

Readback make_readback(const Borrowed& vk_, vk::DeviceSize size) {
  Readback r;
  r.size = size;
  r.buffer = vk::raii::Buffer(vk_.device, vk::BufferCreateInfo({}, size, vk::BufferUsageFlagBits::eTransferDst));
  const vk::MemoryRequirements req = r.buffer.getMemoryRequirements();
  const auto props = vk_.physical.getMemoryProperties();
  const auto want = vk::MemoryPropertyFlagBits::eHostVisible | vk::MemoryPropertyFlagBits::eHostCoherent;
  uint32_t type = UINT32_MAX;
  for (uint32_t i = 0; i < props.memoryTypeCount && type == UINT32_MAX; ++i) {
    if ((req.memoryTypeBits & (1u << i)) && (props.memoryTypes[i].propertyFlags & want) == want) type = i;
  }
  if (type == UINT32_MAX) throw Error("window: no host-visible memory for the capture");
  r.memory = vk::raii::DeviceMemory(vk_.device, vk::MemoryAllocateInfo(req.size, type));
  r.buffer.bindMemory(*r.memory, 0);
  r.mapped = r.memory.mapMemory(0, VK_WHOLE_SIZE);
  return r;
}

// One frame in flight: its command buffer, the image-acquired semaphore and
// the fence of its submission.
struct Slot {
  vk::raii::CommandBuffer cmd{nullptr};
  vk::raii::Semaphore acquired{nullptr};
  vk::raii::Fence fence{nullptr};
  bool submitted = false;
};

}  // namespace

struct detail::WindowImpl {
  Borrowed ctx;
  WindowOptions options;
  GLFWwindow* window = nullptr;
  vk::raii::SurfaceKHR surface{nullptr};
  vk::SurfaceFormatKHR format;
  vk::PresentModeKHR present_mode = vk::PresentModeKHR::eFifo;
  vk::raii::SwapchainKHR swapchain{nullptr};
  vk::Extent2D extent;
  std::vector<vk::Image> images;
  std::vector<vk::raii::ImageView> views;
  std::vector<vk::raii::Framebuffer> framebuffers;
  std::vector<vk::raii::Semaphore> finished;  // per swapchain image: rendering done, may present
  vk::raii::RenderPass render_pass{nullptr};  // Dear ImGui 1.86 draws in a classic render pass
  vk::raii::DescriptorPool ui_pool{nullptr};
  vk::raii::CommandPool pool{nullptr};
  std::vector<Slot> slots;
  uint64_t frame = 0;
  bool ui_started = false, imgui_vulkan = false;
  bool storage = false;  // the swapchain images take storage writes: the renderer shades straight into them
  Readback capture;
  vk::Extent2D captured;
  int captured_slot = -1;

  const render::Context& context;  // its fence waits
  // Held around submits and presents: the context's relay may share the
  // queue (render/context.h, "Queues").
  std::mutex& queue_lock;

  WindowImpl(const render::Context& c, const WindowOptions& o)
      : ctx(c.vulkan()), options(o), context(c), queue_lock(c.queue_lock()) {}
  void create_swapchain();
  void wait(Slot& s) {
    if (!s.submitted) return;
    context.wait(*s.fence);
    s.submitted = false;
  }
  // Every frame this window submitted is done (its own work, not the device's).
  void wait_all() {
    for (Slot& s : slots) wait(s);
  }
  void ensure_slots(uint32_t count);
  void run_once(const std::function<void(vk::CommandBuffer)>& record);
};

void detail::WindowImpl::ensure_slots(uint32_t count) {
  if (slots.size() == count) return;
  wait_all();
  slots.clear();
  for (uint32_t i = 0; i < count; ++i) {
    Slot s;
    s.cmd = std::move(vk::raii::CommandBuffers(ctx.device, vk::CommandBufferAllocateInfo(*pool, vk::CommandBufferLevel::ePrimary, 1))[0]);
    s.acquired = vk::raii::Semaphore(ctx.device, vk::SemaphoreCreateInfo());
    s.fence = vk::raii::Fence(ctx.device, vk::FenceCreateInfo());
    slots.push_back(std::move(s));
  }
}

void detail::WindowImpl::run_once(const std::function<void(vk::CommandBuffer)>& record) {
  vk::raii::CommandBuffer cmd =
      std::move(vk::raii::CommandBuffers(ctx.device, vk::CommandBufferAllocateInfo(*pool, vk::CommandBufferLevel::ePrimary, 1))[0]);
  cmd.begin(vk::CommandBufferBeginInfo(vk::CommandBufferUsageFlagBits::eOneTimeSubmit));
  record(*cmd);
  cmd.end();
  vk::raii::Fence fence(ctx.device, vk::FenceCreateInfo());
  const vk::CommandBufferSubmitInfo cb(*cmd);
  {
    const std::lock_guard lock(queue_lock);
    ctx.queue.submit2(vk::SubmitInfo2({}, {}, cb), *fence);
  }
  context.wait(*fence);
}

void detail::WindowImpl::create_swapchain() {
  wait_all();  // the old images may still be drawn into by this window's frames
  framebuffers.clear();
  views.clear();
  finished.clear();
  const auto caps = ctx.physical.getSurfaceCapabilitiesKHR(*surface);
  int w = 0, h = 0;
  glfwGetFramebufferSize(window, &w, &h);
  extent = caps.currentExtent.width != UINT32_MAX
               ? caps.currentExtent
               : vk::Extent2D(std::clamp(uint32_t(w), caps.minImageExtent.width, caps.maxImageExtent.width),
                              std::clamp(uint32_t(h), caps.minImageExtent.height, caps.maxImageExtent.height));
  if (extent.width == 0 || extent.height == 0) return;  // minimized
  uint32_t count = std::max(caps.minImageCount + 1, 2u);
  if (caps.maxImageCount > 0) count = std::min(count, caps.maxImageCount);
  vk::ImageUsageFlags usage = vk::ImageUsageFlagBits::eColorAttachment | vk::ImageUsageFlagBits::eTransferDst;
  if (caps.supportedUsageFlags & vk::ImageUsageFlagBits::eTransferSrc) usage |= vk::ImageUsageFlagBits::eTransferSrc;
  // Storage where the surface and format allow it: the renderer then skips
  // its present pass (a raster pass, slow on compute-first GPUs).
  storage = (caps.supportedUsageFlags & vk::ImageUsageFlagBits::eStorage) &&
            (ctx.physical.getFormatProperties(format.format).optimalTilingFeatures & vk::FormatFeatureFlagBits::eStorageImage);
  if (storage) usage |= vk::ImageUsageFlagBits::eStorage;
  vk::SwapchainCreateInfoKHR info({}, *surface, count, format.format, format.colorSpace, extent, 1, usage,
                                  vk::SharingMode::eExclusive, {}, caps.currentTransform,
                                  vk::CompositeAlphaFlagBitsKHR::eOpaque, present_mode, VK_TRUE, *swapchain);
  swapchain = vk::raii::SwapchainKHR(ctx.device, info);
  images = swapchain.getImages();
  for (vk::Image image : images) {
    views.emplace_back(ctx.device, vk::ImageViewCreateInfo({}, image, vk::ImageViewType::e2D, format.format, {},
                                                           vk::ImageSubresourceRange(vk::ImageAspectFlagBits::eColor, 0, 1, 0, 1)));
    framebuffers.emplace_back(ctx.device, vk::FramebufferCreateInfo({}, *render_pass, *views.back(), extent.width, extent.height, 1));
    finished.emplace_back(ctx.device, vk::SemaphoreCreateInfo());
  }
  if (imgui_vulkan) ImGui_ImplVulkan_SetMinImageCount(std::max(caps.minImageCount, 2u));
}

Window::Window(render::Context& context, const WindowOptions& options, const WindowCallbacks& callbacks)
    : impl_(std::make_unique<Impl>(context, options)) {
  Impl& w = *impl_;
  ensure_glfw();
  glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
  w.window = glfwCreateWindow(int(options.width), int(options.height), options.title.c_str(), nullptr, nullptr);
  if (!w.window) throw Error("cannot open a window (GLFW)");
  glfwSetWindowUserPointer(w.window, callbacks.user);
  if (callbacks.key) glfwSetKeyCallback(w.window, callbacks.key);
  if (callbacks.mouse_button) glfwSetMouseButtonCallback(w.window, callbacks.mouse_button);
  if (callbacks.cursor) glfwSetCursorPosCallback(w.window, callbacks.cursor);
  if (callbacks.scroll) glfwSetScrollCallback(w.window, callbacks.scroll);

  VkSurfaceKHR raw = VK_NULL_HANDLE;
  if (glfwCreateWindowSurface(static_cast<VkInstance>(*w.ctx.instance), w.window, nullptr, &raw) != VK_SUCCESS) {
    throw Error("cannot create a Vulkan surface for the window");
  }
  w.surface = vk::raii::SurfaceKHR(w.ctx.instance, raw);
  if (!w.ctx.physical.getSurfaceSupportKHR(w.ctx.family, *w.surface)) {
    throw Error("the Vulkan device cannot present to this window");
  }
  // The renderer's output is already sRGB-encoded: a UNORM swapchain passes it through.
  const auto formats = w.ctx.physical.getSurfaceFormatsKHR(*w.surface);
  w.format = formats.front();
  for (const auto& f : formats) {
    if ((f.format == vk::Format::eB8G8R8A8Unorm || f.format == vk::Format::eR8G8B8A8Unorm) &&
        f.colorSpace == vk::ColorSpaceKHR::eSrgbNonlinear) {
      w.format = f;
      break;
    }
  }
  if (!options.vsync) {
    for (const auto m : w.ctx.physical.getSurfacePresentModesKHR(*w.surface)) {
      if (m == vk::PresentModeKHR::eMailbox) w.present_mode = m;
      if (m == vk::PresentModeKHR::eImmediate && w.present_mode != vk::PresentModeKHR::eMailbox) w.present_mode = m;
    }
  }
  vk::AttachmentDescription color({}, w.format.format, vk::SampleCountFlagBits::e1, vk::AttachmentLoadOp::eLoad,
                                  vk::AttachmentStoreOp::eStore, vk::AttachmentLoadOp::eDontCare, vk::AttachmentStoreOp::eDontCare,
                                  vk::ImageLayout::eColorAttachmentOptimal, vk::ImageLayout::ePresentSrcKHR);
  vk::AttachmentReference ref(0, vk::ImageLayout::eColorAttachmentOptimal);
  vk::SubpassDescription subpass({}, vk::PipelineBindPoint::eGraphics, {}, ref);
  vk::SubpassDependency dep(VK_SUBPASS_EXTERNAL, 0, vk::PipelineStageFlagBits::eColorAttachmentOutput | vk::PipelineStageFlagBits::eTransfer,
                            vk::PipelineStageFlagBits::eColorAttachmentOutput, vk::AccessFlagBits::eTransferWrite,
                            vk::AccessFlagBits::eColorAttachmentRead | vk::AccessFlagBits::eColorAttachmentWrite);
  w.render_pass = vk::raii::RenderPass(w.ctx.device, vk::RenderPassCreateInfo({}, color, subpass, dep));
  w.pool = vk::raii::CommandPool(w.ctx.device,
                                 vk::CommandPoolCreateInfo(vk::CommandPoolCreateFlagBits::eResetCommandBuffer, w.ctx.family));
  w.ensure_slots(2);
  w.create_swapchain();

  // Dear ImGui: context, GLFW input (chaining to the callbacks set above), Vulkan drawing.
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini next to the user's data
  ImGui::StyleColorsDark();
  ImGui_ImplGlfw_InitForVulkan(w.window, true);
  const vk::DescriptorPoolSize sizes(vk::DescriptorType::eCombinedImageSampler, 16);
  w.ui_pool = vk::raii::DescriptorPool(
      w.ctx.device, vk::DescriptorPoolCreateInfo(vk::DescriptorPoolCreateFlagBits::eFreeDescriptorSet, 16, sizes));
  ImGui_ImplVulkan_InitInfo init{};
  init.Instance = static_cast<VkInstance>(*w.ctx.instance);
  init.PhysicalDevice = static_cast<VkPhysicalDevice>(*w.ctx.physical);
  init.Device = static_cast<VkDevice>(*w.ctx.device);
  init.QueueFamily = w.ctx.family;
  init.Queue = static_cast<VkQueue>(*w.ctx.queue);
  init.DescriptorPool = static_cast<VkDescriptorPool>(*w.ui_pool);
  init.MinImageCount = 2;
  init.ImageCount = uint32_t(std::max<size_t>(w.images.size(), 2));
  init.MSAASamples = VK_SAMPLE_COUNT_1_BIT;
  init.CheckVkResultFn = check_vk;
  ImGui_ImplVulkan_Init(&init, static_cast<VkRenderPass>(*w.render_pass));
  w.imgui_vulkan = true;
  w.run_once([](vk::CommandBuffer c) { ImGui_ImplVulkan_CreateFontsTexture(static_cast<VkCommandBuffer>(c)); });
  ImGui_ImplVulkan_DestroyFontUploadObjects();
}

Window::~Window() {
  if (!impl_) return;
  Impl& w = *impl_;
  w.wait_all();
  if (w.ui_started) ImGui::EndFrame();
  if (w.imgui_vulkan) ImGui_ImplVulkan_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
  w.framebuffers.clear();
  w.views.clear();
  w.swapchain = nullptr;
  w.surface = nullptr;
  glfwDestroyWindow(w.window);
}

bool Window::should_close() const { return glfwWindowShouldClose(impl_->window) != 0; }
uint32_t Window::width() const {
  int w = 0, h = 0;
  glfwGetFramebufferSize(impl_->window, &w, &h);
  return uint32_t(std::max(w, 0));
}
uint32_t Window::height() const {
  int w = 0, h = 0;
  glfwGetFramebufferSize(impl_->window, &w, &h);
  return uint32_t(std::max(h, 0));
}

void Window::new_ui_frame() {
  ImGui_ImplVulkan_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
  impl_->ui_started = true;
}

bool Window::present(render::Renderer& renderer, const render::Camera& camera, const render::FluidOptions& options,
                     const render::LodOptions& lod, bool ui, bool capture) {
  Impl& w = *impl_;
  const bool have_ui = w.ui_started;
  if (w.ui_started) {
    ImGui::Render();  // always close the UI frame, drawn or not
    w.ui_started = false;
  }
  // One slot per frame the renderer keeps in flight; waiting for this slot's
  // last frame is what the renderer's frames-in-flight contract asks.
  w.ensure_slots(renderer.options().frames_in_flight);
  Slot& slot = w.slots[w.frame % w.slots.size()];
  w.wait(slot);
  if (!*w.swapchain || w.extent.width != width() || w.extent.height != height()) {
    w.create_swapchain();
    return false;
  }
  if (w.extent.width == 0) return false;
  uint32_t index = 0;
  try {
    const auto [result, i] = w.swapchain.acquireNextImage(UINT64_MAX, *slot.acquired, nullptr);
    (void)result;  // suboptimal: still usable this once; rebuilt on the next size check or error
    index = i;
  } catch (const vk::OutOfDateKHRError&) {
    w.create_swapchain();
    return false;
  }

  vk::CommandBuffer cmd = *slot.cmd;
  cmd.reset();
  cmd.begin(vk::CommandBufferBeginInfo(vk::CommandBufferUsageFlagBits::eOneTimeSubmit));
  const vk::Image image = w.images[index];
  render::RenderTarget target;
  target.width = w.extent.width;
  target.height = w.extent.height;
  target.color_image = static_cast<VkImage>(image);
  target.color_view = static_cast<VkImageView>(*w.views[index]);
  target.color_format = static_cast<VkFormat>(w.format.format);
  target.color_layout_before = VK_IMAGE_LAYOUT_UNDEFINED;  // the background covers every pixel
  target.color_layout_after = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
  target.color_storage = w.storage;
  const render::View view = render::camera_view(camera, render::Viewport{0, 0, w.extent.width, w.extent.height});
  const render::FrameSync sync = renderer.record(static_cast<VkCommandBuffer>(cmd), target, {&view, 1}, options, lod);
  cmd.beginRenderPass(vk::RenderPassBeginInfo(*w.render_pass, *w.framebuffers[index], vk::Rect2D({0, 0}, w.extent)),
                      vk::SubpassContents::eInline);
  if (ui && have_ui) ImGui_ImplVulkan_RenderDrawData(ImGui::GetDrawData(), static_cast<VkCommandBuffer>(cmd));
  cmd.endRenderPass();
  const vk::ImageSubresourceRange range(vk::ImageAspectFlagBits::eColor, 0, 1, 0, 1);
  const vk::ImageSubresourceLayers layers(vk::ImageAspectFlagBits::eColor, 0, 0, 1);
  const bool can_capture = capture && (w.ctx.physical.getSurfaceCapabilitiesKHR(*w.surface).supportedUsageFlags &
                                       vk::ImageUsageFlagBits::eTransferSrc);
  if (can_capture) {
    w.wait_all();  // the capture buffer is shared by the slots
    const vk::DeviceSize bytes = vk::DeviceSize(w.extent.width) * w.extent.height * 4;
    if (!*w.capture.buffer || w.capture.size < bytes) w.capture = make_readback(w.ctx, bytes);
    const auto to_read = vk::ImageMemoryBarrier2(Stage::eColorAttachmentOutput, Access::eColorAttachmentWrite, Stage::eCopy,
                                                 Access::eTransferRead, vk::ImageLayout::ePresentSrcKHR,
                                                 vk::ImageLayout::eTransferSrcOptimal, VK_QUEUE_FAMILY_IGNORED,
                                                 VK_QUEUE_FAMILY_IGNORED, image, range);
    cmd.pipelineBarrier2(vk::DependencyInfo({}, {}, {}, to_read));
    cmd.copyImageToBuffer(image, vk::ImageLayout::eTransferSrcOptimal, *w.capture.buffer,
                          vk::BufferImageCopy(0, 0, 0, layers, {}, vk::Extent3D(w.extent, 1)));
    const auto back = vk::ImageMemoryBarrier2(Stage::eCopy, Access::eTransferRead, Stage::eBottomOfPipe, {},
                                              vk::ImageLayout::eTransferSrcOptimal, vk::ImageLayout::ePresentSrcKHR,
                                              VK_QUEUE_FAMILY_IGNORED, VK_QUEUE_FAMILY_IGNORED, image, range);
    const vk::MemoryBarrier2 host(Stage::eCopy, Access::eTransferWrite, Stage::eHost, Access::eHostRead);
    cmd.pipelineBarrier2(vk::DependencyInfo({}, host, {}, back));
    w.captured = w.extent;
    w.captured_slot = int(w.frame % w.slots.size());
  }
  cmd.end();

  const vk::CommandBufferSubmitInfo cb(cmd);
  const std::array waits{vk::SemaphoreSubmitInfo(*slot.acquired, 0, Stage::eAllCommands),
                         vk::SemaphoreSubmitInfo(vk::Semaphore(sync.upload_semaphore), sync.upload_value,
                                                 vk::PipelineStageFlags2(sync.wait_stages))};
  const vk::SemaphoreSubmitInfo signal(*w.finished[index], 0, Stage::eAllCommands);
  w.ctx.device.resetFences(*slot.fence);
  std::unique_lock lock(w.queue_lock);
  w.ctx.queue.submit2(vk::SubmitInfo2({}, waits, cb, signal), *slot.fence);
  slot.submitted = true;
  ++w.frame;
  const vk::Semaphore finished = *w.finished[index];
  const vk::SwapchainKHR chain = *w.swapchain;
  const vk::PresentInfoKHR present(finished, chain, index);
  // Out-of-date results throw in Vulkan-Hpp; the next frame rebuilds the swapchain.
  vk::Result result = vk::Result::eSuccess;
  try {
    result = w.ctx.queue.presentKHR(present);
  } catch (const vk::OutOfDateKHRError&) {
    result = vk::Result::eErrorOutOfDateKHR;
  }
  lock.unlock();
  if (result != vk::Result::eSuccess) w.create_swapchain();
  return true;
}

std::vector<uint8_t> Window::read_presented() {
  Impl& w = *impl_;
  if (w.captured_slot < 0 || !*w.capture.buffer || w.captured.width == 0) return {};
  w.wait(w.slots[size_t(w.captured_slot)]);
  const size_t n = size_t(w.captured.width) * w.captured.height;
  std::vector<uint8_t> out(n * 4);
  std::memcpy(out.data(), w.capture.mapped, out.size());
  // Swapchains are usually BGRA: hand out RGBA.
  if (w.format.format == vk::Format::eB8G8R8A8Unorm || w.format.format == vk::Format::eB8G8R8A8Srgb) {
    for (size_t i = 0; i < n; ++i) std::swap(out[4 * i], out[4 * i + 2]);
  }
  return out;
}

}  // namespace sluice::desktop
