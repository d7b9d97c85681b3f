// Hand colliders: bones that follow the tracked hand by velocity, stop at surfaces, never tunnel.

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
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

// A point on a bone's surface (a grip point, docs/grasping.md) moves with the hand: the bone's roll
// about its axis is carried from the hand's frame down the digit. Taken by the shortest arc from the
// world's +Y, a bone pointing down had no roll to speak of: a hand pointing at the floor and
// wobbling by a third of a degree swung such a point around its bone by up to twice the bone's
// radius from one frame to the next (a pinching thumb's grip point, 15 mm out a frame after the
// grasp, dropped the ball; `rhot-eval grasp --hands tracked --world realistic --seed 31`).
TEST(HandColliders, APointOnABoneMovesWithTheHandWhereverTheBonePoints) {
  World world;
  auto p = physics_for(world, parse(kPlateScene));
  const HandPose pose = pointing_hand(HandSide::kRight);
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 1.0);
  // The fingers (the hand frame's -Z) at the floor, from 0.3 m above the stand's top.
  const Eigen::Quaterniond down(Eigen::AngleAxisd(-std::numbers::pi / 2.0, Eigen::Vector3d::UnitX()));
  std::array<Eigen::Vector3d, kHandBoneCount> before{};
  double worst_m = 0.0, pointing_down = 0.0;
  for (int i = 0; i < 60; ++i) {
    Rigid3d hand;
    hand.translation = Eigen::Vector3d(0.0, 1.2, 0.0);
    const Eigen::Vector3d axis{noise(rng), noise(rng), noise(rng)};
    hand.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.006, axis.normalized())) * down;
    p->step(world, {HandInput{}, hand_input(hand, pose)});
    const HandColliders& h = p->hand(HandSide::kRight);
    for (int b = 0; b < kHandBoneCount; ++b) {
      const btTransform bone = h.tracked_bone(b);
      pointing_down = std::max(pointing_down, -static_cast<double>(quatRotate(bone.getRotation(), btVector3(0, 1, 0)).y()));
      const Eigen::Vector3d on_surface = to_eigen(bone * btVector3(static_cast<btScalar>(h.bone_radius_m(b)), 0, 0));
      if (i > 0) worst_m = std::max(worst_m, (on_surface - before[static_cast<std::size_t>(b)]).norm());
      before[static_cast<std::size_t>(b)] = on_surface;
    }
  }
  EXPECT_GT(pointing_down, 0.999) << "a bone points straight down";
  // Two frames' wobbles of 0.006 rad each, about the wrist, move a point 20 cm out by up to 2.4 mm.
  EXPECT_LT(worst_m, 0.003);
}

// A contact's body is told to be a bone of this hand, which one, or neither: the other hand's bones
// (which carry the same indices) and the scene's bodies are no bone of it.
TEST(HandColliders, EachBoneIsFoundFromItsBodyAndNothingElseIs) {
  World world;
  auto p = physics_for(world, parse(kPlateScene));
  Rigid3d left, right;
  left.translation = Eigen::Vector3d(-0.3, 1.2, 0.0);
  right.translation = Eigen::Vector3d(0.3, 1.2, 0.0);
  p->step(world, {hand_input(left, pointing_hand(HandSide::kLeft)), hand_input(right, pointing_hand(HandSide::kRight))});
  const HandColliders& l = p->hand(HandSide::kLeft);
  const HandColliders& r = p->hand(HandSide::kRight);
  for (int i = 0; i < kHandBoneCount; ++i) {
    EXPECT_EQ(r.bone_of(r.bone(i)), i);
    EXPECT_EQ(l.bone_of(l.bone(i)), i);
    EXPECT_FALSE(r.bone_of(l.bone(i)).has_value()) << i;
    EXPECT_FALSE(l.bone_of(r.bone(i)).has_value()) << i;
  }
  EXPECT_FALSE(r.bone_of(p->physics().body(named(world, "plate"))).has_value());
  EXPECT_FALSE(r.bone_of(p->physics().body(named(world, "stand"))).has_value());
  EXPECT_FALSE(r.bone_of(nullptr).has_value());
}

}  // namespace
}  // namespace rhot
