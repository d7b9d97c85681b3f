// The demo's whole frame, headless on the CPU Vulkan driver: captured frames at fixed moments
// match golden images (simulated cameras, tracking, physics and rendering are all deterministic).

#include <gtest/gtest.h>

#include "../render/golden.h"
#include "engine/app/FrameLoop.h"
#include "engine/demo/DemoRuntime.h"
#include "engine/scene/SceneLoader.h"

namespace rhot {
namespace {

TEST(DemoFrame, CapturedFramesMatchTheGoldenImages) {
  const auto scene = load_scene_file(std::string(RHOT_ASSET_DIR) + "/scenes/default.json");
  ASSERT_TRUE(scene.has_value());
  RendererSettings render;
  render.eye_width_px = 270;
  render.eye_height_px = 300;
  render.device = "cpu";
  render.validation = true;
  auto renderer = Renderer::create(render);
  ASSERT_TRUE(renderer.has_value()) << renderer.error();
  DemoOptions options;
  options.pipeline.asset_dir = RHOT_ASSET_DIR;
  auto runtime = DemoRuntime::create(*scene, renderer->get(), options);
  ASSERT_TRUE(runtime.has_value()) << runtime.error();
  Systems systems;
  (*runtime)->add_systems(systems, "");
  ASSERT_TRUE(systems.build().has_value());
  FrameLoop loop((*runtime)->world(), systems, FrameLoopSettings{});
  // 2.8 s: the right hand holds the red cube up (green: holding); 8.0 s: the left hand carries
  // the star-tracked mug.
  for (const auto& [frame, name] : {std::pair<std::uint64_t, const char*>{252, "demo_frame_252"}, {720, "demo_frame_720"}}) {
    while (loop.frame_index() <= frame) loop.step();
    if (frame == 252) {
      EXPECT_TRUE((*runtime)->pipeline().hand_physics().grasp().holding(HandSide::kRight).has_value()) << "holding the cube";
    }
    const auto eyes = (*renderer)->read_eyes();
    testing::expect_matches_golden(side_by_side(eyes[0], eyes[1]), name);
  }
  EXPECT_EQ((*renderer)->validation_messages(), 0U);
}

}  // namespace
}  // namespace rhot
