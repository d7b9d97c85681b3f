// Joints, buttons, sockets and rules from scene files, through Bullet: limits hold against
// pushes, motors and springs move what they drive, a button presses once per push of a fingertip
// and never for a palm, a socket snaps what it accepts and lets a hand take it out, and rules turn
// events into actions.

#include "engine/interact/Mechanisms.h"

#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "engine/physics/BulletMath.h"
#include "engine/sim/ScriptedHands.h"
#include "tests/engine/physics/PhysicsTestScenes.h"
#include "tracking/core/Solvers.h"

namespace rhot {
namespace {

std::string scene_of(const std::string& entities, const std::string& rest = "") {
  return std::string(R"({"entities": [)") + test::kFloor + ", " + entities + "]" + rest + "}";
}

// A door 40 x 80 x 2 cm hinged at its left edge (x = -0.2 in its frame) about +Y.
std::string door(const std::string& joint_extra) {
  return R"({"name": "door", "transform": {"position": [0, 1.0, 0]}, "mesh": {"shape": "box", "size_m": [0.4, 0.8, 0.02]},
             "body": {"type": "dynamic", "mass_kg": 2}, "joint": {"type": "hinge", "anchor_m": [-0.2, 0, 0], "axis": [0, 1, 0])" +
         joint_extra + "}}";
}

struct Stage {
  World world;
  std::unique_ptr<HandPhysics> physics;
  std::vector<InteractionEvent> events;

  explicit Stage(const std::string& text) : Stage(test::parse(text)) {}
  explicit Stage(const SceneDesc& scene) { physics = test::physics_for(world, scene); }
  Entity named(const char* name) { return find_named(world, name); }
  btRigidBody* body(const char* name) { return physics->physics().body(named(name)); }
  double value(const char* name) { return physics->mechanisms().value(named(name)).value_or(NAN); }
  void step(const std::array<HandInput, 2>& hands = {}) {
    physics->step(world, hands);
    for (const InteractionEvent& e : physics->events()) events.push_back(e);
  }
  void seconds(double s) {
    for (int i = 0; i < static_cast<int>(s * 90.0); ++i) step();
  }
  int count(InteractionEventType type) const {
    return static_cast<int>(std::count_if(events.begin(), events.end(), [&](const InteractionEvent& e) { return e.type == type; }));
  }
};

TEST(Joints, AHingedDoorTurnsOnlyAboutItsHingeAndStopsAtItsLimits) {
  Stage r(scene_of(door(R"(, "limits_deg": [0, 90])")));
  btRigidBody* d = r.body("door");
  ASSERT_NE(d, nullptr);
  EXPECT_NEAR(r.value("door"), 0.0, 1e-3);
  // Shoved hard to open (+Y), for a second: it stops at 90 degrees.
  for (int i = 0; i < 90; ++i) {
    d->applyTorque(btVector3(0, 30, 0));
    r.step();
  }
  EXPECT_NEAR(r.value("door"), 90.0, 2.0);
  // The hinge edge stayed put and the door did not sag under gravity.
  const btVector3 hinge = d->getWorldTransform() * btVector3(-0.2f, 0, 0);
  EXPECT_LT((hinge - btVector3(-0.2f, 1.0f, 0)).length(), 0.005f);
  EXPECT_NEAR(d->getWorldTransform().getOrigin().y(), 1.0f, 0.005f);
  // And shoved back past closed: it stops at 0.
  for (int i = 0; i < 90; ++i) {
    d->applyTorque(btVector3(0, -30, 0));
    r.step();
  }
  EXPECT_NEAR(r.value("door"), 0.0, 2.0);
}

TEST(Joints, FrictionHoldsADoorAndAMotorTurnsIt) {
  Stage r(scene_of(door(R"(, "friction": 50)")));
  btRigidBody* d = r.body("door");
  // A push weaker than the friction does nothing.
  for (int i = 0; i < 45; ++i) {
    d->applyTorque(btVector3(0, 20, 0));
    r.step();
  }
  EXPECT_NEAR(r.value("door"), 0.0, 0.5);
  // Driven at 45 degrees a second for 2 s.
  ASSERT_TRUE(r.physics->mechanisms().drive(r.named("door"), 45.0, 100.0));
  r.seconds(2.0);
  EXPECT_NEAR(r.value("door"), 90.0, 3.0);
  EXPECT_FALSE(r.physics->mechanisms().drive(r.named("floor"), 1.0, 1.0)) << "the floor has no joint";
}

TEST(Joints, ADrawerSlidesWithinItsLimitsAndASpringPullsItBack) {
  const std::string drawer =
      R"({"name": "drawer", "transform": {"position": [0, 0.5, 0]}, "mesh": {"shape": "box", "size_m": [0.3, 0.1, 0.3]},
      "body": {"type": "dynamic", "mass_kg": 1}, "joint": {"type": "slider", "axis": [0, 0, 1], "limits_m": [0, 0.25]}},
      {"name": "sprung", "transform": {"position": [1, 0.5, 0]}, "mesh": {"shape": "box", "size_m": [0.3, 0.1, 0.3]},
      "body": {"type": "dynamic", "mass_kg": 1}, "joint": {"type": "slider", "axis": [0, 0, 1], "limits_m": [-0.3, 0.3],
      "spring": {"stiffness": 100, "damping": 20, "rest": 0.1}}},
      {"name": "driven", "transform": {"position": [2, 0.5, 0]}, "mesh": {"shape": "box", "size_m": [0.3, 0.1, 0.3]},
      "body": {"type": "dynamic", "mass_kg": 1}, "joint": {"type": "slider", "axis": [0, 0, 1], "limits_m": [0, 0.25],
      "motor": {"velocity": 0.1, "max_force": 50}}})";
  Stage r(scene_of(drawer));
  r.body("drawer")->setLinearVelocity(btVector3(0.3f, 0.5f, 2.0f));  // out, and sideways and up
  r.seconds(1.0);
  EXPECT_NEAR(r.value("drawer"), 0.25, 0.005);
  const btVector3 p = r.body("drawer")->getWorldTransform().getOrigin();
  EXPECT_NEAR(p.x(), 0.0f, 0.003f);
  EXPECT_NEAR(p.y(), 0.5f, 0.003f);
  EXPECT_NEAR(p.z(), 0.25f, 0.005f);
  // The driven one moves out at its motor's 10 cm/s, along +axis as the value counts.
  EXPECT_NEAR(r.value("driven"), 0.1, 0.01);
  EXPECT_NEAR(static_cast<double>(r.body("driven")->getWorldTransform().getOrigin().z()), 0.1, 0.01);
  // The sprung one settles at its rest position, 10 cm out.
  r.seconds(3.0);
  EXPECT_NEAR(r.value("sprung"), 0.1, 0.01);
}

