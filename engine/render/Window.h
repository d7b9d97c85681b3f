#pragma once
// A desktop window (GLFW) that shows both eyes side by side. Esc or the close button asks it to
// close; the renderer recreates its swapchain when the window is resized and skips presenting
// while it is minimised. No GLFW type crosses this header.

#include <expected>
#include <memory>
#include <string>
#include <utility>

namespace rhot {

class Window {
 public:
  // Fails with a message where there is no display (or GLFW cannot start).
  [[nodiscard]] static std::expected<std::unique_ptr<Window>, std::string> create(const std::string& title, int width_px, int height_px);
  ~Window();
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;

  // True where DISPLAY or WAYLAND_DISPLAY is set (a window can be tried).
  static bool display_available();

  bool should_close() const;
  void request_close();
  void poll_events();
  // Sets the window's size (as a user dragging its border would); for tests and tools.
  void resize(int width_px, int height_px);
  // In pixels; 0 x 0 while minimised.
  std::pair<int, int> framebuffer_size() const;

  // The GLFWwindow, for engine/render's backend only.
  void* native_handle() const { return handle_; }

 private:
  explicit Window(void* handle) : handle_(handle) {}
  void* handle_;
};

}  // namespace rhot
