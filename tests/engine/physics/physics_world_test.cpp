// The Bullet world behind a scene: bodies from scene entities, glTF hulls, kinematic bodies.

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include <glm/gtc/quaternion.hpp>

#include "engine/core/Transform.h"
#include "engine/core/World.h"
#include "engine/physics/BulletMath.h"
#include "engine/interact/HandPhysics.h"
#include "engine/sim/ScriptedHands.h"
#include "engine/scene/SceneLoader.h"
#include "tests/engine/physics/PhysicsTestScenes.h"

namespace rhot {
namespace {

using test::kFloor;
using test::parse;
using test::physics_for;

using test::named;

TEST(PhysicsWorld, ADroppedBoxComesToRestOnTheFloorAndItsEntityFollows) {
  const SceneDesc scene = parse(std::string(R"({"entities": [)") + kFloor + R"(,
    {"name": "box", "transform": {"position": [0, 0.5, 0], "rotation_deg": [0, 30, 0]}, "mesh": {"shape": "box", "size_m": [0.2, 0.1, 0.2]},
     "body": {"type": "dynamic", "mass_kg": 1}}]})");
  World world;
  auto p = physics_for(world, scene);
  for (int i = 0; i < 270; ++i) p->step(world, {});
  const Entity box = named(world, "box");
  const Transform& t = world.get<Transform>(box);
  EXPECT_NEAR(t.position.y, 0.05f, 0.002f) << "resting on its 0.2 x 0.2 face";
  const glm::vec3 up = t.rotation * glm::vec3(0.0f, 1.0f, 0.0f);
  EXPECT_GT(up.y, std::cos(glm::radians(0.5f))) << "still upright";
  // The entity is where the body is.
  const btTransform& pose = p->physics().body(box)->getWorldTransform();
  EXPECT_NEAR(glm::distance(t.position, to_glm(pose.getOrigin())), 0.0f, 1e-6f);
  EXPECT_NEAR(std::abs(glm::dot(t.rotation, to_glm(pose.getRotation()))), 1.0f, 1e-6f);
  EXPECT_NEAR(glm::distance(glm::vec3(world.get<WorldTransform>(box).world_from_local[3]), t.position), 0.0f, 1e-6f);
  EXPECT_DOUBLE_EQ(p->physics().time_s(), 3.0);
}

TEST(PhysicsWorld, AGltfMeshCollidesAsItsConvexHull) {
  const SceneDesc scene = parse(std::string(R"({"entities": [)") + kFloor + R"(,
    {"name": "mesh", "transform": {"position": [0, 0.5, 0], "scale": [2, 1, 1]}, "mesh": {"shape": "gltf", "file": "box-10cm.gltf"},
     "body": {"type": "dynamic", "mass_kg": 0.5}}]})");
  World world;
  auto p = physics_for(world, scene);
  for (int i = 0; i < 180; ++i) p->step(world, {});
  const Transform& t = world.get<Transform>(named(world, "mesh"));
  EXPECT_NEAR(t.position.y, 0.05f, 0.003f) << "a 10 cm box (scaled 2x along x) rests on its face";
}

TEST(PhysicsWorld, ABrokenGltfMeshFailsAndAddsNothing) {
  const std::string file = (std::filesystem::path(::testing::TempDir()) / "rhot_not_gltf.gltf").lexically_normal().string();
  std::ofstream(file) << "not glTF";
  const SceneDesc scene = parse(std::string(R"({"entities": [)") + kFloor + R"(,
    {"name": "mesh", "mesh": {"shape": "gltf", "file": ")" +
                                file + R"("}, "body": {"type": "dynamic", "mass_kg": 0.5}}]})");
  World world;
  instantiate(scene, world);
  PhysicsWorld physics;
  const auto r = physics.add_scene_bodies(world);
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error().rfind("mesh: " + file + ": not a readable glTF 2.0 file", 0), 0U) << r.error();
  EXPECT_TRUE(physics.entities().empty());
  EXPECT_EQ(physics.bullet().getNumCollisionObjects(), 0);
}

TEST(PhysicsWorld, AKinematicBodyFollowsItsEntityPushesAndIgnoresNonFinitePoses) {
  const SceneDesc scene = parse(std::string(R"({"entities": [)") + kFloor + R"(,
    {"name": "paddle", "transform": {"position": [-0.3, 0.1, 0]}, "mesh": {"shape": "box", "size_m": [0.05, 0.2, 0.4]},
     "body": {"type": "kinematic"}, "tracked_by": 0},
    {"name": "ball", "transform": {"position": [0, 0.05, 0]}, "mesh": {"shape": "sphere", "radius_m": 0.05},
     "body": {"type": "dynamic", "mass_kg": 0.1}}]})");
  World world;
  auto p = physics_for(world, scene);
  const Entity paddle = named(world, "paddle");
  for (int i = 0; i < 90; ++i) {
    world.get<Transform>(paddle).position.x = -0.3f + 0.4f * static_cast<float>(i) / 90.0f;  // 0.4 m/s toward the ball
    update_world_transforms(world);
    p->step(world, {});
  }
  EXPECT_NEAR(p->physics().body(paddle)->getWorldTransform().getOrigin().x(), 0.1f - 0.4f / 90.0f, 1e-5f);
  EXPECT_GT(world.get<Transform>(named(world, "ball")).position.x, 0.1f) << "pushed ahead of the paddle";
  world.get<Transform>(paddle).position.x = std::nanf("");
  update_world_transforms(world);
  p->step(world, {});
  EXPECT_TRUE(finite(p->physics().body(paddle)->getWorldTransform().getOrigin()));
}

}  // namespace
}  // namespace rhot
