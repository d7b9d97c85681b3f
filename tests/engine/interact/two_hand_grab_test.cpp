// Two-handed grabs through Bullet: a bar held at both ends moves with the hands' midpoint, tilts
// with the line between them, hands over to the remaining hand without a jump, and (when the
// scene asks) scales with the hands' distance; an object that is not two-handed is taken over.

#include <algorithm>
#include <cmath>
#include <numbers>
#include <regex>

#include <gtest/gtest.h>

#include "engine/interact/GraspSystem.h"
#include "engine/sim/ScriptedHands.h"
#include "tests/engine/physics/PhysicsTestScenes.h"

namespace rhot {
namespace {

// A 60 cm bar (4 cm square) lying along x on a stand, its top at 0.84 m.
std::string bar_scene(const std::string& grabbable) {
  return std::string(R"({"entities": [)") + test::kFloor +
         R"(, {"name": "stand", "transform": {"position": [0, 0.4, 0]}, "mesh": {"shape": "box", "size_m": [0.2, 0.8, 0.12]},
               "body": {"type": "static", "friction": 0.8}},
             {"name": "bar", "transform": {"position": [0, 0.82, 0]}, "mesh": {"shape": "box", "size_m": [0.6, 0.04, 0.04]},
              "body": {"type": "dynamic", "mass_kg": 0.4, "friction": 0.8}, "grabbable": )" +
         grabbable + "}]}";
}

constexpr double kBarY = 0.82;
constexpr double kGripX = 0.22;  // each hand this far from the bar's middle

struct TwoHands {
  World world;
  std::unique_ptr<HandPhysics> physics;
  Entity bar;
  std::array<GraspPose, 2> grasp{make_grasp(HandSide::kLeft, 0.04, 0.006, 2), make_grasp(HandSide::kRight, 0.04, 0.006, 2)};
  std::array<Eigen::Vector3d, 2> at{Eigen::Vector3d(-kGripX, kBarY, 0.0), Eigen::Vector3d(kGripX, kBarY, 0.0)};
  std::array<double, 2> closure{0.0, 0.0};
  std::array<double, 2> thumb{-1.0, -1.0};  // at or above 0: the hand's thumb at this closure, not at the hand's
  std::vector<InteractionEvent> events;

