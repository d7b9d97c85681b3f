// The desktop window under a real X server (Xvfb, started by CTest through xvfb-run): both eyes
// presented side by side, the swapchain recreated when the window is resized, and closing.

#include <gtest/gtest.h>
#include <imgui.h>

#include "engine/render/Renderer.h"
#include "engine/render/Window.h"

namespace rhot {
namespace {

// A window of w x h pixels with a CPU-driver renderer presenting two eyes of w/2 x h into it.
struct WindowAndRenderer {
  std::unique_ptr<Window> window;
  std::unique_ptr<Renderer> renderer;
};
WindowAndRenderer open_window(const char* title, int w, int h) {
  WindowAndRenderer out;
  auto window = Window::create(title, w, h);
  EXPECT_TRUE(window.has_value()) << window.error();
  if (!window) return out;
  out.window = std::move(*window);
  RendererSettings s;
  s.eye_width_px = w / 2;
  s.eye_height_px = h;
  s.device = "cpu";
  s.validation = true;
  auto renderer = Renderer::create(s, out.window.get());
  EXPECT_TRUE(renderer.has_value()) << renderer.error();
  if (renderer) out.renderer = std::move(*renderer);
  return out;
}

TEST(Window, ResizeRecreatesTheSwapchain) {
  ASSERT_TRUE(Window::display_available()) << "run under xvfb-run";
  auto [window, renderer] = open_window("rhot window test", 320, 180);
  ASSERT_TRUE(window && renderer);
  HeadsetSettings headset;
  FrameInput f;
  f.views = stereo_views(glm::mat4(1.0f), headset);
  f.lines = {{{-1, 0, -2}, glm::vec4(1)}, {{1, 0, -2}, glm::vec4(1)}};

  for (int i = 0; i < 3; ++i) {
    window->poll_events();
    renderer->render(f);
  }
  EXPECT_EQ(renderer->swapchain_recreations(), 1u);
  EXPECT_EQ(renderer->swapchain_extent(), (std::pair<int, int>{320, 180}));

  window->resize(480, 200);
  // The X server applies the new size asynchronously; render until the swapchain follows.
  for (int i = 0; i < 200 && renderer->swapchain_extent() != std::pair<int, int>{480, 200}; ++i) {
    window->poll_events();
    renderer->render(f);
  }
  EXPECT_EQ(renderer->swapchain_extent(), (std::pair<int, int>{480, 200}));
  EXPECT_GE(renderer->swapchain_recreations(), 2u);

  EXPECT_FALSE(window->should_close());
  window->request_close();
  EXPECT_TRUE(window->should_close());
  EXPECT_EQ(renderer->validation_messages(), 0u);
}

// Window-sized pixel difference count inside and outside a rectangle.
struct Diff {
  int inside = 0;
  int outside = 0;
};
Diff count_differences(const Image& a, const Image& b, int x0, int y0, int x1, int y1) {
  Diff d;
  for (int y = 0; y < a.height; ++y) {
    for (int x = 0; x < a.width; ++x) {
      const std::uint8_t* p = a.pixel(x, y);
      const std::uint8_t* q = b.pixel(x, y);
      const bool differs = p[0] != q[0] || p[1] != q[1] || p[2] != q[2];
      const bool in = x >= x0 && x < x1 && y >= y0 && y < y1;
      (in ? d.inside : d.outside) += differs ? 1 : 0;
    }
  }
  return d;
}

TEST(Window, CaptureShowsBothEyesSideBySideAndTheOverlayOnlyInTheWindow) {
  ASSERT_TRUE(Window::display_available()) << "run under xvfb-run";
  auto [window, renderer] = open_window("rhot overlay test", 320, 180);
  ASSERT_TRUE(window && renderer);
  Renderer& r = *renderer;
  HeadsetSettings headset;
  FrameInput f;
  f.views = stereo_views(glm::mat4(1.0f), headset);
  // A white line across the view and a red one low down: something different in each eye.
  f.lines = {{{-1, 0, -2}, glm::vec4(1)}, {{1, 0, -2}, glm::vec4(1)}, {{-1, -0.5f, -2}, {1, 0, 0, 1}}, {{0.3f, -0.5f, -2}, {1, 0, 0, 1}}};
  for (int i = 0; i < 2; ++i) {
    window->poll_events();
    r.render(f);
  }
  ASSERT_TRUE(r.capture_window().has_value());
  r.render(f);
  const Image plain = r.window_image();
  ASSERT_EQ(plain.width, 320);
  ASSERT_EQ(plain.height, 180);
  // Eye and window pixels are 1:1 here, so each half of the window is exactly its eye.
  const auto eyes = r.read_eyes();
  ASSERT_EQ(eyes[0].width, 160);
  EXPECT_EQ(count_differences(side_by_side(eyes[0], eyes[1]), plain, 0, 0, 0, 0).outside, 0);
  EXPECT_EQ(r.overlay_vertices(), 0u);
  EXPECT_FALSE(r.begin_overlay());  // not enabled yet

  ASSERT_TRUE(r.enable_overlay().has_value());
  EXPECT_TRUE(r.overlay_enabled());
  const auto draw_ui = [&] {
    ASSERT_TRUE(r.begin_overlay());
    ImGui::SetNextWindowPos(ImVec2(10, 20));
    ImGui::SetNextWindowSize(ImVec2(120, 60));
    ImGui::Begin("overlay test", nullptr, ImGuiWindowFlags_NoResize);
    ImGui::TextUnformatted("hello");
    ImGui::End();
  };
  for (int i = 0; i < 3; ++i) {  // Dear ImGui lays windows out over a frame or two
    window->poll_events();
    draw_ui();
    r.render(f);
  }
  draw_ui();
  ASSERT_TRUE(r.capture_window().has_value());
  r.render(f);
  EXPECT_GT(r.overlay_vertices(), 20u);
  const Image with_ui = r.window_image();
  const Diff d = count_differences(plain, with_ui, 10, 20, 130, 80);
  EXPECT_GT(d.inside, 120 * 60 / 2) << "the overlay's window should cover its rectangle";
  EXPECT_EQ(d.outside, 0) << "nothing outside the overlay's window changes";
  // The eyes themselves never contain the overlay.
  const auto eyes_after = r.read_eyes();
  EXPECT_EQ(count_differences(eyes[0], eyes_after[0], 0, 0, 0, 0).outside, 0);
  EXPECT_EQ(r.validation_messages(), 0u);
}

TEST(Window, OverlayAndCaptureNeedAWindow) {
  RendererSettings s;
  s.eye_width_px = 32;
  s.eye_height_px = 32;
  s.device = "cpu";
  auto renderer = Renderer::create(s);
  ASSERT_TRUE(renderer.has_value()) << renderer.error();
  EXPECT_EQ((*renderer)->enable_overlay().error(), "the overlay needs a window (the renderer is offscreen)");
  EXPECT_EQ((*renderer)->capture_window().error(), "no window to capture (the renderer is offscreen)");
  EXPECT_FALSE((*renderer)->begin_overlay());
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
