#include "tracking/geometry/CameraVisibility.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

namespace rhot {

namespace {

// A camera's view as four planes through its centre (camera frame; a point p is inside where
// n . p <= 0 for every normal n), or nothing where its image border does not undistort.
std::optional<std::array<Eigen::Vector3d, 4>> view_planes(const Camera& camera) {
  const CameraIntrinsics& k = camera.intrinsics;
  constexpr int kSamplesPerEdge = 32;
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector2d hi = -lo;
  // The sensor spans [-0.5, size - 0.5) in pixels (Camera::in_image).
  const double w = k.width_px - 0.5, h = k.height_px - 0.5;
  for (int s = 0; s <= kSamplesPerEdge; ++s) {
    const double t = static_cast<double>(s) / kSamplesPerEdge;
    const double x = -0.5 + t * (w + 0.5), y = -0.5 + t * (h + 0.5);
    for (const Eigen::Vector2d& pixel :
         {Eigen::Vector2d(x, -0.5), Eigen::Vector2d(x, h), Eigen::Vector2d(-0.5, y), Eigen::Vector2d(w, y)}) {
      const auto xy = undistort_normalised(k.distortion, Eigen::Vector2d((pixel.x() - k.cx) / k.fx, (pixel.y() - k.cy) / k.fy));
      if (!xy) return std::nullopt;
      lo = lo.cwiseMin(*xy);
      hi = hi.cwiseMax(*xy);
    }
  }
  // Between samples the outline bulges a little beyond them.
  const Eigen::Vector2d margin = 0.01 * (hi - lo) + Eigen::Vector2d::Constant(1e-6);
  lo -= margin;
  hi += margin;
  return std::array<Eigen::Vector3d, 4>{Eigen::Vector3d(1.0, 0.0, -hi.x()), Eigen::Vector3d(-1.0, 0.0, lo.x()),
                                        Eigen::Vector3d(0.0, 1.0, -hi.y()), Eigen::Vector3d(0.0, -1.0, lo.y())};
}

}  // namespace

CameraVisibility::CameraVisibility(std::span<const Camera> cameras, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  const Eigen::Vector3d size = hi - lo;
  if (!(size.allFinite() && size.minCoeff() > 0.0)) return;
  lo_ = lo;
  cell_m_ = std::cbrt(size.prod() / kMaxCells);
  const auto fit = [&] {
    for (int a = 0; a < 3; ++a) dims_[static_cast<std::size_t>(a)] = std::max(1, static_cast<int>(std::ceil(size[a] / cell_m_)));
    return static_cast<long>(dims_[0]) * dims_[1] * dims_[2] <= kMaxCells;
  };
  while (!fit()) cell_m_ *= 1.05;
  sets_.assign(static_cast<std::size_t>(dims_[0] * dims_[1] * dims_[2]), 0);

  const double radius = 0.5 * std::sqrt(3.0) * cell_m_;  // a cell's bounding sphere
  for (std::size_t c = 0; c < std::min<std::size_t>(cameras.size(), 64); ++c) {
    const CameraSet bit = CameraSet{1} << c;
    const auto planes = view_planes(cameras[c]);
    const Eigen::Matrix3d rotation = cameras[c].cam_from_world.rotation.toRotationMatrix();
    for (int z = 0; z < dims_[2]; ++z) {
      for (int y = 0; y < dims_[1]; ++y) {
        for (int x = 0; x < dims_[0]; ++x) {
          CameraSet& set = sets_[static_cast<std::size_t>((z * dims_[1] + y) * dims_[0] + x)];
          if (!planes) {
            set |= bit;
            continue;
          }
          const Eigen::Vector3d centre =
              rotation * (lo_ + cell_m_ * Eigen::Vector3d(x + 0.5, y + 0.5, z + 0.5)) + cameras[c].cam_from_world.translation;
          // Every point of the cell at most 1 mm in front: Camera::project refuses it.
          bool seen = centre.z() + radius > 1e-3;
          for (const Eigen::Vector3d& n : *planes) seen = seen && n.dot(centre) <= radius * n.norm();
          if (seen) set |= bit;
        }
      }
    }
  }
}

}  // namespace rhot