  explicit TwoHands(const std::string& grabbable = "true") {
    physics = test::physics_for(world, test::parse(bar_scene(grabbable)));
    bar = find_named(world, "bar");
  }
  void step() {
    std::array<HandInput, 2> hands;
    for (std::size_t h = 0; h < 2; ++h) {
      HandPose pose = grasp[h].pose(closure[h]);
      if (thumb[h] >= 0.0) {
        const HandPose digit = grasp[h].pose(thumb[h]);
        for (const HandJoint j : chain_joints(Finger::kThumb))
          pose.position_m[static_cast<std::size_t>(j)] = digit.position_m[static_cast<std::size_t>(j)];
      }
      hands[h] = hand_input(grasp[h].place(at[h], Eigen::Vector3d::UnitZ()), pose);
    }
    physics->step(world, hands);
    for (const InteractionEvent& e : physics->events()) events.push_back(e);
  }
  // `steps` steps moving the hands linearly by `move` (per hand) and their closures to `close`.
  void go(int steps, const std::array<Eigen::Vector3d, 2>& move, const std::array<double, 2>& close) {
    const auto from = at;
    const auto closure_from = closure;
    for (int i = 1; i <= steps; ++i) {
      const double f = static_cast<double>(i) / steps;
      for (std::size_t h = 0; h < 2; ++h) {
        at[h] = from[h] + f * move[h];
        closure[h] = closure_from[h] + f * (close[h] - closure_from[h]);
      }
      step();
    }
  }
  void grab_both() {
    const Eigen::Vector3d up(0.0, 0.15, 0.0);
    at[0] += up;
    at[1] += up;
    go(45, {-up, -up}, {0.0, 0.0});
    go(45, {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()}, {1.0, 1.0});
  }
  btTransform pose() const { return physics->physics().body(bar)->getWorldTransform(); }
  // Degrees between the bar's rotation and the one the pair's grips ask for (0 while not held).
  double off_grip_deg() const {
    const std::optional<btTransform> target = physics->grasp().grip_target(bar);
    if (!target) return 0.0;
    return static_cast<double>(pose().getRotation().angleShortestPath(target->getRotation())) * 180.0 / std::numbers::pi;
  }
  int count(InteractionEventType type) const {
    return static_cast<int>(std::count_if(events.begin(), events.end(), [&](const InteractionEvent& e) { return e.type == type; }));
  }
};

double degrees(double rad) { return rad * 180.0 / std::numbers::pi; }

TEST(TwoHandGrab, ABarHeldAtBothEndsMovesAndTurnsWithBothHandsAndHandsOverWithoutAJump) {
  TwoHands t;
  t.grab_both();
  ASSERT_EQ(t.count(InteractionEventType::kGrasp), 2);
  const GraspSystem& g = t.physics->grasp();
  ASSERT_TRUE(g.held_by_both(t.bar));
  EXPECT_EQ(g.holding(HandSide::kLeft), t.bar);
  EXPECT_EQ(g.holding(HandSide::kRight), t.bar);
  const btVector3 start = t.pose().getOrigin();

  // Both hands up 10 cm and forward 10 cm: the bar comes along, level, and on its grips' rotation
  // all the way (the stale contacts of the grasping bones once turned it 7-15 degrees off as it
  // left its stand, docs/grasping.md).
  const Eigen::Vector3d lift(0.0, 0.1, 0.1);
  double off_grip_deg = 0.0;
  for (int i = 0; i < 110; ++i) {
    const Eigen::Vector3d move = i < 90 ? Eigen::Vector3d(lift / 90.0) : Eigen::Vector3d::Zero();
    t.go(1, {move, move}, {1.0, 1.0});
    ASSERT_TRUE(g.held_by_both(t.bar)) << "step " << i;
    off_grip_deg = std::max(off_grip_deg, t.off_grip_deg());
  }
  EXPECT_LT(off_grip_deg, 0.5);
  btVector3 moved = t.pose().getOrigin() - start;
  EXPECT_NEAR(moved.y(), 0.1, 0.005);
  EXPECT_NEAR(moved.z(), 0.1, 0.005);
  EXPECT_NEAR(moved.x(), 0.0, 0.005);
  const btVector3 level = quatRotate(t.pose().getRotation(), btVector3(1, 0, 0));
  EXPECT_LT(degrees(std::asin(std::abs(static_cast<double>(level.y())))), 1.0);

  // The right hand 10 cm higher: the bar tilts with the line between the hands.
  t.go(90, {Eigen::Vector3d::Zero(), Eigen::Vector3d(0.0, 0.1, 0.0)}, {1.0, 1.0});
  for (int i = 0; i < 20; ++i) t.step();
  const btVector3 along = quatRotate(t.pose().getRotation(), btVector3(1, 0, 0));
  const double tilt = degrees(std::asin(static_cast<double>(along.y())));
  EXPECT_NEAR(tilt, degrees(std::atan2(0.1, 2 * kGripX)), 1.0);
  EXPECT_NEAR(static_cast<double>(t.pose().getOrigin().y()) - static_cast<double>(start.y()), 0.15, 0.005) << "midway between the hands";

  // The right hand opens: a hand-over to the left, and the bar stays where the pair held it.
  const btTransform before = t.pose();
  const int releases = t.count(InteractionEventType::kRelease);
  t.go(9, {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()}, {1.0, 0.0});
  ASSERT_EQ(t.count(InteractionEventType::kRelease), releases + 1);
  const auto release =
      std::find_if(t.events.rbegin(), t.events.rend(), [](const InteractionEvent& e) { return e.type == InteractionEventType::kRelease; });
  EXPECT_EQ(release->hand, HandSide::kRight);
  EXPECT_TRUE(release->handed_over);
  EXPECT_FALSE(g.held_by_both(t.bar));
  EXPECT_EQ(g.holding(HandSide::kLeft), t.bar);
  EXPECT_FALSE(g.holding(HandSide::kRight).has_value());
  for (int i = 0; i < 10; ++i) t.step();
  EXPECT_LT(static_cast<double>((t.pose().getOrigin() - before.getOrigin()).length()), 0.004);
  EXPECT_LT(degrees(static_cast<double>(t.pose().getRotation().angleShortestPath(before.getRotation()))), 1.0);

  // The left hand alone carries it 10 cm to the left.
  const btVector3 alone = t.pose().getOrigin();
  t.go(45, {Eigen::Vector3d(-0.1, 0.0, 0.0), Eigen::Vector3d::Zero()}, {1.0, 0.0});
  for (int i = 0; i < 10; ++i) t.step();
  EXPECT_NEAR(static_cast<double>(t.pose().getOrigin().x() - alone.x()), -0.1, 0.005);

  // ... and lets go: an ordinary release, and the bar falls.
  t.go(9, {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()}, {0.0, 0.0});
  const auto last =
      std::find_if(t.events.rbegin(), t.events.rend(), [](const InteractionEvent& e) { return e.type == InteractionEventType::kRelease; });
  EXPECT_EQ(last->hand, HandSide::kLeft);
  EXPECT_FALSE(last->handed_over);
  EXPECT_FALSE(g.held_by(t.bar).has_value());
  const double y = static_cast<double>(t.pose().getOrigin().y());
  for (int i = 0; i < 20; ++i) t.step();
  EXPECT_LT(static_cast<double>(t.pose().getOrigin().y()), y - 0.02);
}

// Both hands let go of the bar together (the workbench's rack, seed 3: the left hand let go by its
// thumb): the right opens all the way, the left's thumb a little later and less, out past the
// release distance when the right has let go. The left hand, carrying on alone, keeps how far its
// thumb had opened and lets go as well. Taken afresh from where its thumb was (the rule before;
// GripPoint::out_carried_m left at 0), the thumb would have to open the release distance again, and
// the left hand kept the bar.
TEST(TwoHandGrab, TwoHandsOpeningTogetherBothLetGoThoughOneIsStillOpeningWhenTheOtherHasLetGo) {
  TwoHands t;
  t.grab_both();
  ASSERT_EQ(t.count(InteractionEventType::kGrasp), 2);
  const GraspSystem& g = t.physics->grasp();
  ASSERT_TRUE(g.held_by_both(t.bar));
  const Eigen::Vector3d lift(0.0, 0.1, 0.0);
  t.go(45, {lift, lift}, {1.0, 1.0});
  // The right opens over 9 frames; the left's thumb starts 3 frames later and stops at 0.6 of its
  // closure, the left's fingers closed.
  t.go(3, {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()}, {1.0, 2.0 / 3.0});
  for (int i = 1; i <= 6; ++i) {
    t.thumb[0] = 1.0 - 0.4 * i / 6.0;
    t.go(1, {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()}, {1.0, 2.0 / 3.0 * (1.0 - i / 6.0)});
  }
  for (int i = 0; i < 45; ++i) t.step();
  std::vector<InteractionEvent> releases;
  for (const InteractionEvent& e : t.events)
    if (e.type == InteractionEventType::kRelease) releases.push_back(e);
  std::string said;
  for (const InteractionEvent& e : releases)
    said += std::string(e.hand == HandSide::kLeft ? "left" : "right") + " at " + std::to_string(e.time_s) + ": " + e.reason + "\n";
  ASSERT_EQ(releases.size(), 2u) << said;
  EXPECT_EQ(releases[0].hand, HandSide::kRight) << said;
  EXPECT_TRUE(releases[0].handed_over);
  EXPECT_EQ(releases[1].hand, HandSide::kLeft);
  EXPECT_TRUE(std::regex_match(releases[1].reason, std::regex(R"(thumb opened \d+ mm \(measured\))"))) << said;
  EXPECT_LT(releases[1].time_s - releases[0].time_s, 0.2) << said;
  EXPECT_FALSE(g.held_by(t.bar).has_value());
}

TEST(TwoHandGrab, HandsMovingApartScaleAnObjectThatAsksForIt) {
  TwoHands t(R"({"scale_with_hands": {"min": 0.5, "max": 1.4}})");
  t.grab_both();
  ASSERT_TRUE(t.physics->grasp().held_by_both(t.bar));
  const Eigen::Vector3d out(0.11, 0.0, 0.0);  // each hand: the span grows from 0.44 to 0.66 m
  t.go(45, {-out, out}, {1.0, 1.0});
  for (int i = 0; i < 10; ++i) t.step();
  EXPECT_NEAR(t.physics->physics().scale(t.bar), 1.4, 1e-6) << "capped at max";
  btVector3 lo, hi;
  t.physics->physics().body(t.bar)->getAabb(lo, hi);
  EXPECT_NEAR(static_cast<double>(hi.x() - lo.x()), 0.6 * 1.4, 0.01);
  EXPECT_NEAR(t.world.get<Transform>(t.bar).scale.x, 1.4f, 1e-4f);
  // Back together to a span of 0.55 m: 1.25 times the first.
  const Eigen::Vector3d in(-0.055, 0.0, 0.0);
  t.go(45, {-in, in}, {1.0, 1.0});
  for (int i = 0; i < 10; ++i) t.step();
  EXPECT_NEAR(t.physics->physics().scale(t.bar), 0.55 / (2 * kGripX), 0.02);
  // The right hand lets go: the left carries the stretched bar on (its grip taken afresh, not
  // judged against where its fingers were on the smaller bar).
  t.go(9, {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()}, {1.0, 0.0});
  ASSERT_EQ(t.count(InteractionEventType::kRelease), 1);
  t.go(30, {Eigen::Vector3d::Zero(), Eigen::Vector3d(0.0, 0.2, 0.0)}, {1.0, 0.0});  // the open hand out of the way
  // (The stretched bar rests on the stand, a little above where the hand holds it: measured from
  // the grip's target.)
  const double before = static_cast<double>(t.physics->grasp().grip_target(t.bar)->getOrigin().y());
  t.go(45, {Eigen::Vector3d(0.0, 0.05, 0.0), Eigen::Vector3d::Zero()}, {1.0, 0.0});
  for (int i = 0; i < 10; ++i) t.step();
  EXPECT_EQ(t.count(InteractionEventType::kRelease), 1);
  EXPECT_EQ(t.physics->grasp().holding(HandSide::kLeft), t.bar);
  EXPECT_NEAR(static_cast<double>(t.pose().getOrigin().y()) - before, 0.05, 0.003);
}

TEST(TwoHandGrab, ABarThatIsNotScaledKeepsItsSizeWhenTheHandsMoveApart) {
  TwoHands t;
  t.grab_both();
  const Eigen::Vector3d out(0.05, 0.0, 0.0);
  t.go(45, {-out, out}, {1.0, 1.0});
  EXPECT_EQ(t.physics->physics().scale(t.bar), 1.0);
  EXPECT_TRUE(t.physics->grasp().held_by_both(t.bar));
}

TEST(TwoHandGrab, AnObjectThatIsNotTwoHandedIsTakenOverByTheSecondHand) {
  TwoHands t(R"({"two_handed": false})");
  // The right hand grasps first, then the left.
  t.at[1].y() += 0.15;
  t.go(45, {Eigen::Vector3d::Zero(), Eigen::Vector3d(0.0, -0.15, 0.0)}, {0.0, 0.0});
  t.go(45, {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()}, {0.0, 1.0});
  ASSERT_EQ(t.physics->grasp().holding(HandSide::kRight), t.bar);
  t.go(45, {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()}, {1.0, 1.0});
  ASSERT_EQ(t.count(InteractionEventType::kGrasp), 2);
  ASSERT_EQ(t.count(InteractionEventType::kRelease), 1);
  const auto release =
      std::find_if(t.events.begin(), t.events.end(), [](const InteractionEvent& e) { return e.type == InteractionEventType::kRelease; });
  EXPECT_EQ(release->hand, HandSide::kRight);
  EXPECT_TRUE(release->handed_over);
  EXPECT_EQ(t.physics->grasp().holding(HandSide::kLeft), t.bar);
  EXPECT_FALSE(t.physics->grasp().held_by_both(t.bar));
}

TEST(TwoHandGrab, TwoGripsTooCloseTogetherToSpanAFrameAreATakeOver) {
  // A 5 cm cube on the stand, both hands closing on it at the same spot (hand bones pass through
  // each other): the second hand takes it over instead of pairing.
  World world;
  auto physics = test::physics_for(world, test::parse(std::string(R"({"entities": [)") + test::kFloor + R"(,
      {"name": "stand", "transform": {"position": [0, 0.4, 0]}, "mesh": {"shape": "box", "size_m": [0.12, 0.8, 0.12]}, "body": {"type": "static"}},
      {"name": "cube", "transform": {"position": [0, 0.825, 0]}, "mesh": {"shape": "box", "size_m": [0.05, 0.05, 0.05]},
       "body": {"type": "dynamic", "mass_kg": 0.1, "friction": 0.8}, "grabbable": true}]})"));
  const Entity cube = find_named(world, "cube");
  const std::array<GraspPose, 2> grasp{make_grasp(HandSide::kLeft, 0.05), make_grasp(HandSide::kRight, 0.05)};
  const Eigen::Vector3d at(0.0, 0.825, 0.0);
  std::vector<InteractionEvent> events;
  // The right hand closes first; the left a third of a second later.
  for (int i = 0; i < 150; ++i) {
    std::array<HandInput, 2> hands;
    const double right = std::clamp((i - 10) / 40.0, 0.0, 1.0), left = std::clamp((i - 60) / 40.0, 0.0, 1.0);
    hands[1] = hand_input(grasp[1].place(at, Eigen::Vector3d::UnitX()), grasp[1].pose(right));
    if (i >= 50) hands[0] = hand_input(grasp[0].place(at, -Eigen::Vector3d::UnitX()), grasp[0].pose(left));
    physics->step(world, hands);
    for (const InteractionEvent& e : physics->events()) events.push_back(e);
  }
  const auto count = [&](InteractionEventType type) {
    return std::count_if(events.begin(), events.end(), [&](const InteractionEvent& e) { return e.type == type; });
  };
  ASSERT_EQ(count(InteractionEventType::kGrasp), 2);
  ASSERT_EQ(count(InteractionEventType::kRelease), 1);
  const auto release =
      std::find_if(events.begin(), events.end(), [](const InteractionEvent& e) { return e.type == InteractionEventType::kRelease; });
  EXPECT_EQ(release->hand, HandSide::kRight);
  EXPECT_TRUE(release->handed_over);
  EXPECT_EQ(physics->grasp().holding(HandSide::kLeft), cube);
  EXPECT_FALSE(physics->grasp().held_by_both(cube));
}

TEST(TwoHandGrab, GrabbableOptionsInAScene) {
  const auto error_of = [](const std::string& grabbable) {
    auto scene = parse_scene(bar_scene(grabbable), ".", "s.json");
    return scene ? std::string() : scene.error().to_string();
  };
  EXPECT_EQ(error_of(R"({"two_handed": true, "scale_with_hands": {"max": 3}})"), "");
  EXPECT_EQ(error_of(R"({"two_hands": true})"),
            "s.json: /entities/2/grabbable/two_hands: unknown key \"two_hands\"; expected one of: two_handed, scale_with_hands");
  EXPECT_EQ(error_of(R"({"two_handed": false, "scale_with_hands": {}})"),
            "s.json: /entities/2/grabbable/scale_with_hands: scaling with the hands needs a two-handed grab");
  EXPECT_EQ(error_of(R"({"scale_with_hands": {"min": 2}})"),
            "s.json: /entities/2/grabbable/scale_with_hands/min: expected a factor from 0.05 to 1, got 2");
  EXPECT_EQ(error_of(R"("yes")"), "s.json: /entities/2/grabbable: expected true, false or an object, got \"yes\"");
}

}  // namespace
}  // namespace rhot
