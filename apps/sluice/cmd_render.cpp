// `sluice render`: frames of a .sluice file to PNG images or an MP4, headless
// (offscreen Vulkan; lavapipe works without a GPU or a display).
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "commands.h"
#include "frame_range.h"
#include "human.h"
#include "decode_option.h"
#include "layers_option.h"
#include "playable.h"
#include "reads_text.h"
#include "view_options.h"
#include "progress.h"
#include "sluice/bench/layers_bench.h"
#include "sluice/bench/render_bench.h"
#include "sluice/io/reader.h"
#include "sluice/render/image_io.h"
#include "sluice/bench/live_bench.h"
#include "sluice/render/offscreen.h"
#include "sluice/stream/stream.h"

namespace sluice::app {
namespace {

struct RenderCommand {
  std::string input;
  std::string frames;  // "A:B" inclusive, "A", "A:", ":B"; empty: all
  std::string out = "frames";
  std::string size = "1280x720";
  double fps = 0;
  bool quiet = false, stats = false, no_cache = false, force = false;
  std::string layers = "surface";
  std::string decode = "auto";
};

std::string frame_path(const std::string& out, uint64_t frame, bool single) {
  namespace fs = std::filesystem;
  char name[64];
  if (out.find('%') != std::string::npos) {
    char buf[4096];
    std::snprintf(buf, sizeof buf, out.c_str(), (unsigned long long)frame);
    return buf;
  }
  const fs::path p(out);
  if (p.extension() == ".png") {
    if (single) return out;
    std::snprintf(name, sizeof name, "_%05llu.png", (unsigned long long)frame);
    return (p.parent_path() / p.stem()).string() + name;
  }
  std::snprintf(name, sizeof name, "frame_%05llu.png", (unsigned long long)frame);
  return (p / name).string();
}

// Frames stream through the runtime (read ahead, decoded on every core
// into staging) like playback: every frame due at once, none skipped
// (hold), the first bad frame stops the render with its error; the one
// fixed camera reads the tiers it draws (the same pixels as a full read).
stream::StreamOptions stream_options(const RenderCommand& o, const ViewSettings& v) {
  stream::StreamOptions so;
  so.player.frame_rate = 1e9;
  so.player.end = runtime::EndMode::Stop;
  so.player.policy = runtime::RealTimePolicy::HoldLastFrame;
  so.player.on_error = runtime::ErrorPolicy::Stop;
  so.layers = layer_set(o.layers);
  so.decode = decode_site(o.decode);
  so.motion = stream::ViewMotion::Fixed;
  so.up = v.up_override();
  render::apply_particles(v.particles, so.renderer);
  return so;
}

// Like convert and export: nothing is overwritten unless asked.
void refuse_existing(const RenderCommand& o, const std::vector<uint64_t>& frames, bool video, bool single) {
  namespace fs = std::filesystem;
  std::vector<std::string> outputs;
  if (video) outputs.push_back(o.out);
  else for (uint64_t f : frames) outputs.push_back(frame_path(o.out, f, single));
  for (const std::string& taken : outputs) {
    if (fs::exists(taken) && !o.force) {
      throw std::runtime_error(taken + " exists; pass --force to overwrite it, or -o to write elsewhere");
    }
  }
}

void run_render(const RenderCommand& o, const ViewSettings& v) {
  namespace fs = std::filesystem;
  const PlayableFile input = open_playable(o.input, {o.no_cache, o.quiet});
  render::Context context(v.context_options());
  // A list (0,25,50) plays every frame between its first and last and
  // draws those listed; nothing past the last is read.
  const std::vector<uint64_t> frames = parse_frame_list(o.frames, io::ContainerReader(input.path()).frame_count());
  const uint64_t first = frames.front(), last = frames.back();
  stream::StreamOptions so = stream_options(o, v);
  so.player.frames = last + 1;
  stream::Stream stream(context, input.path(), so);
  const io::ContainerReader& reader = stream.reader();
  const auto [width, height] = parse_size(o.size);
  const bool video = fs::path(o.out).extension() == ".mp4";
  const bool single = frames.size() == 1;
  refuse_existing(o, frames, video, single);
  if (!video && fs::path(o.out).extension() != ".png" && o.out.find('%') == std::string::npos) {
    fs::create_directories(o.out);
  }

  render::Renderer& renderer = stream.renderer();
  render::OffscreenTarget target(context, width, height);
  v.apply_environment(renderer);
  stream.set_look(v.fluid_options(stream.scene()), v.lod_options());
  const render::Camera camera = v.camera(stream.scene(), float(width) / float(height));
  const render::View view = render::camera_view(camera, {0, 0, width, height});
  stream.set_views({&view, 1});
  if (!o.quiet) {
    std::fprintf(stderr, "rendering %s frames %llu..%llu at %ux%u on %s (%s)\n  camera \"%s\"\n  layers: %s\n  particles: %s\n",
                 o.input.c_str(), (unsigned long long)first, (unsigned long long)last, width, height,
                 context.device().name.c_str(), context.device().type.c_str(), camera.to_string().c_str(),
                 layers_text(reader, first, so.layers).c_str(),
                 particles_text(so.renderer, reader, first).c_str());
  }

  std::unique_ptr<render::VideoWriter> writer;
  if (video) {
    const double fps = o.fps > 0 ? o.fps : (reader.header().frame_rate > 0 ? reader.header().frame_rate : 30.0);
    writer = std::make_unique<render::VideoWriter>(o.out, width, height, fps);
  }
  runtime::Player& player = stream.player();
  player.seek(first);
  player.play();
  ProgressBar bar("frames", frames.size(), o.quiet);
  render::Image image{width, height, {}};
  size_t drawn = 0;  // of `frames`
  for (uint64_t f = first; f <= last;) {
    player.wait_for_due();
    const stream::FeedUpdate fed = stream.update();
    if (const auto error = player.pop_error()) throw std::runtime_error(error->text());
    if (!fed.changed || fed.frame != f) {
      if (player.state() == runtime::PlayerState::Ended || player.state() == runtime::PlayerState::Stopped) {
        throw std::runtime_error(o.input + ": playback ended before frame " + std::to_string(f));
      }
      continue;
    }
    if (f != frames[drawn]) {  // between two listed frames
      ++f;
      continue;
    }
    renderer.wait_upload(fed.ticket);  // draw exactly this frame
    const render::FrameStats stats = target.render(renderer, camera, stream.fluid(), stream.lod());
    image.rgba = target.read_rgba8();
    if (writer) writer->add(image);
    else render::write_png(frame_path(o.out, f, single), image);
    if (o.stats) {
      std::string passes;
      for (const render::PassTime& p : stats.passes) passes += " " + p.name + " " + fixed(p.ms, 2);
      bar.print("frame " + std::to_string(f) + ": " + std::to_string(stats.drawn) + "/" + std::to_string(stats.particles) +
               " particles drawn; GPU ms:" + passes + "; total " + fixed(stats.gpu_ms, 2));
      if (stats.classification.ran) bar.print("  " + render::describe(stats.classification));
    }
    bar.update(++drawn);
    ++f;
  }
  if (writer) writer->finish();
  bar.finish();
  if (context.validation_active() && context.validation_errors() > 0) {
    std::fprintf(stderr, "sluice: %llu Vulkan validation errors\n", (unsigned long long)context.validation_errors());
    throw ExitCode{2};
  }
  if (!o.quiet) {
    const std::string where = video ? o.out : single ? frame_path(o.out, first, true) : o.out;
    std::printf("wrote %s (%llu frame%s, %s)\n", where.c_str(), (unsigned long long)frames.size(),
                single ? "" : "s", human_duration(bar.elapsed()).c_str());
  }
}

}  // namespace

void add_render(CLI::App& app) {
  auto o = std::make_shared<RenderCommand>();
  auto v = std::make_shared<ViewSettings>();
  CLI::App* cmd = app.add_subcommand("render", "Render frames to PNG images or an MP4, headless (no display needed)");
  cmd->footer(
      "OUT is a directory (frame_00000.png ...), a .png file (one frame; name_00000.png ... for several),\n"
      "a printf pattern (shot_%04d.png) or a .mp4 file (needs ffmpeg on PATH).\n\n"
      "Examples:\n"
      "  sluice render dam.sluice --frames 12 --out dam.png --size 1920x1080\n"
      "  sluice render dam.sluice --out dam.mp4 --color-by rho --colormap coolwarm\n"
      "  sluice render big.sluice --lod density --lod-level 0.3 --camera \"eye=4,-3,2;target=1,0,0.3\"\n");
  add_input_options(*cmd, "input", o->input, o->no_cache);
  cmd->add_option("--frames", o->frames, "Frames A:B (inclusive), A, A: or :B, or a list of them: 0,25,50 (default: all)");
  cmd->add_option("-o,--out", o->out, "Output directory, .png, pattern or .mp4")->capture_default_str();
  cmd->add_option("--size", o->size, "Image size WIDTHxHEIGHT")->capture_default_str();
  cmd->add_option("--fps", o->fps, "MP4 frame rate (default: the file's)");
  cmd->add_flag("--stats", o->stats, "Print particles drawn and GPU ms per pass for every frame");
  cmd->add_flag("-f,--force", o->force, "Overwrite images or a video that exist");
  cmd->add_flag("-q,--quiet", o->quiet, "No progress bar or notes");
  add_layers_option(*cmd, o->layers);
  add_decode_option(*cmd, o->decode);
  add_view_options(*cmd, *v);
  cmd->callback([o, v] { run_render(*o, *v); });
}

void add_bench_layers(CLI::App& bench) {
  auto o = std::make_shared<bench::LayersBenchOptions>();
  auto size = std::make_shared<std::string>("1280x720");
  CLI::App* cmd = bench.add_subcommand("layers", "The narrow band's picture against every particle's: PSNR, coverage, bytes, GPU ms");
  cmd->footer(
      "FILE must have layers (`sluice convert` writes them), unless --gpu. Each frame is drawn from above,\n"
      "grazing, into the splash (low over the far end), close up and closer, and from the default view,\n"
      "once from its surface and voxel blobs and once from all its particles; fluid pixels are those that\n"
      "differ from the view without particles. With --gpu the surface and blobs come from the GPU\n"
      "classifier (the frame read whole, as a file converted with --no-layers is drawn).\n\n"
      "Examples: sluice bench layers dam.sluice --frames 0,6,12 --images layer_images\n"
      "          sluice bench layers dam.sluice --frames 0,6,12 --gpu\n");
  cmd->add_option("file", o->input, ".sluice file with layers (any .sluice with --gpu)")->required()->check(CLI::ExistingFile);
  cmd->add_flag("--gpu", o->gpu, "Classify the narrow band on the GPU instead of reading the file's layers");
  cmd->add_option("--frames", o->frames, "Frames to compare (default: the last)")->delimiter(',');
  cmd->add_option("--size", *size, "Image size WIDTHxHEIGHT")->capture_default_str();
  cmd->add_option("--repeats", o->repeats, "Renders per case (median GPU time)")->capture_default_str();
  cmd->add_option("--device", o->device, "Vulkan device: index or part of its name");
  cmd->add_option("--images", o->images, "Save both images of every case in this directory");
  cmd->callback([o, size] {
    const auto [w, h] = parse_size(*size);
    o->width = w;
    o->height = h;
    bench::run_layers_bench(*o);
  });
}

void add_bench_render(CLI::App& bench) {
  auto o = std::make_shared<bench::RenderBenchOptions>();
  auto sizes = std::make_shared<std::string>("1M,10M,50M,100M");
  auto size = std::make_shared<std::string>("1920x1080");
  CLI::App* cmd = bench.add_subcommand("render", "GPU ms per renderer pass for 1M..100M particles, cLOD off/on, vs VTK");
  cmd->footer(
      "Synthetic frames are generated in memory (a pool with waves and a collapsing column on a jittered\n"
      "grid, 32^3-particle chunks). --real adds the last frame of a .sluice file; --vtk runs VTK 9's\n"
      "vtkOpenGLFluidMapper on the same frames (python3-vtk9 and xvfb-run; slow on llvmpipe), or with\n"
      "--vtk-peer, the native peer built by bench/vtk_peer/build.sh (VTK with EGL: a GPU, no X server).\n\n"
      "Examples:\n"
      "  sluice bench render\n"
      "  sluice bench render --sizes 100k,1M --real dam.sluice --vtk --images bench_images\n"
      "  sluice bench render --sizes 1M,10M --vtk-peer vtk/bin/vtk_fluid_peer --vtk-max 100M\n");
  cmd->add_option("--sizes", *sizes, "Synthetic particle counts (k, M suffixes; empty for none)")->capture_default_str();
  cmd->add_option("--size", *size, "Image size WIDTHxHEIGHT")->capture_default_str();
  cmd->add_option("--repeats", o->repeats, "Renders per case (median)")->capture_default_str();
  cmd->add_option("--lod-level", o->lod_level, "cLOD level of the 'LOD on' rows")->capture_default_str();
  cmd->add_option("--real", o->real, "A .sluice file whose last frame is measured too")->check(CLI::ExistingFile);
  cmd->add_flag("--vtk", o->vtk, "Also time VTK's vtkOpenGLFluidMapper on the same frames");
  auto vtk_max = std::make_shared<std::string>("1M");
  cmd->add_option("--vtk-max", *vtk_max, "Largest frame handed to VTK (k, M suffixes)")->capture_default_str();
  cmd->add_option("--vtk-peer", o->vtk_peer, "The native VTK peer to run (implies --vtk)")->check(CLI::ExistingFile);
  cmd->add_option("--device", o->device, "Vulkan device: index or part of its name");
  cmd->add_option("--images", o->images, "Save every case's image (and VTK's) in this directory");
  cmd->add_option("--splat", o->splat, "Sphere splatting: auto, compute or raster")->capture_default_str();
  cmd->add_option("--csv", o->csv, "Also write the per-pass table as CSV (for plots of ms against particles)");
  cmd->add_option("--plot", o->plot, "Also draw GPU ms against particles as an SVG chart (log-log, one line per LOD)");
  cmd->add_flag("--layers", o->layers,
                "Also draw each synthetic frame classified into the narrow band: its surface and voxel blobs, and all\n"
                "its particles from the same chunks");
  cmd->add_flag("--with-depth", o->with_depth,
                "Render into a target with a depth image, as a host with its own geometry does: shading tests the fluid\n"
                "against it and writes it, through a copy out and back (--present-pass: the raster pass instead)");
  cmd->add_flag("--untiered", o->untiered,
                "Lay synthetic frames out as files without LOD tiers are: Morton order, one chunk row per block\n"
                "(default: a row per tier, as `sluice convert` writes them, so the cull drops far rows unread)");
  cmd->add_flag("--keep-depth", o->keep_depth,
                "With --with-depth: each frame starts from the depth the last one left, as a host's depth holding its\n"
                "own geometry does; the shading pass reads it in place (default: cleared each frame)");
  cmd->add_flag("--present-pass", o->present_pass,
                "With --with-depth: a depth image that allows no copies, as some hosts give, so a full-viewport raster\n"
                "pass draws the fluid into it (slow on GPUs with few raster units)");
  cmd->add_flag("--stereo", o->stereo,
                "Two eyes of --size each (as a headset: e.g. --size 2064x2208), both in one pass into a 2-layer target,\n"
                "against the same two views as two mono passes");
  cmd->add_flag("--ellipsoids", o->ellipsoids,
                "Also draw each synthetic frame with anisotropic particles (--particles ellipsoids), with the time\n"
                "their ellipsoids take once per frame");
  cmd->callback([o, sizes, size, vtk_max] {
    if (!o->vtk_peer.empty()) o->vtk = true;
    const std::vector<uint64_t> most = bench::parse_counts(*vtk_max);
    if (most.size() != 1) throw CLI::ValidationError("--vtk-max", "one particle count, such as 1M");
    o->vtk_max = most[0];
    o->sizes = sizes->empty() ? std::vector<uint64_t>{} : bench::parse_counts(*sizes);
    const auto [w, h] = parse_size(*size);
    o->width = w;
    o->height = h;
    bench::run_render_bench(*o);
  });

  auto live = std::make_shared<bench::LiveBenchOptions>();
  auto live_sizes = std::make_shared<std::string>("1M,10M");
  auto live_size = std::make_shared<std::string>("1920x1080");
  CLI::App* lc = bench.add_subcommand("live", "Frames pushed from memory (a host's running simulation): encode, decode, copy, render");
  lc->footer(
      "Synthetic frames (the `sluice synth` slosh) are generated first, then pushed through\n"
      "stream::LiveSource as a host would, and drawn.\n\n"
      "Example: sluice bench live --sizes 1M,10M --record /tmp/live.sluice\n");
  lc->add_option("--sizes", *live_sizes, "Particles per frame (k, M suffixes)")->capture_default_str();
  lc->add_option("--frames", live->frames, "Distinct frames pushed (each 3 times after a warm-up)")->capture_default_str();
  lc->add_option("--size", *live_size, "Image size WIDTHxHEIGHT")->capture_default_str();
  lc->add_option("--device", live->device, "Vulkan device: index or part of its name");
  lc->add_option("--record", live->record, "Also record the pushed frames to this .sluice file (overwritten)");
  lc->callback([live, live_sizes, live_size] {
    live->sizes = bench::parse_counts(*live_sizes);
    const auto [w, h] = parse_size(*live_size);
    live->width = w;
    live->height = h;
    bench::run_live_bench(*live);
  });
}

}  // namespace sluice::app
