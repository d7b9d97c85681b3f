#include "engine/interact/SceneRules.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <variant>

#include <glm/gtc/matrix_transform.hpp>

#include "engine/core/Transform.h"
#include "engine/core/World.h"
#include "engine/interact/Interactions.h"
#include "engine/scene/Components.h"
#include "engine/scene/SceneLoader.h"

namespace rhot {

namespace {

InteractionEventType event_type(const std::string& name) {
  if (name == "grasp") return InteractionEventType::kGrasp;
  if (name == "release") return InteractionEventType::kRelease;
  if (name == "press") return InteractionEventType::kPress;
  if (name == "unpress") return InteractionEventType::kUnpress;
  if (name == "snap") return InteractionEventType::kSnap;
  if (name == "unsnap") return InteractionEventType::kUnsnap;
  if (name == "value_above") return InteractionEventType::kValueAbove;
  if (name == "value_below") return InteractionEventType::kValueBelow;
  if (name == "poke") return InteractionEventType::kPoke;
  if (name == "enter") return InteractionEventType::kEnter;
  if (name == "exit") return InteractionEventType::kExit;
  return InteractionEventType::kSuccess;
}

}  // namespace

std::expected<SceneRules, std::string> SceneRules::create(World& world, const std::vector<RuleDesc>& rules, const Mechanisms& mechanisms) {
  SceneRules out;
  const auto find = [&](const std::string& name, const std::string& what) -> std::expected<Entity, std::string> {
    if (name.empty()) return Entity{};
    const Entity e = find_named(world, name);
    if (e.is_null()) return std::unexpected("a rule's " + what + ": no entity \"" + name + "\"");
    return e;
  };
  for (const RuleDesc& d : rules) {
    Rule r;
    r.desc = d;
    auto entity = find(d.when.entity, "entity");
    if (!entity) return std::unexpected(entity.error());
    auto object = find(d.when.object, "object");
    if (!object) return std::unexpected(object.error());
    r.entity = *entity;
    r.object = *object;
    for (const RuleAction& a : d.actions) {
      auto target = find(a.entity, a.action);
      if (!target) return std::unexpected(target.error());
      r.targets.push_back(*target);
    }
    if (d.when.event == "value_above" || d.when.event == "value_below") {
      const auto v = mechanisms.value(r.entity);
      if (!v) return std::unexpected("a rule's entity \"" + d.when.entity + "\" has no joint value");
      r.last_value = *v;
      r.has_value = true;
    }
    if ((d.when.event == "enter" || d.when.event == "exit") &&
        std::find(out.zones_.begin(), out.zones_.end(), r.entity) == out.zones_.end()) {
      out.zones_.push_back(r.entity);
    }
    out.rules_.push_back(std::move(r));
  }
  out.inside_.resize(out.zones_.size());
  out.fired_.assign(out.rules_.size(), 0);
  return out;
}

bool SceneRules::matches(const Rule& rule, const InteractionEvent& e) const {
  const RuleTrigger& w = rule.desc.when;
  if (e.type != event_type(w.event)) return false;
  switch (e.type) {
    case InteractionEventType::kGrasp:
    case InteractionEventType::kRelease:
      return rule.entity.is_null() || e.object == rule.entity;
    case InteractionEventType::kSuccess:
      return w.interaction.empty() || e.interaction == w.interaction;
    case InteractionEventType::kSnap:
    case InteractionEventType::kUnsnap:
    case InteractionEventType::kEnter:
    case InteractionEventType::kExit:
      return (rule.entity.is_null() || e.subject == rule.entity) && (rule.object.is_null() || e.object == rule.object);
    case InteractionEventType::kValueAbove:
    case InteractionEventType::kValueBelow:
      return e.subject == rule.entity && e.value == w.value;
    default:
      return rule.entity.is_null() || e.subject == rule.entity;
  }
}

void SceneRules::update(World& world, PhysicsWorld& physics, Mechanisms& mechanisms, std::vector<InteractionEvent>& events) {
  // Crossings of each value rule's threshold since the last step.
  for (Rule& r : rules_) {
    if (!r.has_value) continue;
    const auto v = mechanisms.value(r.entity);
    if (!v) continue;
    const double t = r.desc.when.value;
    const bool above = r.desc.when.event == "value_above";
    if (above ? (r.last_value <= t && *v > t) : (r.last_value >= t && *v < t)) {
      InteractionEvent e{above ? InteractionEventType::kValueAbove : InteractionEventType::kValueBelow,
                         physics.time_s(),
                         r.entity,
                         std::nullopt,
                         {},
                         false,
                         Eigen::Vector3d::Zero(),
                         r.entity,
                         t,
                         {}};
      events.push_back(std::move(e));
    }
    r.last_value = *v;
  }
  // Objects (dynamic bodies) whose centre came into or left a zone the rules watch. The first
  // step only notes what is inside.
  for (std::size_t z = 0; z < zones_.size(); ++z) {
    const WorldTransform* zone = world.find<WorldTransform>(zones_[z]);
    const Mesh* mesh = world.find<Mesh>(zones_[z]);
    if (!zone || !mesh || !world.alive(zones_[z]) || !std::holds_alternative<BoxShape>(mesh->shape)) continue;
    std::vector<Entity> now;
    for (const Entity e : physics.entities()) {
      const btRigidBody* b = physics.body(e);
      if (!b || b->isStaticOrKinematicObject() || !b->getBroadphaseHandle()) continue;
      if (inside_zone(zone->world_from_local, std::get<BoxShape>(mesh->shape), b->getWorldTransform().getOrigin())) now.push_back(e);
    }
    if (zones_seen_) {
      const auto raise = [&](InteractionEventType type, Entity object) {
        events.push_back({type, physics.time_s(), object, std::nullopt, {}, false, Eigen::Vector3d::Zero(), zones_[z], 0.0, {}});
      };
      for (const Entity e : now) {
        if (std::find(inside_[z].begin(), inside_[z].end(), e) == inside_[z].end()) raise(InteractionEventType::kEnter, e);
      }
      for (const Entity e : inside_[z]) {
        if (std::find(now.begin(), now.end(), e) == now.end()) raise(InteractionEventType::kExit, e);
      }
    }
    inside_[z] = std::move(now);
  }
  zones_seen_ = true;
  for (std::size_t k = 0; k < events.size() && k < kMaxEventsPerStep; ++k) {
    for (std::size_t i = 0; i < rules_.size(); ++i) {
      Rule& r = rules_[i];
      if ((r.desc.once && fired_[i] > 0) || !matches(r, events[k])) continue;
      ++fired_[i];
      for (std::size_t a = 0; a < r.desc.actions.size(); ++a) apply(world, physics, mechanisms, r.desc.actions[a], r.targets[a], events);
    }
  }
}

void SceneRules::apply(World& world, PhysicsWorld& physics, Mechanisms& mechanisms, const RuleAction& action, Entity target,
                       std::vector<InteractionEvent>& events) {
  if (action.action == "succeed") {
    events.push_back({InteractionEventType::kSuccess,
                      physics.time_s(),
                      Entity{},
                      std::nullopt,
                      action.name,
                      false,
                      Eigen::Vector3d::Zero(),
                      Entity{},
                      0.0,
                      {}});
    return;
  }
  if (!world.alive(target)) return;
  if (action.action == "set_color") {
    if (Material* m = world.find<Material>(target)) m->color = action.color;
  } else if (action.action == "enable" || action.action == "disable") {
    const bool enable = action.action == "enable";
    if (enable && world.has<Disabled>(target)) world.remove<Disabled>(target);
    if (!enable && !world.has<Disabled>(target)) world.add<Disabled>(target);
    physics.set_enabled(target, enable);
  } else if (action.action == "motor") {
    mechanisms.drive(target, action.velocity, action.max_force);
  } else if (action.action == "spawn") {
    const WorldTransform* pose = world.find<WorldTransform>(target);
    if (!pose) return;
    // A copy at the root of the scene, where the original is (or at the position given).
    glm::mat4 world_from_local = pose->world_from_local;
    if (action.position) world_from_local[3] = glm::vec4(*action.position, 1.0f);
    // The original's parts copied out before the copy is added (adding may move a pool).
    const Name* name = world.find<Name>(target);
    const std::string copy_name = (name ? name->value : std::string("entity")) + "#" + std::to_string(++spawned_);
    const std::optional<Mesh> mesh = world.has<Mesh>(target) ? std::optional(world.get<Mesh>(target)) : std::nullopt;
    const std::optional<Material> material = world.has<Material>(target) ? std::optional(world.get<Material>(target)) : std::nullopt;
    const std::optional<PhysicsBody> body = world.has<PhysicsBody>(target) ? std::optional(world.get<PhysicsBody>(target)) : std::nullopt;
    const std::optional<Tags> tags = world.has<Tags>(target) ? std::optional(world.get<Tags>(target)) : std::nullopt;
    const std::optional<Grabbable> grabbable = world.has<Grabbable>(target) ? std::optional(world.get<Grabbable>(target)) : std::nullopt;
    Transform t;
    t.position = glm::vec3(world_from_local[3]);
    glm::mat3 r(world_from_local);
    for (int i = 0; i < 3; ++i) {
      t.scale[i] = glm::length(r[i]);
      r[i] /= t.scale[i];
    }
    t.rotation = glm::normalize(glm::quat_cast(r));
    const Entity copy = world.create();
    world.add<Name>(copy, Name{copy_name});
    world.add<Transform>(copy, t);
    world.add<WorldTransform>(copy, WorldTransform{world_from_local});
    if (mesh) world.add<Mesh>(copy, *mesh);
    if (material) world.add<Material>(copy, *material);
    if (body) world.add<PhysicsBody>(copy, *body);
    if (grabbable) world.add<Grabbable>(copy, *grabbable);
    if (tags) world.add<Tags>(copy, *tags);
    (void)physics.add_scene_bodies(world);  // its mesh was loaded once already: cannot fail for it
  }
}

}  // namespace rhot
