#pragma once
// Similarity transforms (scale, rotation, translation) between two frames of one scene, fitted in
// closed form (Horn's / Umeyama's method, through Eigen::umeyama), and rigs moved by them.

#include <optional>
#include <vector>

#include <Eigen/Core>

#include "tracking/camera/Camera.h"

namespace rhot {

// p_new = scale * rotation * p_old + translation.
struct Similarity3 {
  double scale = 1.0;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  Eigen::Vector3d apply(const Eigen::Vector3d& p) const { return scale * (rotation * p) + translation; }
  Similarity3 inverse() const;
};

// The similarity taking `from[i]` nearest to `to[i]` in the least-squares sense (scale fixed at 1
// when `with_scale` is false). Nothing for fewer than 3 pairs, points all on one line, or
// non-finite input.
std::optional<Similarity3> fit_similarity(const std::vector<Eigen::Vector3d>& from, const std::vector<Eigen::Vector3d>& to,
                                          bool with_scale);

// The smallest axis-aligned box of the new frame that holds the old box (all 8 corners moved).
TrackingVolume transform_volume(const TrackingVolume& volume, const Similarity3& new_from_old);

// The same camera described in the new frame: its image of any scene point is unchanged.
Camera transform_camera(const Camera& camera, const Similarity3& new_from_old);

}  // namespace rhot
