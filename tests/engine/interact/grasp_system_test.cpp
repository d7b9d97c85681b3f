// The grasp system on its own rules: a grasp needs a grabbable object, a seen hand, and the thumb
// with an opposing finger on it; opening releases; a hand cannot grasp again at once.

#include "engine/interact/GraspSystem.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <regex>

#include <gtest/gtest.h>

#include "engine/sim/ScriptedHands.h"
#include "tests/engine/physics/PhysicsTestScenes.h"

namespace rhot {
namespace {

// A 5 cm cube on a pedestal (top at 0.8 m), and the right hand's grasp of it.
std::string bench_scene(bool grabbable, const std::string& settings = "") {
  return std::string(R"({)") + settings + R"("entities": [)" + test::kFloor +
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
  Eigen::Vector3d centre{0.0, 0.825, 0.0};          // where the hand puts its grip point, at no lift
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX();  // the grip axis (thumb toward the fingers), horizontal

  explicit Bench(bool grabbable = true, const std::string& settings = "") {
    physics = test::physics_for(world, test::parse(bench_scene(grabbable, settings)));
    cube = find_named(world, "cube");
  }
  // One step with the right hand at `closure` (0 open .. 1 closed), `lift_m` above the cube's
  // start; `seen` false: the hand is not tracked; `confidence` of every joint.
  void step(double closure, double lift_m = 0.0, bool seen = true, double confidence = 1.0) {
    std::array<HandInput, 2> hands;
    hands[1] = hand_input(grasp.place(centre + Eigen::Vector3d(0.0, lift_m, 0.0), axis), grasp.pose(closure));
    hands[1].seen = seen;
    hands[1].confidence.fill(confidence);
    physics->step(world, hands);
    for (const InteractionEvent& e : physics->events()) events.push_back(e);
    t += physics->physics().step_s();
  }
  // One step with the right hand closed but its index at `index_closure` and its thumb's joints
  // at `thumb_confidence` (below `confident`: hidden).
  void step_index(double index_closure, double thumb_confidence) {
    HandPose pose = grasp.pose(1.0);
    const HandPose index = grasp.pose(index_closure);
    for (const HandJoint j : {HandJoint::kIndexIntermediate, HandJoint::kIndexDistal, HandJoint::kIndexTip}) {
      pose.position_m[static_cast<std::size_t>(j)] = index.position_m[static_cast<std::size_t>(j)];
    }
    std::array<HandInput, 2> hands;
    hands[1] = hand_input(grasp.place(Eigen::Vector3d(0.0, 0.825, 0.0), Eigen::Vector3d::UnitX()), pose);
    hands[1].seen = true;
    for (const HandJoint j : {HandJoint::kThumbMetacarpal, HandJoint::kThumbProximal, HandJoint::kThumbDistal, HandJoint::kThumbTip}) {
      hands[1].confidence[static_cast<std::size_t>(j)] = thumb_confidence;
    }
    physics->step(world, hands);
    for (const InteractionEvent& e : physics->events()) events.push_back(e);
    t += physics->physics().step_s();
  }
  // One step with each digit (thumb, index .. little) at its own closure and confidence, the hand
  // `lift_m` above the cube's start.
  void step_digits(const std::array<double, kFingerCount>& closure, const std::array<double, kFingerCount>& confidence,
                   double lift_m = 0.0) {
    HandPose pose = grasp.pose(1.0);
    std::array<HandInput, 2> hands;
    for (int f = 0; f < kFingerCount; ++f) {
      const HandPose digit = grasp.pose(closure[static_cast<std::size_t>(f)]);
      for (const HandJoint j : chain_joints(static_cast<Finger>(f))) {
        pose.position_m[static_cast<std::size_t>(j)] = digit.position_m[static_cast<std::size_t>(j)];
      }
    }
    hands[1] = hand_input(grasp.place(centre + Eigen::Vector3d(0.0, lift_m, 0.0), axis), pose);
    hands[1].seen = true;
    for (int f = 0; f < kFingerCount; ++f) {
      for (const HandJoint j : chain_joints(static_cast<Finger>(f))) {
        hands[1].confidence[static_cast<std::size_t>(j)] = confidence[static_cast<std::size_t>(f)];
      }
    }
    physics->step(world, hands);
    for (const InteractionEvent& e : physics->events()) events.push_back(e);
    t += physics->physics().step_s();
  }
  // Lowers the open hand onto the cube and closes it (as reach_and_close) with its middle finger
  // kept open, every digit measured: the thumb and index grasp the cube.
  void reach_and_close_but_the_middle() {
    const std::array<double, kFingerCount> seen{1.0, 1.0, 1.0, 1.0, 1.0};
    for (int i = 0; i < 45; ++i) step_digits({0.0, 0.0, 0.0, 0.0, 0.0}, seen, 0.15 * (1.0 - i / 44.0));
    for (int i = 0; i < 45; ++i) {
      const double c = i / 44.0;
      step_digits({c, c, 0.0, c, c}, seen);
    }
  }
  // Whether the first release's reason matches `pattern` (a regular expression).
  bool released_as(const std::string& pattern) const {
    const std::size_t i = first(InteractionEventType::kRelease);
    return i < events.size() && std::regex_match(events[i].reason, std::regex(pattern));
  }
  std::string release_reason() const {
    const std::size_t i = first(InteractionEventType::kRelease);
    return i < events.size() ? events[i].reason : "(no release)";
  }
  // Lowers the open hand from 15 cm onto the cube (0.5 s), then closes it (0.5 s).
  void reach_and_close(bool seen = true) {
    for (int i = 0; i < 45; ++i) step(0.0, 0.15 * (1.0 - i / 44.0), seen);
    for (int i = 0; i < 45; ++i) step(i / 44.0, 0.0, seen);
  }
  int count(InteractionEventType type) const {
    return static_cast<int>(std::count_if(events.begin(), events.end(), [&](const InteractionEvent& e) { return e.type == type; }));
  }
  // Frames a grip point must be measured out for an opening: the first and open_for_s after it.
  int frames_to_open() const {
    return static_cast<int>(std::ceil(physics->grasp().settings().open_for_s / physics->physics().step_s() - 1e-9)) + 1;
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
  EXPECT_EQ(grasp.reason, "thumb against index") << "the middle finger touches a step later";
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
  // Open, and held open: released, with the hand's (zero) velocity.
  for (int i = 0; i < 9; ++i) b.step(1.0 - i / 8.0);
  for (int i = 0; i < b.frames_to_open(); ++i) b.step(0.0);
  ASSERT_EQ(b.count(InteractionEventType::kRelease), 1);
  const InteractionEvent& release = b.events[b.first(InteractionEventType::kRelease)];
  EXPECT_FALSE(release.handed_over);
  EXPECT_TRUE(std::regex_match(release.reason, std::regex(R"((thumb|index|index, middle) opened \d+ mm \(measured(, last bone)?\))")))
      << release.reason;
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

// The workbench peg's missed grasps (seed 222): the tracked thumb a few millimetres off, on the
// side face beside the vertical edge it really held, its contact normal square to the fingers' on
// the far face. Here the grip axis turns 36 degrees and moves off the cube's centre, so the
// thumb's first bone touches the near face 3-6 mm from the edge (asserted: 1.5-10) while the index
// presses the far one: with the contacts' own normals (pad_radius_m 0) no placement
// grasps; with the finger pad's (0.01, the default), every one does, and the
// cube comes along when the hand lifts.
TEST(GraspSystem, AThumbBesideABoxsEdgeOpposesTheFingersAsItsPadWrapsTheEdge) {
  const double yaw = 36.0 * std::numbers::pi / 180.0;
  for (const double dz_m : {-0.01, -0.0125, -0.015, -0.0175, -0.02}) {
    for (const bool pad : {false, true}) {
      Bench b(true, pad ? "" : R"("settings": {"grasp": {"pad_radius_m": 0}}, )");
      b.axis = Eigen::Vector3d(std::cos(yaw), 0.0, std::sin(yaw));
      b.centre += Eigen::Vector3d(0.005, 0.0, dz_m);
      // Reach and close (Bench::reach_and_close), keeping the contacts of the grasp's step.
      const btRigidBody* cube = b.physics->physics().body(b.cube);
      std::vector<GraspSystem::Contact> at_grasp;
      for (int i = 0; i < 90; ++i) {
        b.step(i < 45 ? 0.0 : (i - 45) / 44.0, i < 45 ? 0.15 * (1.0 - i / 44.0) : 0.0);
        if (at_grasp.empty() && b.count(InteractionEventType::kGrasp) > 0) at_grasp = b.physics->grasp().contacts()[1].at(b.cube);
      }
      if (!pad) {
        EXPECT_EQ(b.count(InteractionEventType::kGrasp), 0) << "dz " << dz_m << " m: a grasp with the contacts' own normals";
        continue;
      }
      ASSERT_EQ(b.count(InteractionEventType::kGrasp), 1) << "dz " << dz_m << " m";
      EXPECT_EQ(b.events[b.first(InteractionEventType::kGrasp)].reason, "thumb against index");
      // The thumb touches the near face beside the edge (x from -23.5 to -15 mm, the edge at -25),
      // the index the far face: the geometry of the peg's misses.
      bool thumb_beside_edge = false, index_far_face = false;
      for (const GraspSystem::Contact& c : at_grasp) {
        const btVector3 q = cube->getWorldTransform().invXform(c.point);
        const int group = hand_bones()[static_cast<std::size_t>(c.bone)].group;
        thumb_beside_edge = thumb_beside_edge || (group == 0 && q.z() < -0.024f && q.x() < -0.015f && q.x() > -0.0235f);
        index_far_face = index_far_face || (group == 1 && q.x() > 0.024f);
      }
      EXPECT_TRUE(thumb_beside_edge) << "dz " << dz_m << " m";
      EXPECT_TRUE(index_far_face) << "dz " << dz_m << " m";
      for (int i = 0; i < 90; ++i) b.step(1.0, 0.1 * i / 89.0);
      EXPECT_GT(cube->getWorldTransform().getOrigin().y(), 0.825f + 0.08f) << "dz " << dz_m << " m";
    }
  }
}

// The thumb hidden, the grasping index (which touches the cube with its middle bone) opens: its
// last bone leaves the cube as it straightens, and the hand lets go by it, while the contact point
// on its middle bone is still within the release distance. Relaxing back to where it grasped and
// closing again, or twitching, is no opening.
TEST(GraspSystem, AFingerWhoseLastBoneLeavesTheObjectAsItStraightensHasOpened) {
  // The workbench's release distance: 20 mm.
  Bench b(true, R"("settings": {"grasp": {"release_distance_m": 0.02}}, )");
  b.reach_and_close();
  ASSERT_EQ(b.count(InteractionEventType::kGrasp), 1);
  ASSERT_EQ(b.events[b.first(InteractionEventType::kGrasp)].reason, "thumb against index");
  for (int i = 0; i < 20; ++i) b.step_index(1.0, 0.5);  // the thumb hidden
  // Relaxed to 0.85 of its closure (about where it touched the cube) and closed again, then 2 %
  // twitches for a second: held.
  for (int i = 0; i <= 10; ++i) b.step_index(1.0 - 0.015 * i, 0.5);
  for (int i = 0; i <= 10; ++i) b.step_index(0.85 + 0.015 * i, 0.5);
  for (int i = 0; i < 90; ++i) b.step_index(1.0 - 0.02 * (i % 2), 0.5);
  EXPECT_EQ(b.count(InteractionEventType::kRelease), 0);
  ASSERT_TRUE(b.physics->grasp().holding(HandSide::kRight).has_value());
  // The index opens over half a second: released by its last bone.
  double released_at = -1.0;
  for (int i = 1; i <= 45 && released_at < 0.0; ++i) {
    b.step_index(1.0 - i / 45.0, 0.5);
    if (b.count(InteractionEventType::kRelease) == 1) released_at = 1.0 - i / 45.0;
  }
  ASSERT_EQ(b.count(InteractionEventType::kRelease), 1);
  const InteractionEvent& release = b.events[b.first(InteractionEventType::kRelease)];
  EXPECT_TRUE(std::regex_match(release.reason, std::regex(R"(index opened 2\d mm \(measured, last bone\))"))) << release.reason;
  // Measured: at 0.27 of its closure, 0.38 where it was first out (open_for_s 0); before the rule,
  // at 0.16 and nearly open.
  EXPECT_GT(released_at, 0.2) << "released as it opened, not at the end";
  EXPECT_FALSE(b.physics->grasp().holding(HandSide::kRight).has_value());
}

// A measured thumb that jumps out of the surface for a few frames and back (a tracked bone's
// jitter: `rhot-eval grasp --hands tracked --world realistic --seed 12` dropped its pinched cube on
// one frame 13.4 mm out) is no opening; one that stays out is, once open_for_s has passed. With
// open_for_s 0 (the rule before) the same jitter drops the cube.
TEST(GraspSystem, AThumbOutOfTheSurfaceForAFewFramesIsNoOpeningButOneThatStaysOutIs) {
  const std::array<double, kFingerCount> seen{1.0, 1.0, 1.0, 1.0, 1.0};
  const auto jitter = [&seen](Bench& b, int frames) {
    for (int i = 0; i < frames; ++i) b.step_digits({0.0, 1.0, 1.0, 1.0, 1.0}, seen);
    for (int i = 0; i < 10; ++i) b.step_digits({1.0, 1.0, 1.0, 1.0, 1.0}, seen);
  };
  Bench b;
  b.reach_and_close();
  ASSERT_EQ(b.count(InteractionEventType::kGrasp), 1);
  const double open_for_s = b.physics->grasp().settings().open_for_s;
  ASSERT_DOUBLE_EQ(open_for_s, 0.05);
  for (int frames = 1; frames <= 5; ++frames) jitter(b, frames);
  EXPECT_EQ(b.count(InteractionEventType::kRelease), 0) << b.release_reason();
  ASSERT_TRUE(b.physics->grasp().holding(HandSide::kRight).has_value());
  // Out and staying out: let go once it has been out for open_for_s, as the thumb.
  const double out_at = b.t;
  for (int i = 0; i < 12 && b.count(InteractionEventType::kRelease) == 0; ++i) b.step_digits({0.0, 1.0, 1.0, 1.0, 1.0}, seen);
  ASSERT_EQ(b.count(InteractionEventType::kRelease), 1);
  EXPECT_TRUE(b.released_as(R"(thumb opened \d+ mm \(measured\))")) << b.release_reason();
  const double waited = b.events[b.first(InteractionEventType::kRelease)].time_s - (out_at + b.physics->physics().step_s());
  EXPECT_GE(waited, open_for_s - 1e-9);
  EXPECT_LT(waited, open_for_s + b.physics->physics().step_s() + 1e-9);

  Bench before(true, R"("settings": {"grasp": {"open_for_s": 0}}, )");
  before.reach_and_close();
  ASSERT_EQ(before.count(InteractionEventType::kGrasp), 1);
  jitter(before, 1);
  EXPECT_EQ(before.count(InteractionEventType::kRelease), 1) << "one frame out drops it without the rule";
}

// Fingers only estimated when the grasp began (their markers hidden) and then measured somewhere
// else: the jump is no opening; the grip goes on from where they are measured.
TEST(GraspSystem, FingersEstimatedAtTheGraspAreReanchoredWhenFirstMeasured) {
  // How far the fingertips of a half closed hand are from the closed hand's: more than the
  // release distance, so without re-anchoring this would count as opening.
  Bench probe;
  const HandPose closed = probe.grasp.pose(1.0), wider = probe.grasp.pose(0.5);
  const auto tip = static_cast<std::size_t>(HandJoint::kIndexTip);
  ASSERT_GT((wider.position_m[tip] - closed.position_m[tip]).norm(), probe.physics->grasp().settings().release_distance_m + 0.003);

  Bench b;
  for (int i = 0; i < 45; ++i) b.step(0.0, 0.15 * (1.0 - i / 44.0));
  for (int i = 0; i < 45; ++i) b.step(i / 44.0, 0.0, true, 0.5);  // closing, nothing measured
  ASSERT_EQ(b.count(InteractionEventType::kGrasp), 1);
  for (int i = 0; i < 20; ++i) b.step(1.0, 0.0, true, 0.5);
  // Measured, half as closed as the estimate had it: still held, and lifted.
  for (int i = 0; i < 45; ++i) b.step(0.5, 0.1 * i / 44.0);
  EXPECT_EQ(b.count(InteractionEventType::kRelease), 0);
  EXPECT_TRUE(b.physics->grasp().holding(HandSide::kRight).has_value());
  EXPECT_GT(static_cast<double>(b.physics->physics().body(b.cube)->getWorldTransform().getOrigin().y()), 0.825 + 0.08);
  // Opening from there releases.
  for (int i = 0; i < 9; ++i) b.step(0.5 - 0.5 * i / 8.0, 0.1);
  for (int i = 0; i < b.frames_to_open(); ++i) b.step(0.0, 0.1);
  EXPECT_EQ(b.count(InteractionEventType::kRelease), 1);

  // The same jump with the fingers measured at the grasp is an opening.
  Bench measured;
  measured.reach_and_close();
  ASSERT_EQ(measured.count(InteractionEventType::kGrasp), 1);
  for (int i = 0; i < measured.frames_to_open(); ++i) measured.step(0.5);
  EXPECT_EQ(measured.count(InteractionEventType::kRelease), 1);
}

// A grasp begun by the first finger to touch (seed 11 of `rhot-eval grasp --hands tracked`: the
// tracked middle finger grazing the cube's top edge a step before the hidden index closed on it)
// is not ended by that finger alone moving off: a finger that closes on the held object after the
// grasp began joins the grip, and the grip ends when it opens too. Here the thumb and index grasp
// the cube with the middle finger held open; the middle closes on it (the hand's pose now closing
// the fingers 20 mm into the cube, so that the middle reaches it); then the index opens wide. With
// `fingers_join` false the index's opening lets the cube go.
TEST(GraspSystem, AFingerThatClosesOnTheHeldObjectJoinsTheGripAndHoldsItWhenTheFirstOpens) {
  const std::array<double, kFingerCount> seen{1.0, 1.0, 1.0, 1.0, 1.0};
  for (const bool join : {true, false}) {
    Bench b(true, join ? "" : R"("settings": {"grasp": {"fingers_join": false}}, )");
    b.reach_and_close_but_the_middle();
    ASSERT_EQ(b.count(InteractionEventType::kGrasp), 1) << "join " << join;
    ASSERT_EQ(b.events[b.first(InteractionEventType::kGrasp)].reason, "thumb against index") << "join " << join;
    b.grasp = make_grasp(HandSide::kRight, 0.05, 0.02, 2);                                   // held: the thumb and index press on, deeper
    for (int i = 0; i < 23; ++i) b.step_digits({1.0, 1.0, i / 22.0, 1.0, 1.0}, seen);        // the middle closes on the cube
    for (int i = 0; i < 23; ++i) b.step_digits({1.0, 1.0 - i / 22.0, 1.0, 1.0, 1.0}, seen);  // the index opens wide
    if (!join) {
      EXPECT_EQ(b.count(InteractionEventType::kRelease), 1);
      EXPECT_TRUE(b.released_as(R"(index opened \d+ mm \(measured(, last bone)?\))")) << b.release_reason();
      continue;
    }
    EXPECT_EQ(b.count(InteractionEventType::kRelease), 0);
    // Held by the thumb and the middle: lifted 10 cm, the cube comes along.
    for (int i = 0; i < 45; ++i) b.step_digits({1.0, 0.0, 1.0, 1.0, 1.0}, seen, 0.1 * i / 44.0);
    EXPECT_EQ(b.count(InteractionEventType::kRelease), 0);
    EXPECT_GT(static_cast<double>(b.physics->physics().body(b.cube)->getWorldTransform().getOrigin().y()), 0.825 + 0.08);
    // The middle opens too: released, by both.
    for (int i = 0; i < 23 && b.count(InteractionEventType::kRelease) == 0; ++i)
      b.step_digits({1.0, 0.0, 1.0 - i / 22.0, 1.0, 1.0}, seen, 0.1);
    EXPECT_EQ(b.count(InteractionEventType::kRelease), 1);
    EXPECT_TRUE(b.released_as(R"(index, middle opened \d+ mm \(measured(, last bone)?\))")) << b.release_reason();
  }
}

// The same with the middle finger hidden (seed 11's case: the index that really held the cube was
// hidden): it closes with its marker hidden, the hidden-finger rule places it against the cube,
// and it joins the grip unmeasured; the index opens wide, measured, and the cube stays held. When
// the middle finger is first measured, open, it is judged against the surface it was placed on:
// the hand lets go at once, not a release distance later.
TEST(GraspSystem, AHiddenFingerPlacedAgainstTheHeldObjectJoinsTheGripAndOpensWhenSeenOpen) {
  const std::array<double, kFingerCount> seen{1.0, 1.0, 1.0, 1.0, 1.0};
  const std::array<double, kFingerCount> middle_hidden{1.0, 1.0, 0.6, 1.0, 1.0};
  for (const bool join : {true, false}) {
    Bench b(true, join ? "" : R"("settings": {"grasp": {"fingers_join": false}}, )");
    b.reach_and_close_but_the_middle();
    ASSERT_EQ(b.count(InteractionEventType::kGrasp), 1) << "join " << join;
    ASSERT_EQ(b.events[b.first(InteractionEventType::kGrasp)].reason, "thumb against index") << "join " << join;
    for (int i = 0; i < 23; ++i) b.step_digits({1.0, 1.0, i / 22.0, 1.0, 1.0}, middle_hidden);        // the hidden middle closes
    for (int i = 0; i < 23; ++i) b.step_digits({1.0, 1.0 - i / 22.0, 1.0, 1.0, 1.0}, middle_hidden);  // the index opens wide
    if (!join) {
      EXPECT_EQ(b.count(InteractionEventType::kRelease), 1);
      EXPECT_TRUE(b.released_as(R"(index opened \d+ mm \(measured(, last bone)?\))")) << b.release_reason();
      continue;
    }
    for (int i = 0; i < 45; ++i) b.step_digits({1.0, 0.0, 1.0, 1.0, 1.0}, middle_hidden, 0.1 * i / 44.0);
    EXPECT_EQ(b.count(InteractionEventType::kRelease), 0);
    EXPECT_GT(static_cast<double>(b.physics->physics().body(b.cube)->getWorldTransform().getOrigin().y()), 0.825 + 0.08);
    // The middle finger comes into view open: released once seen so for open_for_s.
    for (int i = 0; i < b.frames_to_open(); ++i) b.step_digits({1.0, 0.0, 0.0, 1.0, 1.0}, seen, 0.1);
    EXPECT_EQ(b.count(InteractionEventType::kRelease), 1);
    EXPECT_TRUE(b.released_as(R"(index, middle opened \d+ mm \(measured(, last bone)?\))")) << b.release_reason();
  }
}

}  // namespace
}  // namespace rhot