TEST(Joints, AFixedJointCarriesOneBodyWithAnotherAndABallJointSwingsAboutItsPivot) {
  const std::string parts =
      R"({"name": "base", "transform": {"position": [0, 0.3, 0]}, "mesh": {"shape": "box", "size_m": [0.2, 0.05, 0.2]},
      "body": {"type": "dynamic", "mass_kg": 1}},
      {"name": "mast", "transform": {"position": [0, 0.45, 0]}, "mesh": {"shape": "box", "size_m": [0.02, 0.25, 0.02]},
      "body": {"type": "dynamic", "mass_kg": 0.2}, "joint": {"type": "fixed", "connected_to": "base"}},
      {"name": "bob", "transform": {"position": [1.3, 1.0, 0]}, "mesh": {"shape": "sphere", "radius_m": 0.05},
      "body": {"type": "dynamic", "mass_kg": 0.5}, "joint": {"type": "ball", "anchor_m": [-0.3, 0, 0]}})";
  Stage r(scene_of(parts));
  const btTransform start = r.body("base")->getWorldTransform().inverse() * r.body("mast")->getWorldTransform();
  r.body("base")->setAngularVelocity(btVector3(0, 3, 0));
  double lowest = 10.0;
  for (int i = 0; i < 180; ++i) {
    r.step();
    // The pendulum's bob stays 30 cm from its pivot at (1, 1, 0) as it swings down.
    EXPECT_NEAR((r.body("bob")->getWorldTransform().getOrigin() - btVector3(1, 1, 0)).length(), 0.3f, 0.01f);
    lowest = std::min(lowest, static_cast<double>(r.body("bob")->getWorldTransform().getOrigin().y()));
  }
  EXPECT_LT(lowest, 0.75) << "it swung down";
  const btTransform now = r.body("base")->getWorldTransform().inverse() * r.body("mast")->getWorldTransform();
  EXPECT_LT((now.getOrigin() - start.getOrigin()).length(), 0.005f);
  EXPECT_LT(now.getRotation().angleShortestPath(start.getRotation()), 0.02f);
  EXPECT_LT(r.body("base")->getWorldTransform().getOrigin().y(), 0.1f) << "the pair fell to the floor together";
}

// A button cap 4 x 1.5 x 4 cm in a static panel (its parent, which it does not collide with),
// pushed down 1 cm to its stop.
const std::string kButton = R"({"name": "base", "transform": {"position": [0, 0.4, 0]}, "mesh": {"shape": "box", "size_m": [0.1, 0.8, 0.1]},
      "body": {"type": "static"}},
      {"name": "button", "parent": "base", "transform": {"position": [0, 0.4025, 0]}, "mesh": {"shape": "box", "size_m": [0.04, 0.015, 0.04]},
      "body": {"type": "dynamic", "mass_kg": 0.02}, "button": {"axis": [0, -1, 0], "travel_m": 0.01}},
      {"name": "lamp", "transform": {"position": [0.3, 0.05, 0]}, "mesh": {"shape": "sphere", "radius_m": 0.05},
      "material": {"color": [0.2, 0.2, 0.2]}})";
constexpr double kButtonTop = 0.81;

