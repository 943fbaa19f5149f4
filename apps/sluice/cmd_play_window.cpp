// `sluice play FILE`: a window that plays a .sluice file as liquid, with a
// Dear ImGui HUD (timeline, play/pause, frame i/N, fps, GPU ms per pass,
// stream stats, LOD and filter choice) and keyboard/mouse control. Frames
// come from the streaming runtime (runtime::Player): read ahead and decoded
// on every core straight into Vulkan staging memory (StagingAllocator), then
// copied to the GPU when they are due.
#include <GLFW/glfw3.h>
#include <imgui.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "commands.h"
#include "frame_errors.h"
#include "human.h"
#include "layers_option.h"
#include "play.h"
#include "sluice/desktop/window.h"
#include "sluice/render/image_io.h"
#include "sluice/stream/stream.h"
#include "reads_text.h"
#include "view_options.h"

namespace sluice::app {
namespace {

using Clock = std::chrono::steady_clock;

struct Shortcut {
  const char* keys;
  const char* what;
};
constexpr Shortcut kShortcuts[] = {
    {"Space", "play / pause"},
    {"Left / Right", "previous / next frame"},
    {"Home / End", "first / last frame"},
    {"[ / ]", "half / double playback speed"},
    {"V", "reverse the playback direction"},
    {"L", "at the end: loop, bounce, stop"},
    {"+ / -", "LOD level up / down (turns cLOD on)"},
    {"O", "LOD mode: off, clod, density"},
    {"F", "depth filter: narrow-range, bilateral"},
    {"D", "display mode (transparent, opaque, normals, depth, thickness, ...)"},
    {"G", "ground plane on / off"},
    {"R", "reset the view"},
    {"C", "print the camera string (and copy it)"},
    {"P", "save a screenshot PNG in the current directory"},
    {"H", "hide / show the HUD"},
    {"Q / Esc", "quit"},
    {"mouse", "left drag: orbit, right or shift+left drag: pan, wheel: zoom"},
};

}  // namespace

namespace {

struct Player {
  const io::ContainerReader* reader = nullptr;
  io::LayerSet layers = io::LayerSet::surface();  // --layers
  render::RendererOptions particles;               // --particles: its anisotropic and limit
  runtime::Player* playback = nullptr;
  render::Camera camera, home;
  render::FluidOptions fluid;
  render::LodOptions lod;
  uint64_t frames = 0, frame = 0;
  bool has_frame = false, hud = true, screenshot = false;
  bool times_known = true;        // the file has simulation times (not frame numbers)
  ImVec2 hud_min{0, 0}, hud_max{0, 0};  // where the HUD panel was drawn, pixels
  bool orbiting = false, panning = false;
  double mouse_x = 0, mouse_y = 0;
  render::FrameStats stats;
  std::string classification;  // render::describe() of the newest frame classified on the GPU
  double upload_wall_ms = 0, frame_ms = 0, shown_fps = 0;
  runtime::PlaybackStats stream;
  runtime::PipelineRates rates;
  std::string device, io_mode, message;

