// The eyes' colour and depth swapchains, and a 2D view of each layer of each
// image (the renderer draws one eye's layer at a time).
#include <algorithm>
#include <stdexcept>

#include "session_impl.h"
#include "sluice/error.h"

namespace sluice::xr {
namespace {

// The first of `wanted` the runtime offers, else VK_FORMAT_UNDEFINED.
VkFormat pick(const std::vector<int64_t>& offered, std::initializer_list<VkFormat> wanted) {
  for (VkFormat f : wanted) {
    if (std::find(offered.begin(), offered.end(), int64_t(f)) != offered.end()) return f;
  }
  return VK_FORMAT_UNDEFINED;
}

// A view of `count` layers from `first` (2D for one layer, else 2D_ARRAY);
// depth formats with stencil see both aspects.
VkImageView make_view(VkDevice device, VkImage image, VkFormat format, bool depth, uint32_t first, uint32_t count) {
  VkImageViewCreateInfo v{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
  v.image = image;
  v.viewType = count > 1 ? VK_IMAGE_VIEW_TYPE_2D_ARRAY : VK_IMAGE_VIEW_TYPE_2D;
  v.format = format;
  VkImageAspectFlags aspect = depth ? VK_IMAGE_ASPECT_DEPTH_BIT : VK_IMAGE_ASPECT_COLOR_BIT;
  if (format == VK_FORMAT_D24_UNORM_S8_UINT || format == VK_FORMAT_D32_SFLOAT_S8_UINT) aspect |= VK_IMAGE_ASPECT_STENCIL_BIT;
  v.subresourceRange = {aspect, 0, 1, first, count};
  VkImageView view = VK_NULL_HANDLE;
  if (vkCreateImageView(device, &v, nullptr, &view) != VK_SUCCESS) throw Error("vkCreateImageView failed");
  return view;
}

}  // namespace

void detail::SessionImpl::create_swapchains() {
  uint32_t n = 0;
  check(xrEnumerateSwapchainFormats(session, 0, &n, nullptr), instance, "xrEnumerateSwapchainFormats");
  std::vector<int64_t> formats(n);
  check(xrEnumerateSwapchainFormats(session, n, &n, formats.data()), instance, "xrEnumerateSwapchainFormats");
  // sRGB: the compositor expects display-encoded values, which the hardware
  // writes from the renderer's linear ones.
  info.color_format = pick(formats, {VK_FORMAT_R8G8B8A8_SRGB, VK_FORMAT_B8G8R8A8_SRGB, VK_FORMAT_R8G8B8A8_UNORM,
                                     VK_FORMAT_B8G8R8A8_UNORM});
  if (info.color_format == VK_FORMAT_UNDEFINED) throw Error("the OpenXR runtime offers no 8-bit RGBA swapchain format");
  info.depth_format = info.depth_layer ? pick(formats, {VK_FORMAT_D32_SFLOAT, VK_FORMAT_D24_UNORM_S8_UINT, VK_FORMAT_D16_UNORM,
                                                        VK_FORMAT_D32_SFLOAT_S8_UINT})
                                       : VK_FORMAT_UNDEFINED;
  if (info.depth_format == VK_FORMAT_UNDEFINED) info.depth_layer = false;
  info.array_swapchain = info.eye_width[0] == info.eye_width[1] && info.eye_height[0] == info.eye_height[1];

  const auto make = [&](VkFormat format, XrSwapchainUsageFlags usage, uint32_t width, uint32_t height, uint32_t layers) {
    SwapchainImages s;
    XrSwapchainCreateInfo create{XR_TYPE_SWAPCHAIN_CREATE_INFO};
    create.usageFlags = usage;
    create.format = format;
    create.sampleCount = 1;
    create.width = width;
    create.height = height;
    create.faceCount = 1;
    create.arraySize = layers;
    create.mipCount = 1;
    check(xrCreateSwapchain(session, &create, &s.handle), instance, "xrCreateSwapchain");
    s.width = width;
    s.height = height;
    s.layers = layers;
    s.format = format;
    uint32_t count = 0;
    check(xrEnumerateSwapchainImages(s.handle, 0, &count, nullptr), instance, "xrEnumerateSwapchainImages");
    std::vector<XrSwapchainImageVulkan2KHR> images(count, {XR_TYPE_SWAPCHAIN_IMAGE_VULKAN2_KHR});
    check(xrEnumerateSwapchainImages(s.handle, count, &count, reinterpret_cast<XrSwapchainImageBaseHeader*>(images.data())),
          instance, "xrEnumerateSwapchainImages");
    const bool is_depth = usage & XR_SWAPCHAIN_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT;
    for (const auto& image : images) {
      s.images.push_back(image.image);
      std::array<VkImageView, 2> views{};
      for (uint32_t layer = 0; layer < layers; ++layer) views[layer] = make_view(device, image.image, format, is_depth, layer, 1);
      s.views.push_back(views);
      if (layers > 1) s.array_views.push_back(make_view(device, image.image, format, is_depth, 0, layers));
    }
    return s;
  };
  const XrSwapchainUsageFlags color_usage =
      XR_SWAPCHAIN_USAGE_COLOR_ATTACHMENT_BIT | (options.readable_images ? XR_SWAPCHAIN_USAGE_TRANSFER_SRC_BIT : 0);
  const XrSwapchainUsageFlags depth_usage = XR_SWAPCHAIN_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT;
  if (info.array_swapchain) {
    color.push_back(make(info.color_format, color_usage, info.eye_width[0], info.eye_height[0], 2));
    if (info.depth_layer) depth.push_back(make(info.depth_format, depth_usage, info.eye_width[0], info.eye_height[0], 2));
  } else {
    for (size_t e = 0; e < 2; ++e) {
      color.push_back(make(info.color_format, color_usage, info.eye_width[e], info.eye_height[e], 1));
      if (info.depth_layer) depth.push_back(make(info.depth_format, depth_usage, info.eye_width[e], info.eye_height[e], 1));
    }
  }
}

void detail::SessionImpl::destroy_swapchains() {
  for (auto* list : {&color, &depth}) {
    for (SwapchainImages& s : *list) {
      for (const auto& views : s.views) {
        for (VkImageView v : views) {
          if (v) vkDestroyImageView(device, v, nullptr);
        }
      }
      for (VkImageView v : s.array_views) vkDestroyImageView(device, v, nullptr);
      if (s.handle) xrDestroySwapchain(s.handle);
    }
    list->clear();
  }
}

void detail::SessionImpl::acquire(SwapchainImages& s) {
  XrSwapchainImageAcquireInfo acquire_info{XR_TYPE_SWAPCHAIN_IMAGE_ACQUIRE_INFO};
  check(xrAcquireSwapchainImage(s.handle, &acquire_info, &s.acquired), instance, "xrAcquireSwapchainImage");
  XrSwapchainImageWaitInfo wait{XR_TYPE_SWAPCHAIN_IMAGE_WAIT_INFO};
  wait.timeout = XR_INFINITE_DURATION;
  check(xrWaitSwapchainImage(s.handle, &wait), instance, "xrWaitSwapchainImage");
}

void detail::SessionImpl::release(SwapchainImages& s) {
  if (s.acquired == UINT32_MAX) return;
  XrSwapchainImageReleaseInfo release_info{XR_TYPE_SWAPCHAIN_IMAGE_RELEASE_INFO};
  check(xrReleaseSwapchainImage(s.handle, &release_info), instance, "xrReleaseSwapchainImage");
  s.acquired = UINT32_MAX;
}

}  // namespace sluice::xr
