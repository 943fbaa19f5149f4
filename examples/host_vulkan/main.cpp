// host_vulkan: an application that owns its Vulkan instance, device, queue and
// images, draws its own opaque geometry (a floor and a box standing in the
// fluid) and has sluice stream a sequence and record the fluid into the same
// colour and depth images, frames in flight, no idle waits. It reads top to
// bottom:
//
//   1. instance      (sluice::render::required_instance_extensions)
//   2. device        (required_device_extensions, required_device_features)
//   3. sluice        (a Context from the host's handles, a Stream of the file)
//   4. host things   (images, the box pipeline, per-frame slots)
//   5. frame loop    (Stream::set_views, update; host geometry, then
//                     Stream::record into the same images)
//   6. output        (a PNG; with --check, the occlusion test below)
//
// Usage: host_vulkan [--frames N] [--out image.png] [--check] FILE.sluice
//        host_vulkan [--frames N] [--out image.png] [--check] --live [--record R.sluice]
// With a file it plays the file from its first frame, one frame per drawn
// frame at the file's rate. With --live it runs a small "simulation" of its
// own (a block of water with a travelling wave) and pushes every frame from
// its memory (Stream::push), recording it to R.sluice when asked. --check
// also renders the host geometry alone and the fluid alone and verifies,
// pixel by pixel, that where both are present the nearer one shows (both
// ways must occur); the exit status says whether it held.
#include <vulkan/vulkan_raii.hpp>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "sluice/render/context.h"
#include "sluice/render/image_io.h"
#include "sluice/stream/stream.h"

