#pragma once
// One finger's angles fitted to every marker seen on it at once (docs/tracking.md, "Fingers from
// their markers"): a glove's tip and middle markers, a nail marker off the bone's axis, a predicted
// tip with the finger's seen middle marker.
//
// Levenberg-Marquardt over the four angles (abduction, and the three flexions: the last hinge free,
// not coupled), each step clamped into the finger's limits, an angle held at its limit while the
// descent pushes it outward. What the markers leave open (a lone
// tip marker pins three of the four) is settled by the coupling of the last hinge to the middle
// one, held as a soft prior: a departure of one radian costs as much as a marker missed by
// coupling_m. Where the markers pin the last hinge (a tip and a middle marker: six equations), they
// win but for the prior's pull: 0.15 mm on average over poses drawn freely within the limits, up to
// 0.5 mm where the last hinge is half a radian off the coupling (tests/tracking/hand/finger_fit_test.cpp). Where the nearest fit from the
// last frame's angles is poor (a thumb bent the wrong way), the fit starts again from FABRIK's pose toward the tip, and the better of the
// two is kept.
//
// A point's place on the finger is its layout marker's (HandLayout.h: finger_marker with the
// finger's own chain): its joint's position plus its offset in that bone's frame, whose +Y is the
// back of the finger in the finger's own flexion plane. The fit's steps follow that place's exact
// derivatives.

#include <array>
#include <span>

#include <Eigen/Core>

#include "tracking/hand/FingerIK.h"
#include "tracking/hand/HandLayout.h"
#include "tracking/hand/HandSolver.h"

namespace rhot {

// A point on one finger seen (or predicted) in the hand frame.
struct FingerPoint {
  int joint = 3;                                       // the chain's joint it is given on: 0 root, 1-2 hinges, 3 tip
  Eigen::Vector3d offset_m = Eigen::Vector3d::Zero();  // in that joint's bone frame (the tip's: the last bone's)
  Eigen::Vector3d at_m = Eigen::Vector3d::Zero();      // where it is, hand frame
  double weight = 1.0;
};

// A finger's points fitted at most (the first ones given, finite; a finger carries two or three).
inline constexpr std::size_t kMaxFingerPoints = 8;

// A layout's marker (on this finger's chain) seen at `at_m` (hand frame) as a point to fit.
FingerPoint finger_point(const LayoutMarker& marker, const Eigen::Vector3d& at_m, double weight);

// Where a point (its joint and offset) is on a finger posed at `angles` (hand frame).
Eigen::Vector3d finger_point_at(const FingerChain& chain, const FingerAngles& angles, const FingerPoint& point);

struct FingerFitSettings {
  int max_iterations = 20;
  double tolerance_rad = 2e-5;  // stop once a step turns no angle by more than this (a micrometre at a fingertip)
  // The soft coupling: a radian off (last hinge - coupling x middle one) costs as a marker missed by
  // this much. On the real glove take (docs/PERFORMANCE.md) 4 mm put seen tips 1.20 mm off and hidden
  // ones 1.91 mm (p95 6.1), 1 mm 1.09 and 1.93 (p95 6.0), 0.3 mm 0.84 and 1.87 (p95 7.2).
  double coupling_m = 0.001;
  double restart_m = 0.005;  // a fit whose weighted RMS miss is above this starts again from FABRIK toward the tip
};

// The settings the tracker and the calibration fit a finger with: the defaults, but the thumb's
// last hinge free of the coupling (its IP joint does not follow its MCP joint: in a simulated pinch
// the coupling put the thumb's tip joint 3.5 mm off with its marker reached; on the real glove take
// either way measured alike). A lone thumb tip marker then leaves the split of its two hinges where
// the last frame had it, the fit's damping holding it.
FingerFitSettings finger_fit_settings(Finger finger);

struct FingerFit {
  FingerAngles angles;
  double rms_m = 0.0;  // the points' weighted RMS miss (the coupling prior apart)
  int iterations = 0;  // of both starts together
};

// The angles, within the chain's limits, whose points come nearest where they were seen, starting
// from `start`. Points that are not finite are skipped, and those past kMaxFingerPoints; with none
// left, `start` (clamped) returns.
FingerFit fit_finger(const FingerChain& chain, std::span<const FingerPoint> points, const FingerAngles& start,
                     const FingerFitSettings& settings = {});

}  // namespace rhot
