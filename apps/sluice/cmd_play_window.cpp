// `sluice play`: a window that plays a .sluice file as liquid, with a Dear
// ImGui HUD (timeline, play/pause, frame i/N, fps, GPU ms per pass, stream
// stats, LOD and filter choice) and keyboard/mouse control. Frames are
// decoded on the main thread for now; the streaming runtime will feed the
// renderer's staging instead.
#include <GLFW/glfw3.h>
#include <imgui.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "commands.h"
#include "sluice/io/reader.h"
#include "sluice/render/image_io.h"
#include "sluice/render/renderer.h"
#include "sluice/render/window.h"
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
    {"L", "loop on / off"},
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

struct PlayCommand {
  std::string input;
  std::string size = "1280x720";
  uint64_t start = 0;
  double fps = 0, speed = 1;
  bool paused = false, no_loop = false, no_hud = false, no_vsync = false;
  int exit_after = 0;  // presented frames, 0: run until closed
  std::string screenshot;
};

struct Player {
  const io::ContainerReader* reader = nullptr;
  render::Renderer* renderer = nullptr;
  render::Window* window = nullptr;
  render::Camera camera, home;
  render::FluidOptions fluid;
  render::LodOptions lod;
  uint64_t frames = 0, frame = 0, loaded = UINT64_MAX;
  double clock = 0, fps = 30, speed = 1;
  bool playing = true, loop = true, hud = true, screenshot = false;
  bool orbiting = false, panning = false;
  double mouse_x = 0, mouse_y = 0;
  render::FrameStats stats;
  double load_ms = 0, frame_ms = 0, shown_fps = 0;
  std::string device, message;

