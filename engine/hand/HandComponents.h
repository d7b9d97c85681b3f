#pragma once
// The components of a hand entity (one per hand, named "hand-left" and "hand-right"). Systems
// meet here instead of reaching into each other:
//
//   Hand       written by the tracking system (engine/tracked) each frame the runtime advances:
//              the tracked hand and its gestures
//   HandBody   written by the physics (engine/interact/HandPhysics.h) after its step: where the
//              hand's colliders are, and what the hand holds
//
// The renderer draws the hand where HandBody has it (the "ghost hand"), the debug views draw both.

#include <array>
#include <optional>
#include <vector>

#include "engine/core/Entity.h"
#include "engine/hand/HandInput.h"

namespace rhot {

struct HandGesture {
  double activation = 0.0;  // 0 .. 1
  bool active = false;      // with hysteresis
};

struct Hand {
  HandSide side = HandSide::kRight;
  bool shown = true;               // drawn (a scene may leave a hand out: SceneSettings::left_hand / right_hand)
  HandInput tracked;               // this frame's tracked hand; tracked.seen is false while it is lost
  bool gestures_measured = false;  // pinch and grip come from a hand tracker (a recording has none)
  HandGesture pinch;
  HandGesture grip;
};

// One bone's capsule where the physics has it.
struct HandCapsule {
  Eigen::Vector3d a_world{0, 0, 0};
  Eigen::Vector3d b_world{0, 0, 0};
  double radius_m = 0.0;
  bool soft = false;  // held back, not colliding (see HandColliderSettings)
};

struct HandBody {
  bool active = false;                                          // the colliders are in the world (the hand was tracked)
  std::array<Eigen::Vector3d, kHandJointCount> joints_world{};  // the physical hand: joints from the bone bodies
  std::vector<HandCapsule> capsules;                            // empty before the hand is first tracked
  std::optional<Entity> holding;
};

}  // namespace rhot
