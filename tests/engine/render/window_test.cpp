// The desktop window under a real X server (Xvfb, started by CTest through xvfb-run): both eyes
// presented side by side, the swapchain recreated when the window is resized, and closing.

#include <gtest/gtest.h>

#include "engine/render/Renderer.h"
#include "engine/render/Window.h"

namespace rhot {
namespace {

TEST(Window, ResizeRecreatesTheSwapchain) {
  ASSERT_TRUE(Window::display_available()) << "run under xvfb-run";
  auto window = Window::create("rhot window test", 320, 180);
  ASSERT_TRUE(window.has_value()) << window.error();
  RendererSettings s;
  s.eye_width_px = 160;
  s.eye_height_px = 180;
  s.device = "cpu";
  s.validation = true;
  auto renderer = Renderer::create(s, window->get());
  ASSERT_TRUE(renderer.has_value()) << renderer.error();
  HeadsetSettings headset;
  FrameInput f;
  f.views = stereo_views(glm::mat4(1.0f), headset);
  f.lines = {{{-1, 0, -2}, glm::vec4(1)}, {{1, 0, -2}, glm::vec4(1)}};

  for (int i = 0; i < 3; ++i) {
    (*window)->poll_events();
    (*renderer)->render(f);
  }
  EXPECT_EQ((*renderer)->swapchain_recreations(), 1u);
  EXPECT_EQ((*renderer)->swapchain_extent(), (std::pair<int, int>{320, 180}));

  (*window)->resize(480, 200);
  // The X server applies the new size asynchronously; render until the swapchain follows.
  for (int i = 0; i < 200 && (*renderer)->swapchain_extent() != std::pair<int, int>{480, 200}; ++i) {
    (*window)->poll_events();
    (*renderer)->render(f);
  }
  EXPECT_EQ((*renderer)->swapchain_extent(), (std::pair<int, int>{480, 200}));
  EXPECT_GE((*renderer)->swapchain_recreations(), 2u);

  EXPECT_FALSE((*window)->should_close());
  (*window)->request_close();
  EXPECT_TRUE((*window)->should_close());
  EXPECT_EQ((*renderer)->validation_messages(), 0u);
}

TEST(Window, NoDisplayIsAClearError) {
  // Simulate a machine without a display for this one call.
  const std::string display = std::getenv("DISPLAY") != nullptr ? std::getenv("DISPLAY") : "";
  unsetenv("DISPLAY");
  unsetenv("WAYLAND_DISPLAY");
  auto window = Window::create("x", 64, 64);
  setenv("DISPLAY", display.c_str(), 1);
  ASSERT_FALSE(window.has_value());
  EXPECT_EQ(window.error(), "no display (DISPLAY and WAYLAND_DISPLAY are unset)");
}

}  // namespace
}  // namespace rhot