// The right hand pointing its index finger down, its tip at `tip`.
HandInput pointing_at(const Eigen::Vector3d& tip) {
  const HandPose pose = pointing_hand(HandSide::kRight);
  const Eigen::Vector3d dir = pose.position_m[static_cast<std::size_t>(HandJoint::kIndexTip)] -
                              pose.position_m[static_cast<std::size_t>(HandJoint::kIndexProximal)];
  const Eigen::Quaterniond q = rotation_between(dir, -Eigen::Vector3d::UnitY());
  const Eigen::Vector3d t = tip - q * pose.position_m[static_cast<std::size_t>(HandJoint::kIndexTip)];
  return hand_input(Rigid3d{q, t}, pose);
}

// The right hand's palm at `palm`, back of the hand down, its fingers curled up out of the way
// and the pointing finger 10 cm off to the side.
HandInput palm_at(const Eigen::Vector3d& palm) {
  const HandPose pose = pointing_hand(HandSide::kRight);
  const auto at = [&](HandJoint j) { return pose.position_m[static_cast<std::size_t>(j)]; };
  const Eigen::Quaterniond along = rotation_between(at(HandJoint::kIndexTip) - at(HandJoint::kIndexProximal), Eigen::Vector3d::UnitX());
  Eigen::Vector3d up = along * (at(HandJoint::kMiddleTip) - at(HandJoint::kPalm));
  up.x() = 0.0;
  const Eigen::Quaterniond q = rotation_between(up, Eigen::Vector3d::UnitY()) * along;
  return hand_input(Rigid3d{q, palm - q * at(HandJoint::kPalm)}, pose);
}

TEST(Buttons, AFingertipPressesOncePerPushAndThePalmNever) {
  Stage r(scene_of(kButton));
  // Twice: the fingertip down from 3 cm above the cap to 1.5 cm into it (the cap stops at 1 cm), and up.
  for (int push = 0; push < 2; ++push) {
    for (int i = 0; i <= 60; ++i) {
      const double depth = i <= 30 ? 0.03 - 0.045 * i / 30.0 : -0.015 + 0.045 * (i - 30) / 30.0;
      r.step({HandInput{}, pointing_at(Eigen::Vector3d(0, kButtonTop + depth + 0.008, 0))});
    }
  }
  EXPECT_EQ(r.count(InteractionEventType::kPress), 2);
  EXPECT_EQ(r.count(InteractionEventType::kUnpress), 2);
  EXPECT_FALSE(r.physics->mechanisms().pressed(r.named("button")));
  // The palm pushes it to the bottom: no press.
  Stage palm(scene_of(kButton));
  double deepest = 0.0;
  for (int i = 0; i <= 60; ++i) {
    // The palm's centre from 6 cm above the cap to 1.5 cm below its top, and back.
    const double depth = i <= 30 ? 0.06 - 0.075 * i / 30.0 : -0.015 + 0.075 * (i - 30) / 30.0;
    palm.step({HandInput{}, palm_at(Eigen::Vector3d(0, kButtonTop + depth, 0))});
    deepest = std::max(deepest, palm.value("button"));
  }
  EXPECT_GT(deepest, 0.008) << "the palm did push it down";
  EXPECT_EQ(palm.count(InteractionEventType::kPress), 0);
  // Left alone, the cap springs back out.
  palm.seconds(0.5);
  EXPECT_LT(palm.value("button"), 0.001);
}

// A flat touch panel: its top at 0.8 m.
const std::string kPanel = R"({"name": "panel", "transform": {"position": [0, 0.4, 0]}, "mesh": {"shape": "box", "size_m": [0.1, 0.8, 0.1]},
      "body": {"type": "static"}, "pokeable": true})";

TEST(Pokes, AFingertipTouchingAPokeablePanelPokesOncePerTouchAndThePalmNever) {
  Stage r(
      scene_of(kPanel, R"(, "rules": [{"when": {"event": "poke", "entity": "panel"}, "do": [{"action": "succeed", "name": "poked"}]}])"));
  // Down onto the panel and 3 mm into it, held there 0.5 s (one poke), up 3 cm for 0.3 s, down again.
  const auto touch = [&](double hold_s) {
    for (int i = 0; i <= 20; ++i) r.step({HandInput{}, pointing_at(Eigen::Vector3d(0, 0.8 + 0.03 - 0.033 * i / 20.0 + 0.008, 0))});
    for (int i = 0; i < static_cast<int>(hold_s * 90); ++i) r.step({HandInput{}, pointing_at(Eigen::Vector3d(0, 0.797 + 0.008, 0))});
    for (int i = 0; i <= 27; ++i) r.step({HandInput{}, pointing_at(Eigen::Vector3d(0, 0.83 + 0.008, 0))});
  };
  touch(0.5);
  EXPECT_EQ(r.count(InteractionEventType::kPoke), 1);
  touch(0.2);
  EXPECT_EQ(r.count(InteractionEventType::kPoke), 2);
  EXPECT_EQ(r.count(InteractionEventType::kSuccess), 2);
  const auto poke =
      std::find_if(r.events.begin(), r.events.end(), [](const InteractionEvent& e) { return e.type == InteractionEventType::kPoke; });
  EXPECT_EQ(poke->subject, r.named("panel"));
  // The palm flat on it (the pointing finger off its edge): no poke.
  Stage palm(scene_of(kPanel));
  bool touched = false;
  for (int i = 0; i <= 60; ++i) {
    const double depth = i <= 30 ? 0.06 - 0.062 * i / 30.0 : -0.002 + 0.062 * (i - 30) / 30.0;
    palm.step({HandInput{}, palm_at(Eigen::Vector3d(-0.03, 0.8 + depth, 0))});
    touched = touched || palm.physics->grasp().contacts()[1].contains(palm.named("panel"));
  }
  EXPECT_TRUE(touched) << "the palm touched it";
  EXPECT_EQ(palm.count(InteractionEventType::kPoke), 0);
}

