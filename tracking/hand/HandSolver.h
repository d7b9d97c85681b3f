#pragma once
// A whole hand from what is known of each finger: the hand frame (from the marker star on the back
// of the hand) fixes the palm, wrist and metacarpals; each finger's joints come from its evidence
// (FingerEvidence below: angles fitted to its markers, FingerFit.h, as HandTracker gives them;
// FABRIK toward a tip, FingerIK.h; or bones measured); pinch and grip gestures with hysteresis.
//
// A finger whose tip is hidden (a curling finger hides its own marker) is estimated, not dropped:
// while other fingers are seen, it bends with them, at their mean flexion rate times its own
// coupling to them (learnt while they were seen together: coupling()) shared over its hinges (a
// hand closes on an object and opens again as a whole), and holds still while they do;
// with no finger seen it goes on as it last moved, slowing (kCoast_s), holds, and only after
// kHold_s eases toward a relaxed pose.
//
// Joint confidence: 1 for joints fixed by the hand frame and for a seen fingertip; 0.9 for joints
// fitted to seen markers or placed by IK from a seen tip; kPredictedConfidence for a hidden finger
// fitted to (or placed by IK at) its predicted tip; kEstimatedConfidence for a hidden finger bent at the seen ones' rate; for a finger
// unseen for t seconds with no finger seen, 0.9 exp(-t / 0.5 s).

#include <array>
#include <cstdint>
#include <optional>

#include "tracking/hand/FingerIK.h"
#include "tracking/hand/HandJoints.h"

namespace rhot {

enum class Finger : std::uint8_t { kThumb = 0, kIndex, kMiddle, kRing, kLittle };
inline constexpr int kFingerCount = 5;

// The five chains of a hand with the bone lengths and knuckle positions of `skeleton` (a calibrated
// hand, or reference_open_hand), with the anatomical limits: for the fingers seed 002's flexion
// ranges (knuckle 90, middle joint 110, last joint 90 degrees) and abduction (+-15 degrees, less as
// the knuckle flexes), but with the last joint extending to -15 degrees and the middle finger
// abducting as the others (a real take needs it: HandSolver.cpp); for the thumb
// (which seed 002 does not give; estimates that let it oppose the fingers) CMC abduction +-45,
// flexion -20..60, MCP -20..60, IP -20..80 degrees.
std::array<FingerChain, kFingerCount> hand_chains(const HandPose& skeleton, HandSide side);

// The joints of each chain: root, two hinges, tip.
std::array<HandJoint, 4> chain_joints(Finger finger);

// A chain's angles from its three bones' directions (hand frame), clamped to its limits.
FingerAngles angles_from_bones(const FingerChain& chain, const std::array<Eigen::Vector3d, 3>& bone_directions);

struct GestureSettings {
  double pinch_on_m = 0.010;    // thumb and index tips, less their radii, closer than this: pinch
  double pinch_off_m = 0.015;   // ... further than this: released
  double pinch_zero_m = 0.040;  // activation falls from 1 at pinch_on to 0 here
  double grip_on = 0.65;        // mean curl of middle, ring and little (0 straight, 1 fully bent)
  double grip_off = 0.45;
};

struct Gesture {
  bool active = false;
  double activation = 0.0;  // 0-1
};

// Pinch from the gap between thumb and index tips (less their radii): on below pinch_on (only
// while both tips are seen), off above pinch_off, in between as it was. Grip alike from the curl.
void update_pinch(Gesture& pinch, double gap_m, bool tips_seen, const GestureSettings& settings);
void update_grip(Gesture& grip, double curl, const GestureSettings& settings);

struct HandState {
  HandPose pose;  // hand frame
  std::array<FingerAngles, kFingerCount> angles{};
  std::array<double, kHandJointCount> confidence{};
  std::array<bool, kFingerCount> tip_seen{};
  Gesture pinch;
  Gesture grip;
};

// What is known of one finger this frame (hand frame), for HandSolver::update.
struct FingerEvidence {
  enum class Kind : std::uint8_t {
    kHidden,        // nothing: the rules above (bend with the seen fingers, hold, relax)
    kTip,           // its tip joint seen at tip_m: FABRIK toward it
    kFitted,        // `angles` fitted to its seen markers (FingerFit.h)
    kMeasured,      // `angles` from every bone measured (segment stars): they win
    kPredictedTip,  // hidden: its tip joint predicted at tip_m (HiddenMarkers.h): FABRIK toward it
    kPredictedFit,  // hidden tip: `angles` fitted to its predicted tip marker and the finger's seen markers
  };
  Kind kind = Kind::kHidden;
  Eigen::Vector3d tip_m = Eigen::Vector3d::Zero();
  FingerAngles angles;

