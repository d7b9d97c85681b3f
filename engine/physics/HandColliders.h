#pragma once
// A tracked hand in the physics world: one capsule per bone (19: the thumb's three, four per
// finger including its metacarpal, which together make the palm), each a dynamic body without
// gravity whose velocity is set every step to reach its tracked pose by the end of the step. So a
// bone pushes what it meets with the force the solver allows, stops at surfaces instead of
// sinking into them (the physical hand is then offset from the tracked one: rhot draws the
// physical hand, the "ghost hand" approach), and cannot tunnel through thin objects (the speed is
// a velocity, and continuous collision detection sweeps each bone).
//
// A bone left 3 cm or more behind its tracked pose (the hand pushed into a static wall, or a
// tracking jump) goes "soft": it stops colliding and catches up, and collides again once within
// 1 cm. A hand seen again after being lost is placed at its tracked pose at once.

#include <array>
#include <optional>
#include <vector>

#include <btBulletDynamicsCommon.h>

#include "engine/hand/HandComponents.h"
#include "engine/physics/PhysicsWorld.h"

namespace rhot {

struct HandColliderSettings {
  double bone_mass_kg = 0.05;
  double friction = 1.0;
  double soft_distance_m = 0.03;  // further than this from its tracked pose: soft
  double rigid_again_m = 0.01;    // soft bones collide again within this
  double max_speed_mps = 15.0;    // a bone never moves faster (a tracking jump is a teleport)
  double min_radius_m = 0.004;
};

class HandColliders {
 public:
  HandColliders(PhysicsWorld& physics, HandSide side, HandColliderSettings settings = {});
  ~HandColliders();
  HandColliders(const HandColliders&) = delete;
  HandColliders& operator=(const HandColliders&) = delete;

  // Before a physics step: aim every bone at its tracked pose (non-finite input is ignored: the
  // bones hold still, as for a hand not seen).
  void drive(const HandInput& input);

  HandSide side() const { return side_; }
  bool active() const { return active_; }  // tracked and in the world
  const HandInput& input() const { return input_; }
  btRigidBody* bone(int i) const { return bones_[static_cast<std::size_t>(i)].body.get(); }
  bool soft(int i) const { return bones_[static_cast<std::size_t>(i)].soft; }
  std::optional<int> bone_of(const btCollisionObject* object) const;
  // Tracked pose of bone i (capsule axis along its local +Y, from `from` to `to`), its roll about
  // that axis carried from the hand's frame down the digit, so that a point on the bone's surface
  // (a grip point) moves with the hand (docs/grasping.md, "Bones keep their roll").
  btTransform tracked_bone(int i) const { return bones_[static_cast<std::size_t>(i)].frame; }
  // Bone i's capsule radius (metres; 0 before the hand was first seen).
  double bone_radius_m(int i) const {
    const auto& shape = bones_[static_cast<std::size_t>(i)].shape;
    return shape ? static_cast<double>(shape->getRadius()) : 0.0;
  }
  // The physical hand for drawing: joint positions from the bone bodies (tracked where no bone ends).
  std::array<Eigen::Vector3d, kHandJointCount> physical_joints() const;
  // The bones' capsules where the physics has them, for debug drawing (empty before the hand is
  // first tracked).
  using Capsule = HandCapsule;
  std::vector<Capsule> capsules() const;
  // How far the physical hand is from the tracked one (largest bone distance), metres.
  double largest_offset_m() const;

 private:
  struct Bone {
    std::unique_ptr<btCapsuleShape> shape;
    std::unique_ptr<btDefaultMotionState> motion;
    std::unique_ptr<btRigidBody> body;
    btTransform target = btTransform::getIdentity();  // where the body is driven (its roll from the world's +Y)
    btTransform frame = btTransform::getIdentity();   // the same pose, its roll carried from the hand (tracked_bone)
    double length_m = 0.0;
    bool soft = false;
  };
  void place(Bone& b, const btTransform& pose);
  void set_soft(Bone& b, bool soft);

  PhysicsWorld& physics_;
  HandSide side_;
  HandColliderSettings settings_;
  std::array<Bone, kHandBoneCount> bones_;
  HandInput input_;
  bool active_ = false;
  bool built_ = false;
};

}  // namespace rhot
