#pragma once
// Transforms and the parent/child hierarchy.
//
//   Transform        the entity's pose relative to its parent (or the world): parent_from_local.
//   Parent           the entity's parent; absent for a root.
//   WorldTransform   world_from_local, kept up to date by update_world_transforms() each frame.
//
// Units are metres; the world is right-handed, +Y up, -Z forward.

#include <expected>
#include <string>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "engine/core/Entity.h"

namespace rhot {

class World;

struct Transform {
  glm::vec3 position{0.0f};
  glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};  // unit quaternion (glm order: w, x, y, z)
  glm::vec3 scale{1.0f};

  // parent_from_local = translate * rotate * scale.
  glm::mat4 matrix() const;
};

struct Parent {
  Entity entity;
};

struct WorldTransform {
  glm::mat4 world_from_local{1.0f};
};

// Makes `parent` the parent of `child`, or detaches `child` when parent is null. Refuses, with a
// message, a parent that is stale or that would close a cycle (including the child itself).
// Precondition: child is alive and the world is not iterating.
[[nodiscard]] std::expected<void, std::string> set_parent(World& world, Entity child, Entity parent);

// Recomputes WorldTransform for every entity with a Transform (adding WorldTransform where it is
// missing), parents before children. An entity whose parent is stale or has no Transform is
// treated as a root. Cost: linear in the number of transforms; deep chains use no recursion.
// Precondition: the world is not iterating.
void update_world_transforms(World& world);

// Destroys an entity and, recursively, every entity parented to it.
void destroy_with_children(World& world, Entity root);

}  // namespace rhot
