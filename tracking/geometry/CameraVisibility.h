#pragma once
// Which cameras of a rig may see a point: a grid of cells over a box, each holding the set of
// cameras in whose image some part of the cell may fall. Matching projects a point only into the
// cameras its cell names, instead of into every camera of the rig: on a stage whose cameras each
// see part of it, a third of the projections or more fall outside their image.
//
// The sets are conservative: a camera missing from a point's set never has the point in front of
// it and inside its image (Camera::project then Camera::in_image), so skipping it changes no
// result. Each camera's view is the pyramid through its undistorted image outline (the bounding
// box of the image border's undistorted points, widened by 1 %), tested against each cell's
// bounding sphere. A lens whose radial distortion folds back (r (1 + k1 r^2 + k2 r^4 + k3 r^6)
// stops growing at some radius, as it does wherever the highest k is negative) distorts points far
// off its axis back into the image: a camera is left out only of cells wholly inside the cone
// where its lens does not fold (stopping a tenth short of the fold, for the tangential terms). A
// camera whose border does not undistort (a model that folds inside the image) is in every set.
//
// Sets hold the first 64 cameras; cameras past the 64th are never skipped. A point outside the grid
// (the box, rounded up to whole cells) or NaN has every camera in its set. Built once per rig: a
// few thousand cells, each tested against every camera.

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "tracking/camera/Camera.h"

namespace rhot {

class CameraVisibility {
 public:
  // Bit c: camera c may see the point.
  using CameraSet = std::uint64_t;
  static constexpr CameraSet kAllCameras = ~CameraSet{0};
  static constexpr int kMaxCells = 4096;

  // No box: every point has every camera.
  CameraVisibility() = default;
  // The grid over [lo, hi] in cubic cells, as many as fit kMaxCells.
  CameraVisibility(std::span<const Camera> cameras, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi);

  CameraSet cameras_at(const Eigen::Vector3d& p_world) const {
    if (sets_.empty()) return kAllCameras;
    const Eigen::Vector3d f = (p_world - lo_) / cell_m_;
    // NaN fails every comparison, so it lands here too.
    if (!(f.x() >= 0.0 && f.y() >= 0.0 && f.z() >= 0.0 && f.x() < dims_[0] && f.y() < dims_[1] && f.z() < dims_[2])) return kAllCameras;
    const int x = static_cast<int>(f.x()), y = static_cast<int>(f.y()), z = static_cast<int>(f.z());
    return sets_[static_cast<std::size_t>((z * dims_[1] + y) * dims_[0] + x)];
  }
  // Whether camera c is in the set (cameras past the 64th always are).
  static bool contains(CameraSet set, std::size_t camera) { return camera >= 64 || ((set >> camera) & 1u) != 0; }

 private:
  Eigen::Vector3d lo_{0, 0, 0};
  double cell_m_ = 1.0;
  std::array<int, 3> dims_{0, 0, 0};
  std::vector<CameraSet> sets_;  // x fastest, then y, then z
};

}  // namespace rhot
