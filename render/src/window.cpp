// GLFW window, Vulkan swapchain, and the Dear ImGui backends (see window.h).
// A frame: blit the renderer's RGBA8 output into the swapchain image, draw
// the UI in a render pass on top, optionally copy it out, present.
#include "renderer_impl.h"  // vk_common.h first: GLFW declares its Vulkan entry points only after vulkan.h

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_vulkan.h>
#include <imgui.h>

#include <algorithm>
#include <cstring>
#include <stdexcept>

#include "sluice/render/window.h"

namespace sluice::render {
namespace {

using Stage = vk::PipelineStageFlagBits2;
using Access = vk::AccessFlagBits2;

void check_vk(VkResult r) {
  if (r != VK_SUCCESS) throw std::runtime_error("Dear ImGui Vulkan backend: error " + std::to_string(int(r)));
}

void ensure_glfw() {
  static bool ready = [] {
    if (!glfwInit()) {
      const char* why = nullptr;
      glfwGetError(&why);
      throw std::runtime_error(std::string("cannot open a window: ") + (why ? why : "GLFW failed to start") +
                               " (no display? run it on a desktop, under xvfb-run, or use `sluice play --headless` or `sluice render`)");
    }
    if (!glfwVulkanSupported()) throw std::runtime_error("cannot open a window: GLFW finds no Vulkan loader");
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
  if (!names) throw std::runtime_error("cannot open a window: Vulkan cannot present to this display");
  return std::vector<std::string>(names, names + count);
}

void poll_window_events() { glfwPollEvents(); }

struct Window::Impl {
  Context::Impl& ctx;
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
  vk::raii::CommandBuffer cmd{nullptr};
  vk::raii::Semaphore acquired{nullptr};
  vk::raii::Fence fence{nullptr};
  bool submitted = false, ui_started = false, imgui_vulkan = false;
  Buffer capture;
  vk::Extent2D captured;

  Impl(Context::Impl& c, const WindowOptions& o) : ctx(c), options(o) {}
  void create_swapchain();
  void wait_idle() {
    if (*ctx.device) ctx.device.waitIdle();
  }
};

void Window::Impl::create_swapchain() {
  wait_idle();
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

Window::Window(Context& context, const WindowOptions& options, const WindowCallbacks& callbacks)
    : impl_(std::make_unique<Impl>(context.impl(), options)) {
  Impl& w = *impl_;
  ensure_glfw();
  glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
  w.window = glfwCreateWindow(int(options.width), int(options.height), options.title.c_str(), nullptr, nullptr);
  if (!w.window) throw std::runtime_error("cannot open a window (GLFW)");
  glfwSetWindowUserPointer(w.window, callbacks.user);
  if (callbacks.key) glfwSetKeyCallback(w.window, callbacks.key);
  if (callbacks.mouse_button) glfwSetMouseButtonCallback(w.window, callbacks.mouse_button);
  if (callbacks.cursor) glfwSetCursorPosCallback(w.window, callbacks.cursor);
  if (callbacks.scroll) glfwSetScrollCallback(w.window, callbacks.scroll);

  VkSurfaceKHR raw = VK_NULL_HANDLE;
  if (glfwCreateWindowSurface(static_cast<VkInstance>(*w.ctx.instance), w.window, nullptr, &raw) != VK_SUCCESS) {
    throw std::runtime_error("cannot create a Vulkan surface for the window");
  }
  w.surface = vk::raii::SurfaceKHR(w.ctx.instance, raw);
  if (!w.ctx.physical.getSurfaceSupportKHR(w.ctx.graphics_family, *w.surface)) {
    throw std::runtime_error("the Vulkan device cannot present to this window");
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
                                 vk::CommandPoolCreateInfo(vk::CommandPoolCreateFlagBits::eResetCommandBuffer, w.ctx.graphics_family));
  w.cmd = std::move(vk::raii::CommandBuffers(w.ctx.device, vk::CommandBufferAllocateInfo(*w.pool, vk::CommandBufferLevel::ePrimary, 1))[0]);
  w.acquired = vk::raii::Semaphore(w.ctx.device, vk::SemaphoreCreateInfo());
  w.fence = vk::raii::Fence(w.ctx.device, vk::FenceCreateInfo());
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
  init.QueueFamily = w.ctx.graphics_family;
  init.Queue = static_cast<VkQueue>(*w.ctx.graphics_queue);
  init.DescriptorPool = static_cast<VkDescriptorPool>(*w.ui_pool);
  init.MinImageCount = 2;
  init.ImageCount = uint32_t(std::max<size_t>(w.images.size(), 2));
  init.MSAASamples = VK_SAMPLE_COUNT_1_BIT;
  init.CheckVkResultFn = check_vk;
  ImGui_ImplVulkan_Init(&init, static_cast<VkRenderPass>(*w.render_pass));
  w.imgui_vulkan = true;
  w.ctx.run_once([](vk::CommandBuffer c) { ImGui_ImplVulkan_CreateFontsTexture(static_cast<VkCommandBuffer>(c)); });
  ImGui_ImplVulkan_DestroyFontUploadObjects();
}

Window::~Window() {
  if (!impl_) return;
  Impl& w = *impl_;
  w.wait_idle();
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

GLFWwindow* Window::glfw() const { return impl_->window; }
bool Window::should_close() const { return glfwWindowShouldClose(impl_->window) != 0; }
void Window::request_close() { glfwSetWindowShouldClose(impl_->window, GLFW_TRUE); }
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

bool Window::present(Renderer& renderer, bool ui, bool capture) {
  Impl& w = *impl_;
  const bool have_ui = w.ui_started;
  if (w.ui_started) {
    ImGui::Render();  // always close the UI frame, drawn or not
    w.ui_started = false;
  }
  if (w.submitted) {
    while (w.ctx.device.waitForFences(*w.fence, VK_TRUE, UINT64_MAX) == vk::Result::eTimeout) {
    }
    w.submitted = false;
  }
  if (!*w.swapchain || w.extent.width != width() || w.extent.height != height()) {
    w.create_swapchain();
    return false;
  }
  if (w.extent.width == 0) return false;
  uint32_t index = 0;
  try {
    const auto [result, i] = w.swapchain.acquireNextImage(UINT64_MAX, *w.acquired, nullptr);
    if (result == vk::Result::eSuboptimalKHR) {
      // Still usable this once; rebuilt on the next frame's size check or error.
    }
    index = i;
  } catch (const vk::OutOfDateKHRError&) {
    w.create_swapchain();
    return false;
  }

  const Texture& source = renderer.impl().targets.color;
  vk::CommandBuffer cmd = *w.cmd;
  cmd.reset();
  cmd.begin(vk::CommandBufferBeginInfo(vk::CommandBufferUsageFlagBits::eOneTimeSubmit));
  const vk::ImageSubresourceRange range(vk::ImageAspectFlagBits::eColor, 0, 1, 0, 1);
  const vk::Image target = w.images[index];
  // The renderer's image was written by compute (GENERAL); the swapchain
  // image's old contents do not matter.
  const std::array to_copy{
      vk::ImageMemoryBarrier2(Stage::eComputeShader, Access::eShaderStorageWrite, Stage::eBlit, Access::eTransferRead,
                              vk::ImageLayout::eGeneral, vk::ImageLayout::eTransferSrcOptimal, VK_QUEUE_FAMILY_IGNORED,
                              VK_QUEUE_FAMILY_IGNORED, *source.image, range),
      vk::ImageMemoryBarrier2(Stage::eBlit, {}, Stage::eBlit, Access::eTransferWrite, vk::ImageLayout::eUndefined,
                              vk::ImageLayout::eTransferDstOptimal, VK_QUEUE_FAMILY_IGNORED, VK_QUEUE_FAMILY_IGNORED, target, range)};
  cmd.pipelineBarrier2(vk::DependencyInfo({}, {}, {}, to_copy));
  const vk::ImageSubresourceLayers layers(vk::ImageAspectFlagBits::eColor, 0, 0, 1);
  const std::array<vk::Offset3D, 2> src{vk::Offset3D(0, 0, 0),
                                        vk::Offset3D(int32_t(source.extent.width), int32_t(source.extent.height), 1)};
  const std::array<vk::Offset3D, 2> dst{vk::Offset3D(0, 0, 0),
                                        vk::Offset3D(int32_t(w.extent.width), int32_t(w.extent.height), 1)};
  cmd.blitImage(*source.image, vk::ImageLayout::eTransferSrcOptimal, target, vk::ImageLayout::eTransferDstOptimal,
                vk::ImageBlit(layers, src, layers, dst), vk::Filter::eLinear);
  // The renderer's image goes back to GENERAL for its next frame.
  const std::array to_draw{
      vk::ImageMemoryBarrier2(Stage::eBlit, Access::eTransferWrite, Stage::eColorAttachmentOutput,
                              Access::eColorAttachmentRead | Access::eColorAttachmentWrite, vk::ImageLayout::eTransferDstOptimal,
                              vk::ImageLayout::eColorAttachmentOptimal, VK_QUEUE_FAMILY_IGNORED, VK_QUEUE_FAMILY_IGNORED, target,
                              range),
      vk::ImageMemoryBarrier2(Stage::eBlit, {}, Stage::eComputeShader, Access::eShaderStorageWrite,
                              vk::ImageLayout::eTransferSrcOptimal, vk::ImageLayout::eGeneral, VK_QUEUE_FAMILY_IGNORED,
                              VK_QUEUE_FAMILY_IGNORED, *source.image, range)};
  cmd.pipelineBarrier2(vk::DependencyInfo({}, {}, {}, to_draw));
  cmd.beginRenderPass(vk::RenderPassBeginInfo(*w.render_pass, *w.framebuffers[index], vk::Rect2D({0, 0}, w.extent)),
                      vk::SubpassContents::eInline);
  if (ui && have_ui) ImGui_ImplVulkan_RenderDrawData(ImGui::GetDrawData(), static_cast<VkCommandBuffer>(cmd));
  cmd.endRenderPass();
  const bool can_capture = capture && w.images.size() > 0 &&
                           (w.ctx.physical.getSurfaceCapabilitiesKHR(*w.surface).supportedUsageFlags &
                            vk::ImageUsageFlagBits::eTransferSrc);
  if (can_capture) {
    const vk::DeviceSize bytes = vk::DeviceSize(w.extent.width) * w.extent.height * 4;
    if (!*w.capture.buffer || w.capture.size < bytes) {
      w.capture = create_buffer(w.ctx, bytes, vk::BufferUsageFlagBits::eTransferDst, MemoryKind::Readback);
    }
    const auto to_read = vk::ImageMemoryBarrier2(Stage::eColorAttachmentOutput, Access::eColorAttachmentWrite, Stage::eCopy,
                                                 Access::eTransferRead, vk::ImageLayout::ePresentSrcKHR,
                                                 vk::ImageLayout::eTransferSrcOptimal, VK_QUEUE_FAMILY_IGNORED,
                                                 VK_QUEUE_FAMILY_IGNORED, target, range);
    cmd.pipelineBarrier2(vk::DependencyInfo({}, {}, {}, to_read));
    cmd.copyImageToBuffer(target, vk::ImageLayout::eTransferSrcOptimal, *w.capture.buffer,
                          vk::BufferImageCopy(0, 0, 0, layers, {}, vk::Extent3D(w.extent, 1)));
    const auto back = vk::ImageMemoryBarrier2(Stage::eCopy, Access::eTransferRead, Stage::eBottomOfPipe, {},
                                              vk::ImageLayout::eTransferSrcOptimal, vk::ImageLayout::ePresentSrcKHR,
                                              VK_QUEUE_FAMILY_IGNORED, VK_QUEUE_FAMILY_IGNORED, target, range);
    const vk::MemoryBarrier2 host(Stage::eCopy, Access::eTransferWrite, Stage::eHost, Access::eHostRead);
    cmd.pipelineBarrier2(vk::DependencyInfo({}, host, {}, back));
    w.captured = w.extent;
  }
  cmd.end();

  const vk::CommandBufferSubmitInfo cb(cmd);
  const vk::SemaphoreSubmitInfo wait(*w.acquired, 0, Stage::eBlit | Stage::eColorAttachmentOutput);
  const vk::SemaphoreSubmitInfo signal(*w.finished[index], 0, Stage::eAllCommands);
  w.ctx.device.resetFences(*w.fence);
  w.ctx.graphics_queue.submit2(vk::SubmitInfo2({}, wait, cb, signal), *w.fence);
  w.submitted = true;
  const vk::Semaphore finished = *w.finished[index];
  const vk::SwapchainKHR chain = *w.swapchain;
  const vk::PresentInfoKHR present(finished, chain, index);
  // Out-of-date results throw in Vulkan-Hpp; the next frame rebuilds the swapchain.
  vk::Result result = vk::Result::eSuccess;
  try {
    result = w.ctx.graphics_queue.presentKHR(present);
  } catch (const vk::OutOfDateKHRError&) {
    result = vk::Result::eErrorOutOfDateKHR;
  }
  if (result != vk::Result::eSuccess) {
    while (w.ctx.device.waitForFences(*w.fence, VK_TRUE, UINT64_MAX) == vk::Result::eTimeout) {
    }
    w.submitted = false;
    w.create_swapchain();
  }
  return true;
}

std::vector<uint8_t> Window::read_presented() {
  Impl& w = *impl_;
  if (w.submitted) {
    while (w.ctx.device.waitForFences(*w.fence, VK_TRUE, UINT64_MAX) == vk::Result::eTimeout) {
    }
    w.submitted = false;
  }
  if (!*w.capture.buffer || w.captured.width == 0) return {};
  const size_t n = size_t(w.captured.width) * w.captured.height;
  std::vector<uint8_t> out(n * 4);
  std::memcpy(out.data(), w.capture.mapped, out.size());
  // Swapchains are usually BGRA: hand out RGBA.
  if (w.format.format == vk::Format::eB8G8R8A8Unorm || w.format.format == vk::Format::eB8G8R8A8Srgb) {
    for (size_t i = 0; i < n; ++i) std::swap(out[4 * i], out[4 * i + 2]);
  }
  return out;
}

}  // namespace sluice::render
