#pragma once
// One finger (or the thumb) as a kinematic chain rooted in the hand frame, its anatomical limits
// (seed 002, eq. 2.1-2.4), forward kinematics, and two inverse kinematics solvers for a fingertip
// target: FABRIK (the one rhot uses) and damped least squares on the joint angles (the comparison).
//
// A chain starts at its root joint (the knuckle, MCP, of a finger; the carpometacarpal joint, CMC,
// of the thumb), where it has two degrees of freedom: abduction about the hand's "up" axis, then
// flexion toward the palm. Then two hinges (PIP and DIP; the thumb's MCP and IP), flexing in the
// same plane. Angle zero is straight along the rest direction; flexion is positive toward the palm.
//
// The root's limits form an ellipse, not a box: abduction may reach +-abduction_max only when the
// finger is straight and shrinks to zero at full flexion, as the collateral ligaments tighten
// ((a / a_max)^2 + (f / f_max)^2 <= 1 over the positive flexion range); a box (Caliko's circular cones
// behave alike) allows poses no hand makes.

#include <array>

#include <Eigen/Core>

namespace rhot {

struct FingerLimits {
  double abduction_max_rad = 0.2618;  // +-15 degrees; 0 fixes it (the middle finger)
  std::array<double, 3> flexion_min_rad{0.0, 0.0, 0.0};
  std::array<double, 3> flexion_max_rad{1.5708, 1.9199, 1.5708};  // MCP 90, PIP 110, DIP 90 degrees
  double coupling = 2.0 / 3.0;                                    // the last hinge = coupling x the middle one, when not observed
};

struct FingerChain {
  Eigen::Vector3d root_m{0, 0, 0};           // hand frame
  Eigen::Vector3d rest_direction{0, 0, -1};  // unit: the chain straight
  Eigen::Vector3d up{0, 1, 0};               // unit, orthogonal to rest_direction: the back of the hand
  std::array<double, 3> length_m{0.04, 0.025, 0.02};
  FingerLimits limits;
};

struct FingerAngles {
  double abduction_rad = 0.0;  // positive toward the chain's lateral axis (rest x up)
  std::array<double, 3> flexion_rad{0.0, 0.0, 0.0};
};

// Joint positions (root, two hinges, tip) in the hand frame.
std::array<Eigen::Vector3d, 4> finger_forward(const FingerChain& chain, const FingerAngles& angles);

// The angles clamped into the limits (the ellipse for the root, ranges for the hinges). NaN -> 0.
FingerAngles clamp_to_limits(const FingerLimits& limits, FingerAngles angles);
bool within_limits(const FingerLimits& limits, const FingerAngles& angles, double tolerance_rad = 1e-9);

struct IkResult {
  FingerAngles angles;
  double tip_error_m = 0.0;  // distance from the reached tip to the target
  int iterations = 0;
};

struct IkSettings {
  int max_iterations = 20;
  double tolerance_m = 1e-4;
};

// FABRIK (Aristidou and Lasenby 2011) in the finger's plane: the abduction from the target's
// direction, then backward and forward passes over the three links, each forward placement clamped
// to its hinge's range, the coupling imposed after each pass. Never leaves the limits; the target
// may be unreachable (the closest reachable pose is returned). Non-finite targets return `start`.
IkResult solve_fabrik(const FingerChain& chain, const Eigen::Vector3d& target_m, const FingerAngles& start = {},
                      const IkSettings& settings = {});

// Damped least squares on (abduction, root flexion, middle hinge) with the last hinge coupled,
// clamped to the limits after each step: the textbook Jacobian solver, for comparison.
IkResult solve_dls(const FingerChain& chain, const Eigen::Vector3d& target_m, const FingerAngles& start = {},
                   const IkSettings& settings = {}, double damping = 0.01);

}  // namespace rhot
