// The renderer on a headset through a real OpenXR runtime (tests/support/XrRuntime.h: Monado's
// simulated headset, headless, on the CPU Vulkan driver): the session's states, frames paced and
// drawn into the runtime's swapchains, the eyes where the runtime says they are, its clock, and
// both validation layers silent throughout.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "base/SteadyClock.h"
#include "engine/render/Renderer.h"
#include "engine/render/XrHeadset.h"
#include "tests/support/XrRuntime.h"

namespace rhot {
namespace {

glm::vec3 eye_centre(const StereoViews& v, int eye) { return glm::vec3(glm::inverse(v.eye_from_world[eye])[3]); }

// Polls the runtime's events until `done` or `timeout_s`; false on the timeout.
template <typename Done>
bool poll_until(XrHeadset& xr, Done done, double timeout_s) {
  const double start = steady_now_s();
  while (!done()) {
    if (steady_now_s() - start > timeout_s) return false;
    xr.poll_events();
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return true;
}

TEST(XrHeadset, DrawsIntoTheRuntimesSwapchainsAtItsPaceWithTheEyesWhereItSaysTheyAre) {
  RHOT_REQUIRE_XR_RUNTIME(runtime);
  test::set_xr_test_environment(runtime);
  auto opened = XrHeadset::create({"rhot-test", /*validation=*/true});
  ASSERT_TRUE(opened.has_value()) << opened.error();
  XrHeadset& xr = **opened;
  EXPECT_TRUE(xr.info().validation_enabled);
  RendererSettings settings;
  settings.validation = true;
  auto created = Renderer::create(settings, nullptr, &xr);
  ASSERT_TRUE(created.has_value()) << created.error();
  Renderer& renderer = **created;
  EXPECT_TRUE(renderer.info().headset);
  EXPECT_TRUE(renderer.info().validation_enabled);
  EXPECT_EQ(renderer.headset(), &xr);
  EXPECT_EQ(renderer.eye_width_px(), xr.info().recommended_width_px);
  EXPECT_EQ(renderer.eye_height_px(), xr.info().recommended_height_px);

  // The session begins by itself once the runtime says READY.
  ASSERT_TRUE(poll_until(
      xr, [&] { return xr.session_running(); }, 10.0))
      << "state: " << to_string(xr.state());
  constexpr int kFrames = 24;
  std::vector<glm::vec3> heads;
  double previous_display_s = 0.0;
  std::uint64_t to_render = 0;
  for (int f = 0; f < kFrames; ++f) {
    xr.poll_events();
    const auto timing = xr.begin_frame();
    ASSERT_TRUE(timing.has_value()) << "frame " << f << ", state " << to_string(xr.state());
    EXPECT_EQ(timing->index, static_cast<std::uint64_t>(f));
    // Each frame is shown after the last, and the runtime's clock converts to the steady clock
    // and back to within a microsecond.
    EXPECT_GT(timing->display_s, previous_display_s);
    previous_display_s = timing->display_s;
    to_render += timing->should_render ? 1 : 0;
    EXPECT_NEAR(static_cast<double>(xr.xr_time_from_steady_s(timing->display_s) - timing->display_time), 0.0, 1000.0);
    const auto views = xr.locate_views(0.05, 100.0);
    ASSERT_TRUE(views.has_value()) << "frame " << f << ": the simulated head's pose is not valid";
    // The eyes 63 mm apart (Monado's default IPD), level, either side of the head.
    const glm::vec3 left = eye_centre(*views, kLeftEye);
    const glm::vec3 right = eye_centre(*views, kRightEye);
    EXPECT_NEAR(glm::length(right - left), 0.063, 0.001) << "frame " << f;
    heads.push_back(0.5f * (left + right));
    // rhot's world from the STAGE space moves the eyes by exactly that transform.
    const glm::vec3 shift(1.0f, -0.25f, 2.0f);
    ASSERT_TRUE(xr.set_world_from_stage(glm::translate(glm::mat4(1.0f), shift)).has_value());
    const auto moved = xr.locate_views(0.05, 100.0);
    ASSERT_TRUE(xr.set_world_from_stage(glm::mat4(1.0f)).has_value());
    ASSERT_TRUE(moved.has_value());
    EXPECT_LT(glm::length(eye_centre(*moved, kLeftEye) - (left + shift)), 1e-5f);
    // Each eye's field of view where the runtime says: Monado's simulated headset has +-42.5 degrees
    // across and +-44.62 up and down, so a point that far off each eye's axis lands on the image's
    // right and top edges.
    if (xr.info().system == "Monado: Simulated HMD") {
      for (const int eye : {kLeftEye, kRightEye}) {
        const glm::mat4 world_from_eye = glm::inverse(views->eye_from_world[eye]);
        const int w = renderer.eye_width_px(), h = renderer.eye_height_px();
        const glm::vec3 right_edge(world_from_eye * glm::vec4(std::tan(glm::radians(42.5f)), 0.0f, -1.0f, 1.0f));
        const glm::vec3 top_edge(world_from_eye * glm::vec4(0.0f, std::tan(glm::radians(44.62f)), -1.0f, 1.0f));
        EXPECT_NEAR(project_to_pixel(*views, eye, right_edge, w, h).x, static_cast<float>(w), 0.01f * static_cast<float>(w));
        EXPECT_NEAR(project_to_pixel(*views, eye, top_edge, w, h).y, 0.0f, 0.01f * static_cast<float>(h));
      }
    }
    // Nothing that is not a rigid transform is taken as the registration.
    glm::mat4 sheared(1.0f);
    sheared[1][0] = 0.5f;
    EXPECT_FALSE(xr.set_world_from_stage(sheared).has_value());
    FrameInput frame;
    frame.views = *views;
    frame.lines = {{{-0.5f, 1.0f, -1.0f}, {1, 0, 0, 1}}, {{0.5f, 1.0f, -1.0f}, {1, 0, 0, 1}}};
    renderer.render(frame);
    EXPECT_FALSE(xr.current_frame().has_value()) << "render() ends the headset's frame";
  }
  renderer.finish();
  // Every frame the runtime wanted rendered was drawn into its swapchains (its first, before the
  // session is visible, is not to be rendered), and most of them were.
  EXPECT_EQ(xr.frames_submitted(), to_render);
  EXPECT_GE(to_render, static_cast<std::uint64_t>(kFrames / 2));
  // At about (0, 1.6, 0) in the stage, and moving (the simulated head wobbles).
  float spread = 0.0f;
  for (const glm::vec3& h : heads) {
    EXPECT_NEAR(h.y, 1.6f, 0.2f);
    spread = std::max(spread, glm::length(h - heads.front()));
  }
  EXPECT_GT(spread, 0.001f);
  // Paced by the runtime: Monado's null compositor shows 20 frames a second.
  EXPECT_NEAR(xr.info().refresh_hz, 20.0, 1.0);

  // Asked to end, the session goes through STOPPING (rhot ends it) to EXITING.
  xr.request_exit();
  ASSERT_TRUE(poll_until(
      xr, [&] { return xr.should_exit(); }, 5.0))
      << "state: " << to_string(xr.state());
  EXPECT_EQ(xr.state(), XrState::kExiting);
  EXPECT_EQ(xr.exit_reason(), "the session ended as asked");
  EXPECT_FALSE(xr.session_running());
  EXPECT_FALSE(xr.begin_frame().has_value());
  EXPECT_EQ(xr.validation_messages(), 0u);
  EXPECT_EQ(renderer.validation_messages(), 0u);
}

}  // namespace
}  // namespace rhot