TEST(Zones, AnObjectComingIntoAndLeavingAZoneRaisesEnterAndExit) {
  const std::string entities =
      R"({"name": "zone", "transform": {"position": [0, 0.1, 0]}, "mesh": {"shape": "box", "size_m": [0.3, 0.2, 0.3]}},
      {"name": "cube", "transform": {"position": [-0.5, 0.025, 0]}, "mesh": {"shape": "box", "size_m": [0.05, 0.05, 0.05]},
      "body": {"type": "dynamic", "mass_kg": 0.1, "friction": 0.0}},
      {"name": "lamp", "transform": {"position": [1, 1, 1]}, "mesh": {"shape": "sphere", "radius_m": 0.05}, "material": {"color": [0.2, 0.2, 0.2]}})";
  const std::string rules = R"(, "rules": [
      {"when": {"event": "enter", "entity": "zone", "object": "cube"}, "do": [{"action": "set_color", "entity": "lamp", "color": [1, 1, 0]}]},
      {"when": {"event": "exit", "entity": "zone"}, "do": [{"action": "set_color", "entity": "lamp", "color": [0, 0, 1]}]}])";
  Stage r(scene_of(entities, rules));
  r.seconds(0.2);
  EXPECT_EQ(r.count(InteractionEventType::kEnter), 0);
  // Slid along the floor through the zone at 1 m/s.
  for (int i = 0; i < 90; ++i) {
    r.body("cube")->setLinearVelocity(btVector3(1, 0, 0));
    r.step();
    if (r.count(InteractionEventType::kEnter) == 1 && r.count(InteractionEventType::kExit) == 0) {
      EXPECT_EQ(r.world.get<Material>(r.named("lamp")).color, glm::vec4(1, 1, 0, 1));
    }
  }
  ASSERT_EQ(r.count(InteractionEventType::kEnter), 1);
  ASSERT_EQ(r.count(InteractionEventType::kExit), 1);
  const auto enter =
      std::find_if(r.events.begin(), r.events.end(), [](const InteractionEvent& e) { return e.type == InteractionEventType::kEnter; });
  const auto exit =
      std::find_if(r.events.begin(), r.events.end(), [](const InteractionEvent& e) { return e.type == InteractionEventType::kExit; });
  EXPECT_EQ(enter->subject, r.named("zone"));
  EXPECT_EQ(enter->object, r.named("cube"));
  // Entered at x = -0.15, left at 0.15: 0.3 s apart at 1 m/s.
  EXPECT_NEAR(exit->time_s - enter->time_s, 0.3, 0.03);
  EXPECT_EQ(r.world.get<Material>(r.named("lamp")).color, glm::vec4(0, 0, 1, 1));
}

TEST(Rules, APressLightsTheLampAndADoorOpenedPastSixtyDegreesSucceeds) {
  const std::string rules = R"(, "rules": [
      {"when": {"event": "press", "entity": "button"}, "do": [{"action": "set_color", "entity": "lamp", "color": [1, 0.9, 0.5]},
                                                             {"action": "motor", "entity": "door", "velocity": 90, "max_force": 200}]},
      {"when": {"event": "value_above", "entity": "door", "value": 60}, "do": [{"action": "succeed", "name": "door-open"},
                                                                             {"action": "disable", "entity": "lamp"}], "once": true},
      {"when": {"event": "success", "interaction": "door-open"}, "do": [{"action": "spawn", "entity": "ball", "position": [0.5, 0.3, 0.5]}]}])";
  const std::string ball = R"({"name": "ball", "transform": {"position": [-0.5, 0.05, 0]}, "mesh": {"shape": "sphere", "radius_m": 0.05},
      "body": {"type": "dynamic", "mass_kg": 0.1}, "grabbable": true, "tags": ["toy"]})";
  // The door stands off to the side at x = 1.
  std::string d = door(R"(, "limits_deg": [0, 120])");
  d.replace(d.find("[0, 1.0, 0]"), 11, "[1, 1.0, 0]");
  Stage r(scene_of(std::string(kButton) + ", " + d + ", " + ball, rules.substr(0, rules.size())));
  r.seconds(0.2);
  EXPECT_NEAR(r.value("door"), 0.0, 0.5);
  EXPECT_EQ(r.world.get<Material>(r.named("lamp")).color, glm::vec4(0.2f, 0.2f, 0.2f, 1.0f));
  for (int i = 0; i <= 30; ++i) r.step({HandInput{}, pointing_at(Eigen::Vector3d(0, kButtonTop + 0.03 - 0.045 * i / 30.0 + 0.008, 0))});
  ASSERT_EQ(r.count(InteractionEventType::kPress), 1);
  EXPECT_EQ(r.world.get<Material>(r.named("lamp")).color, glm::vec4(1.0f, 0.9f, 0.5f, 1.0f));
  r.seconds(1.5);  // driven at 90 degrees a second
  EXPECT_GT(r.value("door"), 100.0);
  ASSERT_EQ(r.count(InteractionEventType::kValueAbove), 1);
  ASSERT_EQ(r.count(InteractionEventType::kSuccess), 1);
  const auto success =
      std::find_if(r.events.begin(), r.events.end(), [](const InteractionEvent& e) { return e.type == InteractionEventType::kSuccess; });
  EXPECT_EQ(success->interaction, "door-open");
  EXPECT_TRUE(r.world.has<Disabled>(r.named("lamp")));
  // The spawned copy fell from 30 cm onto the floor at (0.5, 0.05, 0.5), a body of its own.
  const Entity copy = r.named("ball#1");
  ASSERT_FALSE(copy.is_null());
  ASSERT_NE(r.physics->physics().body(copy), nullptr);
  EXPECT_NEAR(r.physics->physics().body(copy)->getWorldTransform().getOrigin().y(), 0.05f, 0.005f);
  EXPECT_TRUE(r.world.has<Grabbable>(copy));
  EXPECT_EQ(r.world.get<Tags>(copy).values, std::vector<std::string>{"toy"});
  EXPECT_EQ(r.physics->rules().fired(), (std::vector<int>{1, 1, 1}));
}

