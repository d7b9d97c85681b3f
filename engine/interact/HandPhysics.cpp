#include "engine/interact/HandPhysics.h"

#include <algorithm>

#include "engine/core/World.h"
#include "engine/hand/HandComponents.h"

namespace rhot {

std::expected<std::unique_ptr<HandPhysics>, std::string> HandPhysics::create(World& world, const SceneDesc& scene,
                                                                             HandColliderSettings hand_settings) {
  std::unique_ptr<HandPhysics> p(new HandPhysics());
  PhysicsSettings settings;
  settings.rate_hz = scene.settings.headset.refresh_hz;
  settings.substeps = scene.settings.physics_substeps;
  settings.gravity_mps2 = scene.settings.gravity_mps2;
  p->physics_ = std::make_unique<PhysicsWorld>(settings);
  if (auto added = p->physics_->add_scene_bodies(world); !added) return std::unexpected(added.error());
  auto interactions = Interactions::create(world, scene.interactions);
  if (!interactions) return std::unexpected(interactions.error());
  p->interactions_ = std::move(*interactions);
  auto mechanisms = Mechanisms::create(world, *p->physics_);
  if (!mechanisms) return std::unexpected(mechanisms.error());
  p->mechanisms_ = std::move(*mechanisms);
  auto rules = SceneRules::create(world, scene.rules, *p->mechanisms_);
  if (!rules) return std::unexpected(rules.error());
  p->rules_ = std::move(*rules);
  p->hands_[0] = std::make_unique<HandColliders>(*p->physics_, HandSide::kLeft, hand_settings);
  p->hands_[1] = std::make_unique<HandColliders>(*p->physics_, HandSide::kRight, hand_settings);
  p->grasp_ = std::make_unique<GraspSystem>(*p->physics_, std::array<HandColliders*, 2>{p->hands_[0].get(), p->hands_[1].get()},
                                            scene.settings.grasp);
  FingerContactSettings contact;
  contact.confident = scene.settings.grasp.confident;
  contact.max_curl_rad = scene.settings.grasp.hidden_finger_curl_rad;
  contact.hover_distance_m = scene.settings.grasp.hover_distance_m;
  // Resting short of an object still touches it for the grasp rule: within half its contact distance.
  contact.rest_gap_m = std::min(contact.rest_gap_m, 0.5 * scene.settings.grasp.contact_distance_m);
  p->finger_contact_ = std::make_unique<FingerContact>(*p->physics_, *p->grasp_, contact);
  return p;
}

void HandPhysics::step(World& world, const std::array<HandInput, 2>& hands) {
  std::array<HandInput, 2> placed = hands;
  for (std::size_t h = 0; h < 2; ++h) {
    placements_[h] = finger_contact_->place(world, h == 0 ? HandSide::kLeft : HandSide::kRight, physics_->time_s(), placed[h]);
    hands_[h]->drive(placed[h]);
  }
  grasp_->pre_step(world);
  physics_->step(world);
  grasp_->post_step(world);
  events_ = grasp_->events();
  mechanisms_->update(world, *grasp_, events_);
  interactions_.update(world, *physics_, *grasp_, events_);
  rules_.update(world, *physics_, *mechanisms_, events_);
}

void HandPhysics::step(World& world) {
  std::array<HandInput, 2> inputs;
  world.view<Hand>().each([&](Entity, Hand& hand) { inputs[hand.side == HandSide::kLeft ? 0 : 1] = hand.tracked; });
  step(world, inputs);
  std::vector<Entity> without_body;
  world.view<Hand>().each([&](Entity e, Hand& hand) {
    if (world.find<HandBody>(e) == nullptr) without_body.push_back(e);
    (void)hand;
  });
  for (const Entity e : without_body) world.add<HandBody>(e);
  world.view<Hand, HandBody>().each([&](Entity, Hand& hand, HandBody& body) {
    const HandColliders& colliders = *hands_[hand.side == HandSide::kLeft ? 0 : 1];
    body.active = colliders.active();
    body.joints_world = colliders.physical_joints();
    body.capsules = colliders.capsules();
    body.holding = grasp_->holding(hand.side);
  });
}

}  // namespace rhot
