#include "engine/render/Window.h"

#include <cstdlib>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

namespace rhot {

namespace {

std::string g_last_glfw_error;

void on_glfw_error(int code, const char* description) {
  g_last_glfw_error = std::string(description) + " (GLFW error " + std::to_string(code) + ")";
}

void on_key(GLFWwindow* window, int key, int /*scancode*/, int action, int /*mods*/) {
  if (key == GLFW_KEY_ESCAPE && action == GLFW_PRESS) glfwSetWindowShouldClose(window, GLFW_TRUE);
}

// GLFW is initialised once per process while any window lives.
int g_windows = 0;

}  // namespace

bool Window::display_available() {
  const char* x11 = std::getenv("DISPLAY");
  const char* wayland = std::getenv("WAYLAND_DISPLAY");
  return (x11 != nullptr && *x11 != '\0') || (wayland != nullptr && *wayland != '\0');
}

std::expected<std::unique_ptr<Window>, std::string> Window::create(const std::string& title, int width_px, int height_px) {
  if (!display_available()) return std::unexpected(std::string("no display (DISPLAY and WAYLAND_DISPLAY are unset)"));
  glfwSetErrorCallback(on_glfw_error);
  if (g_windows == 0 && glfwInit() != GLFW_TRUE) {
    return std::unexpected("cannot open the display: " + g_last_glfw_error);
  }
  if (glfwVulkanSupported() != GLFW_TRUE) {
    if (g_windows == 0) glfwTerminate();
    return std::unexpected(std::string("GLFW finds no Vulkan loader for presenting to a window"));
  }
  glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
  glfwWindowHint(GLFW_RESIZABLE, GLFW_TRUE);
  GLFWwindow* w = glfwCreateWindow(width_px, height_px, title.c_str(), nullptr, nullptr);
  if (w == nullptr) {
    if (g_windows == 0) glfwTerminate();
    return std::unexpected("cannot create a window: " + g_last_glfw_error);
  }
  glfwSetKeyCallback(w, on_key);
  ++g_windows;
  return std::unique_ptr<Window>(new Window(w));
}

Window::~Window() {
  glfwDestroyWindow(static_cast<GLFWwindow*>(handle_));
  if (--g_windows == 0) glfwTerminate();
}

bool Window::should_close() const { return glfwWindowShouldClose(static_cast<GLFWwindow*>(handle_)) == GLFW_TRUE; }
void Window::request_close() { glfwSetWindowShouldClose(static_cast<GLFWwindow*>(handle_), GLFW_TRUE); }
void Window::poll_events() { glfwPollEvents(); }
void Window::resize(int width_px, int height_px) { glfwSetWindowSize(static_cast<GLFWwindow*>(handle_), width_px, height_px); }

std::pair<int, int> Window::framebuffer_size() const {
  int w = 0;
  int h = 0;
  glfwGetFramebufferSize(static_cast<GLFWwindow*>(handle_), &w, &h);
  return {w, h};
}

}  // namespace rhot
