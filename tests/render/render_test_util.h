// Shared by the render tests: one Vulkan context per test binary, with the
// validation layer on; every test ends by checking that it caused no
// validation error (skipped, with a note, where the layer is not installed).
#pragma once

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <memory>

#include "sluice/render/band_classifier.h"
#include "sluice/render/context.h"
#include "sluice/render/inspection.h"
#include "sluice/render/offscreen.h"
#include "sluice/render/load.h"
#include "sluice/render/renderer.h"
#include "sluice/render/staging_allocator.h"
#include "sluice/runtime/pipeline.h"

namespace sluice::render::testing {

inline Context& context() {
  static std::unique_ptr<Context> ctx = [] {
    ContextOptions o;
    o.validation = true;
    o.quiet_validation = true;
    auto c = std::make_unique<Context>(o);
    std::fprintf(stderr, "render tests on %s (%s), validation %s\n", c->device().name.c_str(), c->device().type.c_str(),
                 c->validation_active() ? "on" : "NOT AVAILABLE (VK_LAYER_KHRONOS_validation missing)");
    return c;
  }();
  return *ctx;
}

// One GPU narrow-band classifier per test binary (its pipelines are built once).
inline BandClassifier& band_classifier() {
  static BandClassifier c(context());
  return c;
}

// Checks that no validation error happened since construction.
class ValidationGuard {
 public:
  ValidationGuard() : before_(context().validation_errors()) {}
  ~ValidationGuard() {
    Context& c = context();
    if (!c.validation_active()) return;
    const uint64_t errors = c.validation_errors() - before_;
    EXPECT_EQ(errors, 0u) << "Vulkan validation errors; first messages:\n" << [&] {
      std::string all;
      for (const std::string& m : c.validation_messages()) all += m + "\n";
      return all;
    }();
  }

 private:
  uint64_t before_;
};

// A camera at `eye` looking at `target`, z up, near plane 0.05.
inline Camera camera_at(Vec3 eye, Vec3 target, float fov = 40) {
  Camera c;
  c.eye = eye;
  c.target = target;
  c.up = {0, 0, 1};
  c.fov_deg = fov;
  c.near = 0.05f;
  return c;
}

// Eye-space direction through the centre of pixel (x, y) of a width x height
// image (z = -1), as the shaders compute it, in double.
inline std::array<double, 3> pixel_ray(const Camera& cam, uint32_t x, uint32_t y, uint32_t width, uint32_t height) {
  const double t = std::tan(double(cam.fov_deg) * M_PI / 360.0);
  const double aspect = double(width) / height;
  const double nx = (x + 0.5) / width * 2 - 1, ny = (y + 0.5) / height * 2 - 1;
  return {nx * t * aspect, -ny * t, -1.0};
}

// A camera `distance` in front of the origin on -y, looking along +y, z up,
// 40 degrees, near plane 0.05.
inline Camera camera_looking_along_y(float distance) {
  Camera c;
  c.eye = {0, -distance, 0};
  c.target = {0, 0, 0};
  c.up = {0, 0, 1};
  c.fov_deg = 40;
  c.near = 0.05f;
  return c;
}

// A Renderer drawing into an OffscreenTarget of its own, synchronously: the
// shape most tests want (one frame in, one image out). Uploads are waited for,
// so decoded buffers may be reused as soon as a commit returns.
class OffscreenRenderer {
 public:
  OffscreenRenderer(Context& c, const SceneInfo& scene, uint32_t width, uint32_t height)
      : OffscreenRenderer(c, scene, width, height, debug_options()) {}
  OffscreenRenderer(Context& c, const SceneInfo& scene, uint32_t width, uint32_t height, const RendererOptions& options)
      : renderer(c, scene, options), target(c, width, height) {}
  FrameStats render(const Camera& camera, const FluidOptions& options, const LodOptions& lod) {
    return target.render(renderer, camera, options, lod);
  }
  std::vector<uint8_t> read_rgba8() { return target.read_rgba8(); }
  std::vector<float> read_surface() { return sluice::render::read_surface(renderer); }
  std::vector<float> read_raw_depth() { return sluice::render::read_raw_depth(renderer); }
  void load_frame(const io::ContainerReader& reader, uint64_t frame, int color_attribute) {
    sluice::render::load_frame(renderer, reader, frame, color_attribute);
  }
  void commit(const runtime::FrameHandle& frame, int color_attribute, const StagingAllocator* from) {
    renderer.wait_upload(renderer.commit(render::frame_upload(frame, color_attribute, from)));
  }
  FrameStaging stage_frame(uint64_t particles, uint32_t chunks) { return renderer.stage_frame(particles, chunks); }
  void commit_frame() { renderer.wait_upload(renderer.commit_frame()); }
  void set_environment(const Image& image) { renderer.set_environment(image); }
  operator Renderer&() { return renderer; }  // NOLINT: tests hand it to upload helpers
  uint32_t width() const { return target.width(); }
  uint32_t height() const { return target.height(); }

  Renderer renderer;
  OffscreenTarget target;

  static RendererOptions debug_options() {
    RendererOptions o;
    o.debug_surfaces = true;
    return o;
  }
};

}  // namespace sluice::render::testing
