#pragma once
// Least-squares rigid fit between corresponding point sets (Kabsch, by one 3x3 SVD, the reflection
// case turned into the nearest rotation; weighted when each pair has a weight), with the residual that says whether the sets really are
// one rigid shape, and the scale a similarity fit would need (Umeyama's; 1 for the right shape).

#include <optional>
#include <span>

#include <Eigen/Core>

#include "tracking/core/Rigid3.h"

namespace rhot {

struct RigidFit {
  Rigid3d to_from_from;  // maps `from` points onto `to` points
  double rms_m = 0.0;    // RMS distance between mapped `from` points and `to` points
  double scale = 1.0;    // the similarity fit's scale: far from 1 means a different shape
};

// Nothing when the sets differ in size, have fewer than three points, are (nearly) collinear, or
// contain a value that is not finite. weight: empty for equal weights, else one positive finite
// weight per pair (1/sigma^2 for points of different uncertainty: the maximum-likelihood pose
// under isotropic noise); anything else is refused like a non-finite point. rms_m is unweighted.
std::optional<RigidFit> fit_rigid(std::span<const Eigen::Vector3d> from, std::span<const Eigen::Vector3d> to,
                                  std::span<const double> weight = {});

// The covariance of a fitted pose (Rigid3.h's Matrix6d: position of the `from` frame's origin,
// and a small rotation in the `to` frame) when each mapped `from` point is measured with isotropic
// noise of sigma_m per axis: the inverse of the sum of J^T J / sigma^2, J = [I, -[R from]x], to
// first order. Empty sigma: 1 mm each. Three or more points not in a line give a finite one.
Matrix6d rigid_fit_covariance(const Rigid3d& to_from_from, std::span<const Eigen::Vector3d> from, std::span<const double> sigma_m = {});

}  // namespace rhot
