// The runtime with a source of tracking results of the test's own: whatever the source, its
// results become components (objects' Transforms, the hands' Hand), physics reads the hands and
// writes HandBody, and the systems run in the declared order.

#include "engine/runtime/Runtime.h"

#include <gtest/gtest.h>

#include "engine/app/FrameLoop.h"
#include "engine/core/Transform.h"
#include "engine/scene/SceneLoader.h"

namespace rhot {
namespace {

// Tracking results from a script: the right hand resting open above the table, the mug rising
// 1 cm a second; one stage.
class ScriptedResults final : public ResultSource {
 public:
  std::vector<TrackingStage> stages() override {
    return {{"scripted", [this](double t) {
               ++frames;
               results_ = TrackingResults{};
               results_.t_s = t;
               Rigid3d world_from_hand;
               world_from_hand.translation = Eigen::Vector3d(0.15, 0.95, -0.3);
               results_.hands[1] = hand_input(world_from_hand, reference_open_hand(HandSide::kRight));
               Rigid3d mug;
               mug.translation = Eigen::Vector3d(-0.3, 0.85 + 0.01 * t, -0.15);
               results_.world_from_object[0] = mug;
             }}};
  }
  TrackingResults& results() override { return results_; }
  int frames = 0;

 private:
  TrackingResults results_;
};

struct Scripted {
  std::unique_ptr<Runtime> runtime;
  ScriptedResults* source = nullptr;
};

Scripted make_runtime() {
  const auto scene = load_scene_file(std::string(RHOT_ASSET_DIR) + "/scenes/default.json");
  EXPECT_TRUE(scene.has_value());
  RuntimeSettings settings;
  settings.star_set = std::string(RHOT_ASSET_DIR) + "/stars/seed-case.json";
  Scripted run;
  auto created = Runtime::create(*scene, nullptr, settings,
                                 [&](World&, const TrackedObjects& objects) -> std::expected<std::unique_ptr<ResultSource>, std::string> {
                                   EXPECT_EQ(objects.objects.size(), 3u) << "the default scene's star-tracked objects";
                                   auto source = std::make_unique<ScriptedResults>();
                                   run.source = source.get();
                                   return std::unique_ptr<ResultSource>(std::move(source));
                                 });
  EXPECT_TRUE(created.has_value()) << (created ? "" : created.error());
  run.runtime = std::move(*created);
  return run;
}

TEST(Runtime, AnySourcesResultsBecomeComponentsAndDrivePhysics) {
  Scripted run = make_runtime();
  Runtime& r = *run.runtime;
  Systems systems;
  r.add_stage("physics", {"after-physics", [&](double) { EXPECT_EQ(run.source->frames, static_cast<int>(r.frames())); }});
  r.add_systems(systems, "");
  ASSERT_TRUE(systems.build().has_value());
  EXPECT_EQ(systems.names(),
            (std::vector<std::string>{"clock", "scripted", "tracked", "publish", "transforms", "physics", "after-physics"}));
  FrameLoop loop(r.world(), systems, FrameLoopSettings{});
  for (int i = 0; i < 90; ++i) loop.step();

  EXPECT_EQ(run.source->frames, 90);
  // The mug is where the source says (as float), at the last frame's time.
  const Entity mug = find_named(r.world(), "tracked-mug");
  const glm::vec3 p = r.world().get<Transform>(mug).position;
  EXPECT_FLOAT_EQ(p.y, static_cast<float>(0.85 + 0.01 * r.time_s()));
  EXPECT_FLOAT_EQ(p.x, -0.3f);
  // The right hand's components: tracked as given, and placed in the physics (19 capsules).
  const Hand& right = r.hand(HandSide::kRight);
  EXPECT_TRUE(right.tracked.seen);
  EXPECT_EQ(right.tracked.joints_world, run.source->results().hands[1].joints_world);
  EXPECT_FALSE(right.gestures_measured);
  const HandBody* body = r.hand_body(HandSide::kRight);
  ASSERT_NE(body, nullptr);
  EXPECT_TRUE(body->active);
  EXPECT_EQ(body->capsules.size(), static_cast<std::size_t>(kHandBoneCount));
  EXPECT_FALSE(body->holding.has_value());
  // Resting in free air, the physical hand is where the tracked one is.
  for (std::size_t j = 0; j < kHandJointCount; ++j) EXPECT_LT((body->joints_world[j] - right.tracked.joints_world[j]).norm(), 1e-3) << j;
  // The left hand was never tracked.
  EXPECT_FALSE(r.hand(HandSide::kLeft).tracked.seen);
  EXPECT_FALSE(r.hand_body(HandSide::kLeft)->active);
}

TEST(Runtime, PausedItRunsNoStageButTransformsAndSteppingRunsOne) {
  Scripted run = make_runtime();
  Runtime& r = *run.runtime;
  Systems systems;
  r.add_systems(systems, "");
  ASSERT_TRUE(systems.build().has_value());
  FrameLoop loop(r.world(), systems, FrameLoopSettings{});
  for (int i = 0; i < 10; ++i) loop.step();
  r.set_paused(true);
  for (int i = 0; i < 10; ++i) loop.step();
  EXPECT_EQ(run.source->frames, 10);
  r.step();
  loop.step();
  loop.step();
  EXPECT_EQ(run.source->frames, 11);
  EXPECT_EQ(r.frames(), 11u);
}

TEST(Runtime, AFailingSourceFailsCreationWithItsMessage) {
  const auto scene = load_scene_file(std::string(RHOT_ASSET_DIR) + "/scenes/default.json");
  ASSERT_TRUE(scene.has_value());
  RuntimeSettings settings;
  settings.star_set = std::string(RHOT_ASSET_DIR) + "/stars/seed-case.json";
  const auto failed = Runtime::create(*scene, nullptr, settings, [](World&, const TrackedObjects&) {
    return std::expected<std::unique_ptr<ResultSource>, std::string>(std::unexpected(std::string("camera 2 is unplugged")));
  });
  ASSERT_FALSE(failed.has_value());
  EXPECT_EQ(failed.error(), "camera 2 is unplugged");
  settings.star_set = "/nonexistent/stars.json";
  const auto no_set = Runtime::create(*scene, nullptr, settings, [](World&, const TrackedObjects&) {
    return std::expected<std::unique_ptr<ResultSource>, std::string>(std::make_unique<ScriptedResults>());
  });
  ASSERT_FALSE(no_set.has_value());
  EXPECT_EQ(no_set.error(), "/nonexistent/stars.json: star set file not found");
}

}  // namespace
}  // namespace rhot
