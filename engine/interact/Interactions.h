#pragma once
// Interactions a scene file declares (docs/scene-format.md "interactions"): each watches the
// world and the grasp events and raises one success event, carrying its name, when it happens.
//   place      the object rests inside the zone's box (not held, slower than 5 cm/s) for dwell_s
//   hand_over  the object passes from one hand's grasp directly to the other's

#include <expected>
#include <string>
#include <vector>

#include "engine/core/Entity.h"
#include "engine/interact/GraspSystem.h"
#include "engine/scene/SceneDesc.h"

namespace rhot {

class World;

// Whether `point` (world) lies inside a zone: the box `zone` (a box mesh's size) posed by
// `world_from_zone`.
bool inside_zone(const glm::mat4& world_from_zone, const BoxShape& zone, const btVector3& point);

class Interactions {
 public:
  Interactions() = default;
  // Finds the interactions' entities by name in `world` (instantiated from the same scene).
  [[nodiscard]] static std::expected<Interactions, std::string> create(World& world, const std::vector<InteractionDesc>& list);

  // After the grasp system's post_step: appends success events to `events`.
  void update(World& world, const PhysicsWorld& physics, const GraspSystem& grasp, std::vector<InteractionEvent>& events);

  bool succeeded(const std::string& name) const;
  std::size_t size() const { return items_.size(); }

 private:
  struct Item {
    InteractionDesc desc;
    Entity object;
    Entity zone;
    double inside_since_s = -1.0;
    bool done = false;
  };
  std::vector<Item> items_;
};

}  // namespace rhot
