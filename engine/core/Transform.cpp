#include "engine/core/Transform.h"

#include <cstdint>
#include <unordered_set>
#include <vector>

#include "engine/core/World.h"
#include "base/Check.h"

namespace rhot {

glm::mat4 Transform::matrix() const {
  glm::mat4 m = glm::mat4_cast(rotation);
  m[0] *= scale.x;
  m[1] *= scale.y;
  m[2] *= scale.z;
  m[3] = glm::vec4(position, 1.0f);
  return m;
}

std::expected<void, std::string> set_parent(World& world, Entity child, Entity parent) {
  RHOT_PRECONDITION(world.alive(child), "set_parent: child " + detail::describe_entity(child) + " is not alive");
  RHOT_PRECONDITION(!world.iterating(), "set_parent: not while a view iterates");
  if (parent.is_null()) {
    world.remove<Parent>(child);
    return {};
  }
  if (!world.alive(parent)) {
    return std::unexpected("set_parent: parent " + detail::describe_entity(parent) + " is stale");
  }
  for (Entity a = parent; !a.is_null() && world.alive(a);) {
    if (a == child) {
      return std::unexpected("set_parent: making " + detail::describe_entity(parent) + " the parent of " + detail::describe_entity(child) +
                             " would create a cycle");
    }
    const Parent* p = world.find<Parent>(a);
    a = p != nullptr ? p->entity : kNullEntity;
  }
  world.add<Parent>(child, Parent{parent});
  return {};
}

void update_world_transforms(World& world) {
  RHOT_PRECONDITION(!world.iterating(), "update_world_transforms: not while a view iterates");

  std::vector<Entity> missing;
  world.view<Transform>().each([&](Entity e, Transform&) {
    if (!world.has<WorldTransform>(e)) missing.push_back(e);
  });
  for (const Entity e : missing) world.add<WorldTransform>(e);

  // Per slot: the frame-local state of the walk. Entities are resolved parent-first by walking up
  // to the nearest resolved ancestor (or a root) and then back down, so each is computed once.
  enum : std::uint8_t { kUnvisited = 0, kOnPath = 1, kDone = 2 };
  std::vector<std::uint8_t> state;
  std::vector<Entity> path;

  world.view<Transform, WorldTransform>().each([&](Entity e, Transform&, WorldTransform&) {
    if (e.index >= state.size()) state.resize(std::size_t{e.index} + 1, kUnvisited);
    if (state[e.index] == kDone) return;

    // Walk up until a root, a resolved ancestor, or (defensively, for a Parent added by hand) a
    // cycle, which is broken by treating the repeated entity as a root.
    path.clear();
    glm::mat4 world_from_parent(1.0f);
    for (Entity a = e;;) {
      if (a.index >= state.size()) state.resize(std::size_t{a.index} + 1, kUnvisited);
      if (state[a.index] == kDone) {
        world_from_parent = world.get<WorldTransform>(a).world_from_local;
        break;
      }
      if (state[a.index] == kOnPath) break;
      state[a.index] = kOnPath;
      path.push_back(a);
      const Parent* p = world.find<Parent>(a);
      if (p == nullptr || !world.alive(p->entity) || !world.has<Transform>(p->entity)) break;
      a = p->entity;
    }
    for (auto it = path.rbegin(); it != path.rend(); ++it) {
      world_from_parent = world_from_parent * world.get<Transform>(*it).matrix();
      world.get<WorldTransform>(*it).world_from_local = world_from_parent;
      state[it->index] = kDone;
    }
  });
}

void destroy_with_children(World& world, Entity root) {
  RHOT_PRECONDITION(world.alive(root), "destroy_with_children: " + detail::describe_entity(root) + " is not alive");
  // Collect the subtree first: one pass over the Parent links per level of depth.
  std::unordered_set<Entity> doomed{root};
  for (bool grew = true; grew;) {
    grew = false;
    world.view<Parent>().each([&](Entity e, Parent& p) {
      if (doomed.contains(p.entity) && doomed.insert(e).second) grew = true;
    });
  }
  for (const Entity e : doomed) world.destroy(e);
}

}  // namespace rhot
