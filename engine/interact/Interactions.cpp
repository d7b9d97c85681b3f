#include "engine/interact/Interactions.h"

#include <cmath>

#include "engine/core/Transform.h"
#include "engine/core/World.h"
#include "engine/scene/Components.h"
#include "engine/scene/SceneLoader.h"

namespace rhot {

bool inside_zone(const glm::mat4& world_from_zone, const BoxShape& zone, const btVector3& point) {
  const glm::vec4 local = glm::inverse(world_from_zone) * glm::vec4(point.x(), point.y(), point.z(), 1.0f);
  const glm::vec3 half = 0.5f * zone.size_m;
  return std::abs(local.x) <= half.x && std::abs(local.y) <= half.y && std::abs(local.z) <= half.z;
}

std::expected<Interactions, std::string> Interactions::create(World& world, const std::vector<InteractionDesc>& list) {
  Interactions out;
  const auto find = [&](const std::string& name) { return find_named(world, name); };
  for (const InteractionDesc& d : list) {
    Item item;
    item.desc = d;
    item.object = find(d.object);
    if (item.object.is_null()) return std::unexpected("interaction \"" + d.name + "\": no entity \"" + d.object + "\"");
    if (d.type == InteractionType::kPlace) {
      item.zone = find(d.zone);
      if (item.zone.is_null() || !world.has<Mesh>(item.zone) || !std::holds_alternative<BoxShape>(world.get<Mesh>(item.zone).shape)) {
        return std::unexpected("interaction \"" + d.name + "\": no box zone \"" + d.zone + "\"");
      }
    }
    out.items_.push_back(item);
  }
  return out;
}

bool Interactions::succeeded(const std::string& name) const {
  for (const Item& i : items_) {
    if (i.desc.name == name) return i.done;
  }
  return false;
}

void Interactions::update(World& world, const PhysicsWorld& physics, const GraspSystem& grasp, std::vector<InteractionEvent>& events) {
  const std::size_t grasp_events = events.size();
  for (Item& item : items_) {
    if (item.done || !world.alive(item.object)) continue;
    bool happened = false;
    if (item.desc.type == InteractionType::kHandOver) {
      for (std::size_t k = 0; k < grasp_events; ++k) {
        const InteractionEvent& e = events[k];
        happened = happened || (e.type == InteractionEventType::kRelease && e.handed_over && e.object == item.object);
      }
    } else {
      const btRigidBody* body = physics.body(item.object);
      const WorldTransform* zone = world.find<WorldTransform>(item.zone);
      if (!body || !zone || !world.alive(item.zone)) continue;
      const bool inside =
          inside_zone(zone->world_from_local, std::get<BoxShape>(world.get<Mesh>(item.zone).shape), body->getWorldTransform().getOrigin());
      const bool resting = body->getLinearVelocity().length() < 0.05f;
      if (inside && resting && !grasp.held_by(item.object)) {
        if (item.inside_since_s < 0.0) item.inside_since_s = physics.time_s();
        happened = physics.time_s() - item.inside_since_s >= item.desc.dwell_s - 1e-9;
      } else {
        item.inside_since_s = -1.0;
      }
    }
    if (happened) {
      item.done = true;
      events.push_back({InteractionEventType::kSuccess,
                        physics.time_s(),
                        item.object,
                        std::nullopt,
                        item.desc.name,
                        false,
                        Eigen::Vector3d::Zero(),
                        Entity{},
                        0.0,
                        {}});
    }
  }
}

}  // namespace rhot
