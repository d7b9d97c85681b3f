#pragma once
// Hidden fingers against what the hand holds or closes on (docs/grasping.md, "Hidden fingers").
//
// A finger whose tip marker is hidden (its tip's confidence below `confident`) has only the
// tracker's estimate, which knows nothing of objects: curled at the other fingers' rate, held, or
// relaxed. Where the hand holds an object, or closes on one, such a finger is curled about its
// own knuckles until its bones meet that object's surface: so an object in the hand is held
// between the measured digits and the hidden ones, never with a hidden finger inside it or
// relaxed away from it. A hand holds an object the grasp system holds, or a tracked object it
// carries (one that moves with the hand: FingerContactSettings::carry_moved_m). A hand closes on an object when a measured digit of it
// touched the object in the last step, or when the hidden finger was closing when it was last seen (or a measured finger of the hand is
// closing now, or one hidden less than 0.5 s ago was closing when last seen) and the object is within reach: the palm within
// `hover_distance_m` of its bounding box, or, for a grabbable object, the box within the length of a closing digit hidden in the last
// 0.5 s from its first knuckle. Closing on a grabbable object not yet held, from one side only, they rest `rest_gap_m` off it. A finger
// bends in its own plane (about the hand's lateral axis); the thumb turns toward the object's nearest surface. A hidden finger whose curl
// does not meet the object within `max_curl_rad` is left where the tracker put it (it points elsewhere); one already inside is uncurled to
// the surface. Closing on an object the other hand holds, a hidden digit is curled no farther than its tip can have moved since it hid
// (docs/grasping.md, "Taking from the other hand").
//
// This lives in the engine, not in the tracker, because it needs the physics world's shapes:
// tracking stays free of engine types (docs/tracking.md, "Hidden fingers and objects"). The
// tracked hand (Hand::tracked) is left as the tracker made it; only the colliders, and so the
// drawn hand and the grasps, follow the placed fingers. A placed joint keeps its low confidence.

#include <array>
#include <limits>
#include <optional>

#include "engine/core/Entity.h"
#include "engine/hand/HandInput.h"

class btCollisionObject;

namespace rhot {

class GraspSystem;
class PhysicsWorld;
class World;

struct FingerContactSettings {
  double confident = 0.95;      // a tip with confidence below this is hidden (GraspSettings::confident)
  double max_curl_rad = 1.0;    // a hidden finger is curled at most this much further at each knuckle
  double max_uncurl_rad = 0.6;  // ... and uncurled at most this much out of an object
  // Placed fingers rest on the surface; held between both sides (the thumb or palm, and a
  // finger) they squeeze this far into it, so their bones press as a grasping hand's do.
  double squeeze_m = 0.001;
  // Closing on a grabbable object not yet held, placed fingers on one side only (nothing squeezing
  // from the other yet) stop this short of its surface: an estimate is no evidence of force, and fingers resting on a light peg as
  // the hand closed pushed it 8 cm toward the thumb still on its way and toppled it. Within
  // GraspSettings::contact_distance_m (3 mm) they still touch it for the grasp rule. A button
  // (not grabbable) is there to be pushed: fingers rest on it.
  double rest_gap_m = 0.0015;
  double hover_distance_m = 0.05;  // the palm this close to an object's bounding box: within reach
  double closing_rad_s = 0.3;      // a finger curling faster than this is closing
  // A tracked object (kinematic, following its own marker star: the grasp system never holds it)
  // is carried by a hand once it has moved carry_moved_m with the hand, its pose in the hand frame
  // within carry_slack_m and carry_turn_rad of where it began, the palm within hover_distance_m of
  // its bounding box; it is carried until its pose in the hand changes by more, the palm leaves, or
  // the hand opens.
  double carry_moved_m = 0.03;
  double carry_slack_m = 0.015;
  double carry_turn_rad = 0.2;
  double carry_open_rad = 0.3;  // ... or until a measured digit is this much straighter than when it began,
                                // or one hidden then is seen carry_slack_m off the object
};

// What place() did to one hand.
struct FingerPlacement {
  std::optional<Entity> object;      // the object the hidden fingers were placed against
  std::array<bool, 5> placed{};      // per digit (thumb .. little)
  std::array<double, 5> curl_rad{};  // how far each placed digit was curled (negative: uncurled)
  bool squeezing = false;            // held between both sides: the placed digits squeeze
};

class FingerContact {
 public:
  FingerContact(const PhysicsWorld& physics, const GraspSystem& grasp, FingerContactSettings settings = {})
      : physics_(physics), grasp_(grasp), settings_(settings) {}

  // One hand's input at time t_s, before its colliders are driven: its hidden digits placed against
  // the object it holds or closes on. The hand is left as it is when it holds nothing and closes
  // on nothing, or is not seen.
  FingerPlacement place(const World& world, HandSide side, double t_s, HandInput& hand);

  const FingerContactSettings& settings() const { return settings_; }

 private:
  // A digit's curl over time, while it is measured.
  struct DigitMotion {
    double curl_rad = 0.0;
    double rate_rad_s = 0.0;  // smoothed over about 0.1 s
    double t_s = -1.0;        // when last measured (negative: never)
    bool hidden = true;
    Eigen::Vector3d tip_hand{0, 0, 0};  // its tip in the hand frame when last measured
    double tip_speed_mps = 0.0;         // ... and its speed there, smoothed as rate_rad_s
    // Hidden: the fastest its tip or its hand's have been seen moving since it hid, and how far at
    // that speed its tip may have moved since.
    double hidden_speed_mps = 0.0;
    double may_have_moved_m = 0.0;
  };
  void follow(std::size_t side, double t_s, const HandInput& hand);
  // Which tracked object the hand carries (see FingerContactSettings::carry_moved_m).
  void follow_carry(const World& world, std::size_t side, double t_s, const HandInput& hand);
  std::optional<Entity> object_for(const World& world, HandSide side, const HandInput& hand, const std::array<bool, 5>& closing,
                                   const std::array<bool, 5>& reaching) const;

  const PhysicsWorld& physics_;
  const GraspSystem& grasp_;
  FingerContactSettings settings_;
  std::array<std::array<DigitMotion, 5>, 2> motion_{};
  std::array<double, 2> followed_t_s_{-1.0, -1.0};  // each hand's last follow()
  // Per hand, the tracked object near its palm and how it has moved with the hand.
  struct Carry {
    std::optional<Entity> object;
    Rigid3d hand_from_object;         // when it began moving with the hand
    Eigen::Vector3d from_m{0, 0, 0};  // where it was then (world)
    bool carried = false;
    std::array<double, 5> curl_rad{};  // each digit's curl as last measured then (below -1: never measured)
    std::array<bool, 5> hidden{};      // each digit hidden then (for longer than a flicker)
  };
  std::array<Carry, 2> carry_{};
};

// A digit's curl (radians): the angle between its root bone (a finger's metacarpal, the thumb's
// metacarpal) and its last bone.
double digit_curl_rad(const HandInput& hand, int digit);

// The signed distance (metres, negative: overlapping) between a capsule from a to b of radius r
// and a convex collision object at its current pose; +infinity for a non-convex one.
double capsule_distance_m(const btCollisionObject& object, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius_m);

// The same, with the object's point nearest the capsule and the object's outward normal there
// (world; from the object toward the capsule).
struct CapsuleGap {
  double distance_m = std::numeric_limits<double>::infinity();
  Eigen::Vector3d on_object = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
};
CapsuleGap capsule_gap(const btCollisionObject& object, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius_m);

}  // namespace rhot
