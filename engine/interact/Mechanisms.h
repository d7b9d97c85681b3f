#pragma once
// The mechanical parts of a scene (docs/scene-format.md "joints", "buttons", "sockets"), built on
// Bullet constraints between the scene's bodies:
//   joint   hinge (a door, a lever, a lid), slider (a drawer), fixed or ball, with limits,
//           friction, a spring and a motor; its value (hinge: degrees, slider: metres from where
//           the scene put it) is what rules test. A held object on a joint moves only as the
//           joint lets it: the grip aims the object's velocity and the constraint solver removes
//           what the joint forbids, so the hand drags the door round its hinge.
//   button  the entity's body slides along its axis up to its travel, sprung back out, without
//           gravity; pushed past press_at of its travel while a fingertip touches it, it raises a
//           press; back above release_at, an unpress (hysteresis: one press per push). A palm or
//           knuckle pushing it never presses.
//   socket  an object it accepts, released within snap_distance of its attach pose, is put there
//           and held by a fixed constraint (snap); a hand that grasps it takes it out (unsnap).
//           One object at a time. An object carried in and seated (kept within snap_distance,
//           nearly still, for kSeat_s) stays in the socket when the hand leaves unless the hand
//           is seen to hold it (GraspSystem::grip_seen_closed): the socket takes it out of a grip
//           whose fingers are hidden, as a joint keeps a handle (docs/grasping.md, "Sockets are held").
//
// update() runs after the grasp system's post_step and appends its events.

#include <expected>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "engine/core/Entity.h"
#include "engine/interact/GraspSystem.h"
#include "engine/physics/PhysicsWorld.h"

class btTypedConstraint;

namespace rhot {

class World;

class Mechanisms {
 public:
  ~Mechanisms();
  Mechanisms(const Mechanisms&) = delete;
  Mechanisms& operator=(const Mechanisms&) = delete;

  // Builds the constraints of every entity with a Joint or Button (their bodies already in
  // `physics`) and finds every Socket. Fails, adding nothing, when a joint's other entity has no
  // body. The constraints live as long as this object; `physics` must outlive it.
  [[nodiscard]] static std::expected<std::unique_ptr<Mechanisms>, std::string> create(World& world, PhysicsWorld& physics);

  // After the grasp system's post_step: buttons pressed and released, objects snapped and taken
  // out, pokeable entities touched by a fingertip, seated objects taken from a hidden grip;
  // appends kPress, kUnpress, kSnap, kUnsnap, kPoke events, and the kRelease of an object a socket
  // takes (GraspSystem::let_go), to `events` (which holds the grasp system's of this step).
  void update(World& world, GraspSystem& grasp, std::vector<InteractionEvent>& events);

  // A held object counts as seated in a socket after kSeat_s within its snap distance, moving
  // slower than kSeatSpeed_mps (its velocity smoothed over kSeatSmoothing_s). The hand leaves
  // once the object is kUnseat_m farther from the attach point than it came (or at 90 % of the
  // snap distance); then, unless a finger is seen holding it, the socket takes it.
  static constexpr double kSeat_s = 0.25;
  static constexpr double kSeatSpeed_mps = 0.15;
  static constexpr double kSeatSmoothing_s = 0.1;
  static constexpr double kUnseat_m = 0.02;

  // A hinge's angle in degrees or a slider's position in metres (a button's depth in metres),
  // from where the scene put it; nothing for an entity without one.
  std::optional<double> value(Entity e) const;
  // Drives a hinge or slider joint at `velocity` (degrees/s or m/s) with at most `max_force`;
  // max_force 0 lets it go (back to its friction). False for an entity without one.
  bool drive(Entity e, double velocity, double max_force);
  // The object a socket holds.
  std::optional<Entity> held_in(Entity socket) const;
  bool pressed(Entity button) const;

 private:
  Mechanisms() = default;
  struct Part;
  // A held object near a socket: how long it has rested within the snap distance and how near it came.
  struct Seating {
    bool armed = false;  // carried in from outside the snap distance (not grasped inside it)
    double rested_s = 0.0;
    double nearest_m = 1e9;
    btVector3 velocity{0, 0, 0};  // smoothed
  };
  void seat_held_objects(World& world, GraspSystem& grasp, std::vector<InteractionEvent>& events, double dt);
  bool accepts(World& world, const Part& socket, Entity object) const;
  double last_update_s_ = -1.0;
  PhysicsWorld* physics_ = nullptr;
  std::vector<std::unique_ptr<Part>> parts_;
  std::unordered_map<Entity, std::size_t> by_entity_;
  struct Poked {
    Entity entity;
    double touched_s = -1e9;  // the last step a fingertip touched it
  };
  std::vector<Poked> pokeables_;
  static constexpr double kPokeGap_s = 0.2;  // untouched this long, a touch is a new poke
};

}  // namespace rhot
