// Reading a renderer's intermediate images back (inspection.h).
#include "sluice/render/inspection.h"

#include <cmath>
#include <cstdint>
#include <cstring>

#include "half.h"
#include "renderer_state.h"
#include "sluice/render/renderer.h"
#include "sluice/error.h"

namespace sluice::render {

std::vector<float> read_surface(Renderer& renderer) {
  detail::RendererImpl& r = renderer_impl(renderer);
  if (!r.options.debug_surfaces) throw Error("read_surface: the renderer was made without debug_surfaces");
  const std::vector<std::byte> bytes = r.read_texture(r.targets.aux, 16);
  std::vector<float> out(bytes.size() / 4);
  std::memcpy(out.data(), bytes.data(), bytes.size());
  return out;
}

std::vector<float> read_raw_thickness(Renderer& renderer) {
  detail::RendererImpl& r = renderer_impl(renderer);
  const Texture& t = r.targets.thick_raw;
  const bool half = r.targets.thick_format == vk::Format::eR16G16Sfloat;
  const std::vector<std::byte> bytes = r.read_texture(t, half ? 4 : 8);
  std::vector<float> out(size_t(t.extent.width) * t.extent.height);
  for (size_t i = 0; i < out.size(); ++i) {
    if (half) {
      uint16_t h;
      std::memcpy(&h, bytes.data() + 4 * i, 2);
      out[i] = half_to_float(h);
    } else {
      std::memcpy(&out[i], bytes.data() + 8 * i, 4);
    }
  }
  return out;
}

std::vector<float> read_raw_depth(Renderer& renderer) {
  detail::RendererImpl& r = renderer_impl(renderer);
  const std::vector<std::byte> bytes = r.read_texture(r.targets.depth_raw, 4);
  std::vector<float> out(bytes.size() / 4);
  std::memcpy(out.data(), bytes.data(), bytes.size());
  return out;
}

}  // namespace sluice::render
