#include "engine/interact/Mechanisms.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <BulletDynamics/ConstraintSolver/btGeneric6DofSpring2Constraint.h>
#include <BulletDynamics/ConstraintSolver/btPoint2PointConstraint.h>

#include "engine/core/Transform.h"
#include "engine/core/World.h"
#include "engine/hand/HandInput.h"
#include "engine/physics/BulletMath.h"
#include "engine/scene/Components.h"
#include "engine/scene/SceneLoader.h"

namespace rhot {

namespace {

constexpr double kDegPerRad = 180.0 / std::numbers::pi;
constexpr int kLinearX = 0;   // the 6-DoF constraint's free axis for a slider ...
constexpr int kAngularX = 3;  // ... and for a hinge: the joint frame's x axis

// An entity's pose without its scale.
btTransform pose_of(const glm::mat4& world_from_local) {
  glm::mat3 r(world_from_local);
  for (int i = 0; i < 3; ++i) r[i] = glm::normalize(r[i]);
  return btTransform(to_bt(glm::normalize(glm::quat_cast(r))), to_bt(glm::vec3(world_from_local[3])));
}

// A frame at `anchor` whose x axis is `axis` (unit).
btTransform axis_frame(const glm::vec3& anchor, const glm::vec3& axis) {
  const btVector3 x(1, 0, 0), a = to_bt(axis);
  btQuaternion q = x.dot(a) < -0.9999f ? btQuaternion(btVector3(0, 1, 0), btScalar(std::numbers::pi)) : shortestArcQuat(x, a);
  return btTransform(q, to_bt(anchor));
}

bool is_fingertip_bone(int bone) {
  const HandJoint to = hand_bones()[static_cast<std::size_t>(bone)].to;
  return to == HandJoint::kThumbTip || to == HandJoint::kIndexTip || to == HandJoint::kMiddleTip || to == HandJoint::kRingTip ||
         to == HandJoint::kLittleTip;
}

// A 6-DoF constraint holding `body` at its present pose relative to `other` (or the world), every
// axis locked; the caller frees what a joint allows.
std::unique_ptr<btGeneric6DofSpring2Constraint> locked(btRigidBody& body, btRigidBody* other, const btTransform& frame_in_body) {
  std::unique_ptr<btGeneric6DofSpring2Constraint> c;
  if (other) {
    const btTransform frame_in_other = other->getCenterOfMassTransform().inverse() * body.getCenterOfMassTransform() * frame_in_body;
    c = std::make_unique<btGeneric6DofSpring2Constraint>(*other, body, frame_in_other, frame_in_body);
  } else {
    c = std::make_unique<btGeneric6DofSpring2Constraint>(body, frame_in_body);
  }
  c->setLinearLowerLimit(btVector3(0, 0, 0));
  c->setLinearUpperLimit(btVector3(0, 0, 0));
  c->setAngularLowerLimit(btVector3(0, 0, 0));
  c->setAngularUpperLimit(btVector3(0, 0, 0));
  return c;
}

// A ball joint's constraint: `body` pivots about `anchor` (in its own frame) on `other` or the world.
std::unique_ptr<btTypedConstraint> ball_constraint(btRigidBody& body, btRigidBody* other, const glm::vec3& anchor) {
  const btVector3 pivot = to_bt(anchor);
  if (other) {
    const btVector3 in_other = other->getCenterOfMassTransform().inverse() * (body.getCenterOfMassTransform() * pivot);
    return std::make_unique<btPoint2PointConstraint>(body, *other, pivot, in_other);
  }
  return std::make_unique<btPoint2PointConstraint>(body, pivot);
}

// A fixed, hinge or slider joint's 6-DoF constraint; `axis` becomes a hinge's or slider's free
// axis (kAngularX or kLinearX), left as it is for a fixed joint.
std::unique_ptr<btGeneric6DofSpring2Constraint> six_dof_constraint(btRigidBody& body, btRigidBody* other, const Joint& joint, int& axis) {
  // A hinge's frame turns the other way round its x axis: Bullet's angle is of the other body
  // relative to this one, and the value is this one's turn about `axis` (right-handed).
  auto c = locked(body, other, axis_frame(joint.anchor_m, joint.type == JointType::kHinge ? -joint.axis : joint.axis));
  const bool hinge = joint.type == JointType::kHinge, slider = joint.type == JointType::kSlider;
  if (!hinge && !slider) return c;
  axis = hinge ? kAngularX : kLinearX;
  const double scale = hinge ? 1.0 / kDegPerRad : 1.0;
  // Free (lower above upper) or within the limits.
  const double lo = joint.limits ? (*joint.limits)[0] * scale : 1.0, hi = joint.limits ? (*joint.limits)[1] * scale : -1.0;
  if (hinge) {
    c->setAngularLowerLimit(btVector3(static_cast<btScalar>(lo), 0, 0));
    c->setAngularUpperLimit(btVector3(static_cast<btScalar>(hi), 0, 0));
  } else {
    c->setLinearLowerLimit(btVector3(static_cast<btScalar>(lo), 0, 0));
    c->setLinearUpperLimit(btVector3(static_cast<btScalar>(hi), 0, 0));
  }
  if (joint.spring) {
    c->enableSpring(axis, true);
    c->setStiffness(axis, static_cast<btScalar>(joint.spring->stiffness));
    c->setDamping(axis, static_cast<btScalar>(joint.spring->damping));
    c->setEquilibriumPoint(axis, static_cast<btScalar>(joint.spring->rest * scale));
  }
  return c;
}

// A button's spring along its axis, on `base` (its parent's body) or the world; the button's body
// then floats free of gravity and never sleeps.
std::unique_ptr<btGeneric6DofSpring2Constraint> button_constraint(btRigidBody& body, btRigidBody* base, const Button& button) {
  auto c = locked(body, base, axis_frame(glm::vec3(0.0f), button.axis));
  c->setLinearLowerLimit(btVector3(0, 0, 0));
  c->setLinearUpperLimit(btVector3(static_cast<btScalar>(button.travel_m), 0, 0));
  c->enableSpring(kLinearX, true);
  c->setStiffness(kLinearX, static_cast<btScalar>(button.stiffness));
  // Critically damped: it comes back out without ringing.
  const double mass_kg = 1.0 / std::max(1e-6, static_cast<double>(body.getInvMass()));
  c->setDamping(kLinearX, static_cast<btScalar>(2.0 * std::sqrt(button.stiffness * mass_kg)));
  c->setEquilibriumPoint(kLinearX, 0);
  body.setFlags(body.getFlags() | BT_DISABLE_WORLD_GRAVITY);
  body.setGravity(btVector3(0, 0, 0));
  body.setActivationState(DISABLE_DEACTIVATION);
  return c;
}

}  // namespace

struct Mechanisms::Part {
  enum class Kind { kJoint, kButton, kSocket };
  Kind kind = Kind::kJoint;
  Entity entity;
  JointType joint_type = JointType::kFixed;
  std::unique_ptr<btTypedConstraint> constraint;
  btGeneric6DofSpring2Constraint* six = nullptr;  // constraint, when it is a 6-DoF one
  int axis = -1;                                  // its free axis: kLinearX or kAngularX
  double friction = 0.0;
  Button button;
  bool pressed = false;
  Socket socket;
  std::optional<Entity> held;
  std::unique_ptr<btTypedConstraint> hold;      // a socket's grip on what it holds
  std::unordered_map<Entity, Seating> seating;  // held objects it accepts, near it
};

Mechanisms::~Mechanisms() {
  if (!physics_) return;
  for (auto& p : parts_) {
    if (p->constraint) physics_->bullet().removeConstraint(p->constraint.get());
    if (p->hold) physics_->bullet().removeConstraint(p->hold.get());
  }
}

std::expected<std::unique_ptr<Mechanisms>, std::string> Mechanisms::create(World& world, PhysicsWorld& physics) {
  std::unique_ptr<Mechanisms> made(new Mechanisms());
  Mechanisms& out = *made;
  std::string error;
  const auto label = [&](Entity e) {
    const Name* n = world.find<Name>(e);
    return n ? n->value : std::string("entity");
  };
  world.view<Joint>().each([&](Entity e, Joint& joint) {
    if (!error.empty()) return;
    btRigidBody* body = physics.body(e);
    btRigidBody* other = joint.connected_to.empty() ? nullptr : physics.body(find_named(world, joint.connected_to));
    if (!body || (!joint.connected_to.empty() && !other)) {
      error = label(e) + ": its joint needs " + (!body ? "a body of its own" : "a body on \"" + joint.connected_to + "\"");
      return;
    }
    auto part = std::make_unique<Part>();
    part->kind = Part::Kind::kJoint;
    part->entity = e;
    part->joint_type = joint.type;
    part->friction = joint.friction;
    if (joint.type == JointType::kBall) {
      part->constraint = ball_constraint(*body, other, joint.anchor_m);
    } else {
      auto c = six_dof_constraint(*body, other, joint, part->axis);
      part->six = c.get();
      part->constraint = std::move(c);
    }
    body->setActivationState(DISABLE_DEACTIVATION);
    if (other) other->activate(true);
    out.parts_.push_back(std::move(part));
  });
  if (!error.empty()) return std::unexpected(error);
  world.view<Button>().each([&](Entity e, Button& button) {
    if (!error.empty()) return;
    btRigidBody* body = physics.body(e);
    if (!body || body->isStaticOrKinematicObject()) {
      error = label(e) + ": a button needs a dynamic body";
      return;
    }
    auto part = std::make_unique<Part>();
    part->kind = Part::Kind::kButton;
    part->entity = e;
    part->button = button;
    part->axis = kLinearX;
    // On its parent's body, if it has one (a button in its panel: the two never collide), or on
    // the world.
    const Parent* parent = world.find<Parent>(e);
    btRigidBody* base = parent ? physics.body(parent->entity) : nullptr;
    auto c = button_constraint(*body, base, button);
    part->six = c.get();
    part->constraint = std::move(c);
    out.parts_.push_back(std::move(part));
  });
  if (!error.empty()) return std::unexpected(error);
  world.view<Socket>().each([&](Entity e, Socket& socket) {
    auto part = std::make_unique<Part>();
    part->kind = Part::Kind::kSocket;
    part->entity = e;
    part->socket = socket;
    out.parts_.push_back(std::move(part));
  });
  world.view<Pokeable>().each([&](Entity e, Pokeable&) { out.pokeables_.push_back({e}); });
  // All built: now into the world (nothing half added on failure above).
  out.physics_ = &physics;
  for (std::size_t i = 0; i < out.parts_.size(); ++i) {
    Part& p = *out.parts_[i];
    out.by_entity_[p.entity] = i;
    if (p.constraint) physics.bullet().addConstraint(p.constraint.get(), true);
  }
  // Motors given in the scene start now, joints' friction otherwise.
  world.view<Joint>().each([&](Entity e, Joint& joint) {
    if (joint.type != JointType::kHinge && joint.type != JointType::kSlider) return;
    if (joint.motor) {
      out.drive(e, joint.motor->velocity, joint.motor->max_force);
    } else {
      out.drive(e, 0.0, 0.0);
    }
  });
  return made;
}

std::optional<double> Mechanisms::value(Entity e) const {
  const auto it = by_entity_.find(e);
  if (it == by_entity_.end()) return std::nullopt;
  const Part& p = *parts_[it->second];
  if (!p.six || p.axis < 0) return std::nullopt;
  p.six->calculateTransforms();
  if (p.axis == kAngularX) return static_cast<double>(p.six->getAngle(0)) * kDegPerRad;
  return static_cast<double>(p.six->getRelativePivotPosition(0));
}

bool Mechanisms::drive(Entity e, double velocity, double max_force) {
  const auto it = by_entity_.find(e);
  if (it == by_entity_.end()) return false;
  Part& p = *parts_[it->second];
  if (p.kind != Part::Kind::kJoint || !p.six || p.axis < 0) return false;
  // Bullet's linear motor drives the other body's frame along the axis, the reverse of the value.
  const double scale = p.axis == kAngularX ? 1.0 / kDegPerRad : -1.0;
  // Friction is a motor that holds still with at most the friction force.
  const bool motor = max_force > 0.0;
  const double force = motor ? max_force : p.friction;
  p.six->enableMotor(p.axis, force > 0.0);
  p.six->setTargetVelocity(p.axis, static_cast<btScalar>(motor ? velocity * scale : 0.0));
  p.six->setMaxMotorForce(p.axis, static_cast<btScalar>(force));
  if (btRigidBody* b = physics_->body(e)) b->activate(true);
  return true;
}

std::optional<Entity> Mechanisms::held_in(Entity socket) const {
  const auto it = by_entity_.find(socket);
  if (it == by_entity_.end()) return std::nullopt;
  return parts_[it->second]->held;
}

bool Mechanisms::pressed(Entity button) const {
  const auto it = by_entity_.find(button);
  return it != by_entity_.end() && parts_[it->second]->pressed;
}

bool Mechanisms::accepts(World& world, const Part& socket, Entity object) const {
  if (socket.socket.accepts.empty()) return true;
  const Name* name = world.find<Name>(object);
  const Tags* tags = world.find<Tags>(object);
  for (const std::string& a : socket.socket.accepts) {
    if ((name && name->value == a) || (tags && std::ranges::find(tags->values, a) != tags->values.end())) return true;
  }
  return false;
}

// Held objects seated in a free socket stay there when a hand not seen holding them leaves:
// let go of here, the snap below takes them.
void Mechanisms::seat_held_objects(World& world, GraspSystem& grasp, std::vector<InteractionEvent>& events, double dt) {
  const std::vector<Entity> held = grasp.held_objects();
  for (auto& part : parts_) {
    Part& p = *part;
    if (p.kind != Part::Kind::kSocket) continue;
    std::erase_if(p.seating, [&](const auto& s) { return std::ranges::find(held, s.first) == held.end(); });
    const WorldTransform* socket_pose = world.find<WorldTransform>(p.entity);
    if (p.held || !socket_pose || world.has<Disabled>(p.entity)) {
      p.seating.clear();
      continue;
    }
    const btVector3 attach =
        (pose_of(socket_pose->world_from_local) * btTransform(to_bt(p.socket.attach_rotation), to_bt(p.socket.attach_position)))
            .getOrigin();
    for (const Entity object : held) {
      btRigidBody* body = physics_->body(object);
      if (!body || !accepts(world, p, object)) continue;
      bool in_another = false;
      for (const auto& other : parts_) in_another = in_another || (other->held && *other->held == object);
      if (in_another) continue;
      const double d = static_cast<double>((body->getWorldTransform().getOrigin() - attach).length());
      const bool inside = d <= p.socket.snap_distance_m;
      auto [it, fresh] = p.seating.try_emplace(object);
      Seating& s = it->second;
      if (fresh) s.armed = !inside;  // grasped inside (taken out of the socket, say): not until it has left
      if (!inside) {
        s = Seating{};
        s.armed = true;
        continue;
      }
      if (!s.armed) continue;
      s.nearest_m = std::min(s.nearest_m, d);
      // Its velocity smoothed over kSeatSmoothing_s: a tracked hand held still jitters by millimetres a frame.
      s.velocity += (body->getLinearVelocity() - s.velocity) * static_cast<btScalar>(std::min(1.0, dt / kSeatSmoothing_s));
      if (static_cast<double>(s.velocity.length()) < kSeatSpeed_mps) s.rested_s += dt;
      if (s.rested_s < kSeat_s) continue;
      const double leaving_at = std::min(s.nearest_m + kUnseat_m, 0.9 * p.socket.snap_distance_m);
      if (d <= leaving_at || grasp.grip_seen_closed(object)) continue;
      for (InteractionEvent& e : grasp.let_go(object, "left in the socket (no finger seen holding it)")) events.push_back(std::move(e));
      p.seating.erase(object);
    }
  }
}

void Mechanisms::update(World& world, GraspSystem& grasp, std::vector<InteractionEvent>& events) {
  const double now = physics_->time_s();
  seat_held_objects(world, grasp, events, last_update_s_ < 0.0 ? 0.0 : now - last_update_s_);
  last_update_s_ = now;
  const auto raise = [&](InteractionEventType type, Entity subject, Entity object) {
    InteractionEvent ev{type, now, object, std::nullopt, {}, false, Eigen::Vector3d::Zero(), subject, 0.0, {}};
    events.push_back(std::move(ev));
  };
  const std::size_t grasp_events = events.size();
  const auto fingertip_on = [&](Entity e) {
    for (const auto& hand : grasp.contacts()) {
      const auto it = hand.find(e);
      if (it == hand.end()) continue;
      for (const GraspSystem::Contact& c : it->second) {
        if (is_fingertip_bone(c.bone)) return true;
      }
    }
    return false;
  };
  for (Poked& p : pokeables_) {
    if (!fingertip_on(p.entity)) continue;
    if (now - p.touched_s > kPokeGap_s) raise(InteractionEventType::kPoke, p.entity, p.entity);
    p.touched_s = now;
  }
  for (auto& part : parts_) {
    Part& p = *part;
    if (p.kind == Part::Kind::kButton) {
      const double depth = value(p.entity).value_or(0.0);
      if (!p.pressed && depth >= p.button.press_at * p.button.travel_m) {
        if (fingertip_on(p.entity)) {
          p.pressed = true;
          raise(InteractionEventType::kPress, p.entity, p.entity);
        }
      } else if (p.pressed && depth <= p.button.release_at * p.button.travel_m) {
        p.pressed = false;
        raise(InteractionEventType::kUnpress, p.entity, p.entity);
      }
    } else if (p.kind == Part::Kind::kSocket) {
      // A hand took what it held: let go.
      if (p.held) {
        for (std::size_t k = 0; k < grasp_events; ++k) {
          if (events[k].type != InteractionEventType::kGrasp || events[k].object != *p.held) continue;
          physics_->bullet().removeConstraint(p.hold.get());
          p.hold.reset();
          const Entity object = *p.held;
          p.held.reset();
          raise(InteractionEventType::kUnsnap, p.entity, object);
          break;
        }
      }
      if (p.held || world.has<Disabled>(p.entity)) continue;
      const WorldTransform* socket_pose = world.find<WorldTransform>(p.entity);
      if (!socket_pose) continue;
      const btTransform attach =
          pose_of(socket_pose->world_from_local) * btTransform(to_bt(p.socket.attach_rotation), to_bt(p.socket.attach_position));
      for (std::size_t k = 0; k < grasp_events && !p.held; ++k) {
        const InteractionEvent& ev = events[k];
        if (ev.type != InteractionEventType::kRelease || ev.handed_over || grasp.held_by(ev.object)) continue;
        btRigidBody* object = physics_->body(ev.object);
        if (!object ||
            static_cast<double>((object->getWorldTransform().getOrigin() - attach.getOrigin()).length()) > p.socket.snap_distance_m)
          continue;
        const bool accepted = accepts(world, p, ev.object);
        bool taken = false;  // by another socket
        for (const auto& other : parts_) taken = taken || (other->held && *other->held == ev.object);
        if (!accepted || taken) continue;
        object->setWorldTransform(attach);
        object->getMotionState()->setWorldTransform(attach);
        object->setInterpolationWorldTransform(attach);
        object->setLinearVelocity(btVector3(0, 0, 0));
        object->setAngularVelocity(btVector3(0, 0, 0));
        object->activate(true);
        auto c = locked(*object, physics_->body(p.entity), btTransform::getIdentity());
        physics_->bullet().addConstraint(c.get(), true);
        p.hold = std::move(c);
        p.held = ev.object;
        raise(InteractionEventType::kSnap, p.entity, ev.object);
      }
    }
  }
}

}  // namespace rhot
