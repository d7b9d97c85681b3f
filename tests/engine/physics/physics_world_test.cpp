// The Bullet world behind a scene, and hand colliders in it.

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
#include "engine/physics/HandPhysics.h"
#include "engine/sim/ScriptedHands.h"
#include "engine/scene/SceneLoader.h"

namespace rhot {
namespace {

SceneDesc parse(const std::string& text) {
  auto scene = parse_scene(text, RHOT_SOURCE_DIR "/tests/engine/physics/data");
  EXPECT_TRUE(scene.has_value()) << (scene ? "" : scene.error().to_string());
  return scene.value_or(SceneDesc{});
}

const char* kFloor = R"({"name": "floor", "mesh": {"shape": "plane", "size_m": [4, 4]}, "body": {"type": "static"}})";

std::unique_ptr<HandPhysics> physics_for(World& world, const SceneDesc& scene) {
  instantiate(scene, world);
  auto p = HandPhysics::create(world, scene);
  EXPECT_TRUE(p.has_value()) << (p ? "" : p.error());
  return p ? std::move(*p) : nullptr;
}

Entity named(World& world, const std::string& name) { return find_named(world, name); }

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

const char* kPlateScene = R"({"entities": [
    {"name": "floor", "mesh": {"shape": "plane", "size_m": [4, 4]}, "body": {"type": "static"}},
    {"name": "stand", "transform": {"position": [0, 0.4, 0]}, "mesh": {"shape": "box", "size_m": [0.3, 0.8, 0.3]}, "body": {"type": "static"}},
    {"name": "plate", "transform": {"position": [0, 0.9, 0]}, "mesh": {"shape": "box", "size_m": [0.25, 0.2, 0.004]},
     "body": {"type": "dynamic", "mass_kg": 0.05}}]})";

TEST(HandColliders, AFastHandDoesNotPassThroughAThinPlate) {
  // The pointing hand sweeps at 4 m/s (4.4 cm per frame, ten times the plate's thickness) through
  // where a 4 mm plate stands: the bones must hit it, not skip over it.
  World world;
  auto p = physics_for(world, parse(kPlateScene));
  const HandPose pose = pointing_hand(HandSide::kRight);
  for (int i = 0; i < 30; ++i) {
    Rigid3d hand;
    hand.translation = Eigen::Vector3d(0.0, 0.92, 0.3 - 4.0 * static_cast<double>(i) / 90.0);
    p->step(world, {HandInput{}, hand_input(hand, pose)});
  }
  const Entity plate = named(world, "plate");
  const btRigidBody* body = p->physics().body(plate);
  EXPECT_LT(body->getWorldTransform().getOrigin().z(), -0.02f) << "knocked away by the hand";
}

TEST(HandColliders, BonesStopAtSurfacesInsteadOfSinkingIn) {
  // The tracked hand pressed 1.5 cm into a static block: the physical bones stay on its surface.
  World world;
  auto p = physics_for(world, parse(kPlateScene));
  const HandPose pose = pointing_hand(HandSide::kRight);
  Rigid3d hand;
  hand.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
  for (int i = 0; i < 60; ++i) {
    const double lowest = [&] {
      double y = 1e9;
      for (const auto& j : pose.position_m) y = std::min(y, (hand.rotation * j).y());
      return y;
    }();
    hand.translation = Eigen::Vector3d(0.0, 0.8 + 0.03 - std::min(1.0, i / 30.0) * 0.045 - lowest, 0.10);
    p->step(world, {HandInput{}, hand_input(hand, pose)});
  }
  const HandColliders& h = p->hand(HandSide::kRight);
  double lowest_physical = 1e9;
  for (int i = 0; i < kHandBoneCount; ++i) {
    // The capsule's lowest point: its lower end's sphere.
    const auto* capsule = static_cast<const btCapsuleShape*>(h.bone(i)->getCollisionShape());
    const btTransform& t = h.bone(i)->getWorldTransform();
    const btScalar a = (t * btVector3(0, capsule->getHalfHeight(), 0)).y();
    const btScalar b = (t * btVector3(0, -capsule->getHalfHeight(), 0)).y();
    lowest_physical = std::min(lowest_physical, static_cast<double>(std::min(a, b) - capsule->getRadius()));
    EXPECT_FALSE(h.soft(i)) << "1.5 cm is under the soft distance";
  }
  EXPECT_GT(lowest_physical, 0.8 - 0.003) << "no bone sinks into the stand";
  EXPECT_GT(h.largest_offset_m(), 0.01) << "the physical hand is offset from the tracked one";
}

