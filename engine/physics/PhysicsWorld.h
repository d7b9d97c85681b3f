#pragma once
// The Bullet world behind a scene: one rigid body per entity that has a Mesh, a PhysicsBody and
// a WorldTransform (static, dynamic or kinematic; box, sphere, capsule, plane, or the convex hull
// of a glTF mesh), stepped at a fixed rate with a configurable number of substeps.
//
// Each step: kinematic bodies take their entity's WorldTransform (so an object tracked by a
// marker star, whose Transform the tracking system writes, pushes what it meets), Bullet steps,
// and dynamic bodies write their pose back into their entity's Transform. A non-finite pose from
// the ECS is never given to Bullet (the body keeps its last pose, and the log says so once).
//
// Collision groups: scene bodies collide with everything; hand bones (HandColliders) collide with
// the scene but not with each other or the other hand.

#include <expected>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include <btBulletDynamicsCommon.h>
#include <glm/glm.hpp>

#include "engine/core/Entity.h"
#include "engine/scene/Components.h"

namespace rhot {

class World;

struct PhysicsSettings {
  double rate_hz = 90.0;  // one step() advances 1 / rate_hz seconds
  int substeps = 2;       // Bullet steps per step()
  glm::vec3 gravity_mps2{0.0f, -9.81f, 0.0f};
};

enum CollisionGroup : int { kSceneGroup = 1, kHandGroup = 2 };

class PhysicsWorld {
 public:
  explicit PhysicsWorld(PhysicsSettings settings = {});
  ~PhysicsWorld();
  PhysicsWorld(const PhysicsWorld&) = delete;
  PhysicsWorld& operator=(const PhysicsWorld&) = delete;

  // Adds a body for every entity with Mesh + PhysicsBody + WorldTransform that has none yet.
  // Fails, adding nothing, when a glTF mesh cannot be read or a shape is degenerate.
  [[nodiscard]] std::expected<void, std::string> add_scene_bodies(World& world);

  // Copies kinematic poses in, advances one fixed step, copies dynamic poses out (Transform and
  // WorldTransform of the entity).
  void step(World& world);

  double step_s() const { return 1.0 / settings_.rate_hz; }
  double time_s() const { return time_s_; }
  long steps() const { return steps_; }
  const PhysicsSettings& settings() const { return settings_; }

  btDiscreteDynamicsWorld& bullet() { return *world_; }
  btRigidBody* body(Entity e) const;
  std::optional<Entity> entity_of(const btCollisionObject* object) const;
  const std::vector<Entity>& entities() const { return entities_; }

  // Takes an entity's body out of the simulation (false: nothing meets it, it does not move) or
  // puts it back where it was (true). Nothing for an entity without a body.
  void set_enabled(Entity e, bool enabled);

  // Scales an entity's body, shape and mass distribution, to `factor` times the size it was
  // created with, and its entity's Transform and WorldTransform with it (a two-handed stretch).
  // Nothing for an entity without a body, a static one, or a factor that is not finite and > 0.
  void set_scale(World& world, Entity e, double factor);
  // The factor last set (1 for a body never scaled).
  double scale(Entity e) const;

  // A body owned by someone else (hand bones): added with its group and mask, removed by them.
  void add_external(btRigidBody* body, int group, int mask);
  void remove_external(btRigidBody* body);

 private:
  struct Owned;
  PhysicsSettings settings_;
  std::unique_ptr<btDefaultCollisionConfiguration> config_;
  std::unique_ptr<btCollisionDispatcher> dispatcher_;
  std::unique_ptr<btBroadphaseInterface> broadphase_;
  std::unique_ptr<btSequentialImpulseConstraintSolver> solver_;
  std::unique_ptr<btDiscreteDynamicsWorld> world_;
  std::vector<std::unique_ptr<Owned>> owned_;
  std::vector<Entity> entities_;
  std::unordered_map<Entity, btRigidBody*> bodies_;
  std::unordered_map<Entity, Owned*> owned_by_entity_;
  std::unordered_map<const btCollisionObject*, Entity> entity_by_object_;
  double time_s_ = 0.0;
  long steps_ = 0;
  bool warned_non_finite_ = false;
};

}  // namespace rhot
