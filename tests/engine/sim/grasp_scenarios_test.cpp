// Grasping through real Bullet worlds, hands driven by scripted skeletons (GraspScenarios.h).

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include "engine/sim/GraspScenarios.h"
#include "engine/scene/SceneLoader.h"
#include "tracking/camera/RigFile.h"

namespace rhot {
namespace {

GraspScenarioResult run(std::string_view name, const SceneDesc* scene = nullptr) {
  auto r = run_grasp_scenario(name, scene);
  EXPECT_TRUE(r.has_value()) << (r ? "" : r.error());
  return r.value_or(GraspScenarioResult{});
}

std::vector<InteractionEvent> of_type(const GraspScenarioResult& r, InteractionEventType type) {
  std::vector<InteractionEvent> out;
  std::copy_if(r.events.begin(), r.events.end(), std::back_inserter(out), [&](const InteractionEvent& e) { return e.type == type; });
  return out;
}

TEST(Grasp, ReachGraspLiftACubeHoldItTwoSecondsThenLetItFall) {
  const GraspScenarioResult r = run("lift");
  EXPECT_TRUE(r.grasped);
  EXPECT_GE(r.lift_m, 0.10);
  EXPECT_GE(r.held_s, 2.0);
  EXPECT_LT(r.max_slip_m, 0.005);
  EXPECT_TRUE(r.released);
  EXPECT_TRUE(r.fell_after_release);
  ASSERT_EQ(of_type(r, InteractionEventType::kGrasp).size(), 1U);
  EXPECT_EQ(of_type(r, InteractionEventType::kGrasp)[0].hand, HandSide::kRight);
  // The hand opens at 4.3 s: the release follows within the opening, not before.
  const auto releases = of_type(r, InteractionEventType::kRelease);
  ASSERT_EQ(releases.size(), 1U);
  EXPECT_GT(releases[0].time_s, 4.3);
  EXPECT_LT(releases[0].time_s, 4.5);
  EXPECT_FALSE(of_type(r, InteractionEventType::kContactBegin).empty());
  EXPECT_FALSE(of_type(r, InteractionEventType::kHoverBegin).empty());
}

TEST(Grasp, PinchASmallSphere) {
  const GraspScenarioResult r = run("pinch");
  EXPECT_TRUE(r.grasped);
  EXPECT_GE(r.lift_m, 0.10);
  EXPECT_LT(r.max_slip_m, 0.005);
  EXPECT_TRUE(r.fell_after_release);
}

TEST(Grasp, AThrowLeavesTheHandWithTheHandsVelocity) {
  const GraspScenarioResult r = run("throw");
  ASSERT_TRUE(r.released);
  EXPECT_DOUBLE_EQ(r.hand_speed_mps, 1.5);
  EXPECT_LT(r.throw_velocity_error, 0.10);
  const auto releases = of_type(r, InteractionEventType::kRelease);
  ASSERT_EQ(releases.size(), 1U);
  EXPECT_NEAR(releases[0].velocity_mps.x(), 1.5, 0.15);
}

TEST(Grasp, ASingleFingerPushesWithoutGrasping) {
  const GraspScenarioResult r = run("push");
  EXPECT_FALSE(r.grasped);
  EXPECT_TRUE(of_type(r, InteractionEventType::kGrasp).empty());
  EXPECT_FALSE(of_type(r, InteractionEventType::kContactBegin).empty());
  EXPECT_GT(r.pushed_m, 0.04) << "the finger travels 6 cm past the cube's face";
  EXPECT_LT(r.pushed_m, 0.09);
  EXPECT_LT(r.lift_m, 0.005);
}

TEST(Grasp, AHandOverBetweenTheTwoHands) {
  const GraspScenarioResult r = run("hand-over");
  EXPECT_TRUE(r.handed_over);
  const auto grasps = of_type(r, InteractionEventType::kGrasp);
  ASSERT_EQ(grasps.size(), 2U);
  EXPECT_EQ(grasps[0].hand, HandSide::kRight);
  EXPECT_EQ(grasps[1].hand, HandSide::kLeft);
  // The right hand lets go after the left took it; the object is never dropped.
  EXPECT_FALSE(r.fell_after_release);
  EXPECT_EQ(r.successes, std::vector<std::string>{"pass-the-cube"});
}

TEST(Grasp, AHeldObjectStaysHeldWhileTheFingertipMarkersAreHidden) {
  // Through the hand solver: from 2.8 to 3.3 s no fingertip is seen, the fingers ease toward
  // relaxed (opening) with falling confidence; the grip holds and lets go only when the seen
  // hand opens at 4.3 s.
  const GraspScenarioResult r = run("hidden-markers");
  EXPECT_TRUE(r.grasped);
  const auto releases = of_type(r, InteractionEventType::kRelease);
  ASSERT_EQ(releases.size(), 1U);
  EXPECT_GT(releases[0].time_s, 4.3);
  EXPECT_LT(r.max_slip_m, 0.005);
  EXPECT_GE(r.held_s, 2.0);
}

TEST(Grasp, AnInteractionSceneRaisesItsSuccessEvent) {
  // The shipped example scene, driven by the "place" script.
  const auto scene = load_scene_file(std::string(RHOT_ASSET_DIR) + "/scenes/interaction-place.json");
  ASSERT_TRUE(scene.has_value()) << scene.error().to_string();
  const GraspScenarioResult r = run("place", &*scene);
  EXPECT_TRUE(r.grasped);
  EXPECT_EQ(r.successes, std::vector<std::string>{"cube-in-bin"});
  const auto success = of_type(r, InteractionEventType::kSuccess);
  ASSERT_EQ(success.size(), 1U);
  EXPECT_FALSE(success[0].hand.has_value());
}

TEST(Grasp, ScenariosAreDeterministic) {
  const GraspScenarioResult a = run("throw");
  const GraspScenarioResult b = run("throw");
  EXPECT_EQ(a.throw_velocity_error, b.throw_velocity_error);
  EXPECT_EQ(a.pushed_m, b.pushed_m);
}

// The scenarios' hands through the seated rig (moved over the pedestal) and live tracking, in the
// ideal world: the hands the physics gets are tracked, not given.
ScenarioCameras seated_cameras(unsigned seed) {
  const std::filesystem::path assets(RHOT_ASSET_DIR);
  ScenarioCameras c;
  auto rig = load_rig(assets / "rigs" / "seated-4.yaml");
  EXPECT_TRUE(rig.has_value());
  if (rig) c.rig = *rig;
  for (std::size_t h = 0; h < 2; ++h) {
    auto layout = load_hand_layout(assets / "hands" / (h == 0 ? "low-cost-left.json" : "low-cost-right.json"));
    EXPECT_TRUE(layout.has_value());
    if (layout) c.layouts[h] = *layout;
  }
  c.world = *world_named("ideal");
  c.seed = seed;
  return c;
}

TEST(Grasp, TrackedHandsLiftTheCubeAndNeverConfuseTheHandsInAHandOver) {
  for (const unsigned seed : {1U, 2U}) {
    const ScenarioCameras cameras = seated_cameras(seed);
    auto lift = run_grasp_scenario("lift", nullptr, &cameras);
    ASSERT_TRUE(lift.has_value()) << lift.error();
    EXPECT_TRUE(lift->grasped) << "seed " << seed;
    EXPECT_GE(lift->lift_m, 0.10) << "seed " << seed;
    EXPECT_GE(lift->held_s, 2.0) << "seed " << seed;
    EXPECT_EQ(lift->hand_frames_seen, lift->frames) << "seed " << seed << ": the right hand is seen in every frame";
    EXPECT_EQ(lift->reported_wrong_frames, 0) << "seed " << seed;
    auto over = run_grasp_scenario("hand-over", nullptr, &cameras);
    ASSERT_TRUE(over.has_value()) << over.error();
    // (The hand-over itself succeeds in two of seeds 1-4 through tracked hands: the left hand's
    // grasp from the side is fragile; docs/PERFORMANCE.md.)
    EXPECT_TRUE(over->grasped) << "seed " << seed;
    EXPECT_GT(over->hand_frames_seen, over->frames) << "seed " << seed << ": both hands are seen";
    EXPECT_EQ(over->hand_confusion_frames, 0) << "seed " << seed;
    EXPECT_EQ(over->reported_wrong_frames, 0) << "seed " << seed;
  }
  ScenarioCameras bad = seated_cameras(1);
  bad.world.sigma_px = -1.0;
  EXPECT_EQ(run_grasp_scenario("lift", nullptr, &bad).error(), "world: " + bad.world.check().error());
}

// The hand-over through tracked hands in the realistic world: the taking hand's thumb and index
// hid behind the cube as they closed, and were placed against it as soon as they could reach it,
// so the left hand took the cube from the right 0.27 and 0.29 s (seeds 3 and 6) before the real
// fingers closed on it: an unintended release of the right hand's grip. Closing on an object the
// other hand holds, a hidden digit goes no farther than its tip can have moved since it hid
// (docs/grasping.md, "Taking from the other hand"): the take now comes 0.04-0.12 s before the
// script's own hands' on these seeds, as the right hand's release then does, and never later than
// the 0.25 s that rhot-eval counts as the same moment.
TEST(Grasp, HiddenFingersTakeTheCubeFromTheOtherHandNoSoonerThanTheRealOnesCould) {
  const auto take_s = [](const GraspScenarioResult& r) {
    for (const InteractionEvent& e : of_type(r, InteractionEventType::kGrasp))
      if (e.hand == HandSide::kLeft) return e.time_s;
    return -1.0;
  };
  const double perfect_s = take_s(run("hand-over"));
  ASSERT_GT(perfect_s, 3.0);
  for (const unsigned seed : {3U, 6U}) {
    ScenarioCameras cameras = seated_cameras(seed);
    cameras.world = *world_named("realistic");
    const auto tracked = run_grasp_scenario("hand-over", nullptr, &cameras);
    ASSERT_TRUE(tracked.has_value()) << tracked.error();
    EXPECT_TRUE(tracked->handed_over) << "seed " << seed;
    EXPECT_GE(take_s(*tracked), perfect_s - 0.2) << "seed " << seed << ": taken before the fingers could close";
    EXPECT_LE(take_s(*tracked), perfect_s + 0.25) << "seed " << seed << ": taken late";
  }
}

// Whatever the heap held before, a tracked scenario photographs the same hands: the simulated
// world's seed for the users' own hands was once left uninitialised, so that a run after other
// tests saw other hands than a run alone (found by Valgrind; in a release build the hand-over
// failed after most other Grasp tests and passed alone). Blocks of the sizes a scenario allocates
// are filled with a pattern and freed between two runs, for the second to reuse. (Under
// AddressSanitizer, which fills every new block with one byte, the two runs agree either way.)
TEST(Grasp, TrackedScenariosSeeTheSameHandsWhateverTheHeapHeld) {
  const ScenarioCameras cameras = seated_cameras(1);
  const auto first = run_grasp_scenario("hand-over", nullptr, &cameras);
  ASSERT_TRUE(first.has_value()) << first.error();
  {
    std::vector<std::unique_ptr<unsigned char[]>> blocks;
    for (std::size_t size = 16; size <= 4096; size += 16) {
      blocks.emplace_back(new unsigned char[size]);
      std::memset(blocks.back().get(), 0xa5, size);
    }
  }
  const auto second = run_grasp_scenario("hand-over", nullptr, &cameras);
  ASSERT_TRUE(second.has_value()) << second.error();
  EXPECT_EQ(first->fingertip_mean_mm, second->fingertip_mean_mm);
  EXPECT_EQ(first->events.size(), second->events.size());
  EXPECT_EQ(first->grasped, second->grasped);
  EXPECT_EQ(first->held_s, second->held_s);
  EXPECT_EQ(first->hand_frames_seen, second->hand_frames_seen);
}

TEST(Grasp, UnknownScenarioIsNamed) {
  const auto r = run_grasp_scenario("juggle");
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error(), "no grasp scenario \"juggle\"");
}

}  // namespace
}  // namespace rhot
