// `sluice bench layers`: surface + blobs against all particles, per view.
#include "sluice/bench/layers_bench.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "sluice/io/reader.h"
#include "sluice/render/context.h"
#include "sluice/render/image_io.h"
#include "sluice/render/offscreen.h"
#include "sluice/render/renderer.h"
#include "sluice/render/load.h"
#include "sluice/bench/table.h"

namespace sluice::bench {
namespace {

using render::Bounds;
using render::Camera;
using render::Vec3;

struct NamedView {
  std::string name;
  Camera camera;
};

Bounds bounds_of(const io::Aabb& b) {
  return {{b.min[0], b.min[1], b.min[2]}, {b.max[0], b.max[1], b.max[2]}};
}

// The world axis most across `up` with the longest extent: the fluid's
// "length" (a dam break runs along it).
Vec3 length_axis(const Bounds& b, Vec3 up) {
  Vec3 best{1, 0, 0};
  float longest = -1;
  for (int a = 0; a < 3; ++a) {
    Vec3 axis{0, 0, 0};
    axis[a] = 1;
    if (std::abs(dot(axis, up)) > 0.5f) continue;
    const float extent = b.max[a] - b.min[a];
    if (extent > longest) longest = extent, best = axis;
  }
  return best;
}

// The views of the quality table, all from outside the fluid (from inside
// the bulk the interior is what one sees: docs/narrow_band.md): from above,
// grazing (3 degrees over the surface), into the splash (low over the far
// end of the length axis, where a dam break's wave runs up, looking back
// along the fluid), a close-up of the top surface, and the player's default.
std::vector<NamedView> views_of(const Bounds& box, Vec3 up, float aspect) {
  const Vec3 c = box.center();
  const float diag = box.diagonal();
  const Vec3 along = length_axis(box, up);
  const Vec3 across = normalize(cross(up, along));
  const float length = dot(box.max - box.min, along);
  const float height = std::abs(dot(box.max - box.min, up));
  std::vector<NamedView> out;
  Camera above;
  above.up = along;
  above.target = c;
  above.eye = c + up * diag + across * (0.02f * diag);
  above.fit(box, aspect);
  out.push_back({"above", above});
  Camera grazing;
  grazing.up = up;
  grazing.target = c;
  const float e = 3.0f * 3.14159265f / 180.0f;
  grazing.eye = c - across * (std::cos(e) * diag) + up * (std::sin(e) * diag);
  grazing.fit(box, aspect);
  out.push_back({"grazing", grazing});
  Camera splash;
  splash.up = up;
  splash.eye = c + along * (0.5f * length + 0.1f * diag) + up * (0.6f * height) + across * (0.1f * diag);
  splash.target = c + along * (0.2f * length);
  out.push_back({"splash", splash});
  for (const float d : {0.5f, 0.3f}) {
    Camera close;
    close.up = up;
    close.target = c + up * (0.25f * height);
    close.eye = close.target + normalize(up * 0.8f - across) * (d * diag);
    out.push_back({d == 0.5f ? "close-up" : "closer", close});
  }
  out.push_back({"default", Camera::framing(box, up, aspect)});
  return out;
}

// Pixels where `a` differs from `empty`, as a fraction of the image.
double coverage(const std::vector<uint8_t>& a, const std::vector<uint8_t>& empty) {
  size_t fluid = 0;
  for (size_t p = 0; p + 3 < a.size(); p += 4) {
    fluid += a[p] != empty[p] || a[p + 1] != empty[p + 1] || a[p + 2] != empty[p + 2];
  }
  return a.empty() ? 0.0 : double(fluid) / double(a.size() / 4);
}

// Pixels across the largest splat of a particle in front of the eye and
// inside the view (its centre within the image), as cull_particles.comp sizes it.
double largest_splat(const std::vector<float>& xyz, const Camera& camera, float radius, uint32_t width, uint32_t height) {
  const Vec3 f = camera.forward();
  const Vec3 right = normalize(cross(f, camera.up));
  const Vec3 up = cross(right, f);
  const float tan_half = std::tan(camera.fov_deg * 3.14159265f / 360.0f);
  const float aspect = float(width) / float(height);
  const float focal = 0.5f * float(height) / tan_half;  // pixels per unit at distance 1
  double largest = 0;
  for (size_t i = 0; i + 2 < xyz.size(); i += 3) {
    const Vec3 d = Vec3{xyz[i], xyz[i + 1], xyz[i + 2]} - camera.eye;
    const float z = dot(d, f);
    if (z <= radius) continue;
    if (std::abs(dot(d, right)) > z * tan_half * aspect || std::abs(dot(d, up)) > z * tan_half) continue;
    largest = std::max(largest, double(2 * radius * focal / (z - radius)));
  }
  return largest;
}

struct Shot {
  std::vector<uint8_t> rgba;
  uint64_t drawn = 0;
  double gpu_ms = 0;       // median, the classification left out
  double classify_ms = 0;  // the narrow band classified on the GPU (the first render of a frame)
  std::string classification;
};

Shot shoot(render::OffscreenTarget& target, render::Renderer& r, const Camera& camera, const render::FluidOptions& fluid,
           const render::LodOptions& lod, int repeats) {
  Shot s;
  std::vector<double> ms;
  for (int k = 0; k < std::max(1, repeats); ++k) {
    const render::FrameStats stats = target.render(r, camera, fluid, lod);
    double classify = 0;
    for (const render::PassTime& p : stats.passes) classify += p.name == "classify" ? p.ms : 0.0;
    ms.push_back(stats.gpu_ms - classify);
    s.classify_ms = std::max(s.classify_ms, classify);
    if (stats.classification.ran) s.classification = render::describe(stats.classification);
    s.drawn = stats.drawn;
  }
  s.rgba = target.read_rgba8();
  s.gpu_ms = median(ms);
  return s;
}

}  // namespace

std::vector<LayersRow> compare_layers(const LayersBenchOptions& o) {
  namespace fs = std::filesystem;
  const io::ContainerReader reader(o.input);
  if (reader.frame_count() == 0) throw std::runtime_error(o.input + ": the file has no frames");
  std::vector<uint64_t> frames = o.frames;
  if (frames.empty()) frames.push_back(reader.frame_count() - 1);
  render::ContextOptions co;
  co.device = o.device;
  co.validation = o.validation;
  co.quiet_validation = true;
  render::Context context(co);
  const render::SceneInfo scene = render::scene_info(reader);
  render::RendererOptions gpu_options;
  gpu_options.classify_unlayered = o.gpu;
  render::Renderer all(context, scene), surface(context, scene, gpu_options);
  render::OffscreenTarget target(context, o.width, o.height);
  const render::FluidOptions fluid;  // the player's defaults: transparent fluid, narrow-range filter
  render::LodOptions lod, empty = lod;
  empty.near_cull_distance = 1e30f;  // nothing drawn: the background alone
  if (!o.images.empty()) fs::create_directories(o.images);
  std::vector<LayersRow> rows;
  for (const uint64_t f : frames) {
    if (f >= reader.frame_count()) throw std::runtime_error(o.input + ": no frame " + std::to_string(f));
    const io::FrameIndexEntry& e = reader.index().frames[f];
    if (!e.layered() && !o.gpu) {
      throw std::runtime_error(o.input + ": frame " + std::to_string(f) +
                               " has no layers (convert it again with a sluice that writes format 1.3)");
    }
    sluice::render::load_frame(all, reader, f, -1, io::LayerSet::particles());
    if (o.gpu) {
      // Every particle, its layers forgotten: a frame the renderer classifies.
      const std::vector<std::byte> record = reader.read_record(f);
      io::FrameHeader header = reader.parse_record(f, record);
      io::keep_layers(header, io::LayerSet::particles());
      for (io::ChunkDesc& c : header.chunks) c.layer = io::Layer::All;
      surface.wait_upload(sluice::render::commit_record(surface, record, header, reader.header(), -1, reader.location(f)));
    } else {
      sluice::render::load_frame(surface, reader, f, -1, io::LayerSet::surface());
    }
    const io::FrameHeader table = reader.read_table(f);
    const std::vector<float> xyz = io::world_positions(io::decode_frame(reader, f), reader.header().position_coding);
    const float radius = render::effective_radius(fluid, scene);
    const size_t attributes = reader.header().attributes.size();
    const float aspect = float(o.width) / float(o.height);
    for (const NamedView& v : views_of(bounds_of(e.bounds), scene.up, aspect)) {
      const uint64_t errors_before = context.validation_errors();
      const Shot a = shoot(target, all, v.camera, fluid, lod, o.repeats);
      const Shot s = shoot(target, surface, v.camera, fluid, lod, o.repeats);
      const Shot none = shoot(target, all, v.camera, fluid, empty, 1);
      LayersRow row;
      row.view = v.name;
      row.frame = f;
      const render::Image ia{o.width, o.height, a.rgba}, is{o.width, o.height, s.rgba};
      row.psnr = render::psnr(ia, is);
      row.coverage_all = coverage(a.rgba, none.rgba);
      row.coverage_surface = coverage(s.rgba, none.rgba);
      row.drawn_all = a.drawn;
      row.drawn_surface = s.drawn;
      row.gpu_ms_all = a.gpu_ms;
      row.gpu_ms_surface = s.gpu_ms;
      row.bytes_all = io::layers_end(table, io::LayerSet::particles(), attributes);
      row.bytes_surface = io::layers_end(table, o.gpu ? io::LayerSet::particles() : io::LayerSet::surface(), attributes);
      row.classify_ms = s.classify_ms;
      row.classification = s.classification;
      row.validation_errors = context.validation_errors() - errors_before;
      row.largest_splat_px = largest_splat(xyz, v.camera, radius, o.width, o.height);
      row.splat_limit_px = lod.max_splat_pixels > 0 ? std::min(lod.max_splat_pixels, context.device().max_point_size)
                                                    : context.device().max_point_size;
      if (!o.images.empty()) {
        const std::string stem = (fs::path(o.images) / ("f" + std::to_string(f) + "_" + v.name)).string();
        render::write_png(stem + "_all.png", ia);
        render::write_png(stem + "_surface.png", is);
      }
      rows.push_back(row);
    }
  }
  return rows;
}

void run_layers_bench(const LayersBenchOptions& o) {
  const std::vector<LayersRow> rows = compare_layers(o);
  std::printf("sluice bench layers: %s at %ux%u\n", o.input.c_str(), o.width, o.height);
  std::vector<std::string> columns{"frame", "view", "PSNR dB", "fluid pixels, all", "surface + blobs", "difference",
                                   "drawn, all", "surface + blobs", "bytes read, all", "surface + blobs", "GPU ms, all",
                                   "surface + blobs", "largest splat px"};
  if (o.gpu) columns.push_back("GPU classification ms");
  Table t(columns);
  bool near = false;
  for (const LayersRow& r : rows) {
    const double diff = r.coverage_all > 0 ? (r.coverage_surface - r.coverage_all) / r.coverage_all : 0.0;
    std::vector<std::string> cells{std::to_string(r.frame), r.view, std::isinf(r.psnr) ? "identical" : fixed(r.psnr, 1),
                                   fixed(100 * r.coverage_all, 2) + "%", fixed(100 * r.coverage_surface, 2) + "%",
                                   fixed(100 * diff, 3) + "%", count_name(r.drawn_all), count_name(r.drawn_surface),
                                   count_name(r.bytes_all), count_name(r.bytes_surface), fixed(r.gpu_ms_all, 2),
                                   fixed(r.gpu_ms_surface, 2),
                                   fixed(r.largest_splat_px, 0) + (r.near_cull() ? " > " + fixed(r.splat_limit_px, 0) + " *" : "")};
    if (o.gpu) cells.push_back(r.classify_ms > 0 ? fixed(r.classify_ms, 3) : "-");
    t.row(cells);
    near = near || r.near_cull();
  }
  t.print(o.gpu ? "Narrow band classified on the GPU (surface + voxel blobs) against every particle; difference in "
                  "fluid pixels relative to all"
                : "Narrow band (surface + voxel blobs) against every particle; difference in fluid pixels relative to all");
  for (const LayersRow& r : rows) {
    if (!r.classification.empty()) std::printf("frame %llu: %s\n", (unsigned long long)r.frame, r.classification.c_str());
  }
  if (near) {
    std::printf("* splats larger than the renderer draws: the nearest particles are culled in both pictures, and\n"
                "  where surface particles go the narrow band shows the hollow inside (docs/narrow_band.md)\n");
  }
}

}  // namespace sluice::bench
