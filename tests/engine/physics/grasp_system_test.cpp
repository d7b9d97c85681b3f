// The grasp system on its own rules: a grasp needs a grabbable object, a seen hand, and the thumb
// with an opposing finger on it; opening releases; a hand cannot grasp again at once.

#include "engine/physics/GraspSystem.h"

#include <algorithm>

#include <gtest/gtest.h>

#include "engine/sim/ScriptedHands.h"
#include "tests/engine/physics/PhysicsTestScenes.h"

namespace rhot {
namespace {

// A 5 cm cube on a pedestal (top at 0.8 m), and the right hand's grasp of it.
std::string bench_scene(bool grabbable) {
  return std::string(R"({"entities": [)") + test::kFloor +
         R"(, {"name": "pedestal", "transform": {"position": [0, 0.4, 0]}, "mesh": {"shape": "box", "size_m": [0.12, 0.8, 0.12]},
               "body": {"type": "static", "friction": 0.8}},
             {"name": "cube", "transform": {"position": [0, 0.825, 0]}, "mesh": {"shape": "box", "size_m": [0.05, 0.05, 0.05]},
              "body": {"type": "dynamic", "mass_kg": 0.1, "friction": 0.8}, "grabbable": )" +
         (grabbable ? "true" : "false") + "}]}";
}

struct Bench {
  World world;
  std::unique_ptr<HandPhysics> physics;
  Entity cube;
  GraspPose grasp = make_grasp(HandSide::kRight, 0.05, 0.006, 2);
  std::vector<InteractionEvent> events;  // every step's, in order
  double t = 0.0;

  explicit Bench(bool grabbable = true) {
    physics = test::physics_for(world, test::parse(bench_scene(grabbable)));
    cube = find_named(world, "cube");
  }
  // One step with the right hand at `closure` (0 open .. 1 closed), `lift_m` above the cube's
  // start; `seen` false: the hand is not tracked.
  void step(double closure, double lift_m = 0.0, bool seen = true) {
    std::array<HandInput, 2> hands;
    hands[1] = hand_input(grasp.place(Eigen::Vector3d(0.0, 0.825 + lift_m, 0.0), Eigen::Vector3d::UnitX()), grasp.pose(closure));
    hands[1].seen = seen;
    physics->step(world, hands);
    for (const InteractionEvent& e : physics->events()) events.push_back(e);
    t += physics->physics().step_s();
  }
  // Lowers the open hand from 15 cm onto the cube (0.5 s), then closes it (0.5 s).
  void reach_and_close(bool seen = true) {
    for (int i = 0; i < 45; ++i) step(0.0, 0.15 * (1.0 - i / 44.0), seen);
    for (int i = 0; i < 45; ++i) step(i / 44.0, 0.0, seen);
  }
  int count(InteractionEventType type) const {
    return static_cast<int>(std::count_if(events.begin(), events.end(), [&](const InteractionEvent& e) { return e.type == type; }));
  }
  std::size_t first(InteractionEventType type) const {
    return static_cast<std::size_t>(std::find_if(events.begin(), events.end(), [&](const InteractionEvent& e) { return e.type == type; }) -
                                    events.begin());
  }
};

TEST(GraspSystem, ClosingThumbAndFingersOnAGrabbableObjectGraspsIt) {
  Bench b;
  b.reach_and_close();
  ASSERT_EQ(b.count(InteractionEventType::kGrasp), 1);
  EXPECT_LT(b.first(InteractionEventType::kHoverBegin), b.first(InteractionEventType::kContactBegin));
  EXPECT_LT(b.first(InteractionEventType::kContactBegin), b.first(InteractionEventType::kGrasp));
  const InteractionEvent& grasp = b.events[b.first(InteractionEventType::kGrasp)];
  EXPECT_EQ(grasp.object, b.cube);
  EXPECT_EQ(grasp.hand, HandSide::kRight);
  const GraspSystem& g = b.physics->grasp();
  EXPECT_EQ(g.holding(HandSide::kRight), b.cube);
  EXPECT_EQ(g.held_by(b.cube), HandSide::kRight);
  EXPECT_FALSE(g.holding(HandSide::kLeft).has_value());
  ASSERT_TRUE(g.grip_target(b.cube).has_value());
  // Lifted 10 cm, the held cube comes along.
  for (int i = 0; i < 90; ++i) b.step(1.0, 0.1 * i / 89.0);
  EXPECT_GT(b.physics->physics().body(b.cube)->getWorldTransform().getOrigin().y(), 0.825f + 0.08f);
}

TEST(GraspSystem, AnObjectThatIsNotGrabbableIsTouchedButNeverHeld) {
  Bench b(false);
  b.reach_and_close();
  EXPECT_GT(b.count(InteractionEventType::kContactBegin), 0);
  EXPECT_EQ(b.count(InteractionEventType::kGrasp), 0);
  EXPECT_FALSE(b.physics->grasp().holding(HandSide::kRight).has_value());
}

TEST(GraspSystem, AHandThatIsNotSeenNeitherTouchesNorHolds) {
  Bench b;
  b.reach_and_close(false);
  EXPECT_TRUE(b.events.empty());
  EXPECT_FALSE(b.physics->grasp().holding(HandSide::kRight).has_value());
}

TEST(GraspSystem, OpeningReleasesAndTheHandCannotGraspAgainAtOnce) {
  Bench b;
  b.reach_and_close();
  ASSERT_EQ(b.count(InteractionEventType::kGrasp), 1);
  // Open: released, with the hand's (zero) velocity.
  for (int i = 0; i < 9; ++i) b.step(1.0 - i / 8.0);
  ASSERT_EQ(b.count(InteractionEventType::kRelease), 1);
  const InteractionEvent& release = b.events[b.first(InteractionEventType::kRelease)];
  EXPECT_FALSE(release.handed_over);
  EXPECT_LT(release.velocity_mps.norm(), 0.05);
  EXPECT_FALSE(b.physics->grasp().holding(HandSide::kRight).has_value());
  // Closed again at once (within regrasp_delay_s, 0.2 s): no grasp; held closed past it: grasped.
  const double released_at = release.time_s;
  for (int i = 0; i < 9; ++i) b.step(i / 8.0);
  EXPECT_EQ(b.count(InteractionEventType::kGrasp), 1) << "not within the regrasp delay";
  for (int i = 0; i < 45; ++i) b.step(1.0);
  ASSERT_EQ(b.count(InteractionEventType::kGrasp), 2);
  const InteractionEvent& again =
      b.events[b.events.size() - 1 -
               static_cast<std::size_t>(std::find_if(b.events.rbegin(), b.events.rend(),
                                                     [](const InteractionEvent& e) { return e.type == InteractionEventType::kGrasp; }) -
                                        b.events.rbegin())];
  EXPECT_GE(again.time_s - released_at, b.physics->grasp().settings().regrasp_delay_s - 1e-9);
}

}  // namespace
}  // namespace rhot
