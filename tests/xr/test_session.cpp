// Sessions against a real OpenXR runtime: Monado (scripts/monado.sh), its
// in-process runtime with the null compositor and the simulated headset,
// on lavapipe. CTest sets XR_RUNTIME_JSON and the runtime's variables.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <vector>

#include "sluice/render/renderer.h"
#include "sluice/render/synthetic.h"
#include "sluice/xr/placement.h"
#include "sluice/xr/session.h"

namespace sluice::xr {
namespace {

// A host-visible buffer on the session's device that eye images are copied into.
class Readback {
 public:
  Readback(render::Context& context, VkDeviceSize bytes) : device_(context.vulkan().device) {
    VkBufferCreateInfo b{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    b.size = bytes;
    b.usage = VK_BUFFER_USAGE_TRANSFER_DST_BIT;
    vkCreateBuffer(device_, &b, nullptr, &buffer_);
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(device_, buffer_, &req);
    VkPhysicalDeviceMemoryProperties props;
    vkGetPhysicalDeviceMemoryProperties(context.vulkan().physical_device, &props);
    const VkMemoryPropertyFlags want = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
    VkMemoryAllocateInfo a{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    a.allocationSize = req.size;
    for (uint32_t i = 0; i < props.memoryTypeCount; ++i) {
      if ((req.memoryTypeBits & (1u << i)) && (props.memoryTypes[i].propertyFlags & want) == want) {
        a.memoryTypeIndex = i;
        break;
      }
    }
    vkAllocateMemory(device_, &a, nullptr, &memory_);
    vkBindBufferMemory(device_, buffer_, memory_, 0);
    vkMapMemory(device_, memory_, 0, bytes, 0, &mapped_);
  }
  ~Readback() {
    vkDestroyBuffer(device_, buffer_, nullptr);
    vkFreeMemory(device_, memory_, nullptr);
  }
  // Records a copy of `target`'s colour layer (in COLOR_ATTACHMENT_OPTIMAL,
  // left there) to byte `offset`.
  void copy(VkCommandBuffer cmd, const render::RenderTarget& target, VkDeviceSize offset) const {
    VkImageMemoryBarrier2 to{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2};
    to.srcStageMask = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT;
    to.srcAccessMask = VK_ACCESS_2_MEMORY_WRITE_BIT;
    to.dstStageMask = VK_PIPELINE_STAGE_2_COPY_BIT;
    to.dstAccessMask = VK_ACCESS_2_TRANSFER_READ_BIT;
    to.oldLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
    to.newLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
    to.srcQueueFamilyIndex = to.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    to.image = target.color_image;
    to.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, target.base_layer, 1};
    VkDependencyInfo dep{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
    dep.imageMemoryBarrierCount = 1;
    dep.pImageMemoryBarriers = &to;
    vkCmdPipelineBarrier2(cmd, &dep);
    VkBufferImageCopy region{};
    region.bufferOffset = offset;
    region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, target.base_layer, 1};
    region.imageExtent = {target.width, target.height, 1};
    vkCmdCopyImageToBuffer(cmd, target.color_image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, buffer_, 1, &region);
    VkImageMemoryBarrier2 back = to;
    back.srcStageMask = VK_PIPELINE_STAGE_2_COPY_BIT;
    back.srcAccessMask = 0;
    back.dstStageMask = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT;
    back.dstAccessMask = VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT;
    back.oldLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
    back.newLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
    dep.pImageMemoryBarriers = &back;
    vkCmdPipelineBarrier2(cmd, &dep);
    VkMemoryBarrier2 host{VK_STRUCTURE_TYPE_MEMORY_BARRIER_2};
    host.srcStageMask = VK_PIPELINE_STAGE_2_COPY_BIT;
    host.srcAccessMask = VK_ACCESS_2_TRANSFER_WRITE_BIT;
    host.dstStageMask = VK_PIPELINE_STAGE_2_HOST_BIT;
    host.dstAccessMask = VK_ACCESS_2_HOST_READ_BIT;
    VkDependencyInfo host_dep{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
    host_dep.memoryBarrierCount = 1;
    host_dep.pMemoryBarriers = &host;
    vkCmdPipelineBarrier2(cmd, &host_dep);
  }
  const uint8_t* bytes() const { return static_cast<const uint8_t*>(mapped_); }

 private:
  VkDevice device_;
  VkBuffer buffer_ = VK_NULL_HANDLE;
  VkDeviceMemory memory_ = VK_NULL_HANDLE;
  void* mapped_ = nullptr;
};

// A ball of particles, radius 1 data unit.
std::vector<float> ball(float spacing) {
  std::vector<float> xyz;
  const int n = int(std::lround(1.0f / spacing));
  for (int i = -n; i <= n; ++i) {
    for (int j = -n; j <= n; ++j) {
      for (int k = -n; k <= n; ++k) {
        if (i * i + j * j + k * k <= n * n) xyz.insert(xyz.end(), {float(i) * spacing, float(j) * spacing, float(k) * spacing});
      }
    }
  }
  return xyz;
}

// Where a room point lands in an eye's image, pixels (pinhole through its pose and fov).
std::array<double, 2> pixel_of(const Eye& eye, Vec3 room, uint32_t width, uint32_t height) {
  const Vec3 e = transform(inverse(eye.pose), room);
  const double x = double(e.x) / -double(e.z), y = double(e.y) / -double(e.z);
  const double l = std::tan(double(eye.fov.left)), r = std::tan(double(eye.fov.right));
  const double u = std::tan(double(eye.fov.up)), d = std::tan(double(eye.fov.down));
  return {(x - l) / (r - l) * width, (u - y) / (u - d) * height};
}

std::array<double, 2> fluid_centroid(const uint8_t* rgba, uint32_t width, uint32_t height) {
  double sx = 0, sy = 0, n = 0;
  for (uint32_t y = 0; y < height; ++y) {
    for (uint32_t x = 0; x < width; ++x) {
      if (rgba[(size_t(y) * width + x) * 4 + 3] == 0) continue;
      sx += x + 0.5;
      sy += y + 0.5;
      n += 1;
    }
  }
  return n > 0 ? std::array<double, 2>{sx / n, sy / n} : std::array<double, 2>{-1, -1};
}

TEST(Monado, SessionReachesFocusedDrawsBothEyesWithDepthAndExitsCleanly) {
  SessionOptions so;
  so.validation = true;
  so.quiet_validation = true;
  so.readable_images = true;
  Session session(so);
  const SystemInfo& sys = session.system();
  std::printf("runtime %s, system %s, %ux%u per eye, %s swapchain, depth %s, %s space\n", sys.runtime.c_str(),
              sys.system.c_str(), sys.eye_width[0], sys.eye_height[0], sys.array_swapchain ? "array" : "per-eye",
              sys.depth_layer ? "yes" : "no", sys.floor == Floor::Stage ? "STAGE" : "LOCAL");
  ASSERT_GT(sys.eye_width[0], 0u);
  EXPECT_TRUE(sys.depth_layer) << "Monado offers XR_KHR_composition_layer_depth; the depth path must be exercised";

  const std::vector<float> xyz = ball(0.1f);
  const render::SceneInfo scene = render::scene_for_points(xyz, 0.1f);
  render::RendererOptions ro;
  ro.frames_in_flight = Session::kRecordsInFlight;
  render::Renderer renderer(session.context(), scene, ro);
  render::upload_points(renderer, xyz, std::vector<uint16_t>(xyz.size() / 3, 0));
  const uint32_t w = sys.eye_width[0], h = sys.eye_height[0];
  Readback readback(session.context(), VkDeviceSize(w) * h * 4 * 2);

  constexpr uint64_t kFrames = 100;
  constexpr uint64_t kChecked = 60;  // the frame whose pictures are read back
  uint64_t drawn = 0;
  bool exit_asked = false;
  std::array<Eye, 2> checked_eyes;
  std::array<uint64_t, 2> tracked_hands{};  // frames with the hand's grip pose located
  Vec3 ball_centre;
  const auto start = std::chrono::steady_clock::now();
  while (session.poll()) {
    ASSERT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(120)) << "the session never ended";
    if (!session.running()) continue;
    Frame frame = session.begin_frame();
    render::FrameSync sync;
    if (frame.render) {
      // The ball 1.5 m in front of the point between the eyes, 0.2 m across.
      const Vec3 mid = (frame.eyes[0].pose.position + frame.eyes[1].pose.position) * 0.5f;
      const Vec3 ahead = rotate(frame.eyes[0].pose.orientation, {0, 0, -1.5f});
      Placement placement;
      placement.scale = 0.1f;
      placement.pose.position = mid + ahead;
      std::array<render::View, 2> views;
      for (size_t e = 0; e < 2; ++e) {
        views[e] = eye_view(frame.eyes[e].pose, frame.eyes[e].fov, placement, so.near, so.far, frame.eyes[e].viewport);
      }
      // Both eyes in one pass (Monado's eyes share a size: an array swapchain).
      ASSERT_TRUE(frame.stereo);
      frame.stereo_target.background = false;  // only the fluid: alpha says where it is
      sync = renderer.record(frame.command_buffer, frame.stereo_target, views, {}, {});
      if (drawn == kChecked) {
        for (size_t e = 0; e < 2; ++e) readback.copy(frame.command_buffer, frame.eyes[e].target, VkDeviceSize(w) * h * 4 * e);
      }
      if (drawn == kChecked) {
        checked_eyes = frame.eyes;
        ball_centre = placement.pose.position;
      }
    }
    session.end_frame(frame, sync);
    if (frame.render) ++drawn;
    for (size_t hand = 0; hand < 2; ++hand) tracked_hands[hand] += frame.actions.hands[hand].pose_valid ? 1 : 0;
    if (drawn >= kFrames && !exit_asked) {
      session.request_exit();
      exit_asked = true;
    }
  }
  vkDeviceWaitIdle(session.context().vulkan().device);
  const SessionCounters n = session.counters();
  for (State s : {State::Ready, State::Synchronized, State::Visible, State::Focused, State::Stopping, State::Exiting}) {
    EXPECT_TRUE(n.states_seen & (1u << unsigned(s))) << "never reached " << to_string(s);
  }
  EXPECT_GE(n.projection_layers, kFrames);
  EXPECT_EQ(n.depth_layers, n.projection_layers);
  // The simulated controllers (SIMULATED_LEFT/RIGHT=simple) through the
  // khr/simple_controller bindings: the grip poses are located while focused.
  std::printf("frames with a tracked hand: left %llu, right %llu\n", (unsigned long long)tracked_hands[0],
              (unsigned long long)tracked_hands[1]);
  EXPECT_GT(tracked_hands[0], kFrames / 2);
  EXPECT_GT(tracked_hands[1], kFrames / 2);
  EXPECT_EQ(session.validation_errors(), 0u) << [&] {
    std::string all;
    for (const std::string& m : session.validation_messages()) all += m + "\n";
    return all;
  }();

  // Each eye shows the ball where its own pose and field of view put it; the
  // parallax between them is the runtime's eye separation at 1.5 m.
  std::array<std::array<double, 2>, 2> seen{}, expected{};
  for (size_t e = 0; e < 2; ++e) {
    seen[e] = fluid_centroid(readback.bytes() + size_t(w) * h * 4 * e, w, h);
    expected[e] = pixel_of(checked_eyes[e], ball_centre, w, h);
    std::printf("eye %zu: ball at (%.2f, %.2f) px, expected (%.2f, %.2f)\n", e, seen[e][0], seen[e][1], expected[e][0], expected[e][1]);
    ASSERT_GE(seen[e][0], 0) << "eye " << e << " shows no fluid";
    EXPECT_NEAR(seen[e][0], expected[e][0], 0.5);
    EXPECT_NEAR(seen[e][1], expected[e][1], 0.5);
  }
  const double separation = double(render::length(checked_eyes[0].pose.position - checked_eyes[1].pose.position));
  std::printf("eye separation %.4f m, disparity %.3f px (expected %.3f)\n", separation, seen[0][0] - seen[1][0],
              expected[0][0] - expected[1][0]);
  EXPECT_GT(separation, 0.04);
  EXPECT_NEAR(seen[0][0] - seen[1][0], expected[0][0] - expected[1][0], 0.5);
}

}  // namespace
}  // namespace sluice::xr
