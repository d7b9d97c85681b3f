// The whole frame from simulated cameras to physics, headless and deterministic.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>

#include <gtest/gtest.h>

#include "engine/core/Transform.h"
#include "engine/core/World.h"
#include "engine/math/EigenGlm.h"
#include "engine/scene/Components.h"
#include "engine/sim/Demo.h"
#include "engine/sim/DemoPickups.h"
#include "engine/tracked/Recording.h"
#include "engine/tracked/TrackingResults.h"
#include "engine/scene/SceneLoader.h"
#include "tracking/sim/Realism.h"

namespace rhot {
namespace {

Entity named(World& world, const std::string& name) { return find_named(world, name); }

struct DemoRun {
  double block_lift_m = 0.0;
  int right_grasps_of_block = 0;
  int right_releases_of_block = 0;
  double mug_worst_error_m = 0.0;
  double mug_lift_m = 0.0;
  int mug_seen_frames = 0;
  double hands_seen_fraction = 0.0;
  Eigen::Vector3d block_end = Eigen::Vector3d::Zero();
};

DemoRun run_default_scene(int frames, bool perfect_hands = false, unsigned seed = 1) {
  const auto scene = load_scene_file(std::string(RHOT_ASSET_DIR) + "/scenes/default.json");
  EXPECT_TRUE(scene.has_value());
  DemoSettings settings;
  settings.asset_dir = RHOT_ASSET_DIR;
  settings.perfect_hands = perfect_hands;
  settings.seed = seed;
  auto created = Demo::create(*scene, nullptr, settings);
  EXPECT_TRUE(created.has_value()) << (created ? "" : created.error());
  Demo& demo = **created;
  Runtime& p = demo.runtime();
  World& world = p.world();
  const Entity block = named(world, "cube-red");
  const Entity mug = named(world, "tracked-mug");
  const float block_y0 = world.get<Transform>(block).position.y;
  const float mug_y0 = world.get<Transform>(mug).position.y;
  DemoRun r;
  long seen = 0;
  for (int f = 0; f < frames; ++f) {
    const double t = f / 90.0;
    p.run_frame(t);
    for (const InteractionEvent& e : p.physics().events()) {
      if (e.object != block || e.hand != HandSide::kRight) continue;
      r.right_grasps_of_block += e.type == InteractionEventType::kGrasp ? 1 : 0;
      r.right_releases_of_block += e.type == InteractionEventType::kRelease ? 1 : 0;
    }
    r.block_lift_m = std::max(r.block_lift_m, static_cast<double>(world.get<Transform>(block).position.y - block_y0));
    const glm::vec3 m = world.get<Transform>(mug).position;
    const Eigen::Vector3d truth = demo.simulated()->truth()->world_from_object.at(0).translation;
    const auto& seen_ids = p.tracking().results().counts.seen_star_ids;
    if (std::find(seen_ids.begin(), seen_ids.end(), 0) != seen_ids.end()) {
      ++r.mug_seen_frames;
      r.mug_worst_error_m = std::max(r.mug_worst_error_m, (to_eigen(m) - truth).norm());
    }
    r.mug_lift_m = std::max(r.mug_lift_m, static_cast<double>(m.y - mug_y0));
    const TrackingCounts& counts = p.tracking().results().counts;
    seen += (counts.hands_seen[0] ? 1 : 0) + (counts.hands_seen[1] ? 1 : 0);
  }
  const glm::vec3 b = world.get<Transform>(block).position;
  r.block_end = to_eigen(b);
  r.hands_seen_fraction = static_cast<double>(seen) / (2.0 * frames);
  return r;
}

TEST(Demo, FromSimulatedCamerasTheRightHandLiftsTheBlockAndTheLeftCarriesTheTrackedMug) {
  const DemoRun r = run_default_scene(1080);
  EXPECT_GT(r.hands_seen_fraction, 0.95);
  EXPECT_EQ(r.right_grasps_of_block, 1);
  EXPECT_EQ(r.right_releases_of_block, 1);
  EXPECT_GE(r.block_lift_m, 0.10) << "lifted through tracking and physics";
  EXPECT_NEAR(r.block_end.x(), -0.35 + 0.15, 0.03) << "set down where the script put it";
  EXPECT_NEAR(r.block_end.z(), -0.35 - 0.1, 0.03);
  EXPECT_GE(r.mug_lift_m, 0.10) << "the star-tracked mug follows the hand that carries it";
  EXPECT_GT(r.mug_seen_frames, 1080 * 9 / 10) << "its star is seen in most frames, also while carried";
  EXPECT_LT(r.mug_worst_error_m, 0.005) << "where seen, its tracked pose is within 5 mm of the truth";
}

TEST(Demo, TheTrackedMugStaysWithinFiveMillimetresWithOtherSeedsOfTheNoise) {
  // Seeds 3 and 6 once put it 5.0 mm off in single frames where only three of its markers were
  // seen, one by two cameras: the star's pose is now fitted with each point weighted by its
  // triangulation uncertainty.
  for (const unsigned seed : {3U, 6U}) {
    const DemoRun r = run_default_scene(1080, false, seed);
    EXPECT_GT(r.mug_seen_frames, 1080 * 9 / 10) << "seed " << seed;
    EXPECT_LT(r.mug_worst_error_m, 0.005) << "seed " << seed;
  }
}

// In the realistic world the scene's bodies hide markers, as a desk does (issue 37): the table, its
// legs and every object with a shape are occluders where the cameras see them, a star-tracked
// object where it truly is. Its own markers stay in view. (The block is then not lifted in this
// seed's first 4 s, where it is without them: the cube hides a grasping fingertip, the failure
// issue 37's grasps from evidence are to mend; docs/PERFORMANCE.md.)
TEST(Demo, InTheRealisticWorldTheTableAndTheObjectsHideMarkers) {
  const auto scene = load_scene_file(std::string(RHOT_ASSET_DIR) + "/scenes/default.json");
  ASSERT_TRUE(scene.has_value());
  const auto realistic = world_named("realistic");
  ASSERT_TRUE(realistic.has_value());
  DemoSettings settings;
  settings.asset_dir = RHOT_ASSET_DIR;
  settings.world = *realistic;
  settings.sigma_px = realistic->sigma_px;
  auto created = Demo::create(*scene, nullptr, settings);
  ASSERT_TRUE(created.has_value()) << created.error();
  Demo& demo = **created;
  World& world = demo.world();
  int mug_seen = 0;
  const Entity block = named(world, "cube-red");
  bool grasped = false;
  const auto rest_y = static_cast<double>(world.get<Transform>(block).position.y);
  double lift_m = 0.0;
  constexpr int kFrames = 360;  // the right hand reaches for the block, closes on it and lifts it
  for (int f = 0; f < kFrames; ++f) {
    demo.runtime().run_frame(f / 90.0);
    const auto& seen_ids = demo.runtime().tracking().results().counts.seen_star_ids;
    mug_seen += std::find(seen_ids.begin(), seen_ids.end(), 0) != seen_ids.end() ? 1 : 0;
    for (const InteractionEvent& e : demo.runtime().physics().events())
      grasped = grasped || (e.object == block && e.hand == HandSide::kRight && e.type == InteractionEventType::kGrasp);
    lift_m = std::max(lift_m, static_cast<double>(world.get<Transform>(block).position.y) - rest_y);
  }
  // The block hides the right thumb's and index's tips as they close on it; placed against it
  // (engine/interact/FingerContact.h) they grasp it all the same (with hidden_finger_curl_rad 0
  // this grasp never began).
  EXPECT_TRUE(grasped);
  EXPECT_GE(lift_m, kPickupLift_m);
  // One occluder for each body with a box, sphere or capsule (not the floor's plane).
  int bodies = 0;
  world.view<Mesh, PhysicsBody>().each(
      [&](const Mesh& m, const PhysicsBody&) { bodies += std::holds_alternative<PlaneShape>(m.shape) ? 0 : 1; });
  const std::vector<Occluder> occluders = demo.simulated()->body_occluders();
  EXPECT_EQ(static_cast<int>(occluders.size()), bodies);
  EXPECT_GE(bodies, 18);
  const auto blocked = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
    return std::any_of(occluders.begin(), occluders.end(), [&](const Occluder& o) { return o.blocks(p, q); });
  };
  // The table top (0.7-0.74 m, centred at z -0.5): a marker under it is hidden from a camera
  // above, one on it is not (a clear spot of the table, right front).
  const Eigen::Vector3d above(0.5, 1.8, -0.3);
  EXPECT_TRUE(blocked({0.5, 0.68, -0.2}, above));
  EXPECT_FALSE(blocked({0.5, 0.76, -0.2}, above));
  // The mug (a capsule 8 cm across) where the truth has it: a point at its centre is inside.
  const Eigen::Vector3d mug = demo.simulated()->truth()->world_from_object.at(0).translation;
  EXPECT_TRUE(blocked(mug, above));
  EXPECT_GT(mug_seen, kFrames * 8 / 10) << "its own body does not hide its star";
  // The ideal world hides markers behind the hands' bones only.
  DemoSettings ideal;
  ideal.asset_dir = RHOT_ASSET_DIR;
  auto plain = Demo::create(*scene, nullptr, ideal);
  ASSERT_TRUE(plain.has_value()) << plain.error();
  (*plain)->runtime().run_frame(0.0);
  EXPECT_TRUE((*plain)->simulated()->body_occluders().empty());
}

TEST(Demo, WithPerfectHandsTooTheBlockIsLifted) {
  // The cube's part of the script only (lifted by 3.2 s).
  const DemoRun r = run_default_scene(330, true);
  EXPECT_EQ(r.right_grasps_of_block, 1);
  EXPECT_GE(r.block_lift_m, 0.10);
}

// The placements where the first pickup failed: each is lifted, with either seed of the
// simulated noise, and neither hand is ever reported where the other one is.
PickupResult pickup_at(const Eigen::Vector2d& spot, unsigned seed) {
  const auto scene = load_scene_file(std::string(RHOT_ASSET_DIR) + "/scenes/default.json");
  EXPECT_TRUE(scene.has_value());
  DemoSettings settings;
  settings.asset_dir = RHOT_ASSET_DIR;
  settings.seed = seed;
  const auto r = run_pickup(*scene, spot, settings);
  EXPECT_TRUE(r.has_value()) << (r ? "" : r.error());
  return r.value_or(PickupResult{});
}

TEST(Demo, TheCubeTwentyCentimetresNearerTheUserIsLiftedAndTheHandsAreNeverConfused) {
  // The right hand reaches past the resting left hand: with one shared assignment and a left hand
  // star of its own, neither hand takes the other's markers.
  for (const unsigned seed : {1U, 2U}) {
    const PickupResult r = pickup_at({-0.35, -0.15}, seed);
    EXPECT_TRUE(r.grasped) << "seed " << seed;
    EXPECT_GE(r.lift_m, kPickupLift_m) << "seed " << seed;
    EXPECT_EQ(r.hand_confusion_frames, 0) << "seed " << seed;
    EXPECT_EQ(r.reported_wrong_frames, 0) << "seed " << seed << " of " << r.hand_frames_seen;
  }
}

TEST(Demo, TheCubeFourteenCentimetresLeftAndBackIsLifted) {
  for (const unsigned seed : {1U, 2U}) {
    const PickupResult r = pickup_at({-0.49, -0.49}, seed);
    EXPECT_TRUE(r.grasped) << "seed " << seed;
    EXPECT_GE(r.lift_m, kPickupLift_m) << "seed " << seed;
    EXPECT_EQ(r.hand_confusion_frames, 0) << "seed " << seed;
  }
}

TEST(DemoPickups, SpotsLieOnTheTableClearOfTheOtherObjects) {
  const auto scene = load_scene_file(std::string(RHOT_ASSET_DIR) + "/scenes/default.json");
  ASSERT_TRUE(scene.has_value());
  const auto spots = pickup_spots(*scene, 200, 7);
  ASSERT_TRUE(spots.has_value()) << spots.error();
  ASSERT_EQ(spots->size(), 200U);
  for (const Eigen::Vector2d& p : *spots) {
    // The table spans x -0.6..0.6, z -0.9..-0.1; the carry goes 0.15 to +x and 0.1 to -z.
    EXPECT_GT(p.x(), -0.6 + 0.05);
    EXPECT_LT(p.x() + 0.15, 0.6 - 0.05);
    EXPECT_GT(p.y() - 0.10, -0.9 + 0.05);
    EXPECT_LT(p.y(), -0.1 - 0.05);
    for (const EntityDesc& e : scene->entities) {
      if (e.name == "cube-red" || !e.body || !e.grabbable) continue;
      EXPECT_GE(std::hypot(p.x() - static_cast<double>(e.transform.position.x), p.y() - static_cast<double>(e.transform.position.z)), 0.11)
          << e.name;
    }
  }
  EXPECT_EQ(pickup_spots(*scene, 200, 7)->front(), spots->front()) << "deterministic for a seed";
  SceneDesc no_cube = *scene;
  std::erase_if(no_cube.entities, [](const EntityDesc& e) { return e.name == "cube-red"; });
  EXPECT_EQ(pickup_spots(no_cube, 1, 1).error(), "the scene has no entity \"cube-red\" to pick up");
  EXPECT_EQ(run_pickup(no_cube, {0.0, -0.3}, DemoSettings{}).error(), "the scene has no entity \"cube-red\" to pick up");
}

TEST(Demo, ARecordingReplaysToThePosesItRecorded) {
  const auto scene = load_scene_file(std::string(RHOT_ASSET_DIR) + "/scenes/default.json");
  ASSERT_TRUE(scene.has_value());
  const std::string file = ::testing::TempDir() + "rhot_pipeline_recording.jsonl";
  constexpr int kFrames = 300;
  std::vector<std::array<HandInput, 2>> recorded_hands;
  std::vector<glm::vec3> recorded_mug;
  {
    DemoSettings settings;
    settings.asset_dir = RHOT_ASSET_DIR;
    settings.record = file;
    auto demo = Demo::create(*scene, nullptr, settings);
    ASSERT_TRUE(demo.has_value()) << demo.error();
    Runtime& p = (*demo)->runtime();
    World& world = p.world();
    const Entity mug = named(world, "tracked-mug");
    for (int f = 0; f < kFrames; ++f) {
      p.run_frame(f / 90.0);
      recorded_hands.push_back({p.hand(HandSide::kLeft).tracked, p.hand(HandSide::kRight).tracked});
      recorded_mug.push_back(world.get<Transform>(mug).position);
    }
  }
  const auto recording = load_recording(file);
  ASSERT_TRUE(recording.has_value()) << recording.error();
  EXPECT_EQ(recording->frames.size(), static_cast<std::size_t>(kFrames));
  EXPECT_EQ(recording->objects, (std::vector<std::string>{"tracked-mug", "tracked-screwdriver", "tracked-part"}));
  // The right hand's grasp of the block is in it, with its reason, and the frames after it say so.
  std::size_t grasped_at = 0;
  for (std::size_t f = 0; f < recording->frames.size() && !grasped_at; ++f) {
    for (const RecordedGraspEvent& e : recording->frames[f].grasp_events) {
      if (e.type == "grasp" && e.hand == "right" && e.object == "cube-red") {
        grasped_at = f;
        EXPECT_EQ(e.reason.rfind("thumb against ", 0), 0u) << e.reason;
      }
    }
  }
  ASSERT_GT(grasped_at, 0u);
  EXPECT_EQ(recording->frames[grasped_at].holding[1], "cube-red");
  EXPECT_EQ(recording->frames[grasped_at - 1].holding[1], "");

  DemoSettings settings;
  settings.asset_dir = RHOT_ASSET_DIR;
  settings.replay = file;
  auto demo = Demo::create(*scene, nullptr, settings);
  ASSERT_TRUE(demo.has_value()) << demo.error();
  Runtime& p = (*demo)->runtime();
  ASSERT_NE(p.tracking().playback(), nullptr);
  World& world = p.world();
  const Entity mug = named(world, "tracked-mug");
  double worst_joint = 0.0;
  float worst_mug = 0.0f;
  for (int f = 0; f < kFrames; ++f) {
    p.run_frame(f / 90.0);
    for (std::size_t h = 0; h < 2; ++h) {
      const HandInput& replayed = p.hand(h == 0 ? HandSide::kLeft : HandSide::kRight).tracked;
      ASSERT_EQ(replayed.seen, recorded_hands[static_cast<std::size_t>(f)][h].seen) << f;
      for (std::size_t j = 0; j < kHandJointCount; ++j) {
        worst_joint =
            std::max(worst_joint, (replayed.joints_world[j] - recorded_hands[static_cast<std::size_t>(f)][h].joints_world[j]).norm());
      }
    }
    if (f > 0)
      worst_mug = std::max(worst_mug, glm::distance(world.get<Transform>(mug).position, recorded_mug[static_cast<std::size_t>(f)]));
  }
  EXPECT_LT(worst_joint, 1e-9);
  EXPECT_LT(worst_mug, 1e-6f);
}

// Frame-to-frame motion of the tracked right index tip while the script holds the hand still
// above the cube (0.1-0.8 s): pixel noise only.
double resting_tip_jitter_m(bool filter, bool filter_frame) {
  const auto scene = load_scene_file(std::string(RHOT_ASSET_DIR) + "/scenes/default.json");
  EXPECT_TRUE(scene.has_value());
  DemoSettings settings;
  settings.asset_dir = RHOT_ASSET_DIR;
  settings.filter_hands = filter;
  settings.filter_hand_frames = filter_frame;
  auto created = Demo::create(*scene, nullptr, settings);
  EXPECT_TRUE(created.has_value()) << (created ? "" : created.error());
  Runtime& p = (*created)->runtime();
  LiveTracking& live = *(*created)->live();
  double sum = 0.0;
  int n = 0;
  Eigen::Vector3d last = Eigen::Vector3d::Zero();
  for (int f = 0; f < 72; ++f) {
    p.run_frame(f / 90.0);
    const TrackedHand& right = live.tracked_hand(HandSide::kRight);
    const Eigen::Vector3d tip = right.joints_world[static_cast<std::size_t>(HandJoint::kIndexTip)];
    if (f > 9 && right.hand_seen) {
      sum += (tip - last).norm();
      ++n;
    }
    last = tip;
  }
  EXPECT_GT(n, 50);
  return n > 0 ? sum / n : 0.0;
}

TEST(Demo, TheOneEuroFilterSteadiesAHandAtRest) {
  const double raw = resting_tip_jitter_m(false, false);
  const double frame = resting_tip_jitter_m(false, true);  // the default: the hand frame alone filtered
  const double filtered = resting_tip_jitter_m(true, true);
  // Measured: 1.03 mm a frame raw, 0.86 mm with the hand frame filtered (the default), 0.30 mm with
  // the fingertips filtered too.
  std::printf("index tip at rest, mean motion per frame: %.4f mm raw, %.4f mm frame filtered, %.4f mm filtered\n", 1e3 * raw, 1e3 * frame,
              1e3 * filtered);
  EXPECT_GT(raw, 0.0);
  EXPECT_LT(frame, 0.9 * raw) << "raw " << raw << " m, frame filtered " << frame << " m";
  EXPECT_LT(filtered, 0.6 * raw) << "raw " << raw << " m, filtered " << filtered << " m";
}

// The tracker's thread count (LaunchSettings::threads) changes nothing it delivers: the realistic
// world's demo run on one thread and on three gives the same points, objects and hands, bit for bit.
TEST(Demo, TheThreadCountChangesNoResult) {
  const auto scene = load_scene_file(std::string(RHOT_ASSET_DIR) + "/scenes/default.json");
  ASSERT_TRUE(scene.has_value());
  const auto realistic = world_named("realistic");
  ASSERT_TRUE(realistic.has_value());
  const auto run = [&](int threads) {
    DemoSettings settings;
    settings.asset_dir = RHOT_ASSET_DIR;
    settings.world = *realistic;
    settings.sigma_px = realistic->sigma_px;
    settings.threads = threads;
    auto created = Demo::create(*scene, nullptr, settings);
    EXPECT_TRUE(created.has_value()) << (created ? "" : created.error());
    std::vector<TrackingResults> frames;
    for (int f = 0; f < 240; ++f) {
      (*created)->runtime().run_frame(f / 90.0);
      frames.push_back((*created)->runtime().tracking().results());
    }
    return frames;
  };
  const std::vector<TrackingResults> one = run(1);
  const std::vector<TrackingResults> three = run(3);
  ASSERT_EQ(one.size(), three.size());
  const auto same = [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return std::memcmp(a.data(), b.data(), sizeof(double) * 3) == 0;
  };
  std::size_t points = 0;
  for (std::size_t f = 0; f < one.size(); ++f) {
    SCOPED_TRACE(testing::Message() << "frame " << f);
    ASSERT_EQ(one[f].points.size(), three[f].points.size());
    for (std::size_t p = 0; p < one[f].points.size(); ++p) ASSERT_TRUE(same(one[f].points[p], three[f].points[p])) << "point " << p;
    points += one[f].points.size();
    ASSERT_EQ(one[f].world_from_object.size(), three[f].world_from_object.size());
    for (const auto& [id, pose] : one[f].world_from_object) {
      ASSERT_TRUE(three[f].world_from_object.contains(id)) << "object " << id;
      EXPECT_TRUE(same(pose.translation, three[f].world_from_object.at(id).translation)) << "object " << id;
    }
    for (std::size_t h = 0; h < 2; ++h) {
      ASSERT_EQ(one[f].hands[h].seen, three[f].hands[h].seen) << "hand " << h;
      for (std::size_t j = 0; j < one[f].hands[h].joints_world.size(); ++j)
        ASSERT_TRUE(same(one[f].hands[h].joints_world[j], three[f].hands[h].joints_world[j])) << "hand " << h << " joint " << j;
    }
  }
  EXPECT_GT(points, 240U * 10U) << "the run tracked markers";
}

}  // namespace
}  // namespace rhot