TEST(HandColliders, NonFiniteHandsAreIgnored) {
  World world;
  auto p = physics_for(world, parse(kPlateScene));
  Rigid3d hand;
  hand.translation = Eigen::Vector3d(0.0, 1.2, 0.0);
  HandInput good = hand_input(hand, pointing_hand(HandSide::kRight));
  p->step(world, {HandInput{}, good});
  HandInput bad = good;
  bad.joints_world[7].x() = std::numeric_limits<double>::quiet_NaN();
  for (int i = 0; i < 10; ++i) p->step(world, {bad, bad});
  EXPECT_FALSE(p->hand(HandSide::kRight).active());
  for (int i = 0; i < kHandBoneCount; ++i) EXPECT_TRUE(finite(p->hand(HandSide::kRight).bone(i)->getWorldTransform().getOrigin()));
  p->step(world, {HandInput{}, good});
  EXPECT_TRUE(p->hand(HandSide::kRight).active());
}

TEST(HandPhysics, AThousandRandomHandMotionsThroughTheDefaultSceneStayInTheWorld) {
  const auto scene = load_scene_file(std::string(RHOT_ASSET_DIR) + "/scenes/default.json");
  ASSERT_TRUE(scene.has_value());
  World world;
  auto p = physics_for(world, *scene);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const std::array<GraspPose, 2> grasps{make_grasp(HandSide::kLeft, 0.05), make_grasp(HandSide::kRight, 0.05)};
  // Each motion: from the last pose to a random one over the table in 12 frames (hands up to
  // about 6 m/s, a fast throw).
  std::array<Eigen::Vector3d, 2> from{Eigen::Vector3d(-0.2, 0.9, -0.5), Eigen::Vector3d(0.2, 0.9, -0.5)};
  std::array<double, 2> closure_from{0.0, 0.0};
  long contacts = 0;
  for (int motion = 0; motion < 1000; ++motion) {
    std::array<Eigen::Vector3d, 2> to;
    std::array<double, 2> closure_to;
    for (std::size_t h = 0; h < 2; ++h) {
      to[h] = Eigen::Vector3d(-0.3 + 0.6 * u(rng), 0.74 + 0.25 * u(rng), -0.75 + 0.5 * u(rng));
      closure_to[h] = u(rng);
    }
    for (int k = 1; k <= 12; ++k) {
      const double s = k / 12.0;
      std::array<HandInput, 2> in;
      for (std::size_t h = 0; h < 2; ++h) {
        const Eigen::Vector3d c = from[h] + s * (to[h] - from[h]);
        in[h] = hand_input(grasps[h].place(c, h == 0 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitX()),
                           grasps[h].pose(closure_from[h] + s * (closure_to[h] - closure_from[h])));
      }
      p->step(world, in);
      for (const InteractionEvent& e : p->events()) contacts += e.type == InteractionEventType::kContactBegin ? 1 : 0;
    }
    from = to;
    closure_from = closure_to;
    for (const Entity e : p->physics().entities()) {
      const btRigidBody* b = p->physics().body(e);
      const btVector3 pos = b->getWorldTransform().getOrigin();
      ASSERT_TRUE(finite(pos) && finite(b->getLinearVelocity())) << "motion " << motion;
      ASSERT_GT(pos.y(), -0.01f) << world.get<Name>(e).value << " fell through the floor, motion " << motion;
      ASSERT_LT(std::abs(pos.x()), 3.0f) << world.get<Name>(e).value << " left the room, motion " << motion;
      ASSERT_LT(std::abs(pos.z()), 3.0f) << world.get<Name>(e).value << " left the room, motion " << motion;
      ASSERT_LT(b->getLinearVelocity().length(), 25.0f) << world.get<Name>(e).value << " exploded, motion " << motion;
    }
  }
  EXPECT_GT(contacts, 20) << "the hands hit the objects (43 contacts with this seed), so the test tests something";
}

}  // namespace
}  // namespace rhot
