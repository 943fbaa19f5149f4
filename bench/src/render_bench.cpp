// `sluice bench render`: per-pass GPU time (timestamps) of the renderer on
// synthetic and real frames, cLOD off and on, and the VTK fluid mapper on
// the same frame as the peer.
#include "sluice/bench/render_bench.h"
#include "svg_plot.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <memory>
#include <stdexcept>

#include "machine.h"
#include "sluice/io/reader.h"
#include "sluice/render/image_io.h"
#include "sluice/render/offscreen.h"
#include "sluice/render/renderer.h"
#include "sluice/render/synthetic.h"
#include "sluice/render/load.h"
#include "sluice/io/codec.h"
#include "sluice/io/lod.h"
#include "sluice/bench/table.h"

namespace sluice::bench {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// The VTK peer: reads float32 xyz, renders with vtkOpenGLFluidMapper (narrow
// range filter, transparent fluid volume) and prints seconds per Render().
// The two settings without which VTK 9.1 silently draws nothing under Xvfb
// are set (no multisampling, the renderer's last culler removed).
constexpr const char* kVtkPeer = R"PY(
import sys, time
import numpy as np
import vtk
from vtk.util import numpy_support as ns
path, w, h, radius, reps, out = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4]), int(sys.argv[5]), sys.argv[6]
cam = [float(v) for v in sys.argv[7].split(',')]
xyz = np.fromfile(path, dtype=np.float32).reshape(-1, 3)
points = vtk.vtkPoints()
points.SetData(ns.numpy_to_vtk(xyz, deep=1))
poly = vtk.vtkPolyData()
poly.SetPoints(points)
mapper = vtk.vtkOpenGLFluidMapper()
mapper.SetInputData(poly)
mapper.SetParticleRadius(radius)
mapper.SetSurfaceFilterMethod(vtk.vtkOpenGLFluidMapper.NarrowRange)
mapper.SetDisplayMode(vtk.vtkOpenGLFluidMapper.TransparentFluidVolume)
mapper.SetAttenuationColor(0.6, 0.15, 0.06)
volume = vtk.vtkVolume()
volume.SetMapper(mapper)
renderer = vtk.vtkRenderer()
renderer.SetBackground(0.78, 0.85, 0.92)
renderer.AddVolume(volume)
cullers = renderer.GetCullers()
cullers.RemoveItem(cullers.GetLastItem())
window = vtk.vtkRenderWindow()
window.SetMultiSamples(0)
window.SetSize(w, h)
window.AddRenderer(renderer)
camera = renderer.GetActiveCamera()
camera.SetPosition(cam[0:3])
camera.SetFocalPoint(cam[3:6])
camera.SetViewUp(cam[6:9])
camera.SetViewAngle(cam[9])
renderer.ResetCameraClippingRange()
window.Render()
times = []
for i in range(reps):
    t = time.perf_counter()
    window.Render()
    times.append(time.perf_counter() - t)
