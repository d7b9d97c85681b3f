// HandPhysics: everything physical in a scene stepped together, from hand inputs or hand components.

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
      to[h] = Eigen::Vector3d{-0.3 + 0.6 * u(rng), 0.74 + 0.25 * u(rng), -0.75 + 0.5 * u(rng)};
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
