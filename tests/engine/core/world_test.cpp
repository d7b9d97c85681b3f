#include "engine/core/World.h"

#include <algorithm>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace rhot {
namespace {

struct Position {
  float x = 0, y = 0;
};
struct Velocity {
  float dx = 0, dy = 0;
};
struct Tag {};
struct Label {
  std::string text;
};

TEST(World, CreateGivesDistinctLiveEntities) {
  World w;
  const Entity a = w.create();
  const Entity b = w.create();
  EXPECT_NE(a, b);
  EXPECT_TRUE(w.alive(a));
  EXPECT_TRUE(w.alive(b));
  EXPECT_EQ(w.size(), 2u);
  EXPECT_FALSE(w.alive(kNullEntity));
}

TEST(World, DestroyMakesHandleStaleAndRemovesComponents) {
  World w;
  const Entity a = w.create();
  w.add<Position>(a, 1.0f, 2.0f);
  w.add<Label>(a, "a");
  w.destroy(a);
  EXPECT_FALSE(w.alive(a));
  EXPECT_EQ(w.size(), 0u);
  EXPECT_EQ(w.count<Position>(), 0u);
  EXPECT_EQ(w.count<Label>(), 0u);
  EXPECT_EQ(w.find<Position>(a), nullptr);
}

TEST(World, ReusedSlotGetsNewGenerationAndOldHandleStaysStale) {
  World w;
  const Entity a = w.create();
  w.add<Position>(a, 1.0f, 1.0f);
  w.destroy(a);
  const Entity b = w.create();
  EXPECT_EQ(b.index, a.index) << "the freed slot is reused";
  EXPECT_EQ(b.generation, a.generation + 1);
  EXPECT_FALSE(w.alive(a));
  EXPECT_TRUE(w.alive(b));
  // The old handle must not reach the new entity's components.
  w.add<Position>(b, 5.0f, 5.0f);
  EXPECT_FALSE(w.has<Position>(a));
  EXPECT_EQ(w.find<Position>(a), nullptr);
  EXPECT_EQ(w.get<Position>(b).x, 5.0f);
}

TEST(WorldDeathTest, StaleHandleIsDetectedNotReused) {
  World w;
  const Entity a = w.create();
  w.destroy(a);
  const Entity b = w.create();
  w.add<Position>(b);
  EXPECT_DEATH(w.get<Position>(a), "World::get: entity 0 \\(generation 0\\) is stale");
  EXPECT_DEATH(w.add<Position>(a), "World::add: entity 0 \\(generation 0\\) is stale");
  EXPECT_DEATH(w.destroy(a), "World::destroy: entity 0 \\(generation 0\\) is stale");
  EXPECT_DEATH(w.remove<Position>(a), "World::remove: entity 0 \\(generation 0\\) is stale");
  EXPECT_DEATH(w.get<Position>(kNullEntity), "World::get: null entity");
}

TEST(WorldDeathTest, GetOfMissingComponentNamesIt) {
  World w;
  const Entity a = w.create();
  w.add<Velocity>(a);
  EXPECT_DEATH(w.get<Position>(a), "entity 0 \\(generation 0\\) has no component .*Position");
}

TEST(World, AddReplacesExistingComponent) {
  World w;
  const Entity a = w.create();
  w.add<Position>(a, 1.0f, 2.0f);
  w.add<Position>(a, 3.0f, 4.0f);
  EXPECT_EQ(w.count<Position>(), 1u);
  EXPECT_EQ(w.get<Position>(a).x, 3.0f);
  EXPECT_EQ(w.get<Position>(a).y, 4.0f);
}

TEST(World, RemoveKeepsOtherEntitiesComponentsIntact) {
  World w;
  std::vector<Entity> es;
  for (int i = 0; i < 10; ++i) {
    es.push_back(w.create());
    w.add<Position>(es.back(), static_cast<float>(i), 0.0f);
  }
  w.remove<Position>(es[3]);  // swap-and-pop moves the last one into the hole
  w.remove<Position>(es[0]);
  EXPECT_EQ(w.count<Position>(), 8u);
  for (int i = 0; i < 10; ++i) {
    if (i == 3 || i == 0) {
      EXPECT_FALSE(w.has<Position>(es[i]));
    } else {
      EXPECT_EQ(w.get<Position>(es[i]).x, static_cast<float>(i));
    }
  }
}

TEST(View, VisitsExactlyTheEntitiesWithAllComponents) {
  World w;
  std::set<std::uint32_t> expected;
  for (int i = 0; i < 100; ++i) {
    const Entity e = w.create();
    if (i % 2 == 0) w.add<Position>(e, static_cast<float>(i), 0.0f);
    if (i % 3 == 0) w.add<Velocity>(e, 1.0f, 0.0f);
    if (i % 2 == 0 && i % 3 == 0) expected.insert(e.index);
  }
  std::set<std::uint32_t> seen;
  w.view<Position, Velocity>().each([&](Entity e, Position& p, Velocity& v) {
    EXPECT_TRUE(seen.insert(e.index).second) << "visited twice";
    EXPECT_EQ(p.x, static_cast<float>(e.index));
    EXPECT_EQ(v.dx, 1.0f);
  });
  EXPECT_EQ(seen, expected);

  int single = 0;
  w.view<Position>().each([&](Position&) { ++single; });
  EXPECT_EQ(single, 50);
}

TEST(View, WritesThroughReferences) {
  World w;
  const Entity e = w.create();
  w.add<Position>(e, 1.0f, 1.0f);
  w.add<Velocity>(e, 2.0f, 3.0f);
  w.view<Position, Velocity>().each([](Position& p, const Velocity& v) {
    p.x += v.dx;
    p.y += v.dy;
  });
  EXPECT_EQ(w.get<Position>(e).x, 3.0f);
  EXPECT_EQ(w.get<Position>(e).y, 4.0f);
}

TEST(View, OverMissingTypeVisitsNothing) {
  World w;
  w.add<Position>(w.create());
  int n = 0;
  w.view<Position, Tag>().each([&](Position&, Tag&) { ++n; });
  EXPECT_EQ(n, 0);
  EXPECT_EQ((w.view<Position, Tag>().size_hint()), 0u);
}

TEST(MutationDuringIteration, DestroyingEveryVisitedEntityVisitsEachOnce) {
  World w;
  for (int i = 0; i < 50; ++i) w.add<Position>(w.create(), static_cast<float>(i), 0.0f);
  int visits = 0;
  w.view<Position>().each([&](Entity e, Position& p) {
    ++visits;
    w.destroy(e);
    EXPECT_TRUE(w.alive(e)) << "destruction is deferred to the end of the iteration";
    p.x = -1.0f;  // the reference stays valid for the rest of the callback
  });
  EXPECT_EQ(visits, 50);
  EXPECT_EQ(w.size(), 0u);
  EXPECT_EQ(w.count<Position>(), 0u);
}

TEST(MutationDuringIteration, DestroyingOtherEntitiesSkipsAndRepeatsNothing) {
  World w;
  std::vector<Entity> es;
  for (int i = 0; i < 20; ++i) {
    es.push_back(w.create());
    w.add<Position>(es.back(), static_cast<float>(i), 0.0f);
  }
  std::multiset<std::uint32_t> visited;
  w.view<Position>().each([&](Entity e, Position&) {
    visited.insert(e.index);
    if (e == es[0]) {
      for (int i = 1; i < 20; i += 2) w.destroy(es[i]);  // would swap-and-pop mid-walk if immediate
    }
  });
  EXPECT_EQ(visited.size(), 20u);
  for (const Entity e : es) EXPECT_EQ(visited.count(e.index), 1u);
  EXPECT_EQ(w.size(), 10u);
  for (int i = 0; i < 20; ++i) EXPECT_EQ(w.alive(es[i]), i % 2 == 0);
}

TEST(MutationDuringIteration, AddedComponentsAndEntitiesAppearAfterTheIteration) {
  World w;
  std::vector<Entity> es;
  for (int i = 0; i < 10; ++i) {
    es.push_back(w.create());
    w.add<Position>(es.back(), static_cast<float>(i), 0.0f);
  }
  int visits = 0;
  w.view<Position>().each([&](Entity e, Position& p) {
    ++visits;
    const Entity spawned = w.create();       // immediate; has no components yet
    w.add<Position>(spawned, 100.0f, 0.0f);  // deferred: this pass does not see it
    w.add<Velocity>(e, p.x, 0.0f);           // deferred
    EXPECT_FALSE(w.has<Velocity>(e));
    EXPECT_GT(w.pending_changes(), 0u);
  });
  EXPECT_EQ(visits, 10);
  EXPECT_EQ(w.count<Position>(), 20u);
  EXPECT_EQ(w.count<Velocity>(), 10u);
  for (int i = 0; i < 10; ++i) EXPECT_EQ(w.get<Velocity>(es[i]).dx, static_cast<float>(i));
  EXPECT_EQ(w.pending_changes(), 0u);
}

TEST(MutationDuringIteration, RemovingComponentsOfTheIteratedTypes) {
  World w;
  for (int i = 0; i < 30; ++i) {
    const Entity e = w.create();
    w.add<Position>(e, static_cast<float>(i), 0.0f);
    w.add<Velocity>(e);
  }
  int visits = 0;
  w.view<Position, Velocity>().each([&](Entity e, Position& p, Velocity&) {
    ++visits;
    if (static_cast<int>(p.x) % 3 == 0) w.remove<Velocity>(e);
  });
  EXPECT_EQ(visits, 30);
  EXPECT_EQ(w.count<Velocity>(), 20u);
  EXPECT_EQ(w.count<Position>(), 30u);
}

TEST(MutationDuringIteration, ChangesApplyInOrderAfterNestedIterations) {
  World w;
  const Entity a = w.create();
  w.add<Position>(a);
  w.add<Velocity>(a);
  w.view<Position>().each([&](Entity e, Position&) {
    w.view<Velocity>().each([&](Entity f, Velocity&) {
      w.add<Label>(f, "first");
      EXPECT_TRUE(w.iterating());
    });
    EXPECT_EQ(w.pending_changes(), 1u) << "the inner iteration must not flush while the outer one runs";
    w.add<Label>(e, "second");  // same entity: applied after, so it wins
    w.destroy(e);               // then destroyed: later adds for it are dropped
    w.add<Tag>(e);
  });
  EXPECT_FALSE(w.iterating());
  EXPECT_FALSE(w.alive(a));
  EXPECT_EQ(w.count<Label>(), 0u);
  EXPECT_EQ(w.count<Tag>(), 0u);
}

TEST(MutationDuringIteration, LastChangeToAComponentWins) {
  World w;
  const Entity a = w.create();
  w.add<Position>(a, 1.0f, 0.0f);
  w.view<Position>().each([&](Entity e, Position&) {
    w.add<Label>(e, "x");
    w.remove<Label>(e);
    w.add<Label>(e, "y");
  });
  ASSERT_TRUE(w.has<Label>(a));
  EXPECT_EQ(w.get<Label>(a).text, "y");
}

TEST(World, ManyCreateDestroyCyclesKeepHandlesUnique) {
  World w;
  std::set<std::pair<std::uint32_t, std::uint32_t>> ever;
  std::vector<Entity> live;
  for (int round = 0; round < 200; ++round) {
    for (int i = 0; i < 5; ++i) {
      const Entity e = w.create();
      EXPECT_TRUE(ever.insert({e.index, e.generation}).second) << "a handle was handed out twice";
      live.push_back(e);
    }
    for (int i = 0; i < 4; ++i) {
      w.destroy(live.front());
      live.erase(live.begin());
    }
  }
  EXPECT_EQ(w.size(), live.size());
  for (const Entity e : live) EXPECT_TRUE(w.alive(e));
}

}  // namespace
}  // namespace rhot
