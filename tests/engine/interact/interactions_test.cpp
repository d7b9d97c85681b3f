// Scene interactions on their own: "place" succeeds once the object rests in its box zone for the
// dwell time, "hand over" on a release the other hand took; entities are checked when created.

#include "engine/interact/Interactions.h"

#include <gtest/gtest.h>

#include "tests/engine/physics/PhysicsTestScenes.h"

namespace rhot {
namespace {

// A cube dropped from 10 cm at x, a box zone 12 x 10 x 12 cm standing on the floor at x = 0.3.
std::string drop_scene(double x, double dwell_s) {
  return std::string(R"({"entities": [)") + test::kFloor +
         R"(, {"name": "zone", "transform": {"position": [0.3, 0.05, 0]}, "mesh": {"shape": "box", "size_m": [0.12, 0.1, 0.12]}},
             {"name": "cube", "transform": {"position": [)" +
         std::to_string(x) + R"(, 0.1, 0]}, "mesh": {"shape": "box", "size_m": [0.04, 0.04, 0.04]},
              "body": {"type": "dynamic", "mass_kg": 0.1}, "grabbable": true}],
          "interactions": [{"name": "cube-in-zone", "type": "place", "object": "cube", "zone": "zone", "dwell_s": )" +
         std::to_string(dwell_s) + "}]}";
}

// Steps with no hands for `seconds`; the success events and when they came.
std::vector<InteractionEvent> run(World& world, HandPhysics& physics, double seconds) {
  std::vector<InteractionEvent> out;
  const int steps = static_cast<int>(seconds / physics.physics().step_s());
  for (int i = 0; i < steps; ++i) {
    physics.step(world, {});
    for (const InteractionEvent& e : physics.events()) {
      if (e.type == InteractionEventType::kSuccess) out.push_back(e);
    }
  }
  return out;
}

TEST(Interactions, PlaceSucceedsOnceAfterTheObjectRestsInTheZoneForTheDwell) {
  World world;
  auto physics = test::physics_for(world, test::parse(drop_scene(0.3, 0.5)));
  ASSERT_EQ(physics->interactions().size(), 1u);
  const auto events = run(world, *physics, 2.0);
  ASSERT_EQ(events.size(), 1u) << "once, never again";
  EXPECT_EQ(events[0].interaction, "cube-in-zone");
  EXPECT_EQ(events[0].object, find_named(world, "cube"));
  EXPECT_FALSE(events[0].hand.has_value());
  // Dropped 8 cm, it lands within about 0.15 s and settles; the dwell counts from rest.
  EXPECT_GE(events[0].time_s, 0.5);
  EXPECT_LT(events[0].time_s, 1.0);
  EXPECT_TRUE(physics->interactions().succeeded("cube-in-zone"));
  EXPECT_FALSE(physics->interactions().succeeded("no-such-interaction"));
}

TEST(Interactions, AnObjectRestingOutsideTheZoneNeverSucceeds) {
  World world;
  auto physics = test::physics_for(world, test::parse(drop_scene(-0.3, 0.25)));
  EXPECT_TRUE(run(world, *physics, 2.0).empty());
  EXPECT_FALSE(physics->interactions().succeeded("cube-in-zone"));
}

TEST(Interactions, MissingEntitiesAreNamed) {
  World world;
  const SceneDesc scene = test::parse(drop_scene(0.3, 0.25));
  instantiate(scene, world);
  std::vector<InteractionDesc> list = {{"lost", InteractionType::kPlace, "ghost", "zone", 0.25}};
  EXPECT_EQ(Interactions::create(world, list).error(), "interaction \"lost\": no entity \"ghost\"");
  list = {{"no-zone", InteractionType::kPlace, "cube", "floor", 0.25}};
  EXPECT_EQ(Interactions::create(world, list).error(), "interaction \"no-zone\": no box zone \"floor\"");
  list = {{"pass", InteractionType::kHandOver, "cube", "", 0.0}};
  EXPECT_TRUE(Interactions::create(world, list).has_value());
}

TEST(Interactions, AHandOverSucceedsOnAReleaseTheOtherHandTook) {
  World world;
  const SceneDesc scene = test::parse(drop_scene(0.3, 0.25));
  auto physics = test::physics_for(world, scene);
  const Entity cube = find_named(world, "cube");
  auto interactions = Interactions::create(world, {{"pass", InteractionType::kHandOver, "cube", "", 0.0}});
  ASSERT_TRUE(interactions.has_value());
  std::vector<InteractionEvent> events = {{InteractionEventType::kRelease, 0.5, cube, HandSide::kRight, {}, false, {}, {}, 0.0, {}}};
  interactions->update(world, physics->physics(), physics->grasp(), events);
  EXPECT_EQ(events.size(), 1u) << "a plain release is no hand-over";
  events = {{InteractionEventType::kRelease, 0.6, cube, HandSide::kRight, {}, true, {}, {}, 0.0, {}}};
  interactions->update(world, physics->physics(), physics->grasp(), events);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[1].type, InteractionEventType::kSuccess);
  EXPECT_EQ(events[1].interaction, "pass");
  EXPECT_TRUE(interactions->succeeded("pass"));
}

}  // namespace
}  // namespace rhot
