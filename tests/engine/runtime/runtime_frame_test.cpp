// The demo's whole frame, headless on the CPU Vulkan driver: captured frames at fixed moments
// match golden images (simulated cameras, tracking, physics and rendering are all deterministic).

#include <gtest/gtest.h>

#include "tests/support/Golden.h"
#include "engine/app/FrameLoop.h"
#include "engine/core/Transform.h"
#include "engine/math/EigenGlm.h"
#include "engine/sim/Demo.h"
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
  DemoSettings options;
  options.asset_dir = RHOT_ASSET_DIR;
  // The hands as tracked: predicted to the display time they would move with the machine's speed.
  options.predict = false;
  auto demo = Demo::create(*scene, renderer->get(), options);
  ASSERT_TRUE(demo.has_value()) << demo.error();
  Runtime* runtime = &(*demo)->runtime();
  Systems systems;
  runtime->add_systems(systems, "");
  ASSERT_TRUE(systems.build().has_value());
  FrameLoop loop(runtime->world(), systems, FrameLoopSettings{});
  // 2.8 s: the right hand holds the red cube up (green: holding); 8.0 s: the left hand carries
  // the star-tracked mug.
  for (const auto& [frame, name] : {std::pair<std::uint64_t, const char*>{252, "demo_frame_252"}, {720, "demo_frame_720"}}) {
    while (loop.frame_index() <= frame) loop.step();
    if (frame == 252) {
      EXPECT_TRUE(runtime->physics().grasp().holding(HandSide::kRight).has_value()) << "holding the cube";
    }
    const auto eyes = (*renderer)->read_eyes();
    testing::expect_matches_golden(side_by_side(eyes[0], eyes[1]), name);
  }
  // The same moment again with every debug view: marker points, rays from the cameras, the
  // cameras' frusta, the hands' collider capsules and tracked skeletons (paused: the state stays).
  runtime->set_paused(true);
  runtime->debug_views() = DebugViews{true, true, true, true};
  loop.step();
  const auto eyes = (*renderer)->read_eyes();
  testing::expect_matches_golden(side_by_side(eyes[0], eyes[1]), "demo_debug_views_720");
  EXPECT_EQ((*renderer)->validation_messages(), 0U);
}

struct Headless {
  std::unique_ptr<Demo> demo;
  Runtime* runtime = nullptr;
  Systems systems;
  std::unique_ptr<FrameLoop> loop;
};

std::unique_ptr<Headless> headless_demo() {
  auto h = std::make_unique<Headless>();
  const auto scene = load_scene_file(std::string(RHOT_ASSET_DIR) + "/scenes/default.json");
  EXPECT_TRUE(scene.has_value());
  DemoSettings options;
  options.asset_dir = RHOT_ASSET_DIR;
  auto demo = Demo::create(*scene, nullptr, options);
  EXPECT_TRUE(demo.has_value()) << demo.error();
  h->demo = std::move(*demo);
  h->runtime = &h->demo->runtime();
  h->runtime->add_systems(h->systems, "");
  EXPECT_TRUE(h->systems.build().has_value());
  h->loop = std::make_unique<FrameLoop>(h->runtime->world(), h->systems, FrameLoopSettings{});
  return h;
}

Eigen::Vector3d position_of(Runtime& d, const char* name) {
  const glm::vec3 p = d.world().get<Transform>(find_named(d.world(), name)).position;
  return Eigen::Vector3f{p.x, p.y, p.z}.cast<double>();
}

