#pragma once
// A scene's rules (docs/scene-format.md "rules"): when an event of a kind happens to an entity,
// do actions, without code. Events: grasp, release (of an object), press, unpress (a button),
// snap, unsnap (a socket), value_above, value_below (a joint's value crossing a threshold,
// raised here), poke (a pokeable entity touched by a fingertip), enter, exit (an object's centre
// into or out of a zone, raised here), success (an interaction or a "succeed" action). Actions: set_color, enable,
// disable (an entity leaves the drawn and the physical world and comes back), motor (drive a
// joint), spawn (a copy of an entity), succeed (raise a success event with a name).
//
// update() runs last in a physics step: it raises the value events, then walks the step's events
// in order, those its own actions raise included (a "succeed" may trigger a rule on "success"),
// at most kMaxEventsPerStep of them.

#include <cstddef>
#include <expected>
#include <string>
#include <vector>

#include "engine/core/Entity.h"
#include "engine/interact/GraspSystem.h"
#include "engine/interact/Mechanisms.h"
#include "engine/physics/PhysicsWorld.h"
#include "engine/scene/SceneDesc.h"

namespace rhot {

class World;

class SceneRules {
 public:
  static constexpr std::size_t kMaxEventsPerStep = 1000;

  SceneRules() = default;
  // Finds the rules' entities by name in `world` (instantiated from the same scene).
  [[nodiscard]] static std::expected<SceneRules, std::string> create(World& world, const std::vector<RuleDesc>& rules,
                                                                     const Mechanisms& mechanisms);

  void update(World& world, PhysicsWorld& physics, Mechanisms& mechanisms, std::vector<InteractionEvent>& events);

  // How many times each rule fired, in the scene's order.
  const std::vector<int>& fired() const { return fired_; }
  std::size_t size() const { return rules_.size(); }

 private:
  struct Rule {
    RuleDesc desc;
    Entity entity;                // when.entity, or null for any
    Entity object;                // when.object, or null for any
    std::vector<Entity> targets;  // per action (null for succeed)
    double last_value = 0.0;
    bool has_value = false;
  };
  bool matches(const Rule& rule, const InteractionEvent& e) const;
  void apply(World& world, PhysicsWorld& physics, Mechanisms& mechanisms, const RuleAction& action, Entity target,
             std::vector<InteractionEvent>& events);

  std::vector<Rule> rules_;
  std::vector<int> fired_;
  int spawned_ = 0;
  std::vector<Entity> zones_;                // the zones enter and exit rules watch
  std::vector<std::vector<Entity>> inside_;  // per zone: the objects inside after the last step
  bool zones_seen_ = false;
};

}  // namespace rhot
