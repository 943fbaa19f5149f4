// sluice/desktop/window.h: a desktop window (GLFW) with a Vulkan swapchain
// into which a Renderer records the fluid, with a Dear ImGui HUD drawn on
// top. A host of the renderer like any other: it uses only sluice_render's
// public API (Context::vulkan() for the handles, Renderer::record() into the
// swapchain image). Built only where GLFW and Dear ImGui are found.
//
// Usage: window_instance_extensions() -> Context(with them, presentation)
// -> Window -> per frame: poll_window_events(), new_ui_frame(), ImGui::
// calls, present(renderer, camera, ...).
// Frames in flight: as many as the renderer was made for; present() waits
// for the fence of the frame that used the same slot that many frames ago
// (the renderer's contract), never for the device.
// Threads: everything on the thread that created the window (GLFW's rule).
// Ownership: the Window borrows the Context, which must outlive it.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "sluice/render/context.h"
#include "sluice/render/renderer.h"

struct GLFWwindow;

namespace sluice::desktop {

struct WindowOptions {
  uint32_t width = 1280, height = 720;  // initial size in screen coordinates
  std::string title = "sluice";
  bool vsync = true;  // FIFO presentation; off: MAILBOX/IMMEDIATE where offered
};

// Initializes GLFW (once per process) and returns the instance extensions
// Vulkan needs for its windows. Throws desktop::Error when there is no
// display (no X server / Wayland compositor) or GLFW lacks Vulkan.
std::vector<std::string> window_instance_extensions();

// Processes pending window events (input callbacks run inside).
void poll_window_events();

// GLFW input callbacks of the application; Dear ImGui's run first and call these.
struct WindowCallbacks {
  void (*key)(GLFWwindow*, int key, int scancode, int action, int mods) = nullptr;
  void (*mouse_button)(GLFWwindow*, int button, int action, int mods) = nullptr;
  void (*cursor)(GLFWwindow*, double x, double y) = nullptr;
  void (*scroll)(GLFWwindow*, double dx, double dy) = nullptr;
  void* user = nullptr;  // glfwGetWindowUserPointer
};

namespace detail {
struct WindowImpl;  // defined in desktop/src, seen by no caller
}  // namespace detail

class Window {
 public:
  // The context must have been created with window_instance_extensions() and
  // presentation = true. Also sets up Dear ImGui (context, GLFW and Vulkan
  // backends), which chains to the input callbacks given here.
  Window(render::Context& context, const WindowOptions& options, const WindowCallbacks& callbacks = {});
  ~Window();
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;

  bool should_close() const;
  // Framebuffer size in pixels (0 x 0 while minimized).
  uint32_t width() const;
  uint32_t height() const;

  // Starts a Dear ImGui frame: build the HUD with ImGui:: calls, then present().
  void new_ui_frame();
  // Records `renderer` for `camera` over the whole window into the next
  // swapchain image, the UI on top (when `ui`; else the UI frame is
  // discarded), submits and presents. Returns false when the frame was
  // dropped because the swapchain had to be rebuilt (resize, minimized): go on.
  // `capture` keeps a copy of what was presented for read_presented().
  bool present(render::Renderer& renderer, const render::Camera& camera, const render::FluidOptions& options,
               const render::LodOptions& lod, bool ui, bool capture = false);
  // The last captured presented image: width*height RGBA8, top row first
  // (waits for that frame).
  std::vector<uint8_t> read_presented();


 private:
  using Impl = detail::WindowImpl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sluice::desktop
