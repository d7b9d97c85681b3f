#pragma once
// Everything physical in a scene, stepped together once per frame: the Bullet world with the
// scene's bodies, a collider per tracked hand, the grasp system and the scene's interactions.
// One step():
//   hidden fingers placed against what each hand holds or touches (FingerContact.h) -> hand
//   colliders aimed at the hands -> held objects aimed at their grips -> Bullet
//   steps (with substeps) -> contacts read, grasps begun and ended -> buttons, sockets
//   (Mechanisms.h) -> interactions checked -> the scene's rules (SceneRules.h).

#include <array>
#include <expected>
#include <memory>
#include <string>
#include <vector>

#include "engine/interact/FingerContact.h"
#include "engine/interact/GraspSystem.h"
#include "engine/physics/HandColliders.h"
#include "engine/interact/Interactions.h"
#include "engine/interact/Mechanisms.h"
#include "engine/physics/PhysicsWorld.h"
#include "engine/interact/SceneRules.h"
#include "engine/scene/SceneDesc.h"

namespace rhot {

class World;

class HandPhysics {
 public:
  // `world` holds the scene's instantiated entities. Fails, building nothing, on a bad glTF mesh
  // or an interaction, joint or rule whose entities are missing.
  [[nodiscard]] static std::expected<std::unique_ptr<HandPhysics>, std::string> create(World& world, const SceneDesc& scene,
                                                                                       HandColliderSettings hand_settings = {});

  // One frame: hands[0] the left hand, hands[1] the right (seen = false for a hand not tracked).
  void step(World& world, const std::array<HandInput, 2>& hands);
  // One frame of the runtime: the hands are the entities with a Hand component (a side with none
  // is not tracked); afterwards each of them gets a HandBody with where its colliders are and what
  // it holds (engine/hand/HandComponents.h).
  void step(World& world);

  // Events of the last step (grasp system's, the mechanisms', interactions' successes, then what
  // the rules raised).
  const std::vector<InteractionEvent>& events() const { return events_; }
  PhysicsWorld& physics() { return *physics_; }
  const PhysicsWorld& physics() const { return *physics_; }
  GraspSystem& grasp() { return *grasp_; }
  const GraspSystem& grasp() const { return *grasp_; }
  HandColliders& hand(HandSide side) { return *hands_[side == HandSide::kLeft ? 0 : 1]; }
  const Interactions& interactions() const { return interactions_; }
  Mechanisms& mechanisms() { return *mechanisms_; }
  const Mechanisms& mechanisms() const { return *mechanisms_; }
  const SceneRules& rules() const { return rules_; }
  // What the last step did to each hand's hidden fingers (left, right).
  const std::array<FingerPlacement, 2>& placements() const { return placements_; }

 private:
  HandPhysics() = default;
  std::unique_ptr<PhysicsWorld> physics_;
  std::array<std::unique_ptr<HandColliders>, 2> hands_;
  std::unique_ptr<GraspSystem> grasp_;
  std::unique_ptr<FingerContact> finger_contact_;
  std::array<FingerPlacement, 2> placements_;
  Interactions interactions_;
  std::unique_ptr<Mechanisms> mechanisms_;
  SceneRules rules_;
  std::vector<InteractionEvent> events_;
};

}  // namespace rhot