  bool playing() const { return playback->state() == runtime::PlayerState::Playing; }
  void toggle_play() { playing() ? playback->pause() : playback->play(); }
  void step(int64_t by) { playback->step(by); }
  void go_to(uint64_t f) { playback->scrub(std::min(f, frames - 1)); }
  void set_speed(double factor) {
    const double r = playback->rate() * factor;
    playback->set_rate(std::copysign(std::clamp(std::abs(r), 1.0 / 64, 64.0), r));
  }
  void next_end_mode() {
    const runtime::EndMode e = playback->end_mode();
    playback->set_end_mode(e == runtime::EndMode::Loop     ? runtime::EndMode::Bounce
                           : e == runtime::EndMode::Bounce ? runtime::EndMode::Stop
                                                           : runtime::EndMode::Loop);
  }
  void lod_level(float delta) {
    if (lod.mode == render::LodMode::Off) lod.mode = render::LodMode::DensityPreserving;
    lod.level = std::clamp(lod.level + delta, 0.0f, 1.0f);
  }
  void print_camera() {
    const std::string text = camera.to_string();
    std::printf("camera: --camera \"%s\"\n", text.c_str());
    std::fflush(stdout);
    ImGui::SetClipboardText(text.c_str());
    message = "camera copied to the clipboard and printed";
  }
};

Player& player_of(GLFWwindow* w) { return *static_cast<Player*>(glfwGetWindowUserPointer(w)); }

void on_key(GLFWwindow* w, int key, int, int action, int mods) {
  if (action == GLFW_RELEASE || ImGui::GetIO().WantCaptureKeyboard) return;
  Player& p = player_of(w);
  switch (key) {
    case GLFW_KEY_SPACE: p.toggle_play(); break;
    case GLFW_KEY_RIGHT: p.step(+1); break;
    case GLFW_KEY_LEFT: p.step(-1); break;
    case GLFW_KEY_HOME: p.go_to(0); break;
    case GLFW_KEY_END: p.go_to(p.frames - 1); break;
    case GLFW_KEY_LEFT_BRACKET: p.set_speed(0.5); break;
    case GLFW_KEY_RIGHT_BRACKET: p.set_speed(2); break;
    case GLFW_KEY_V: p.playback->set_rate(-p.playback->rate()); break;
    case GLFW_KEY_L: p.next_end_mode(); break;
    case GLFW_KEY_EQUAL:
    case GLFW_KEY_KP_ADD: p.lod_level(0.05f); break;
    case GLFW_KEY_MINUS:
    case GLFW_KEY_KP_SUBTRACT: p.lod_level(-0.05f); break;
    case GLFW_KEY_O: p.lod.mode = render::LodMode((uint32_t(p.lod.mode) + 1) % 3); break;
    case GLFW_KEY_F:
      p.fluid.surface_filter_method = p.fluid.surface_filter_method == render::SurfaceFilterMethod::NarrowRange
                                          ? render::SurfaceFilterMethod::BilateralGaussian
                                          : render::SurfaceFilterMethod::NarrowRange;
      break;
    case GLFW_KEY_D:
      p.fluid.display_mode = render::DisplayMode((uint32_t(p.fluid.display_mode) + ((mods & GLFW_MOD_SHIFT) ? 8 : 1)) % 9);
      break;
    case GLFW_KEY_G: p.fluid.ground = !p.fluid.ground; break;
    case GLFW_KEY_R: p.camera = p.home; break;
    case GLFW_KEY_C: p.print_camera(); break;
    case GLFW_KEY_P: p.screenshot = true; break;
    case GLFW_KEY_H: p.hud = !p.hud; break;
    case GLFW_KEY_Q:
    case GLFW_KEY_ESCAPE: glfwSetWindowShouldClose(w, GLFW_TRUE); break;
    default: break;
  }
}

void on_mouse_button(GLFWwindow* w, int button, int action, int mods) {
  Player& p = player_of(w);
  if (action == GLFW_PRESS && ImGui::GetIO().WantCaptureMouse) return;
  const bool down = action == GLFW_PRESS;
  if (button == GLFW_MOUSE_BUTTON_LEFT) {
    if (down && (mods & GLFW_MOD_SHIFT)) p.panning = true;
    else if (down) p.orbiting = true;
    else p.orbiting = p.panning = false;
  } else if (button == GLFW_MOUSE_BUTTON_RIGHT || button == GLFW_MOUSE_BUTTON_MIDDLE) {
    p.panning = down;
  }
  glfwGetCursorPos(w, &p.mouse_x, &p.mouse_y);
}

void on_cursor(GLFWwindow* w, double x, double y) {
  Player& p = player_of(w);
  const double dx = x - p.mouse_x, dy = y - p.mouse_y;
  p.mouse_x = x;
  p.mouse_y = y;
  int width = 1, height = 1;
  glfwGetWindowSize(w, &width, &height);
  if (p.orbiting) p.camera.orbit(float(-dx / width * 2 * M_PI), float(dy / height * M_PI));
  if (p.panning) p.camera.pan(float(-dx / height), float(dy / height));
}

void on_scroll(GLFWwindow* w, double, double dy) {
  if (ImGui::GetIO().WantCaptureMouse) return;
  player_of(w).camera.zoom(float(std::pow(0.9, dy)));
}

template <class Enum>
bool combo(const char* label, Enum& value, const std::vector<std::string>& names) {
  int i = int(value);
  std::string items;
  for (const std::string& n : names) items += n + '\0';
  items += '\0';
  if (!ImGui::Combo(label, &i, items.c_str())) return false;
  value = Enum(i);
  return true;
}

// The panel opens compact (playback and the timeline); performance, view
// settings and keys unfold under their headers.
void draw_hud(Player& p, const std::string& file) {
  ImGui::SetNextWindowPos(ImVec2(10, 10), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowBgAlpha(0.8f);
  ImGui::Begin("sluice", nullptr, ImGuiWindowFlags_AlwaysAutoResize);
  ImGui::TextUnformatted(std::filesystem::path(file).filename().c_str());
  if (p.times_known) {
    // 0-based, as the timeline and --frames count: frame 14 / 50 of 51.
    ImGui::Text("frame %llu / %llu   t = %.4g s   %s", (unsigned long long)p.frame, (unsigned long long)p.frames - 1,
                p.reader->index().frames[p.frame].time, runtime::state_name(p.playback->state()));
  } else {
    ImGui::Text("frame %llu / %llu (no simulation times)   %s", (unsigned long long)p.frame,
                (unsigned long long)p.frames - 1, runtime::state_name(p.playback->state()));
  }
  ImGui::TextUnformatted(("layers: " + layers_text(*p.reader, p.frame, p.layers)).c_str());
  ImGui::TextUnformatted(
      ("particles: " + particles_text(p.particles, *p.reader, p.frame)).c_str());
  if (!p.classification.empty()) ImGui::TextUnformatted(("  newest frame " + p.classification).c_str());
  if (ImGui::Button(p.playing() ? "Pause" : "Play")) p.toggle_play();
  ImGui::SameLine();
  if (ImGui::Button("<")) p.step(-1);
  ImGui::SameLine();
  if (ImGui::Button(">")) p.step(+1);
  ImGui::SameLine();
  if (ImGui::Button(runtime::end_mode_name(p.playback->end_mode()))) p.next_end_mode();
  ImGui::SameLine();
  ImGui::Text("x%.3g   %.0f fps", p.playback->rate(), p.shown_fps);
  int f = int(p.frame);
  ImGui::SetNextItemWidth(320);
  if (ImGui::SliderInt("##timeline", &f, 0, int(p.frames) - 1, "frame %d")) p.go_to(uint64_t(f));
  if (!p.message.empty()) ImGui::TextUnformatted(p.message.c_str());
  if (ImGui::CollapsingHeader("Performance")) {
    ImGui::Text("%.1f fps   frame %.1f ms   GPU %.2f ms", p.shown_fps, p.frame_ms, p.stats.gpu_ms);
    if (ImGui::BeginTable("passes", 2, ImGuiTableFlags_SizingFixedFit)) {
      for (const render::PassTime& t : p.stats.passes) {
        ImGui::TableNextRow();
        ImGui::TableNextColumn();
        ImGui::TextUnformatted(t.name.c_str());
        ImGui::TableNextColumn();
        ImGui::Text("%7.3f ms", t.ms);
      }
      ImGui::EndTable();
    }
    ImGui::Text("particles %llu drawn of %llu, %llu chunks visible", (unsigned long long)p.stats.drawn,
                (unsigned long long)p.stats.particles, (unsigned long long)p.stats.visible_chunks);
    const runtime::PlaybackStats& st = p.stream;
    ImGui::Text("stream: read %s/s, decode %s/s, %zu workers (%s)", human_bytes(p.rates.read_mbps * 1e6).c_str(),
                human_bytes(p.rates.decode_mbps * 1e6).c_str(), p.rates.worker_decode_mbps.size(), p.io_mode.c_str());
    ImGui::TextUnformatted(reads_text(st.pipeline).c_str());
    ImGui::Text("window %u/%u frames, %u ready, %s held", st.pipeline.active_frames, st.pipeline.window_frames,
                st.pipeline.frames_ready, human_bytes(double(st.pipeline.held_bytes)).c_str());
    ImGui::Text("stalls %llu  drops %llu  errors %llu   upload %.2f ms GPU, %.2f ms wall", (unsigned long long)st.stalls,
                (unsigned long long)st.drops, (unsigned long long)st.errors, p.stats.upload_ms, p.upload_wall_ms);
    if (p.stats.decoded_on_gpu) {
      ImGui::Text("decoded on the GPU: %.2f ms%s", p.stats.decode_ms,
                  p.stats.decode_errors > 0 ? "  (chunks with corrupt planes!)" : "");
      if (st.pipeline.frames_relayed > 0) {
        ImGui::Text("relayed to device memory as read: %llu of %llu frames", (unsigned long long)st.pipeline.frames_relayed,
                    (unsigned long long)st.pipeline.frames_read);
      }
    } else {
      ImGui::Text("decoded on the CPU");
    }
    ImGui::TextDisabled("%s", p.device.c_str());
  }
  if (ImGui::CollapsingHeader("View")) {
    combo("LOD", p.lod.mode, {"off", "clod", "density"});
    ImGui::SliderFloat("LOD level", &p.lod.level, 0.0f, 1.0f, "%.2f");
    combo("filter", p.fluid.surface_filter_method, {"bilateral", "narrow-range"});
    ImGui::SliderInt("iterations", &p.fluid.surface_filter_iterations, 0, 3);
    ImGui::SliderInt("filter radius", &p.fluid.surface_filter_radius, 1, 40);
    combo("display", p.fluid.display_mode, render::display_mode_names());
    combo("splatting", p.fluid.splatting, {"compute", "raster", "auto"});
    ImGui::Checkbox("ground", &p.fluid.ground);
    if (ImGui::Button("Reset view")) p.camera = p.home;
    ImGui::SameLine();
    if (ImGui::Button("Copy camera")) p.print_camera();
    ImGui::SameLine();
    if (ImGui::Button("Screenshot")) p.screenshot = true;
  }
  if (ImGui::CollapsingHeader("Keys")) {
    for (const Shortcut& s : kShortcuts) ImGui::BulletText("%s: %s", s.keys, s.what);
  }
  p.hud_min = ImGui::GetWindowPos();
  p.hud_max = ImVec2(p.hud_min.x + ImGui::GetWindowSize().x, p.hud_min.y + ImGui::GetWindowSize().y);
  ImGui::End();
}

// The part of a width x height window beside a panel at the top left
// (right of it or below it, whichever frames the data larger), as fractions.
render::ScreenRect free_beside(ImVec2 panel_min, ImVec2 panel_max, uint32_t width, uint32_t height) {
  const float w = float(std::max(width, 1u)), h = float(std::max(height, 1u)), margin = 8;
  const float right = std::clamp(panel_max.x + margin, 0.0f, w - 1), below = std::clamp(panel_max.y + margin, 0.0f, h - 1);
  // A framed box fills about the smaller side of its rectangle.
  const float right_size = std::min(w - right, h), below_size = std::min(w, h - below);
  if (panel_max.x <= panel_min.x) return {};
  if (right_size >= below_size) return {right / w, 0, 1, 1};
  return {0, below / h, 1, 1};
}

double display_refresh_hz() {
  GLFWmonitor* monitor = glfwGetPrimaryMonitor();
  const GLFWvidmode* mode = monitor ? glfwGetVideoMode(monitor) : nullptr;
  return mode && mode->refreshRate > 0 ? double(mode->refreshRate) : 60.0;
}

}  // namespace

namespace {

// What the window shows at the start: the file, the look, the first frame.
Player initial_state(const io::ContainerReader& reader, const stream::StreamOptions& so, const PlayOptions& o,
                     const WindowPlayOptions& wo, const render::SceneInfo& scene, const render::Context& context) {
  const ViewSettings& v = wo.view;
  Player p;
  p.reader = &reader;
  p.layers = so.layers;
  p.particles = so.renderer;
  p.frames = reader.frame_count();
  p.frame = std::min<uint64_t>(o.start, p.frames - 1);
  p.hud = !wo.no_hud;
  p.fluid = v.fluid_options(scene);
  p.lod = v.lod_options();
  p.device = context.device().name + " (" + context.device().type + ")";
  p.times_known = io::times_stated(reader.header());
  return p;
}

// The HUD's frame rate and stream rates, over the last half second or so.
struct HudRates {
  Clock::time_point since;
  int frames = 0;
  runtime::PlaybackStats before;
  void tick(Player& p, runtime::Player& playback, Clock::time_point now) {
    ++frames;
    const double span = std::chrono::duration<double>(now - since).count();
    if (span < 0.5) return;
    p.shown_fps = double(frames) / span;
    frames = 0;
    since = now;
    // Stream stats refresh with the rates, not every frame (a snapshot allocates).
    p.stream = playback.stats();
    p.rates = runtime::rates_between(before.pipeline, p.stream.pipeline);
    before = p.stream;
  }
};

// The frame just presented, saved as a PNG: to `path` (--screenshot), or
// sluice_FRAME.png beside where sluice runs (the S key).
void save_capture(desktop::Window& window, Player& p, const std::string& path) {
  const render::Image shot{window.width(), window.height(), window.read_presented()};
  if (!shot.rgba.empty()) {
    char name[64];
    std::snprintf(name, sizeof name, "sluice_%05llu.png", (unsigned long long)p.frame);
    const std::string to = path.empty() ? name : path;
    render::write_png(to, shot);
    p.message = "saved " + to;
    std::printf("saved %s\n", to.c_str());
  } else {
    p.message = "this swapchain cannot be read back";
  }
  p.screenshot = false;
}

void report_played(const std::string& file, const runtime::PlaybackStats& s, const render::StagingAllocator& staging,
                   const render::Camera& camera) {
  std::printf("played %s: %llu frames shown, stalls %llu, drops %llu, errors %llu; staging held %s at most%s\n",
              file.c_str(), (unsigned long long)s.frames_shown, (unsigned long long)s.stalls, (unsigned long long)s.drops,
              (unsigned long long)s.errors, human_bytes(double(staging.peak_held_bytes())).c_str(),
              staging.fallback_allocations() ? " (some frames in host memory: the driver refused more staging)" : "");
  std::printf("  last view: --camera \"%s\"\n", camera.to_string().c_str());
}

}  // namespace

void run_play_window(const PlayOptions& o, const WindowPlayOptions& wo) {
  const ViewSettings& v = wo.view;
  const auto [w, h] = parse_size(wo.size);
  render::ContextOptions co = v.context_options();
  co.instance_extensions = desktop::window_instance_extensions();
  co.presentation = true;
  render::Context context(co);
  // Frames stream through the runtime: read ahead (only the tiers the
  // window's view draws, with a margin for the camera's moves) and decoded
  // into staging memory the GPU copies from. The window takes the context's
  // queue lock (desktop/window.h).
  stream::StreamOptions so = stream_options(o, v, true);
  so.player.display_rate = o.display_hz > 0 ? o.display_hz : display_refresh_hz();
  stream::Stream stream(context, o.file, so);
  const io::ContainerReader& reader = stream.reader();
  const render::SceneInfo& scene = stream.scene();

  Player p = initial_state(reader, so, o, wo, scene, context);

  desktop::WindowOptions options;
  options.width = w;
  options.height = h;
  const std::string shown = o.source.empty() ? o.file : o.source;
  options.title = "sluice - " + std::filesystem::path(shown).filename().string();
  options.vsync = !wo.no_vsync;
  desktop::Window window(context, options, {on_key, on_mouse_button, on_cursor, on_scroll, &p});
  v.apply_environment(stream.renderer());
  const auto aspect = [&] { return float(std::max(window.width(), 1u)) / float(std::max(window.height(), 1u)); };
  p.camera = p.home = v.camera(scene, aspect());
  const auto window_view = [&] {
    return render::camera_view(p.camera, {0, 0, std::max(window.width(), 1u), std::max(window.height(), 1u)});
  };
  const render::View first_view = window_view();
  stream.set_look(p.fluid, p.lod);
  stream.set_views({&first_view, 1});
  runtime::Player& playback = stream.player();
  p.playback = &playback;
  p.io_mode = playback.pipeline().io_mode();
  if (!o.paused) playback.play();

  auto last = Clock::now();
  HudRates rates{last, 0, playback.stats()};
  int presented = 0;
  FrameErrors errors;
  while (!window.should_close()) {
    desktop::poll_window_events();
    if (window.width() == 0 || window.height() == 0) {
      glfwWaitEventsTimeout(0.1);  // minimized
      continue;
    }
    const auto now = Clock::now();
    p.frame_ms = std::chrono::duration<double, std::milli>(now - last).count();
    last = now;
    rates.tick(p, playback, now);

    // Frames are read for the view and look the next frames are drawn with.
    const render::View view = window_view();
    stream.set_look(p.fluid, p.lod);
    stream.set_views({&view, 1});
    const stream::FeedUpdate fed = stream.update();
    if (fed.changed) {
      p.upload_wall_ms = fed.commit_wall_ms;
      p.frame = fed.frame;
      p.has_frame = true;
    }
    if (std::string newest = errors.drain(playback); !newest.empty()) p.message = std::move(newest);
    if (!p.has_frame && playback.state() == runtime::PlayerState::Stopped) {
      throw std::runtime_error(o.file + ": playback stopped before any frame could be shown");
    }

    p.stats = stream.renderer().last_stats();
    if (p.stats.classification.ran) p.classification = render::describe(p.stats.classification);
    window.new_ui_frame();
    if (p.hud) draw_hud(p, shown);
    // The default view frames the data beside the HUD; it follows the
    // window's size and the panel's until the user moves the camera.
    const render::ScreenRect free = p.hud ? free_beside(p.hud_min, p.hud_max, window.width(), window.height())
                                          : render::ScreenRect{};
    if (p.camera == p.home) p.camera = p.home = v.camera(scene, aspect(), free);
    // --exit-after counts frames that show data (the first may take a moment to decode).
    const bool last_for_exit = wo.exit_after > 0 && p.has_frame && presented + 1 >= wo.exit_after;
    const bool capture = p.screenshot || (last_for_exit && !wo.screenshot.empty());
    if (!window.present(stream.renderer(), p.camera, p.fluid, p.lod, p.hud, capture)) continue;
    if (p.has_frame) ++presented;
    if (capture) save_capture(window, p, last_for_exit ? wo.screenshot : std::string());
    if (wo.exit_after > 0 && presented >= wo.exit_after) break;
  }
  errors.print_unshown();
  if (!o.quiet) report_played(o.file, playback.stats(), stream.staging(), p.camera);
  if (context.validation_active() && context.validation_errors() > 0) {
    std::fprintf(stderr, "sluice: %llu Vulkan validation errors\n", (unsigned long long)context.validation_errors());
    throw ExitCode{2};
  }
}

// The window's options on `sluice play` (the shared ones are cmd_play.cpp's).
std::shared_ptr<WindowPlayOptions> add_window_play_options(CLI::App& cmd) {
  auto o = std::make_shared<WindowPlayOptions>();
  std::string keys = "Window keys:\n";
  for (const Shortcut& s : kShortcuts) {
    keys += "  " + std::string(s.keys) + std::string(14 - std::string(s.keys).size(), ' ') + s.what + "\n";
  }
  cmd.footer(cmd.get_footer() + "\n\n" + keys +
             "\nWindow examples:\n"
             "  sluice play dam.sluice\n"
             "  sluice play big.sluice --lod density --lod-level 0.3 --color-by rho\n"
             "  xvfb-run -a sluice play dam.sluice --exit-after 10 --screenshot shot.png   # no display\n");
  const std::string group = "Window";
  cmd.add_option("--size", o->size, "Window size WIDTHxHEIGHT")->capture_default_str()->group(group);
  cmd.add_flag("--no-hud", o->no_hud, "Start with the HUD hidden")->group(group);
  cmd.add_flag("--no-vsync", o->no_vsync, "Present as fast as possible")->group(group);
  cmd.add_option("--exit-after", o->exit_after, "Quit after presenting this many frames with data (tests, timing)")
      ->group(group);
  cmd.add_option("--screenshot", o->screenshot, "With --exit-after: save the last presented frame here (PNG)")
      ->group(group);
  cmd.add_flag("--gpu", o->gpu,
               "With --headless: play through the renderer into an offscreen image of --size (frames in flight, no "
               "window) and report frame, upload and render times")
      ->group(group);
  add_view_options(cmd, o->view);
  return o;
}

}  // namespace sluice::app