// The grasp bench's cube on a pedestal (top at 0.8 m) with a socket 7.5 cm above it.
std::string socket_scene(const std::string& accepts) {
  return scene_of(R"({"name": "pedestal", "transform": {"position": [0, 0.4, 0]}, "mesh": {"shape": "box", "size_m": [0.12, 0.8, 0.12]},
      "body": {"type": "static", "friction": 0.8}},
      {"name": "cube", "transform": {"position": [0, 0.825, 0]}, "mesh": {"shape": "box", "size_m": [0.05, 0.05, 0.05]},
      "body": {"type": "dynamic", "mass_kg": 0.1, "friction": 0.8}, "grabbable": true, "tags": ["peg"]},
      {"name": "holder", "transform": {"position": [0, 0.9, 0], "rotation_deg": [0, 30, 0]},
      "socket": {"accepts": [)" +
                  accepts + R"(], "snap_distance_m": 0.03, "attach": {"position": [0, 0.01, 0]}}})");
}

struct SocketStage : Stage {
  GraspPose grasp = make_grasp(HandSide::kRight, 0.05, 0.006, 2);
  explicit SocketStage(const std::string& accepts) : Stage(socket_scene(accepts)) {}
  bool hidden = false;  // every fingertip hidden from the cameras (confidence 0.6, as the tracker estimates them)
  void hand(double closure, double lift_m, double across_m = 0.0) {
    std::array<HandInput, 2> hands;
    hands[1] = hand_input(grasp.place(Eigen::Vector3d(across_m, 0.825 + lift_m, 0.0), Eigen::Vector3d::UnitX()), grasp.pose(closure));
    if (hidden) {
      for (int digit = 0; digit < 5; ++digit)
        hands[1].confidence[static_cast<std::size_t>(chain_joints(static_cast<Finger>(digit))[3])] = 0.6;
    }
    step(hands);
  }
  // Reach and close on the cube with every finger seen, lift it 8 cm (its centre 5 mm from the
  // attach point), and rest there `rest_s` with the fingertips hidden and the hand closed.
  void carry_in_and_hide(double rest_s) {
    for (int i = 0; i < 45; ++i) hand(0.0, 0.15 * (1.0 - i / 44.0));
    for (int i = 0; i < 45; ++i) hand(i / 44.0, 0.0);
    for (int i = 0; i < 45; ++i) hand(1.0, 0.08 * i / 44.0);
    hidden = true;
    for (int i = 0; i < static_cast<int>(rest_s * 90.0); ++i) hand(1.0, 0.08);
  }
  const InteractionEvent* first(InteractionEventType type) const {
    const auto it = std::ranges::find_if(events, [&](const InteractionEvent& e) { return e.type == type; });
    return it == events.end() ? nullptr : &*it;
  }
  // Reach, close, lift 8 cm (the cube's centre 5 mm from the attach point), open, take the hand up.
  void carry_and_let_go() {
    for (int i = 0; i < 45; ++i) hand(0.0, 0.15 * (1.0 - i / 44.0));
    for (int i = 0; i < 45; ++i) hand(i / 44.0, 0.0);
    for (int i = 0; i < 45; ++i) hand(1.0, 0.08 * i / 44.0);
    for (int i = 0; i < 30; ++i) hand(1.0 - i / 29.0, 0.08);
    for (int i = 0; i < 45; ++i) hand(0.0, 0.08 + 0.2 * i / 44.0);
  }
};

TEST(Sockets, AnAcceptedObjectReleasedNearTheAttachPoseSnapsAndAHandTakesItOut) {
  SocketStage r(R"("peg")");
  r.carry_and_let_go();
  ASSERT_EQ(r.count(InteractionEventType::kRelease), 1);
  ASSERT_EQ(r.count(InteractionEventType::kSnap), 1);
  EXPECT_EQ(r.physics->mechanisms().held_in(r.named("holder")), r.named("cube"));
  r.seconds(1.0);
  // Held at the attach pose (0, 0.91, 0), turned 30 degrees with the socket, against gravity.
  const btTransform pose = r.body("cube")->getWorldTransform();
  EXPECT_LT((pose.getOrigin() - btVector3(0, 0.91f, 0)).length(), 0.002f);
  EXPECT_LT(pose.getRotation().angleShortestPath(btQuaternion(btVector3(0, 1, 0), 0.5236f)), 0.01f);
  // The hand comes back, grasps it (unsnap) and lifts it away.
  for (int i = 0; i < 45; ++i) r.hand(0.0, 0.085 + 0.1 * (1.0 - i / 44.0));
  for (int i = 0; i < 45; ++i) r.hand(i / 44.0, 0.085);
  ASSERT_EQ(r.count(InteractionEventType::kUnsnap), 1);
  for (int i = 0; i < 45; ++i) r.hand(1.0, 0.085 + 0.1 * i / 44.0);
  EXPECT_GT(r.body("cube")->getWorldTransform().getOrigin().y(), 0.97f);
  EXPECT_FALSE(r.physics->mechanisms().held_in(r.named("holder")).has_value());
}

// The peg of the workbench: a palm-down hand hides its own grip, so a hand that opened over the
// socket was seen to open only seconds later, and the peg left with it (seeds 201, 218, 219).
TEST(Sockets, ASeatedObjectStaysWhenAHandWhoseGripIsHiddenLeaves) {
  SocketStage r(R"("peg")");
  r.carry_in_and_hide(0.5);
  ASSERT_EQ(r.count(InteractionEventType::kGrasp), 1);
  ASSERT_EQ(r.count(InteractionEventType::kRelease), 0) << "resting in the socket, not yet let go";
  // The hand goes up, still closed as far as anything measured says.
  for (int i = 0; i < 45; ++i) r.hand(1.0, 0.08 + 0.2 * i / 44.0);
  ASSERT_EQ(r.count(InteractionEventType::kRelease), 1);
  EXPECT_EQ(r.first(InteractionEventType::kRelease)->reason, "left in the socket (no finger seen holding it)");
  ASSERT_EQ(r.count(InteractionEventType::kSnap), 1);
  EXPECT_EQ(r.physics->mechanisms().held_in(r.named("holder")), r.named("cube"));
  r.seconds(1.0);
  EXPECT_LT((r.body("cube")->getWorldTransform().getOrigin() - btVector3(0, 0.91f, 0)).length(), 0.002f);
}

TEST(Sockets, AnObjectSeenHeldCarriedPastOrTakenOutLeavesWithTheHand) {
  {
    // Every fingertip seen closed on it: the hand is seen holding it, whatever the socket.
    SocketStage r(R"("peg")");
    r.carry_in_and_hide(0.5);
    r.hidden = false;
    for (int i = 0; i < 45; ++i) r.hand(1.0, 0.08 + 0.2 * i / 44.0);
    EXPECT_EQ(r.count(InteractionEventType::kRelease), 0);
    EXPECT_EQ(r.count(InteractionEventType::kSnap), 0);
    EXPECT_GT(r.body("cube")->getWorldTransform().getOrigin().y(), 1.05f);
  }
  for (int jump = 3; jump <= 9; ++jump) {
    // Seen closed on it, but for one frame of the way up (the `jump`th) measured half open (its
    // fingertips more than the release distance out of the cube: a tracking jump): one frame is no
    // opening, and the socket leaves it in the hand. (It took it, "left in the socket", when one
    // frame was enough.)
    SocketStage r(R"("peg")");
    r.carry_in_and_hide(0.5);
    r.hidden = false;
    for (int i = 0; i < 45; ++i) r.hand(i == jump ? 0.5 : 1.0, 0.08 + 0.2 * i / 44.0);
    EXPECT_EQ(r.count(InteractionEventType::kRelease), 0) << "the jump at frame " << jump;
    EXPECT_EQ(r.count(InteractionEventType::kSnap), 0) << "the jump at frame " << jump;
    EXPECT_GT(r.body("cube")->getWorldTransform().getOrigin().y(), 1.05f) << "the jump at frame " << jump;
  }
  {
    // Hidden, but swept through the socket at 0.25 m/s without resting there.
    SocketStage r(R"("peg")");
    r.carry_in_and_hide(0.0);
    for (int i = 0; i < 65; ++i) r.hand(1.0, 0.08, 0.18 * i / 64.0);
    EXPECT_EQ(r.count(InteractionEventType::kRelease), 0);
    EXPECT_GT(r.body("cube")->getWorldTransform().getOrigin().x(), 0.15f);
  }
  {
    // Put in the socket, then grasped in it and taken out by a hand whose fingertips hide.
    SocketStage r(R"("peg")");
    r.carry_and_let_go();
    ASSERT_EQ(r.count(InteractionEventType::kSnap), 1);
    for (int i = 0; i < 45; ++i) r.hand(0.0, 0.085 + 0.1 * (1.0 - i / 44.0));
    for (int i = 0; i < 45; ++i) r.hand(i / 44.0, 0.085);
    ASSERT_EQ(r.count(InteractionEventType::kUnsnap), 1);
    r.hidden = true;
    for (int i = 0; i < 45; ++i) r.hand(1.0, 0.085);
    for (int i = 0; i < 45; ++i) r.hand(1.0, 0.085 + 0.1 * i / 44.0);
    EXPECT_EQ(r.count(InteractionEventType::kSnap), 1) << "not put back";
    EXPECT_GT(r.body("cube")->getWorldTransform().getOrigin().y(), 0.97f);
  }
}

TEST(Sockets, AnObjectTheSocketDoesNotAcceptFalls) {
  SocketStage r(R"("bolt", "washer")");
  r.carry_and_let_go();
  ASSERT_EQ(r.count(InteractionEventType::kRelease), 1);
  EXPECT_EQ(r.count(InteractionEventType::kSnap), 0);
  r.seconds(1.0);
  EXPECT_NEAR(r.body("cube")->getWorldTransform().getOrigin().y(), 0.825f, 0.005f) << "back on the pedestal";
}

TEST(SceneRulesFile, UnknownEventsActionsAndWrongEntitiesAreRefusedNamingWhere) {
  const auto error = [](const std::string& entities, const std::string& rest) {
    auto scene = parse_scene(scene_of(entities, rest), RHOT_SOURCE_DIR "/tests/engine/physics/data", "s.json");
    return scene ? std::string("loaded") : scene.error().to_string();
  };
  const std::string d = door(R"(, "limits_deg": [0, 90])");
  EXPECT_EQ(error(d, R"(, "rules": [{"when": {"event": "explode"}, "do": [{"action": "succeed", "name": "x"}]}])"),
            "s.json: /rules/0/when/event: unknown event \"explode\"; expected one of: \"grasp\", \"release\", \"press\", \"unpress\", "
            "\"snap\", \"unsnap\", \"value_above\", \"value_below\", \"poke\", \"enter\", \"exit\", \"success\"");
  EXPECT_EQ(error(d, R"(, "rules": [{"when": {"event": "press"}, "do": [{"action": "teleport", "entity": "door"}]}])"),
            "s.json: /rules/0/do/0/action: unknown action \"teleport\"; expected one of: \"set_color\", \"enable\", \"disable\", "
            "\"motor\", \"spawn\", \"succeed\"");
  EXPECT_EQ(error(d, R"(, "rules": [{"when": {"event": "press", "entity": "door"}, "do": [{"action": "succeed", "name": "x"}]}])"),
            "s.json: /rules/0/when/entity: \"door\" is not a button");
  EXPECT_EQ(
      error(
          d,
          R"(, "rules": [{"when": {"event": "value_above", "entity": "floor", "value": 3}, "do": [{"action": "succeed", "name": "x"}]}])"),
      "s.json: /rules/0/when/entity: \"floor\" has no hinge or slider joint to take a value from");
  EXPECT_EQ(
      error(d,
            R"(, "rules": [{"when": {"event": "grasp"}, "do": [{"action": "motor", "entity": "floor", "velocity": 1, "max_force": 1}]}])"),
      "s.json: /rules/0/do/0/entity: \"floor\" has no hinge or slider joint to drive");
  EXPECT_EQ(error(d, R"(, "rules": [{"when": {"event": "grasp"}, "do": []}])"), "s.json: /rules/0/do: expected at least one action");
  EXPECT_EQ(error(d, R"(, "rules": [{"when": {"event": "poke", "entity": "door"}, "do": [{"action": "succeed", "name": "x"}]}])"),
            "s.json: /rules/0/when/entity: \"door\" is not pokeable");
  EXPECT_EQ(error(d, R"(, "rules": [{"when": {"event": "enter", "entity": "door"}, "do": [{"action": "succeed", "name": "x"}]}])"),
            "s.json: /rules/0/when/entity: \"door\" is not a zone (a box mesh without a body)");
  EXPECT_EQ(error(d, R"(, "rules": [{"when": {"event": "exit"}, "do": [{"action": "succeed", "name": "x"}]}])"),
            "s.json: /rules/0/when: an exit rule needs the zone as its \"entity\"");
  EXPECT_EQ(error(R"({"name": "p", "mesh": {"shape": "sphere", "radius_m": 0.1}, "pokeable": true})", ""),
            "s.json: /entities/1/pokeable: only an entity with a body can be poked");
  EXPECT_EQ(
      error(d, R"(, "rules": [{"when": {"event": "success", "interaction": "nope"}, "do": [{"action": "enable", "entity": "door"}]}])"),
      "s.json: /rules/0/when/interaction: no interaction or \"succeed\" action is named \"nope\"");
  EXPECT_EQ(error(door(R"(, "limits_deg": [90, 0])"), ""),
            "s.json: /entities/1/joint/limits_deg: expected [lower, upper] with lower <= upper, got an array");
  EXPECT_EQ(error(door(R"(, "limits_m": [0, 1])"), ""),
            "s.json: /entities/1/joint/limits_m: unknown key \"limits_m\"; expected one of: type, connected_to, anchor_m, axis, "
            "limits_deg, friction, spring, motor");
  EXPECT_EQ(error(door(R"(, "connected_to": "ghost")"), ""), "s.json: /entities/1/joint/connected_to: no entity is named \"ghost\"");
  EXPECT_EQ(
      error(R"({"name": "b", "mesh": {"shape": "sphere", "radius_m": 0.1}, "body": {"type": "static"}, "joint": {"type": "ball"}})", ""),
      "s.json: /entities/1/joint: a joint moves a dynamic body; give the entity a \"body\" of type \"dynamic\"");
  EXPECT_EQ(
      error(
          R"({"name": "b", "mesh": {"shape": "sphere", "radius_m": 0.1}, "body": {"type": "dynamic", "mass_kg": 1}, "joint": {"type": "hinge", "axis": [0, 0, 0]}})",
          ""),
      "s.json: /entities/1/joint/axis: expected a direction [x, y, z] that is not zero, got an array");
  EXPECT_EQ(
      error(
          R"({"name": "b", "mesh": {"shape": "box", "size_m": [0.04, 0.01, 0.04]}, "body": {"type": "dynamic", "mass_kg": 0.02}, "button": {"press_at": 0.3, "release_at": 0.5}})",
          ""),
      "s.json: /entities/1/button/release_at: expected release_at below press_at (0.300000)");
  EXPECT_EQ(error(d, R"(, "rules": [{"when": {"event": "grasp"}, "do": [{"action": "spawn", "entity": "door"}]}])"),
            "s.json: /rules/0/do/0/entity: \"door\" cannot be copied: a copy takes its mesh, material, body and tags, not a joint, button, "
            "socket or marker star");
}

// The showcase scene: untouched, nothing fires; the door pushed, the drawer pulled and the button
// pressed by a fingertip, each raises its success.
TEST(Workbench, UntouchedNothingFiresAndEachMechanismSucceedsWhenWorked) {
  const auto scene = load_scene_file(RHOT_ASSET_DIR "/scenes/workbench.json");
  ASSERT_TRUE(scene.has_value()) << scene.error().to_string();
  Stage r(*scene);
  ASSERT_NE(r.physics, nullptr);
  const auto successes = [&] {
    std::vector<std::string> names;
    for (const InteractionEvent& e : r.events) {
      if (e.type == InteractionEventType::kSuccess) names.push_back(e.interaction);
    }
    return names;
  };
  r.seconds(2.0);
  EXPECT_TRUE(r.events.empty()) << r.events.size() << " events, the first " << event_name(r.events.front().type);
  EXPECT_NEAR(r.value("door"), 0.0, 0.5);
  EXPECT_NEAR(r.value("drawer"), 0.0, 0.002);
  // The door swung open toward the user (+z) by a push on its free edge.
  for (int i = 0; i < 90; ++i) {
    r.body("door")->applyForce(btVector3(0, 0, 1.0f), r.body("door")->getWorldTransform().getBasis() * btVector3(0.12f, 0, 0));
    r.step();
  }
  EXPECT_GT(r.value("door"), 60.0);
  EXPECT_LE(r.value("door"), 112.0);
  EXPECT_GT(r.body("door")->getWorldTransform().getOrigin().z(), -0.69f) << "it opened outward";
  // The drawer pulled out.
  for (int i = 0; i < 45; ++i) {
    r.body("drawer")->applyCentralForce(btVector3(0, 0, 8.0f));
    r.step();
  }
  EXPECT_NEAR(r.value("drawer"), 0.2, 0.01);
  // The button pressed by a fingertip.
  const btVector3 cap = r.body("button")->getWorldTransform().getOrigin();
  const double top = static_cast<double>(cap.y()) + 0.0075;
  for (int i = 0; i <= 40; ++i) {
    r.step({HandInput{}, pointing_at(Eigen::Vector3d(static_cast<double>(cap.x()), top + 0.04 - 0.055 * i / 40.0 + 0.008,
                                                     static_cast<double>(cap.z())))});
  }
  for (int i = 0; i <= 40; ++i) r.step({HandInput{}, pointing_at(Eigen::Vector3d(0.0, top + 0.2, 0.0))});
  EXPECT_EQ(r.world.get<Material>(r.named("lamp")).color, glm::vec4(1.0f, 0.9f, 0.55f, 1.0f));
  std::vector<std::string> got = successes();
  std::sort(got.begin(), got.end());
  EXPECT_EQ(got, (std::vector<std::string>{"door-open", "drawer-open", "lamp-on"}));
  // (The socket's snap through a scripted hand is tested on its own above; carrying this tall peg
  // there belongs with the scripted tracked-hand run of the showcase, still to come.)
}

}  // namespace
}  // namespace rhot