  void step(int64_t by) {
    playing = false;
    const int64_t n = int64_t(frames);
    frame = uint64_t(((int64_t(frame) + by) % n + n) % n);
    clock = double(frame);
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
    case GLFW_KEY_SPACE: p.playing = !p.playing; break;
    case GLFW_KEY_RIGHT: p.step(+1); break;
    case GLFW_KEY_LEFT: p.step(-1); break;
    case GLFW_KEY_HOME: p.step(-int64_t(p.frame)); break;
    case GLFW_KEY_END: p.step(int64_t(p.frames) - 1 - int64_t(p.frame)); break;
    case GLFW_KEY_LEFT_BRACKET: p.speed = std::max(p.speed / 2, 1.0 / 64); break;
    case GLFW_KEY_RIGHT_BRACKET: p.speed = std::min(p.speed * 2, 64.0); break;
    case GLFW_KEY_L: p.loop = !p.loop; break;
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

void draw_hud(Player& p, const std::string& file) {
  ImGui::SetNextWindowPos(ImVec2(10, 10), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowBgAlpha(0.8f);
  ImGui::Begin("sluice", nullptr, ImGuiWindowFlags_AlwaysAutoResize);
  ImGui::TextUnformatted(std::filesystem::path(file).filename().c_str());
  ImGui::Text("frame %llu / %llu   t = %.4g s", (unsigned long long)p.frame + 1, (unsigned long long)p.frames,
              p.reader->index().frames[p.frame].time);
  if (ImGui::Button(p.playing ? "Pause" : "Play")) p.playing = !p.playing;
  ImGui::SameLine();
  if (ImGui::Button("<")) p.step(-1);
  ImGui::SameLine();
  if (ImGui::Button(">")) p.step(+1);
  ImGui::SameLine();
  ImGui::Checkbox("loop", &p.loop);
  ImGui::SameLine();
  ImGui::Text("x%.3g", p.speed);
  int f = int(p.frame);
  ImGui::SetNextItemWidth(320);
  if (ImGui::SliderInt("##timeline", &f, 0, int(p.frames) - 1, "frame %d")) {
    p.frame = uint64_t(f);
    p.clock = double(f);
    p.playing = false;
  }
  ImGui::Separator();
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
  ImGui::Text("stream: read+decode %.1f ms, upload %.2f ms (GPU)", p.load_ms, p.stats.upload_ms);
  ImGui::Separator();
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
  if (!p.message.empty()) ImGui::TextUnformatted(p.message.c_str());
  if (ImGui::CollapsingHeader("Keys")) {
    for (const Shortcut& s : kShortcuts) ImGui::BulletText("%s: %s", s.keys, s.what);
  }
  ImGui::TextDisabled("%s", p.device.c_str());
  ImGui::End();
}

void run_play(const PlayCommand& o, const ViewSettings& v) {
  const io::ContainerReader reader(o.input);
  if (reader.frame_count() == 0) throw std::runtime_error(o.input + ": the file has no frames");
  unsigned w = 0, h = 0;
  char x = 0;
  if (std::sscanf(o.size.c_str(), "%u%c%u", &w, &x, &h) != 3 || w == 0 || h == 0) {
    throw std::runtime_error("--size: expected WIDTHxHEIGHT, got '" + o.size + "'");
  }
  render::ContextOptions co = v.context_options();
  co.instance_extensions = render::window_instance_extensions();
  co.presentation = true;
  render::Context context(co);
  const render::SceneInfo scene = render::scene_info(reader);

  Player p;
  p.reader = &reader;
  p.frames = reader.frame_count();
  p.frame = std::min<uint64_t>(o.start, p.frames - 1);
  p.clock = double(p.frame);
  p.fps = o.fps > 0 ? o.fps : (reader.header().frame_rate > 0 ? reader.header().frame_rate : 30.0);
  p.speed = o.speed;
  p.playing = !o.paused;
  p.loop = !o.no_loop;
  p.hud = !o.no_hud;
  p.fluid = v.fluid_options(scene);
  p.lod = v.lod_options();
  p.device = context.device().name + " (" + context.device().type + ")";

  render::WindowOptions wo;
  wo.width = w;
  wo.height = h;
  wo.title = "sluice - " + std::filesystem::path(o.input).filename().string();
  wo.vsync = !o.no_vsync;
  render::Window window(context, wo, {on_key, on_mouse_button, on_cursor, on_scroll, &p});
  render::Renderer renderer(context, scene, std::max(window.width(), 1u), std::max(window.height(), 1u));
  p.renderer = &renderer;
  p.window = &window;
  p.camera = p.home = v.camera(scene, float(renderer.width()) / float(renderer.height()));

  auto last = Clock::now(), fps_since = last;
  int presented = 0, fps_frames = 0;
  bool capture_for_exit = false;
  while (!window.should_close()) {
    render::poll_window_events();
    if (window.width() == 0 || window.height() == 0) {
      glfwWaitEventsTimeout(0.1);  // minimized
      continue;
    }
    if (window.width() != renderer.width() || window.height() != renderer.height()) {
      renderer.resize(window.width(), window.height());
    }
    const auto now = Clock::now();
    const double dt = std::chrono::duration<double>(now - last).count();
    last = now;
    p.frame_ms = dt * 1e3;
    // Frames per second over the last half second or so.
    ++fps_frames;
    const double window_s = std::chrono::duration<double>(now - fps_since).count();
    if (window_s >= 0.5) {
      p.shown_fps = double(fps_frames) / window_s;
      fps_frames = 0;
      fps_since = now;
    }
    if (p.playing) {
      p.clock += dt * p.fps * p.speed;
      if (p.clock >= double(p.frames)) {
        if (p.loop) {
          p.clock = std::fmod(p.clock, double(p.frames));
        } else {
          p.clock = double(p.frames - 1);
          p.playing = false;
        }
      }
      p.frame = std::min(uint64_t(p.clock), p.frames - 1);
    }
    if (p.frame != p.loaded) {
      const auto t0 = Clock::now();
      renderer.load_frame(reader, p.frame, p.fluid.scalar_visibility ? p.fluid.color_attribute : -1);
      p.load_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
      p.loaded = p.frame;
    }
    p.stats = renderer.render(p.camera, p.fluid, p.lod);
    window.new_ui_frame();
    if (p.hud) draw_hud(p, o.input);
    capture_for_exit = o.exit_after > 0 && presented + 1 >= o.exit_after && !o.screenshot.empty();
    const bool capture = p.screenshot || capture_for_exit;
    if (!window.present(renderer, p.hud, capture)) continue;
    ++presented;
    if (capture) {
      const render::Image shot{window.width(), window.height(), window.read_presented()};
      if (!shot.rgba.empty()) {
        char name[64];
        std::snprintf(name, sizeof name, "sluice_%05llu.png", (unsigned long long)p.frame);
        const std::string path = capture_for_exit ? o.screenshot : name;
        render::write_png(path, shot);
        p.message = "saved " + path;
        std::printf("saved %s\n", path.c_str());
      } else {
        p.message = "this swapchain cannot be read back";
      }
      p.screenshot = false;
    }
    if (o.exit_after > 0 && presented >= o.exit_after) break;
  }
  if (context.validation_active() && context.validation_errors() > 0) {
    std::fprintf(stderr, "sluice: %llu Vulkan validation errors\n", (unsigned long long)context.validation_errors());
    throw ExitCode{2};
  }
}

}  // namespace

// `sluice play` with a window. The streaming runtime registers `play` too
// (its --headless mode plays into a null sink): this adds the window
// player's options to that subcommand and runs the window unless --headless
// is given, before the runtime's callback (which then does not run). Without
// the runtime's command, it creates `play` itself.
void add_play_window(CLI::App& app) {
  auto o = std::make_shared<PlayCommand>();
  auto v = std::make_shared<ViewSettings>();
  CLI::App* cmd = nullptr;
  try {
    cmd = app.get_subcommand("play");
  } catch (const CLI::OptionNotFound&) {
    cmd = app.add_subcommand("play", "Play a .sluice file in a window, with a HUD");
    cmd->add_option("file", o->input, ".sluice file")->required()->check(CLI::ExistingFile);
  }
  std::string keys = "Window keys:\n";
  for (const Shortcut& s : kShortcuts) {
    keys += "  " + std::string(s.keys) + std::string(14 - std::string(s.keys).size(), ' ') + s.what + "\n";
  }
  cmd->footer(cmd->get_footer() + (cmd->get_footer().empty() ? "" : "\n\n") + keys +
              "\nWindow examples:\n"
              "  sluice play dam.sluice\n"
              "  sluice play big.sluice --lod density --lod-level 0.3 --color-by rho\n"
              "  xvfb-run -a sluice play dam.sluice --exit-after 10 --screenshot shot.png   # no display\n");
  const std::string group = "Window";
  cmd->add_option("--size", o->size, "Window size WIDTHxHEIGHT")->capture_default_str()->group(group);
  cmd->add_option("--frame", o->start, "Frame to start at")->group(group);
  CLI::Option* fps = cmd->get_option_no_throw("--fps");
  if (!fps) fps = cmd->add_option("--fps", o->fps, "Playback frame rate (default: the file's)")->group(group);
  cmd->add_option("--speed", o->speed, "Playback speed factor")->capture_default_str()->group(group);
  cmd->add_flag("--paused", o->paused, "Start paused")->group(group);
  cmd->add_flag("--no-loop", o->no_loop, "Stop at the last frame")->group(group);
  cmd->add_flag("--no-hud", o->no_hud, "Start with the HUD hidden")->group(group);
  cmd->add_flag("--no-vsync", o->no_vsync, "Present as fast as possible")->group(group);
  cmd->add_option("--exit-after", o->exit_after, "Quit after presenting this many frames (tests, timing)")->group(group);
  cmd->add_option("--screenshot", o->screenshot, "With --exit-after: save the last presented frame here (PNG)")
      ->group(group);
  add_view_options(*cmd, *v);
  CLI::Option* headless = cmd->get_option_no_throw("--headless");
  CLI::Option* file = cmd->get_option_no_throw("file");
  cmd->parse_complete_callback([cmd, o, v, fps, headless, file] {
    if (headless && headless->count() > 0) return;  // the runtime's null-sink player runs instead
    if (file && file->count() > 0) o->input = file->as<std::string>();
    if (fps && fps->count() > 0) o->fps = fps->as<double>();
    run_play(*o, *v);
    (void)cmd;
    throw ExitCode{0};
  });
}

}  // namespace sluice::app