times.sort()
print("VTKPEER %.6f %s" % (times[len(times) // 2], vtk.vtkVersion.GetVTKVersion()))
if out:
    grab = vtk.vtkWindowToImageFilter()
    grab.SetInput(window)
    grab.Update()
    writer = vtk.vtkPNGWriter()
    writer.SetFileName(out)
    writer.SetInputConnection(grab.GetOutputPort())
    writer.Write()
)PY";

struct Case {
  std::string name;
  uint64_t particles = 0;
  std::string lod;
  render::FrameStats stats;  // median over repeats, per pass
  double wall_ms = 0;        // render() call: submit to fence, median
  double vtk_ms = -1;        // peer, when run
  double ellipsoids_ms = -1; // anisotropic particles: their pass, at the frame's first draw
};


// Renders `views` `repeats` times after one warm-up; per-pass medians.
Case measure(render::Renderer& r, render::OffscreenTarget& out, std::span<const render::View> views,
             const render::FluidOptions& fluid, const render::LodOptions& lod, int repeats) {
  Case c;
  // Warm-up: first-use costs (shader JIT on lavapipe), and the frame's
  // once-per-frame passes (the ellipsoids), timed here.
  const render::FrameStats first = out.render(r, views, fluid, lod);
  for (const render::PassTime& p : first.passes) {
    if (p.name == "ellipsoids") c.ellipsoids_ms = p.ms;
  }
  std::map<std::string, std::vector<double>> passes;
  std::vector<double> total, wall;
  render::FrameStats last;
  for (int i = 0; i < std::max(repeats, 1); ++i) {
    const auto t0 = Clock::now();
    last = out.render(r, views, fluid, lod);
    wall.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    for (const render::PassTime& p : last.passes) passes[p.name].push_back(p.ms);
    total.push_back(last.gpu_ms);
  }
  c.stats = last;
  for (render::PassTime& p : c.stats.passes) p.ms = median(passes[p.name]);
  c.stats.gpu_ms = median(total);
  c.wall_ms = median(wall);
  return c;
}

// The two eyes of `cam`: moved -/+ half the separation along its right axis.
std::array<render::View, 2> eye_views(const render::Camera& cam, float separation, uint32_t width, uint32_t height,
                                      bool side_by_side) {
  const render::Vec3 forward = render::normalize(cam.target - cam.eye);
  const render::Vec3 right = render::normalize(render::cross(forward, cam.up));
  std::array<render::View, 2> v;
  for (uint32_t e = 0; e < 2; ++e) {
    render::Camera c = cam;
    const render::Vec3 shift = right * ((e == 0 ? -0.5f : 0.5f) * separation);
    c.eye = c.eye + shift;
    c.target = c.target + shift;
    v[e] = render::camera_view(c, {side_by_side ? e * width : 0, 0, width, height});
  }
  return v;
}

// The command line that runs the VTK peer: the native one directly, or the
// Python script under a virtual X server.
std::string peer_command(const RenderBenchOptions& o, const fs::path& dir, const fs::path& data, const std::string& raw,
                         float radius, const render::Camera& cam) {
  char camera[512];
  std::snprintf(camera, sizeof camera, "%g,%g,%g,%g,%g,%g,%g,%g,%g,%g", double(cam.eye.x), double(cam.eye.y),
                double(cam.eye.z), double(cam.target.x), double(cam.target.y), double(cam.target.z), double(cam.up.x),
                double(cam.up.y), double(cam.up.z), double(cam.fov_deg));
  const std::string args = data.string() + " " + std::to_string(o.width) + " " + std::to_string(o.height) + " " +
                           std::to_string(radius) + " ";
  if (!o.vtk_peer.empty()) {
    return "'" + o.vtk_peer + "' " + args + std::to_string(std::max(1, o.repeats)) + " '" + raw + "' " + camera;
  }
  const fs::path script = dir / "peer.py";
  std::ofstream(script) << kVtkPeer;
  return "xvfb-run -a -s '-screen 0 " + std::to_string(o.width + 64) + "x" + std::to_string(o.height + 64) +
         "x24' /usr/bin/python3 " + script.string() + " " + args + std::to_string(std::max(1, std::min(o.repeats, 3))) +
         " '" + raw + "' " + camera;
}

// Runs the VTK peer on the positions; seconds per frame, or -1 with a note.
// The Python peer writes `image` as a PNG itself; the native one writes raw
// RGBA rows, turned into the PNG here.
double run_vtk_peer(const std::vector<float>& xyz, const RenderBenchOptions& o, float radius, const render::Camera& cam,
                    const std::string& image) {
  const fs::path dir = fs::temp_directory_path() / ("sluice_vtk_peer_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path data = dir / "xyz.f32", log = dir / "out.txt";
  {
    std::ofstream f(data, std::ios::binary);
    f.write(reinterpret_cast<const char*>(xyz.data()), std::streamsize(xyz.size() * sizeof(float)));
  }
  const bool native = !o.vtk_peer.empty();
  const std::string raw = image.empty() ? "" : native ? (dir / "image.rgba").string() : image;
  const std::string cmd = peer_command(o, dir, data, raw, radius, cam) + " > " + log.string() + " 2>&1";
  const int rc = std::system(cmd.c_str());
  double seconds = -1;
  std::string version, renderer;
  {
    std::ifstream in(log);
    for (std::string line; std::getline(in, line);) {
      std::istringstream words(line);
      std::string word;
      if (words >> word && word == "VTKPEER" && (words >> seconds >> version)) {
        std::getline(words >> std::ws, renderer);
        break;
      }
    }
  }
  if (rc != 0 || seconds < 0) {
    std::fprintf(stderr, "note: the VTK peer failed (%s); its output is in %s\n",
                 native ? o.vtk_peer.c_str() : "needs python3-vtk9, xvfb-run", log.c_str());
    return -1;
  }
  std::fprintf(stderr, "  VTK %s%s%s: %.2f ms a frame\n", version.c_str(), renderer.empty() ? "" : " on ",
               renderer.c_str(), seconds * 1e3);
  if (native && !image.empty()) {
    render::Image picture{o.width, o.height, std::vector<uint8_t>(size_t(o.width) * o.height * 4)};
    std::ifstream in(raw, std::ios::binary);
    if (in.read(reinterpret_cast<char*>(picture.rgba.data()), std::streamsize(picture.rgba.size()))) {
      render::write_png(image, picture);
    } else {
      std::fprintf(stderr, "note: the VTK peer's image %s is short; no PNG written\n", raw.c_str());
    }
  }
  fs::remove_all(dir);
  return seconds;
}

// A synthetic frame encoded with the narrow band's layers, stored chunks (as
// live frames are: nothing to decompress).
struct LayeredFrame {
  io::FileHeader file;
  io::EncodedFrame frame;
};

LayeredFrame layered_frame(const render::SyntheticFluid& f) {
  const std::vector<float> xyz = render::synthetic_points(f);
  const std::vector<uint16_t> lod = io::lod_values({}, xyz.size() / 3);
  LayeredFrame out;
  out.file.particle_spacing = f.spacing;
  io::FrameInput in;
  in.positions = xyz;
  in.lod = lod;
  io::EncodeOptions options;
  options.planes = io::PlaneCoding::Stored;
  options.layers = true;
  out.frame = io::encode_frame(in, out.file, options);
  return out;
}

}  // namespace

std::vector<uint64_t> parse_counts(const std::string& text) {
  std::vector<uint64_t> out;
  size_t pos = 0;
  while (pos <= text.size()) {
    const size_t comma = std::min(text.find(',', pos), text.size());
    const std::string item = text.substr(pos, comma - pos);
    pos = comma + 1;
    if (item.empty()) continue;
    size_t used = 0;
    double v = 0;
    try {
      v = std::stod(item, &used);
    } catch (const std::exception&) {
      throw std::invalid_argument("bad particle count '" + item + "'");
    }
    const std::string suffix = item.substr(used);
    if (suffix == "k" || suffix == "K") v *= 1e3;
    else if (suffix == "M" || suffix == "m") v *= 1e6;
    else if (suffix == "G" || suffix == "g") v *= 1e9;
    else if (!suffix.empty()) throw std::invalid_argument("bad particle count '" + item + "' (use k, M or G)");
    if (!(v >= 1)) throw std::invalid_argument("bad particle count '" + item + "'");
    out.push_back(uint64_t(std::llround(v)));
  }
  return out;
}

namespace {

// The per-pass table of every case.
void print_passes(const std::vector<Case>& cases) {
  std::vector<std::string> header{"frame", "particles", "LOD", "drawn"};
  if (!cases.empty()) {
    for (const render::PassTime& p : cases[0].stats.passes) header.push_back(p.name);
  }
  header.insert(header.end(), {"GPU ms", "wall ms", "cull Mp/ms", "upload ms", "ellipsoids ms (once a frame)"});
  Table passes(header);
  for (const Case& c : cases) {
    std::vector<std::string> row{c.name, count_name(c.particles), c.lod, count_name(c.stats.drawn)};
    double cull = 0;
    for (const render::PassTime& p : c.stats.passes) {
      row.push_back(fixed(p.ms, 2));
      if (p.name == "cull") cull = p.ms;
    }
    row.push_back(fixed(c.stats.gpu_ms, 2));
    row.push_back(fixed(c.wall_ms, 1));
    row.push_back(cull > 0 ? fixed(double(c.particles) / 1e6 / cull, 2) : "-");
    row.push_back(fixed(c.stats.upload_ms, 2));
    row.push_back(c.ellipsoids_ms < 0 ? "-" : fixed(c.ellipsoids_ms, 2));
    passes.row(row);
  }
  passes.print("Per-pass time (ms, from timestamps; 'wall' is the render() call, submit to fence)");
}

// The cases as CSV (o.csv), one row each, the device named.
void write_csv(const RenderBenchOptions& o, const std::vector<Case>& cases, const render::DeviceInfo& dev) {
  std::ofstream csv(o.csv);
  csv << "frame,particles,lod,drawn";
  if (!cases.empty()) {
    for (const render::PassTime& p : cases[0].stats.passes) csv << "," << p.name << "_ms";
  }
  csv << ",gpu_ms,wall_ms,vtk_ms,ellipsoids_ms,device\n";
  for (const Case& c : cases) {
    csv << '"' << c.name << "\"," << c.particles << ",\"" << c.lod << "\"," << c.stats.drawn;
    for (const render::PassTime& p : c.stats.passes) csv << "," << p.ms;
    csv << "," << c.stats.gpu_ms << "," << c.wall_ms << "," << (c.vtk_ms < 0 ? std::string() : std::to_string(c.vtk_ms))
        << "," << (c.ellipsoids_ms < 0 ? std::string() : std::to_string(c.ellipsoids_ms)) << ",\"" << dev.name << "\"\n";
  }
  if (!csv) throw std::runtime_error(o.csv + ": cannot write");
  std::printf("\nwrote %s\n", o.csv.c_str());
}

// GPU ms against particles, one line per LOD setting of the synthetic
// frames (and VTK's wall ms where it ran), as an SVG (o.plot).
void write_plot(const RenderBenchOptions& o, const std::vector<Case>& cases, const render::DeviceInfo& dev) {
  std::vector<PlotSeries> series;
  auto series_named = [&](const std::string& name) -> PlotSeries& {
    for (PlotSeries& s : series) {
      if (s.name == name) return s;
    }
    return series.emplace_back(PlotSeries{name, {}});
  };
  for (const Case& c : cases) {
    if (c.name.rfind("synthetic", 0) == 0) {
      series_named("sluice, LOD " + c.lod).points.emplace_back(double(c.particles), c.stats.gpu_ms);
    }
    if (c.vtk_ms >= 0) series_named("VTK fluid mapper (wall)").points.emplace_back(double(c.particles), c.vtk_ms);
  }
  write_loglog_svg(o.plot, "Frame time at " + std::to_string(o.width) + "x" + std::to_string(o.height) + ", " + dev.name,
                   "particles per frame", "GPU ms per frame", std::move(series));
  std::printf("wrote %s\n", o.plot.c_str());
}

// One stereo pass against two mono passes, per frame and LOD setting.
void print_stereo(const RenderBenchOptions& o, const std::vector<Case>& cases) {
  // Beside the budget of a 90 Hz headset (11.1 ms for both eyes).
  Table stereo({"frame", "LOD", "drawn (one pass)", "one pass ms", "two mono passes ms", "two / one", "within 11.1 ms"});
  for (size_t i = 0; i + 1 < cases.size(); i += 2) {
    const Case& one = cases[i];
    const Case& two = cases[i + 1];
    const std::string frame = one.name.substr(0, one.name.rfind(", stereo"));
    stereo.row({frame, one.lod, count_name(one.stats.drawn), fixed(one.stats.gpu_ms, 2), fixed(two.stats.gpu_ms, 2),
                fixed(two.stats.gpu_ms / std::max(one.stats.gpu_ms, 1e-9), 2) + "x", one.stats.gpu_ms <= 11.1 ? "yes" : "no"});
  }
  stereo.print("Stereo: both eyes at " + std::to_string(o.width) + "x" + std::to_string(o.height) +
               " each, in one pass (2-layer target) against two mono passes of the same views (GPU ms)");
}

// sluice against VTK's fluid mapper, where the peer ran.
void print_peer(const RenderBenchOptions& o, const std::vector<Case>& cases) {
  bool any_vtk = false;
  Table peer({"frame", "particles", "sluice GPU ms", "sluice wall ms", "VTK ms", "VTK / sluice (wall)"});
  for (const Case& c : cases) {
    if (c.vtk_ms < 0) continue;
    any_vtk = true;
    peer.row({c.name, count_name(c.particles), fixed(c.stats.gpu_ms, 1), fixed(c.wall_ms, 1), fixed(c.vtk_ms, c.vtk_ms < 100 ? 1 : 0),
              fixed(c.vtk_ms / c.wall_ms, 1) + "x"});
  }
  if (any_vtk) {
    peer.print("Against VTK 9 vtkOpenGLFluidMapper (same frame, camera, radius and size; NarrowRange, "
               "TransparentFluidVolume; VTK time is " +
                 std::string(o.vtk_peer.empty() ? "a Render() call under Xvfb)" : "a Render() call and glFinish, EGL)"));
  }
}

}  // namespace

void run_render_bench(const RenderBenchOptions& o) {
  render::ContextOptions co;
  co.device = o.device;
  render::Context context(co);
  render::OffscreenOptions oo;
  oo.depth = o.with_depth;
  oo.depth_transfer = !o.present_pass;
  oo.keep_depth = o.keep_depth;
  render::OffscreenTarget out(context, o.width, o.height, oo);
  // Stereo: both eyes in one 2-layer target, and the same eyes side by side.
  std::unique_ptr<render::OffscreenTarget> stereo_out, pair_out;
  if (o.stereo) {
    render::OffscreenOptions so = oo;
    so.layers = 2;
    stereo_out = std::make_unique<render::OffscreenTarget>(context, o.width, o.height, so);
    pair_out = std::make_unique<render::OffscreenTarget>(context, 2 * o.width, o.height, oo);
  }
  const render::DeviceInfo& dev = context.device();
  std::printf("sluice bench render: %ux%u%s, median of %d renders after a warm-up\n", o.width, o.height,
              o.stereo ? " per eye, two eyes" : "", o.repeats);
  std::printf("device: %s (%s, %s)%s\n", dev.name.c_str(), dev.type.c_str(), dev.driver.c_str(),
              dev.type == "cpu" ? "  -- a CPU implementation: these are CPU milliseconds, not GPU ones" : "");
  std::printf("host: %s, %d cores; splatting %s; target %s\n", cpu_model().c_str(), core_count(), o.splat.c_str(),
              !o.with_depth    ? "colour only (shading writes it)"
              : o.present_pass ? "colour + depth (present pass with the depth test)"
              : o.keep_depth   ? "colour + depth holding the last frame's (shading tests and writes it, the depth read in place, copied back)"
                               : "colour + depth cleared each frame (shading tests and writes it, the depth copied back)");
  if (!o.images.empty()) fs::create_directories(o.images);

  render::FluidOptions fluid;  // transparent fluid, narrow-range filter, defaults
  fluid.splatting = render::parse_splatting(o.splat);
  std::vector<Case> cases;
  const auto run_frame = [&](const std::string& name, render::Renderer& r, const render::SceneInfo& scene,
                             const std::vector<float>* xyz) {
    render::Camera cam = render::Camera::framing(scene.bounds, render::Vec3{0, 0, 1}, float(o.width) / float(o.height));
    for (bool lod_on : {false, true}) {
      render::LodOptions lod;
      if (lod_on) {
        lod.mode = render::LodMode::DensityPreserving;
        lod.level = o.lod_level;
      }
      const std::string lod_name = lod_on ? "density " + fixed(o.lod_level, 2) : "off";
      if (o.stereo) {
        const render::Bounds& b = scene.bounds;
        const float extent = std::max({b.max.x - b.min.x, b.max.y - b.min.y, b.max.z - b.min.z});
        const float separation = extent * 0.064f / 1.5f;
        for (const bool one_pass : {true, false}) {
          const auto views = eye_views(cam, separation, o.width, o.height, !one_pass);
          Case c = measure(r, one_pass ? *stereo_out : *pair_out, views, fluid, lod, o.repeats);
          c.name = name + (one_pass ? ", stereo one pass" : ", stereo two mono passes");
          c.particles = c.stats.particles;
          c.lod = lod_name;
          std::fprintf(stderr, "  %s, LOD %s: %.1f ms GPU\n", c.name.c_str(), c.lod.c_str(), c.stats.gpu_ms);
          cases.push_back(c);
        }
        continue;
      }
      const render::View view = render::camera_view(cam, {0, 0, o.width, o.height});
      Case c = measure(r, out, std::span(&view, 1), fluid, lod, o.repeats);
      c.name = name;
      c.particles = c.stats.particles;
      c.lod = lod_name;
      if (!o.images.empty()) {
        render::write_png((fs::path(o.images) / (name + (lod_on ? "_lod" : "") + ".png")).string(),
                          {o.width, o.height, out.read_rgba8()});
      }
      if (!lod_on && o.vtk && xyz && c.particles <= o.vtk_max) {
        std::fprintf(stderr, "running the VTK peer on %s (%s particles)...\n", name.c_str(), count_name(c.particles).c_str());
        const std::string image = o.images.empty() ? "" : (fs::path(o.images) / (name + "_vtk.png")).string();
        const double s = run_vtk_peer(*xyz, o, render::effective_radius(fluid, scene), cam, image);
        if (s > 0) c.vtk_ms = s * 1e3;
      }
      std::fprintf(stderr, "  %s, LOD %s: %.1f ms GPU\n", name.c_str(), c.lod.c_str(), c.stats.gpu_ms);
      cases.push_back(c);
    }
  };

  if (!o.real.empty()) {
    const io::ContainerReader reader(o.real);
    const render::SceneInfo scene = render::scene_info(reader);
    render::Renderer r(context, scene);
    const uint64_t frame = reader.frame_count() - 1;
    sluice::render::load_frame(r, reader, frame, -1);
    std::vector<float> xyz;
    if (o.vtk) xyz = io::world_positions(io::decode_frame(reader, frame), reader.header().position_coding);
    run_frame("real " + fs::path(o.real).stem().string(), r, scene, &xyz);
  }
  for (uint64_t n : o.sizes) {
    std::fprintf(stderr, "generating %s synthetic particles...\n", count_name(n).c_str());
    const render::SyntheticFluid f = render::synthetic_fluid(n, !o.untiered);
    {
      render::Renderer r(context, f.scene);
      render::upload_synthetic(r, f);
      std::vector<float> xyz;
      if (o.vtk && f.particles <= o.vtk_max) xyz = render::synthetic_points(f);
      run_frame("synthetic " + count_name(n), r, f.scene, &xyz);
    }
    if (o.ellipsoids) {
      render::RendererOptions anisotropic;
      anisotropic.anisotropic = true;
      render::Renderer r(context, f.scene, anisotropic);
      render::upload_synthetic(r, f);
      run_frame("synthetic " + count_name(n) + ", ellipsoids", r, f.scene, nullptr);
    }
    if (o.layers) {
      std::fprintf(stderr, "classifying the narrow band of %s particles...\n", count_name(n).c_str());
      const LayeredFrame layered = layered_frame(f);
      for (const bool surface : {false, true}) {
        render::Renderer r(context, f.scene);
        io::FrameHeader header = layered.frame.header;
        io::keep_layers(header, surface ? io::LayerSet::surface() : io::LayerSet::particles());
        r.wait_upload(sluice::render::commit_record(r, layered.frame.record, header, layered.file, -1, {}));
        run_frame("synthetic " + count_name(n) + (surface ? ", surface + blobs" : ", all (layered)"), r, f.scene, nullptr);
      }
    }
  }

  print_passes(cases);
  if (!o.csv.empty()) write_csv(o, cases, dev);
  if (!o.plot.empty()) write_plot(o, cases, dev);
  if (o.stereo) print_stereo(o, cases);
  print_peer(o, cases);
}

}  // namespace sluice::bench