  bool seen() const { return kind == Kind::kTip || kind == Kind::kFitted || kind == Kind::kMeasured; }
  bool predicted() const { return kind == Kind::kPredictedTip || kind == Kind::kPredictedFit; }
};

class HandSolver {
 public:
  HandSolver(HandSide side, const HandPose& skeleton, GestureSettings gestures = {});

  // One frame: each finger's evidence. A seen finger takes its angles from it (confidence 0.9,
  // its tip 1, every joint 1 where its bones were measured); a predicted one too, with
  // kPredictedConfidence; a hidden one follows the rules above. Evidence that is not finite
  // counts as none.
  const HandState& update(double time_s, const std::array<FingerEvidence, kFingerCount>& fingers);
  // The same from fingertip positions in the hand frame (nothing for a tip not seen), and, where a
  // finger's every bone was measured (stars on the segments), its angles, which then win. A hidden
  // tip's `predicted` place is reached by IK in place of the rules, with kPredictedConfidence.
  const HandState& update(double time_s, const std::array<std::optional<Eigen::Vector3d>, kFingerCount>& tips_hand_m,
                          const std::array<std::optional<FingerAngles>, kFingerCount>& measured = {},
                          const std::array<std::optional<Eigen::Vector3d>, kFingerCount>& predicted = {});
  const HandState& state() const { return state_; }
  const std::array<FingerChain, kFingerCount>& chains() const { return chains_; }

  // How long a finger takes to relax once it has been unseen for kHold_s with no other finger
  // seen (time constant); how fast its last motion dies away before that (time constant); the
  // confidence of a hidden finger estimated from the seen ones.
  static constexpr double kRelaxTime_s = 0.5;
  static constexpr double kHold_s = 1.0;
  static constexpr double kCoast_s = 0.15;
  static constexpr double kEstimatedConfidence = 0.6;
  // How a hidden finger bends with the seen ones is learnt while they are seen together: each
  // finger's flexion rate against the others' mean (a least-squares slope over the last
  // kCouplingMemory_s, exponentially weighted), starting from 1 (bend as fast as they do) and
  // worth kCouplingPrior_rad2_s2 of (rad/s)^2 of evidence before any is seen. A thumb closes a fist
  // at about a third of the fingers' rate; bent at their rate, as before, it passed through the
  // fingers 60 mm from where it was.
  static constexpr double kCouplingMemory_s = 4.0;
  static constexpr double kCouplingPrior_rad2_s2 = 10.0;
  // Each finger's learnt slope (1 until it has been seen bending with the others).
  double coupling(Finger finger) const;
  static constexpr double kPredictedConfidence = 0.75;

 private:
  std::array<FingerChain, kFingerCount> chains_;
  std::array<FingerAngles, kFingerCount> relaxed_;
  std::array<double, kFingerCount> last_seen_s_{};
  std::array<FingerAngles, kFingerCount> rate_{};  // each finger's angular rates, rad/s (seen: measured; hidden: estimated)
  std::array<bool, kFingerCount> estimated_{};     // hidden and estimated from the seen fingers
  // Per finger, the exponentially weighted sums of (own rate x others' mean rate) and (others'
  // mean rate)^2 over the frames it was seen with others (rad^2/s^2 x seconds): the coupling's slope.
  std::array<double, kFingerCount> coupling_xy_{};
  std::array<double, kFingerCount> coupling_xx_{};
  std::array<bool, kFingerCount> predicted_{};  // hidden and placed at a predicted tip
  GestureSettings gestures_;
  HandState state_;
  double time_s_ = 0.0;
  bool started_ = false;
};

}  // namespace rhot
