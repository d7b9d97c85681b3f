#include "engine/physics/HandColliders.h"

#include <algorithm>
#include <cmath>

#include "engine/physics/BulletMath.h"
#include "tracking/core/Solvers.h"

namespace rhot {

namespace {

std::size_t at(HandJoint j) { return static_cast<std::size_t>(j); }

bool input_finite(const HandInput& in) {
  if (!in.world_from_hand.translation.allFinite() || !in.world_from_hand.rotation.coeffs().allFinite()) return false;
  for (const auto& p : in.joints_world) {
    if (!p.allFinite()) return false;
  }
  for (const double r : in.radius_m) {
    if (!std::isfinite(r)) return false;
  }
  return true;
}

// A capsule along +Y from a to b, turned by the shortest arc from `reference`'s +Y. A bone's body
// is driven with the world's (the identity). Its frame (HandColliders::tracked_bone) takes the
// frame of the bone before it in its digit, or, for a digit's first bone, the hand's with +Y turned
// to the fingers (-Z); so its roll follows the hand and never flips. From the world's +Y a bone
// pointing down (a pinching thumb) had its roll swing half a turn between two frames, and a grip
// point on its surface 15 mm with it (docs/grasping.md, "Bones keep their roll"). (btTransform
// takes the quaternion's length out: a product of unit ones needs no normalising.)
btTransform bone_pose(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                      const Eigen::Quaterniond& reference = Eigen::Quaterniond::Identity()) {
  const Eigen::Vector3d d = b - a;
  const double n = d.norm();
  const Eigen::Quaterniond q = n > 1e-9 ? rotation_between(reference * Eigen::Vector3d::UnitY(), d / n) * reference : reference;
  return btTransform(to_bt(q), to_bt(0.5 * (a + b)));
}

}  // namespace

HandColliders::HandColliders(PhysicsWorld& physics, HandSide side, HandColliderSettings settings)
    : physics_(physics), side_(side), settings_(settings) {}

HandColliders::~HandColliders() {
  if (!built_) return;
  for (Bone& b : bones_) physics_.remove_external(b.body.get());
}

std::optional<int> HandColliders::bone_of(const btCollisionObject* object) const {
  // Each bone's body carries its index (set when built); the other hand's bones and the scene's
  // bodies fail the comparison. The grasp system asks this of every contact manifold twice a step
  // (a search of the 19 bones was 5 % of a physics step).
  if (!built_ || !object) return std::nullopt;
  const int i = object->getUserIndex();
  if (i < 0 || i >= kHandBoneCount || bones_[static_cast<std::size_t>(i)].body.get() != object) return std::nullopt;
  return i;
}

void HandColliders::place(Bone& b, const btTransform& pose) {
  b.body->setWorldTransform(pose);
  b.body->getMotionState()->setWorldTransform(pose);
  b.body->setInterpolationWorldTransform(pose);
  b.body->setLinearVelocity({0, 0, 0});
  b.body->setAngularVelocity({0, 0, 0});
}

void HandColliders::set_soft(Bone& b, bool soft) {
  if (b.soft == soft) return;
  b.soft = soft;
  const int flags = b.body->getCollisionFlags();
  b.body->setCollisionFlags(soft ? flags | btCollisionObject::CF_NO_CONTACT_RESPONSE : flags & ~btCollisionObject::CF_NO_CONTACT_RESPONSE);
}

void HandColliders::drive(const HandInput& input) {
  const bool usable = input.seen && input_finite(input);
  if (!usable) {
    // Lost: the bones hold still and stop colliding until the hand is seen again.
    if (built_) {
      for (Bone& b : bones_) {
        b.body->setLinearVelocity({0, 0, 0});
        b.body->setAngularVelocity({0, 0, 0});
        set_soft(b, true);
      }
    }
    active_ = false;
    return;
  }
  input_ = input;
  if (!built_) {
    for (std::size_t i = 0; i < hand_bones().size(); ++i) {
      Bone& b = bones_[i];
      const auto& def = hand_bones()[i];
      b.length_m = (input.joints_world[at(def.to)] - input.joints_world[at(def.from)]).norm();
      const double r = std::max(settings_.min_radius_m, std::min(input.radius_m[at(def.from)], input.radius_m[at(def.to)]));
      b.shape = std::make_unique<btCapsuleShape>(static_cast<btScalar>(r), static_cast<btScalar>(b.length_m));
      const btScalar mass = static_cast<btScalar>(settings_.bone_mass_kg);
      btVector3 inertia;
      b.shape->calculateLocalInertia(mass, inertia);
      b.motion = std::make_unique<btDefaultMotionState>(btTransform::getIdentity());
      btRigidBody::btRigidBodyConstructionInfo info(mass, b.motion.get(), b.shape.get(), inertia);
      info.m_friction = static_cast<btScalar>(settings_.friction);
      b.body = std::make_unique<btRigidBody>(info);
      b.body->setUserIndex(static_cast<int>(i));  // bone_of
      b.body->setActivationState(DISABLE_DEACTIVATION);
      b.body->setFlags(b.body->getFlags() | BT_DISABLE_WORLD_GRAVITY);
      b.body->setCcdMotionThreshold(static_cast<btScalar>(0.5 * r));
      b.body->setCcdSweptSphereRadius(static_cast<btScalar>(0.8 * r));
      physics_.add_external(b.body.get(), kHandGroup, kSceneGroup);
      b.body->setGravity({0, 0, 0});
    }
    built_ = true;
  }
  const btScalar dt = static_cast<btScalar>(physics_.step_s());
  // The hand's frame with its +Y turned to the fingers (-Z): a digit's first bone's reference.
  const Eigen::Quaterniond hand_reference =
      input.world_from_hand.rotation * rotation_between(Eigen::Vector3d::UnitY(), -Eigen::Vector3d::UnitZ());
  for (std::size_t i = 0; i < hand_bones().size(); ++i) {
    Bone& b = bones_[i];
    const auto& def = hand_bones()[i];
    const Eigen::Vector3d a = input.joints_world[at(def.from)];
    const Eigen::Vector3d e = input.joints_world[at(def.to)];
    const btVector3 previous_target = b.target.getOrigin();
    // hand_bones() lists each digit's bones from the hand out: one whose start is the last one's end follows it.
    const bool follows = i > 0 && hand_bones()[i - 1].to == def.from;
    b.frame = bone_pose(a, e, follows ? to_eigen(bones_[i - 1].frame.getRotation()) : hand_reference);
    // The body itself is driven to the same axis with its roll turned from the world's +Y, as it
    // always was: a capsule is the same whichever way it is rolled, but how its contacts persist
    // from step to step is not, and the grasps were tuned with these.
    b.target = bone_pose(a, e);
    if (!active_) {
      place(b, b.target);  // seen again (or first seen): no sweep from where it was lost
      set_soft(b, false);
      continue;
    }
    const btTransform& now = b.body->getWorldTransform();
    const btVector3 to_target = b.target.getOrigin() - now.getOrigin();
    // How far the bone was held back last step: from where it was sent to where it got (not how
    // far the hand moves this frame, which may be more than the soft distance at speed).
    const double lag = static_cast<double>((previous_target - now.getOrigin()).length());
    if (lag >= settings_.soft_distance_m) set_soft(b, true);
    if (b.soft && lag <= settings_.rigid_again_m) set_soft(b, false);
    btVector3 v = to_target / dt;
    const btScalar speed = v.length();
    if (speed > static_cast<btScalar>(settings_.max_speed_mps)) {
      place(b, b.target);  // a jump, not a motion
      continue;
    }
    b.body->setLinearVelocity(v);
    b.body->setAngularVelocity(angular_velocity(now.getRotation(), b.target.getRotation(), dt));
  }
  active_ = true;
}

std::array<Eigen::Vector3d, kHandJointCount> HandColliders::physical_joints() const {
  std::array<Eigen::Vector3d, kHandJointCount> out = input_.joints_world;
  if (!built_) return out;
  for (std::size_t i = 0; i < hand_bones().size(); ++i) {
    const Bone& b = bones_[i];
    const btTransform& t = b.body->getWorldTransform();
    const btVector3 half = t.getBasis() * btVector3(0, static_cast<btScalar>(0.5 * b.length_m), 0);
    out[at(hand_bones()[i].from)] = to_eigen(t.getOrigin() - half);
    out[at(hand_bones()[i].to)] = to_eigen(t.getOrigin() + half);
  }
  return out;
}

std::vector<HandColliders::Capsule> HandColliders::capsules() const {
  std::vector<Capsule> out;
  if (!built_) return out;
  out.reserve(bones_.size());
  for (const Bone& b : bones_) {
    const btTransform& t = b.body->getWorldTransform();
    const btVector3 half = t.getBasis() * btVector3(0, static_cast<btScalar>(0.5 * b.length_m), 0);
    out.push_back({to_eigen(t.getOrigin() - half), to_eigen(t.getOrigin() + half), static_cast<double>(b.shape->getRadius()), b.soft});
  }
  return out;
}

double HandColliders::largest_offset_m() const {
  double worst = 0.0;
  if (!built_) return worst;
  for (const Bone& b : bones_)
    worst = std::max(worst, static_cast<double>((b.body->getWorldTransform().getOrigin() - b.target.getOrigin()).length()));
  return worst;
}

}  // namespace rhot