namespace {

const uint32_t kBoxVert[] =
#include "box.vert.inc"
    ;
const uint32_t kBoxFrag[] =
#include "box.frag.inc"
    ;

constexpr uint32_t kWidth = 480, kHeight = 320, kFramesInFlight = 2;
constexpr vk::Format kColor = vk::Format::eR8G8B8A8Unorm, kDepth = vk::Format::eD32Sfloat;
int validation_messages = 0;  // warnings and errors of every kind, performance ones too

VKAPI_ATTR VkBool32 VKAPI_CALL on_validation(VkDebugUtilsMessageSeverityFlagBitsEXT, VkDebugUtilsMessageTypeFlagsEXT,
                                             const VkDebugUtilsMessengerCallbackDataEXT* data, void*) {
  ++validation_messages;
  std::fprintf(stderr, "validation: %s\n", data->pMessage);
  return VK_FALSE;
}

struct Image {
  vk::raii::Image image{nullptr};
  vk::raii::DeviceMemory memory{nullptr};
  vk::raii::ImageView view{nullptr};
};

uint32_t memory_type(const vk::raii::PhysicalDevice& pd, uint32_t bits, vk::MemoryPropertyFlags want) {
  const auto props = pd.getMemoryProperties();
  for (uint32_t i = 0; i < props.memoryTypeCount; ++i) {
    if ((bits & (1u << i)) && (props.memoryTypes[i].propertyFlags & want) == want) return i;
  }
  throw std::runtime_error("no suitable memory type");
}

Image make_image(const vk::raii::Device& device, const vk::raii::PhysicalDevice& pd, vk::Format format,
                 vk::ImageUsageFlags usage, vk::ImageAspectFlags aspect) {
  Image i;
  i.image = vk::raii::Image(device, vk::ImageCreateInfo({}, vk::ImageType::e2D, format, vk::Extent3D(kWidth, kHeight, 1), 1, 1,
                                                        vk::SampleCountFlagBits::e1, vk::ImageTiling::eOptimal, usage));
  const auto req = i.image.getMemoryRequirements();
  i.memory = vk::raii::DeviceMemory(device, vk::MemoryAllocateInfo(req.size, memory_type(pd, req.memoryTypeBits, {})));
  i.image.bindMemory(*i.memory, 0);
  i.view = vk::raii::ImageView(device, vk::ImageViewCreateInfo({}, *i.image, vk::ImageViewType::e2D, format, {},
                                                               vk::ImageSubresourceRange(aspect, 0, 1, 0, 1)));
  return i;
}

// The host's own math (a real host brings its library): column-major 4x4
// matrices, a right-handed camera looking down -z, standard depth (0 near,
// 1 far) with a finite far plane. sluice takes the matrices as they are.
using Matrix = std::array<float, 16>;
struct Vec {
  float x, y, z;
};
Vec operator-(Vec a, Vec b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Vec cross(Vec a, Vec b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
float dot(Vec a, Vec b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
Vec normalize(Vec a) {
  const float n = std::sqrt(dot(a, a));
  return {a.x / n, a.y / n, a.z / n};
}

Matrix multiply(const Matrix& a, const Matrix& b) {
  Matrix r{};
  for (int col = 0; col < 4; ++col) {
    for (int row = 0; row < 4; ++row) {
      for (int k = 0; k < 4; ++k) r[col * 4 + row] += a[k * 4 + row] * b[col * 4 + k];
    }
  }
  return r;
}

Matrix look_at(Vec eye, Vec target, Vec up) {
  const Vec f = normalize(target - eye), s = normalize(cross(f, up)), u = cross(s, f);
  return {s.x, u.x, -f.x, 0, s.y, u.y, -f.y, 0, s.z, u.z, -f.z, 0, -dot(s, eye), -dot(u, eye), dot(f, eye), 1};
}

Matrix projection(float fov_deg, float aspect, float near, float far) {
  const float f = 1.0f / std::tan(fov_deg * 0.5f * 3.14159265f / 180.0f);
  Matrix p{};
  p[0] = f / aspect;
  p[5] = -f;  // Vulkan: y down
  p[10] = far / (near - far);
  p[11] = -1;
  p[14] = near * far / (near - far);
  return p;
}

// The region the host frames: the data's bounds.
struct Box {
  Vec lo, hi;
};

struct BoxPush {
  Matrix clip_from_world;
  float lo[4], size[4], color[4];
};

struct Args {
  int frames = 3;
  bool check = false, live = false;
  std::string out = "host_vulkan.png", file, record;
};

// The command line; nullopt after --help or a usage error (`status` says which).
std::optional<Args> parse_args(int argc, char** argv, int& status) {
  Args a;
  const char* usage = "usage: host_vulkan [--frames N] [--out image.png] [--check] (FILE.sluice | --live [--record R.sluice])\n";
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--frames" && i + 1 < argc) a.frames = std::max(1, std::atoi(argv[++i]));
    else if (arg == "--out" && i + 1 < argc) a.out = argv[++i];
    else if (arg == "--check") a.check = true;
    else if (arg == "--live") a.live = true;
    else if (arg == "--record" && i + 1 < argc) a.record = argv[++i];
    else if (arg == "--help") {
      std::printf("%s", usage);
      status = 0;
      return std::nullopt;
    } else a.file = arg;
  }
  if (a.file.empty() == !a.live) {
    std::fprintf(stderr, "host_vulkan: give a .sluice file, or --live\n%s", usage);
    status = 2;
    return std::nullopt;
  }
  return a;
}

// 1. Instance: Vulkan 1.3, what sluice asks for, and validation when installed.
struct Instance {
  vk::raii::Instance instance{nullptr};
  vk::raii::DebugUtilsMessengerEXT messenger{nullptr};
};

Instance make_instance(const vk::raii::Context& loader) {
  std::vector<const char*> layers, extensions = sluice::render::required_instance_extensions();
  for (const auto& l : loader.enumerateInstanceLayerProperties()) {
    if (std::strcmp(l.layerName, "VK_LAYER_KHRONOS_validation") == 0) {
      layers.push_back("VK_LAYER_KHRONOS_validation");
      extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
    }
  }
  const vk::ApplicationInfo app("host_vulkan", 1, nullptr, 0, VK_API_VERSION_1_3);
  Instance i;
  i.instance = vk::raii::Instance(loader, vk::InstanceCreateInfo({}, &app, layers, extensions));
  if (!layers.empty()) {
    using S = vk::DebugUtilsMessageSeverityFlagBitsEXT;
    using T = vk::DebugUtilsMessageTypeFlagBitsEXT;
    i.messenger = vk::raii::DebugUtilsMessengerEXT(
        i.instance, vk::DebugUtilsMessengerCreateInfoEXT({}, S::eWarning | S::eError,
                                                         T::eValidation | T::eGeneral | T::ePerformance, &on_validation));
  }
  return i;
}

// 2. Device: the first sluice can run on, one graphics+compute queue, sluice's extensions and features.
struct Device {
  vk::raii::PhysicalDevice physical{nullptr};
  vk::raii::Device device{nullptr};
  vk::raii::Queue queue{nullptr};
  uint32_t family = 0;
  bool memory_budget = false;  // VK_EXT_memory_budget enabled
};

Device make_device(const vk::raii::Instance& instance) {
  Device d;
  for (auto& pd : vk::raii::PhysicalDevices(instance)) {
    if (sluice::render::device_unusable_reason(*instance, *pd).empty()) {
      d.physical = std::move(pd);
      break;
    }
  }
  if (!*d.physical) throw std::runtime_error("no Vulkan device can run sluice");
  const auto families = d.physical.getQueueFamilyProperties();
  while (d.family < families.size() && !(families[d.family].queueFlags & vk::QueueFlagBits::eGraphics)) ++d.family;
  const float priority = 1;
  const vk::DeviceQueueCreateInfo queue_info({}, d.family, 1, &priority);
  const std::vector<const char*> extensions = sluice::render::required_device_extensions(*d.physical);
  sluice::render::DeviceFeatures features = sluice::render::required_device_features();
  vk::DeviceCreateInfo device_info({}, queue_info, {}, extensions);
  device_info.pNext = &features.features2;
  d.device = vk::raii::Device(d.physical, device_info);
  d.queue = vk::raii::Queue(d.device, d.family, 0);
  for (const char* e : extensions) d.memory_budget |= std::strcmp(e, VK_EXT_MEMORY_BUDGET_EXTENSION_NAME) == 0;
  std::printf("host device: %s\n", d.physical.getProperties().deviceName.data());
  return d;
}

// The host's own "simulation": a 2 x 1 block of water, 0.5 deep, with a
// wave travelling along x; particle i keeps its place, so LOD is stable.
std::vector<float> simulate(int step, float h) {
  std::vector<float> xyz;
  for (int i = 0; i < 100; ++i) {
    for (int j = 0; j < 50; ++j) {
      const float x = (float(i) + 0.5f) * h, y = (float(j) + 0.5f) * h;
      const float top = 0.45f + 0.12f * std::sin(3.0f * x - 0.25f * float(step));
      for (float z = 0.5f * h; z < top; z += h) xyz.insert(xyz.end(), {x, y, z});
    }
  }
  return xyz;
}

// 4. The host's things: its colour and depth images, a pipeline drawing lit
// boxes, a camera, and one command buffer + fence per frame in flight.
class HostScene {
 public:
  // `queue_lock`: the context's (Context::queue_lock()), held around every
  // submission to the queue it shares with sluice's relay (stream.h, "Queues").
  HostScene(const Device& d, const Box& b, std::mutex& queue_lock) : d_(d), queue_lock_(queue_lock) {
    using U = vk::ImageUsageFlagBits;
    color_ = make_image(d.device, d.physical, kColor, U::eColorAttachment | U::eTransferSrc, vk::ImageAspectFlagBits::eColor);
    depth_ = make_image(d.device, d.physical, kDepth, U::eDepthStencilAttachment | U::eTransferSrc, vk::ImageAspectFlagBits::eDepth);
    make_pipeline();
    pool_ = vk::raii::CommandPool(d.device, vk::CommandPoolCreateInfo(vk::CommandPoolCreateFlagBits::eResetCommandBuffer, d.family));
    slots_.resize(kFramesInFlight);
    for (Slot& s : slots_) {
      s.cmd = std::move(vk::raii::CommandBuffers(d.device, vk::CommandBufferAllocateInfo(*pool_, vk::CommandBufferLevel::ePrimary, 1))[0]);
      s.fence = vk::raii::Fence(d.device, vk::FenceCreateInfo());
    }
    place_camera_and_boxes(b);
  }

  // The camera as sluice takes it: the host's matrices over the whole image.
  sluice::render::View view() const { return {{view_}, {projection_}, {0, 0, kWidth, kHeight}}; }

  // One frame: the host clears and draws its geometry (or not), then the
  // stream records the fluid into the same images (occluded by the host's
  // depth, writing its own), or not; submitted, not waited for.
  void draw(bool host_geometry, sluice::stream::Stream* fluid) {
    Slot& slot = slots_[next_++ % slots_.size()];
    wait_for(slot);  // the frames-in-flight contract: this slot's previous frame is done
    vk::CommandBuffer cmd = *slot.cmd;
    cmd.reset();
    cmd.begin(vk::CommandBufferBeginInfo(vk::CommandBufferUsageFlagBits::eOneTimeSubmit));
    draw_geometry(cmd, host_geometry);
    const sluice::render::View camera = view();
    const auto sync = fluid ? fluid->record(static_cast<VkCommandBuffer>(cmd), target(), {&camera, 1}) : sluice::render::FrameSync{};
    if (!fluid) to_transfer_source(cmd);
    cmd.end();
    const vk::CommandBufferSubmitInfo cb(cmd);
    const vk::SemaphoreSubmitInfo wait(vk::Semaphore(sync.upload_semaphore), sync.upload_value,
                                       vk::PipelineStageFlags2(sync.wait_stages));
    submit(vk::SubmitInfo2({}, fluid ? 1u : 0u, &wait, 1, &cb), *slot.fence);
    slot.busy = true;
  }

  // The colour and depth of the last frame (after waiting for it).
  void read_back(std::vector<uint32_t>& rgba, std::vector<float>& z) {
    for (Slot& s : slots_) wait_for(s);
    const vk::DeviceSize bytes = vk::DeviceSize(kWidth) * kHeight * 4;
    vk::raii::Buffer buffer(d_.device, vk::BufferCreateInfo({}, 2 * bytes, vk::BufferUsageFlagBits::eTransferDst));
    const auto req = buffer.getMemoryRequirements();
    using M = vk::MemoryPropertyFlagBits;
    vk::raii::DeviceMemory memory(
        d_.device, vk::MemoryAllocateInfo(req.size, memory_type(d_.physical, req.memoryTypeBits, M::eHostVisible | M::eHostCoherent)));
    buffer.bindMemory(*memory, 0);
    Slot& slot = slots_[0];
    vk::CommandBuffer cmd = *slot.cmd;
    cmd.reset();
    cmd.begin(vk::CommandBufferBeginInfo(vk::CommandBufferUsageFlagBits::eOneTimeSubmit));
    cmd.copyImageToBuffer(*color_.image, vk::ImageLayout::eTransferSrcOptimal, *buffer,
                          vk::BufferImageCopy(0, 0, 0, {vk::ImageAspectFlagBits::eColor, 0, 0, 1}, {}, {kWidth, kHeight, 1}));
    cmd.copyImageToBuffer(*depth_.image, vk::ImageLayout::eTransferSrcOptimal, *buffer,
                          vk::BufferImageCopy(bytes, 0, 0, {vk::ImageAspectFlagBits::eDepth, 0, 0, 1}, {}, {kWidth, kHeight, 1}));
    cmd.end();
    const vk::CommandBufferSubmitInfo cb(cmd);
    submit(vk::SubmitInfo2({}, {}, cb), *slot.fence);
    slot.busy = true;
    wait_for(slot);
    const auto* mapped = static_cast<const std::byte*>(memory.mapMemory(0, 2 * bytes));
    rgba.resize(size_t(kWidth) * kHeight);
    z.resize(rgba.size());
    std::memcpy(rgba.data(), mapped, bytes);
    std::memcpy(z.data(), mapped + bytes, bytes);
  }

 private:
  struct Slot {
    vk::raii::CommandBuffer cmd{nullptr};
    vk::raii::Fence fence{nullptr};
    bool busy = false;
  };

  void wait_for(Slot& s) {
    if (!s.busy) return;
    while (d_.device.waitForFences(*s.fence, true, UINT64_MAX) == vk::Result::eTimeout) {
    }
    d_.device.resetFences(*s.fence);
    s.busy = false;
  }

  void make_pipeline() {
    const vk::PushConstantRange push_range(vk::ShaderStageFlagBits::eVertex | vk::ShaderStageFlagBits::eFragment, 0, sizeof(BoxPush));
    layout_ = vk::raii::PipelineLayout(d_.device, vk::PipelineLayoutCreateInfo({}, {}, push_range));
    const vk::raii::ShaderModule vs(d_.device, vk::ShaderModuleCreateInfo({}, sizeof kBoxVert, kBoxVert));
    const vk::raii::ShaderModule fs(d_.device, vk::ShaderModuleCreateInfo({}, sizeof kBoxFrag, kBoxFrag));
    const std::array stages{vk::PipelineShaderStageCreateInfo({}, vk::ShaderStageFlagBits::eVertex, *vs, "main"),
                            vk::PipelineShaderStageCreateInfo({}, vk::ShaderStageFlagBits::eFragment, *fs, "main")};
    const vk::PipelineVertexInputStateCreateInfo vertex_input;
    const vk::PipelineInputAssemblyStateCreateInfo assembly({}, vk::PrimitiveTopology::eTriangleList);
    const vk::Viewport viewport(0, 0, float(kWidth), float(kHeight), 0, 1);
    const vk::Rect2D area({0, 0}, {kWidth, kHeight});
    const vk::PipelineViewportStateCreateInfo viewport_state({}, viewport, area);
    const vk::PipelineRasterizationStateCreateInfo raster({}, false, false, vk::PolygonMode::eFill, vk::CullModeFlagBits::eNone,
                                                          vk::FrontFace::eCounterClockwise, false, 0, 0, 0, 1);
    const vk::PipelineMultisampleStateCreateInfo multisample;
    const vk::PipelineDepthStencilStateCreateInfo depth_state({}, true, true, vk::CompareOp::eLess);
    vk::PipelineColorBlendAttachmentState blend;
    blend.colorWriteMask = vk::ColorComponentFlagBits::eR | vk::ColorComponentFlagBits::eG | vk::ColorComponentFlagBits::eB |
                           vk::ColorComponentFlagBits::eA;
    const vk::PipelineColorBlendStateCreateInfo blend_state({}, false, vk::LogicOp::eCopy, blend);
    vk::PipelineRenderingCreateInfo rendering(0, kColor, kDepth);
    vk::GraphicsPipelineCreateInfo info({}, stages, &vertex_input, &assembly, nullptr, &viewport_state, &raster, &multisample,
                                        &depth_state, &blend_state, nullptr, *layout_);
    info.pNext = &rendering;
    pipeline_ = vk::raii::Pipeline(d_.device, nullptr, info);
  }

  // The host's camera looking at the data, a floor under it and a box standing in its middle.
  void place_camera_and_boxes(const Box& b) {
    const Vec e = b.hi - b.lo, c{b.lo.x + 0.5f * e.x, b.lo.y + 0.5f * e.y, b.lo.z + 0.5f * e.z};
    const Vec eye{c.x - 0.35f * e.x, b.lo.y - 1.3f * std::max(e.x, e.y), b.hi.z + 0.9f * e.z};
    view_ = look_at(eye, {c.x, c.y, b.lo.z + 0.3f * e.z}, {0, 0, 1});
    projection_ = projection(45, float(kWidth) / kHeight, 0.05f * e.x, 20 * (e.x + e.y + e.z));
    const Matrix clip_from_world = multiply(projection_, view_);
    floor_ = {clip_from_world, {b.lo.x - 0.3f * e.x, b.lo.y - 0.3f * e.y, b.lo.z - 0.02f * e.z, 0},
              {1.6f * e.x, 1.6f * e.y, 0.02f * e.z, 0}, {0.55f, 0.5f, 0.45f, 1}};
    box_ = {clip_from_world, {c.x - 0.08f * e.x, c.y - 0.12f * e.y, b.lo.z, 0}, {0.16f * e.x, 0.24f * e.y, 1.4f * e.z, 0},
            {0.85f, 0.25f, 0.2f, 1}};
  }

  // Clears the images and draws the floor and the box (or only clears),
  // leaving both in ATTACHMENT_OPTIMAL.
  void draw_geometry(vk::CommandBuffer cmd, bool host_geometry) {
    using S = vk::PipelineStageFlagBits2;
    using A = vk::AccessFlagBits2;
    const std::array to_draw{
        vk::ImageMemoryBarrier2(S::eAllCommands, A::eMemoryRead, S::eColorAttachmentOutput, A::eColorAttachmentWrite,
                                vk::ImageLayout::eUndefined, vk::ImageLayout::eColorAttachmentOptimal, VK_QUEUE_FAMILY_IGNORED,
                                VK_QUEUE_FAMILY_IGNORED, *color_.image,
                                vk::ImageSubresourceRange(vk::ImageAspectFlagBits::eColor, 0, 1, 0, 1)),
        vk::ImageMemoryBarrier2(S::eAllCommands, A::eMemoryRead, S::eEarlyFragmentTests | S::eLateFragmentTests,
                                A::eDepthStencilAttachmentWrite | A::eDepthStencilAttachmentRead, vk::ImageLayout::eUndefined,
                                vk::ImageLayout::eDepthStencilAttachmentOptimal, VK_QUEUE_FAMILY_IGNORED, VK_QUEUE_FAMILY_IGNORED,
                                *depth_.image, vk::ImageSubresourceRange(vk::ImageAspectFlagBits::eDepth, 0, 1, 0, 1))};
    cmd.pipelineBarrier2(vk::DependencyInfo({}, {}, {}, to_draw));
    vk::RenderingAttachmentInfo color_attachment(*color_.view, vk::ImageLayout::eColorAttachmentOptimal, {}, {}, {},
                                                 vk::AttachmentLoadOp::eClear, vk::AttachmentStoreOp::eStore,
                                                 vk::ClearColorValue(std::array<float, 4>{0.12f, 0.13f, 0.16f, 1}));
    vk::RenderingAttachmentInfo depth_attachment(*depth_.view, vk::ImageLayout::eDepthStencilAttachmentOptimal, {}, {}, {},
                                                 vk::AttachmentLoadOp::eClear, vk::AttachmentStoreOp::eStore,
                                                 vk::ClearDepthStencilValue(1.0f, 0));
    cmd.beginRendering(vk::RenderingInfo({}, vk::Rect2D({0, 0}, {kWidth, kHeight}), 1, 0, color_attachment, &depth_attachment));
    if (host_geometry) {
      cmd.bindPipeline(vk::PipelineBindPoint::eGraphics, *pipeline_);
      for (const BoxPush* push : {&floor_, &box_}) {
        cmd.pushConstants<BoxPush>(*layout_, vk::ShaderStageFlagBits::eVertex | vk::ShaderStageFlagBits::eFragment, 0, *push);
        cmd.draw(36, 1, 0, 0);
      }
    }
    cmd.endRendering();
  }

  // The host's images as sluice's target: drawn over (its clear colour
  // stays where there is no fluid), left ready for the read-back.
  sluice::render::RenderTarget target() const {
    const VkImageLayout read_back = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
    sluice::render::RenderTarget t = sluice::render::render_target(
        kWidth, kHeight, {*color_.image, *color_.view, VkFormat(kColor), VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, read_back},
        {*depth_.image, *depth_.view, VkFormat(kDepth), VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL, read_back});
    t.background = false;
    return t;
  }

  // Without the fluid, the host moves its images to the read-back layout itself.
  void to_transfer_source(vk::CommandBuffer cmd) const {
    using S = vk::PipelineStageFlagBits2;
    using A = vk::AccessFlagBits2;
    const std::array to_read{
        vk::ImageMemoryBarrier2(S::eColorAttachmentOutput, A::eColorAttachmentWrite, S::eAllCommands, A::eMemoryRead,
                                vk::ImageLayout::eColorAttachmentOptimal, vk::ImageLayout::eTransferSrcOptimal, VK_QUEUE_FAMILY_IGNORED,
                                VK_QUEUE_FAMILY_IGNORED, *color_.image,
                                vk::ImageSubresourceRange(vk::ImageAspectFlagBits::eColor, 0, 1, 0, 1)),
        vk::ImageMemoryBarrier2(S::eLateFragmentTests, A::eDepthStencilAttachmentWrite, S::eAllCommands, A::eMemoryRead,
                                vk::ImageLayout::eDepthStencilAttachmentOptimal, vk::ImageLayout::eTransferSrcOptimal,
                                VK_QUEUE_FAMILY_IGNORED, VK_QUEUE_FAMILY_IGNORED, *depth_.image,
                                vk::ImageSubresourceRange(vk::ImageAspectFlagBits::eDepth, 0, 1, 0, 1))};
    cmd.pipelineBarrier2(vk::DependencyInfo({}, {}, {}, to_read));
  }

  // The queue is the one sluice was handed, which its relay may share:
  // StreamOptions::queue_lock is HostTakesIt, so every submission holds
  // the context's lock.
  void submit(const vk::SubmitInfo2& info, vk::Fence fence) {
    const std::lock_guard lock(queue_lock_);
    d_.queue.submit2(info, fence);
  }

  const Device& d_;
  std::mutex& queue_lock_;
  Image color_, depth_;
  vk::raii::PipelineLayout layout_{nullptr};
  vk::raii::Pipeline pipeline_{nullptr};
  vk::raii::CommandPool pool_{nullptr};
  std::vector<Slot> slots_;
  size_t next_ = 0;
  Matrix view_{}, projection_{};
  BoxPush floor_{}, box_{};
};

// 6. --check: the host's geometry alone and the fluid alone, against both
// drawn together. Where both drew, the nearer one must show: the box in
// front hides the fluid, the fluid in front of the box hides it.
bool check_occlusion(HostScene& scene, sluice::stream::Stream& stream, const std::vector<uint32_t>& both,
                     const std::vector<float>& both_z) {
  std::vector<uint32_t> host_only, fluid_only;
  std::vector<float> host_z, fluid_z;
  scene.draw(true, nullptr);
  scene.read_back(host_only, host_z);
  scene.draw(false, &stream);
  scene.read_back(fluid_only, fluid_z);
  size_t host_in_front = 0, fluid_in_front = 0, wrong = 0, fluid_pixels = 0;
  for (size_t i = 0; i < both.size(); ++i) {
    const bool has_host = host_z[i] < 1.0f, has_fluid = fluid_z[i] < 1.0f;
    fluid_pixels += has_fluid;
    if (!has_host || !has_fluid || host_z[i] == fluid_z[i]) continue;
    if (fluid_z[i] < host_z[i]) {
      ++fluid_in_front;
      wrong += both[i] != fluid_only[i] || both_z[i] != fluid_z[i];
    } else {
      ++host_in_front;
      wrong += both[i] != host_only[i] || both_z[i] != host_z[i];
    }
  }
  std::printf("occlusion: %zu fluid pixels; where both drew, the host's geometry is in front at %zu pixels and the fluid at "
              "%zu; %zu pixels show the wrong one\n",
              fluid_pixels, host_in_front, fluid_in_front, wrong);
  const bool ok = host_in_front > 200 && fluid_in_front > 200 && wrong == 0;
  std::printf("check %s\n", ok ? "passed" : "FAILED");
  return ok;
}

}  // namespace

int main(int argc, char** argv) try {
  int status = 0;
  const std::optional<Args> args = parse_args(argc, argv, status);
  if (!args) return status;
  vk::raii::Context loader;
  const Instance instance = make_instance(loader);       // 1.
  const Device device = make_device(instance.instance);  // 2.

  // 3. sluice on the host's handles: a stream of the file's frames, or of
  // frames the host computes (pushed from its memory, recorded when asked).
  sluice::render::Context context(sluice::render::HostVulkan{
      {*instance.instance, *device.physical, *device.device, device.family, *device.queue}, device.memory_budget});
  // The host submits under context.queue_lock() (HostScene::submit), so
  // frames the GPU decodes may be relayed to device memory as they are read
  // even where the relay shares the host's one queue (relay_queue_shared()).
  const sluice::stream::StreamOptions options{
      .renderer = {.frames_in_flight = kFramesInFlight},
      .queue_lock = sluice::stream::QueueLock::HostTakesIt,
      .motion = sluice::stream::ViewMotion::Fixed};  // the host's camera stays put
  sluice::stream::LiveOptions live;
  live.particle_spacing = 0.02f;
  live.frame_rate = 30;
  live.record = args->record;
  live.ids = false;  // the host keeps its particle order: LOD values follow the index
  std::unique_ptr<sluice::stream::Stream> stream =
      args->live ? std::make_unique<sluice::stream::Stream>(context, sluice::render::Bounds{{0, 0, 0}, {2, 1, 1}}, live,
                                                            options)
                 : std::make_unique<sluice::stream::Stream>(context, args->file, options);
  sluice::render::FluidOptions look = stream->fluid();
  look.ground = false;  // the host draws its own floor
  stream->set_look(look, {});

  // 4. The host's images, pipeline, camera (framing the data) and frames in flight.
  const sluice::render::Bounds data = stream->scene().bounds;
  HostScene scene(device, {{data.min.x, data.min.y, data.min.z}, {data.max.x, data.max.y, data.max.z}}, context.queue_lock());

  // 5. The frame loop: the views, the frame due, the host's drawing and sluice's.
  if (!args->live) stream->player().play();
  for (int f = 0; f < args->frames; ++f) {
    if (args->live) stream->push({simulate(f, live.particle_spacing), {}, {}, f / 30.0});  // a frame from the host's memory
    const sluice::render::View camera = scene.view();
    stream->set_views({&camera, 1});
    stream->update();
    scene.draw(true, stream.get());
  }
  if (args->live) {
    stream->finish();
    std::printf("pushed %d live frames%s%s\n", args->frames, args->record.empty() ? "" : ", recorded to ", args->record.c_str());
  } else {
    stream->player().pause();  // on the frame due
    stream->player().wait_for_due();
  }
  // The checks below compare three draws of one frame: drawn once its copy is done.
  stream->renderer().wait_upload(stream->update().ticket);
  scene.draw(true, stream.get());

  // 6. Output, and with --check the occlusion test.
  std::vector<uint32_t> both;
  std::vector<float> both_z;
  scene.read_back(both, both_z);
  sluice::render::Image png{kWidth, kHeight, std::vector<uint8_t>(both.size() * 4)};
  std::memcpy(png.rgba.data(), both.data(), png.rgba.size());
  sluice::render::write_png(args->out, png);
  std::printf("wrote %s (%ux%u, %d frames, %d validation messages)\n", args->out.c_str(), kWidth, kHeight, args->frames,
              validation_messages);
  const bool checked = !args->check || check_occlusion(scene, *stream, both, both_z);
  return checked && validation_messages == 0 ? 0 : 1;
} catch (const std::exception& e) {
  std::fprintf(stderr, "host_vulkan: %s\n", e.what());
  return 1;
}
