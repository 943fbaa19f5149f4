// The screen-space targets of one view size. Re-creating them never waits:
// the old ones are retired until the frames in flight that use them are done,
// and the new ones are initialized by the next frame's commands.
#include "renderer_state.h"

namespace sluice::render {

void detail::RendererImpl::ensure_targets(uint32_t width, uint32_t height, bool half, uint32_t layers) {
  Targets& t = targets;
  if (t.generation > 0 && t.size == vk::Extent2D(width, height) && t.half_thickness == half && t.layers == layers) return;
  using U = vk::ImageUsageFlagBits;
  Targets next;
  next.generation = t.generation + 1;
  next.size = vk::Extent2D(width, height);
  next.thick_size = half ? vk::Extent2D((width + 1) / 2, (height + 1) / 2) : next.size;
  next.half_thickness = half;
  next.layers = layers;
  // Every target is an array of one layer per eye, seen through an array
  // view (the shaders index the layer by eye).
  const auto texture = [&](vk::Extent2D e, vk::Format f, vk::ImageUsageFlags u) { return create_texture(ctx, e, f, u, layers, true); };
  next.thick_format = thick_format;
  const auto cleared = U::eTransferDst;  // cleared at their first frame
  next.depth_hw = texture(next.size, vk::Format::eD32Sfloat, U::eDepthStencilAttachment);
  next.depth_raw = texture(next.size, vk::Format::eR32Sfloat, U::eColorAttachment | U::eStorage | U::eTransferSrc | cleared);
  next.depth_a = texture(next.size, vk::Format::eR32Sfloat, U::eStorage | U::eTransferSrc | cleared);
  next.depth_b = texture(next.size, vk::Format::eR32Sfloat, U::eStorage | cleared);
  next.thick_raw = texture(next.thick_size, thick_format,
                                  U::eColorAttachment | U::eStorage | U::eSampled | U::eTransferSrc | cleared);
  next.thick_a = texture(next.thick_size, thick_format, U::eStorage | U::eSampled | cleared);
  next.thick_b = texture(next.thick_size, thick_format, U::eStorage | cleared);
  next.depth_u = texture(next.size, vk::Format::eR32Uint, U::eStorage | cleared);
  next.thick_u = texture(next.thick_size, vk::Format::eR32Uint, U::eStorage | cleared);
  next.thick_attr_u = texture(next.thick_size, vk::Format::eR32Uint, U::eStorage | cleared);
  next.color = texture(next.size, vk::Format::eR8G8B8A8Unorm, U::eStorage | U::eTransferSrc | cleared);
  // Eye normals and depth for tests; a 1x1 stand-in keeps the descriptor valid otherwise.
  next.aux = texture(options.debug_surfaces ? next.size : vk::Extent2D(1, 1), vk::Format::eR32G32B32A32Sfloat,
                            U::eStorage | U::eTransferSrc | cleared);
  retire(std::move(t));
  t = std::move(next);
}

}  // namespace sluice::render
