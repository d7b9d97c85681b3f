// The tracking system's side in the world: which entities tracking moves, where their stars sit,
// and the copy of a frame's results into components.

#include "engine/tracked/TrackedObjects.h"

#include <gtest/gtest.h>

#include "engine/core/Transform.h"
#include "engine/core/World.h"
#include "engine/scene/SceneLoader.h"

namespace rhot {
namespace {

SceneDesc scene_with_two_tracked_boxes() {
  const auto scene = parse_scene(R"({"settings": {"hands": ["right"]}, "entities": [
      {"name": "crate", "transform": {"position": [0, 1, 0], "scale": 2}, "mesh": {"shape": "box", "size_m": [0.1, 0.1, 0.1]},
       "tracked_by": 3},
      {"name": "lid", "mesh": {"shape": "sphere", "radius_m": 0.02}, "tracked_by": 5},
      {"name": "table", "mesh": {"shape": "box", "size_m": [1, 0.1, 1]}}]})",
                                 ".");
  EXPECT_TRUE(scene.has_value()) << (scene ? "" : scene.error().to_string());
  return scene.value_or(SceneDesc{});
}

StarSet set_with(std::initializer_list<int> ids) {
  StarSet set;
  for (const int id : ids) {
    MarkerStar s;
    s.id = id;
    set.stars.push_back(s);
  }
  return set;
}

TEST(TrackedObjects, EachTrackedEntityGetsItsStarStandingBehindIt) {
  World world;
  instantiate(scene_with_two_tracked_boxes(), world);
  const auto objects = find_tracked_objects(world, set_with({1, 3, 5}), "set.json");
  ASSERT_TRUE(objects.has_value()) << objects.error();
  ASSERT_EQ(objects->objects.size(), 2u);
  ASSERT_EQ(objects->stars.stars.size(), 2u);
  const TrackedObject* crate = objects->by_star(3);
  ASSERT_NE(crate, nullptr);
  EXPECT_EQ(crate->name, "crate");
  // Half the box's depth, scaled (0.05 * 2), plus 4 mm clearance, on the -Z side, turned to face out.
  EXPECT_NEAR(crate->object_from_star.translation.z(), -0.104, 1e-7);  // float sizes
  EXPECT_NEAR(std::abs(crate->object_from_star.rotation.y()), 1.0, 1e-12);
  EXPECT_NEAR(objects->by_star(5)->object_from_star.translation.z(), -0.024, 1e-7);
  EXPECT_EQ(objects->by_star(1), nullptr);
}

TEST(TrackedObjects, AStarTheSetLacksIsNamed) {
  World world;
  instantiate(scene_with_two_tracked_boxes(), world);
  const auto objects = find_tracked_objects(world, set_with({3}), "set.json");
  ASSERT_FALSE(objects.has_value());
  EXPECT_EQ(objects.error(), "lid: tracked by star 5, which set.json does not have");
}

TEST(TrackedObjects, ResultsMoveTheObjectsSeenAndFillTheHands) {
  World world;
  const SceneDesc scene = scene_with_two_tracked_boxes();
  instantiate(scene, world);
  const auto objects = find_tracked_objects(world, set_with({3, 5}), "set.json");
  ASSERT_TRUE(objects.has_value());
  create_tracking_entities(world, scene.settings, nullptr);
  TrackingResults r;
  Rigid3d pose;
  pose.translation = Eigen::Vector3d(0.25, 0.5, -0.75);
  r.world_from_object[3] = pose;  // the crate seen, the lid not
  r.hands[1].seen = true;
  r.hands[1].joints_world[5] = Eigen::Vector3d(1, 2, 3);
  r.gestures_measured = true;
  r.pinch[1] = {0.8, true};
  r.points = {Eigen::Vector3d(0, 1, 0)};
  r.point_cameras = {{0, 2}};
  const glm::vec3 lid_before = world.get<Transform>(find_named(world, "lid")).position;
  apply_tracking_results(world, r, *objects);
  EXPECT_EQ(world.get<Transform>(find_named(world, "crate")).position, glm::vec3(0.25f, 0.5f, -0.75f));
  EXPECT_EQ(world.get<Transform>(find_named(world, "lid")).position, lid_before);
  const Hand& right = world.get<Hand>(find_named(world, "hand-right"));
  EXPECT_EQ(right.side, HandSide::kRight);
  EXPECT_TRUE(right.shown);
  EXPECT_TRUE(right.tracked.seen);
  EXPECT_EQ(right.tracked.joints_world[5], Eigen::Vector3d(1, 2, 3));
  EXPECT_TRUE(right.pinch.active);
  const Hand& left = world.get<Hand>(find_named(world, "hand-left"));
  EXPECT_FALSE(left.shown) << "the scene leaves the left hand out";
  EXPECT_FALSE(left.tracked.seen);
  const TrackedMarkers& markers = world.get<TrackedMarkers>(find_named(world, "tracking"));
  EXPECT_EQ(markers.points, r.points);
  EXPECT_EQ(markers.point_cameras, r.point_cameras);
  EXPECT_TRUE(world.get<TrackingCameras>(find_named(world, "tracking")).cameras.empty());
}

}  // namespace
}  // namespace rhot
