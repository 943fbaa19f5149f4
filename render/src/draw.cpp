#include "sluice/render/draw.h"

#include <string>

namespace sluice::render {

std::string describe(const FrameStats::Classification& c) {
  if (!c.ran) return "";
  const auto count = [](uint64_t v) {
    std::string digits = std::to_string(v), out;
    for (size_t i = 0; i < digits.size(); ++i) {
      if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
      out += digits[i];
    }
    return out;
  };
  if (!c.grid_fits) {
    return "drawn whole: its voxel grid (" + std::to_string(c.cells[0]) + " x " + std::to_string(c.cells[1]) + " x " +
           std::to_string(c.cells[2]) + ") has 2^32 cells or more";
  }
  if (!c.narrowed) return "drawn whole: " + count(c.blobs) + " blobs, room for " + count(c.blob_room);
  return "classified on the GPU: " + count(c.surface) + " surface + " + count(c.blobs) + " blobs";
}

RenderTarget render_target(uint32_t width, uint32_t height, const TargetImage& color, const TargetImage& depth) {
  RenderTarget t;
  t.width = width;
  t.height = height;
  t.color_image = color.image;
  t.color_view = color.view;
  t.color_format = color.format;
  t.color_layout_before = color.before;
  t.color_layout_after = color.after;
  if (depth.image == VK_NULL_HANDLE) return t;
  t.depth_image = depth.image;
  t.depth_view = depth.view;
  t.depth_format = depth.format;
  t.depth_layout_before = depth.before;
  t.depth_layout_after = depth.after;
  return t;
}

}  // namespace sluice::render
