#include "engine/core/Transform.h"

#include <cmath>

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include "engine/core/World.h"

namespace rhot {
namespace {

glm::vec3 world_point(const World& w, Entity e, glm::vec3 local) {
  return glm::vec3(w.get<WorldTransform>(e).world_from_local * glm::vec4(local, 1.0f));
}

void expect_near(glm::vec3 a, glm::vec3 b, float tol = 1e-5f) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

TEST(Transform, MatrixIsTranslateRotateScale) {
  Transform t;
  t.position = {1, 2, 3};
  t.rotation = glm::angleAxis(glm::radians(90.0f), glm::vec3(0, 1, 0));
  t.scale = {2, 2, 2};
  // +X scaled to 2, rotated 90 deg about +Y to -Z, then moved by (1, 2, 3).
  const glm::vec3 p = glm::vec3(t.matrix() * glm::vec4(1, 0, 0, 1));
  expect_near(p, {1, 2, 1});
}

TEST(Transform, ChildWorldMatrixComposesParents) {
  World w;
  const Entity table = w.create();
  const Entity cup = w.create();
  const Entity handle = w.create();
  Transform tt;
  tt.position = {0, 0.75f, -0.5f};
  tt.rotation = glm::angleAxis(glm::radians(90.0f), glm::vec3(0, 1, 0));
  w.add<Transform>(table, tt);
  Transform ct;
  ct.position = {0.2f, 0.05f, 0};
  w.add<Transform>(cup, ct);
  Transform ht;
  ht.position = {0.04f, 0, 0};
  w.add<Transform>(handle, ht);
  // Parent order is deliberately the reverse of creation order.
  ASSERT_TRUE(set_parent(w, handle, cup).has_value());
  ASSERT_TRUE(set_parent(w, cup, table).has_value());

  update_world_transforms(w);
  // The table turns +X into -Z: the cup sits 0.2 m toward -Z from the table's centre.
  expect_near(world_point(w, cup, {0, 0, 0}), {0, 0.8f, -0.7f});
  expect_near(world_point(w, handle, {0, 0, 0}), {0, 0.8f, -0.74f});

  // Moving the root moves the whole chain on the next update.
  w.get<Transform>(table).position.x = 1.0f;
  update_world_transforms(w);
  expect_near(world_point(w, handle, {0, 0, 0}), {1.0f, 0.8f, -0.74f});
}

TEST(Transform, SetParentRefusesCycles) {
  World w;
  const Entity a = w.create();
  const Entity b = w.create();
  const Entity c = w.create();
  ASSERT_TRUE(set_parent(w, b, a).has_value());
  ASSERT_TRUE(set_parent(w, c, b).has_value());
  const auto r = set_parent(w, a, c);
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error(), "set_parent: making entity 2 (generation 0) the parent of entity 0 (generation 0) would create a cycle");
  EXPECT_FALSE(set_parent(w, a, a).has_value());
  EXPECT_FALSE(w.has<Parent>(a));
}

TEST(Transform, StaleParentIsRefusedAndOrphanBecomesRoot) {
  World w;
  const Entity parent = w.create();
  const Entity child = w.create();
  Transform pt;
  pt.position = {5, 0, 0};
  w.add<Transform>(parent, pt);
  Transform ct;
  ct.position = {1, 0, 0};
  w.add<Transform>(child, ct);
  ASSERT_TRUE(set_parent(w, child, parent).has_value());
  update_world_transforms(w);
  expect_near(world_point(w, child, {0, 0, 0}), {6, 0, 0});

  w.destroy(parent);
  EXPECT_FALSE(set_parent(w, child, parent).has_value());
  update_world_transforms(w);
  expect_near(world_point(w, child, {0, 0, 0}), {1, 0, 0});
}

TEST(Transform, DeepChainNeedsNoRecursion) {
  World w;
  constexpr int kDepth = 100000;
  Entity prev = kNullEntity;
  Entity last = kNullEntity;
  for (int i = 0; i < kDepth; ++i) {
    const Entity e = w.create();
    Transform t;
    t.position = {0.001f, 0, 0};
    w.add<Transform>(e, t);
    if (!prev.is_null()) w.add<Parent>(e, Parent{prev});
    prev = last = e;
  }
  update_world_transforms(w);
  EXPECT_NEAR(world_point(w, last, {0, 0, 0}).x, 100.0f, 0.05f);
}

TEST(Transform, DestroyWithChildrenRemovesTheSubtreeOnly) {
  World w;
  const Entity root = w.create();
  const Entity a = w.create();
  const Entity b = w.create();
  const Entity other = w.create();
  ASSERT_TRUE(set_parent(w, a, root).has_value());
  ASSERT_TRUE(set_parent(w, b, a).has_value());
  destroy_with_children(w, root);
  EXPECT_FALSE(w.alive(root));
  EXPECT_FALSE(w.alive(a));
  EXPECT_FALSE(w.alive(b));
  EXPECT_TRUE(w.alive(other));
}

}  // namespace
}  // namespace rhot
