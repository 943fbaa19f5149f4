// The frame loop: wait, begin, locate the eyes, acquire the images, hand a
// command buffer out; submit, release, end with the projection (and depth)
// layer.
#include <stdexcept>

#include "session_impl.h"
#include "sluice/error.h"

namespace sluice::xr {
namespace {

XrPosef to_xr(const Pose& p) {
  XrPosef x;
  x.orientation = {p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w};
  x.position = {p.position.x, p.position.y, p.position.z};
  return x;
}

}  // namespace

Frame Session::begin_frame() {
  Impl& s = *impl_;
  if (!s.running) throw Error("begin_frame: the session is not running (call poll() until running())");
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
    if (vkQueueSubmit2(s.graphics_queue, 1, &submit, s.fences[slot]) != VK_SUCCESS) throw Error("vkQueueSubmit2 failed");
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