TEST(DemoFrame, PausingFreezesTheDemoAndSteppingRunsOneFrame) {
  auto straight = headless_demo();
  auto paused = headless_demo();
  Runtime& d = *paused->runtime;
  for (int i = 0; i < 60; ++i) paused->loop->step();
  const double t = d.time_s();
  const Eigen::Vector3d cube = position_of(d, "cube-red");
  const Eigen::Vector3d mug = position_of(d, "tracked-mug");
  d.set_paused(true);
  for (int i = 0; i < 20; ++i) paused->loop->step();
  EXPECT_EQ(d.time_s(), t);
  EXPECT_EQ(d.frames(), 60u);
  EXPECT_EQ(position_of(d, "cube-red"), cube);
  EXPECT_EQ(position_of(d, "tracked-mug"), mug);
  d.step();
  paused->loop->step();
  EXPECT_EQ(d.frames(), 61u);
  EXPECT_DOUBLE_EQ(d.time_s(), t + paused->loop->dt_s());
  for (int i = 0; i < 5; ++i) paused->loop->step();
  EXPECT_EQ(d.frames(), 61u);
  d.set_paused(false);
  while (d.frames() < 120) paused->loop->step();
  // The pause changed nothing but the wall time: the demo is where an uninterrupted run is.
  for (int i = 0; i < 120; ++i) straight->loop->step();
  EXPECT_DOUBLE_EQ(d.time_s(), straight->runtime->time_s());
  EXPECT_EQ(position_of(d, "cube-red"), position_of(*straight->runtime, "cube-red"));
  EXPECT_EQ(position_of(d, "tracked-mug"), position_of(*straight->runtime, "tracked-mug"));
}

TEST(DemoFrame, DebugViewsDrawTheCamerasRaysMarkersAndColliders) {
  auto h = headless_demo();
  Runtime& d = *h->runtime;
  for (int i = 0; i < 252; ++i) h->loop->step();  // the right hand holds the cube
  const TrackingResults& p = d.tracking().results();
  const CameraRig& rig = *d.tracking().rig();
  DebugDraw none;
  d.fill_debug(none);
  EXPECT_TRUE(none.lines().empty());
  EXPECT_TRUE(none.points().empty());

  d.debug_views() = DebugViews{.markers = true};
  DebugDraw markers;
  d.fill_debug(markers);
  ASSERT_GT(p.points.size(), 10u);
  ASSERT_EQ(markers.points().size(), p.points.size());
  EXPECT_EQ(markers.points()[3].position, to_glm(p.points[3]));

  d.debug_views() = DebugViews{.rays = true};
  DebugDraw rays;
  d.fill_debug(rays);
  std::size_t observations = 0;
  for (const auto& cams : p.point_cameras) observations += cams.size();
  ASSERT_EQ(rays.lines().size(), 2 * observations);
  // The first point's first ray runs from the camera that saw it to the point.
  const int first_camera = p.point_cameras[0][0];
  EXPECT_EQ(rays.lines()[0].position, to_glm(rig.cameras[static_cast<std::size_t>(first_camera)].centre_world()));
  EXPECT_EQ(rays.lines()[1].position, to_glm(p.points[0]));

  d.debug_views() = DebugViews{.frusta = true};
  DebugDraw frusta;
  d.fill_debug(frusta);
  ASSERT_EQ(frusta.lines().size(), rig.cameras.size() * 16);  // 8 lines per camera
  for (std::size_t c = 0; c < rig.cameras.size(); ++c) {
    const glm::vec3 apex = frusta.lines()[c * 16].position;
    EXPECT_LT(glm::distance(apex, to_glm(rig.cameras[c].centre_world())), 1e-5f) << "camera " << c;
  }

  d.debug_views() = DebugViews{.colliders = true};
  DebugDraw colliders;
  d.fill_debug(colliders);
  std::size_t capsules = 0;
  std::size_t skeleton_lines = 0;
  for (const HandSide side : {HandSide::kLeft, HandSide::kRight}) {
    capsules += d.physics().hand(side).capsules().size();
    if (d.hand(side).tracked.seen) skeleton_lines += hand_bones().size();
  }
  EXPECT_EQ(capsules, 2u * kHandBoneCount);
  EXPECT_EQ(colliders.lines().size(), 2 * (capsules * 29 + skeleton_lines));  // a capsule: axis, two 12-segment rings, 4 sides
}

}  // namespace
}  // namespace rhot
