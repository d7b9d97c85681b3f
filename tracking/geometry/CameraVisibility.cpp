#include "tracking/geometry/CameraVisibility.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

namespace rhot {

namespace {

// The radius (x/z, y/z) beyond which the lens's radial distortion folds back (r (1 + k1 r^2 + k2
// r^4 + k3 r^6) stops growing), infinity where it never does. Scanned in steps of 0.2 % from r =
// 0.001 to 100 (89.4 degrees off the axis); a fold further out than that is taken to begin there.
double fold_radius(const std::array<double, 5>& k) {
  constexpr double kScanTo = 100.0;
  constexpr int kSteps = 5760;  // 1.002^5760 = 1e5
  for (int s = 0; s <= kSteps; ++s) {
    const double r = kScanTo * std::pow(1.002, s - kSteps);
    const double u = r * r;
    if (!(1.0 + u * (3.0 * k[0] + u * (5.0 * k[1] + u * 7.0 * k[4])) > 0.0)) return r;
  }
  const double leading = k[4] != 0.0 ? k[4] : (k[1] != 0.0 ? k[1] : k[0]);
  return leading < 0.0 ? kScanTo : std::numeric_limits<double>::infinity();
}

// A camera's view: four planes through its centre (camera frame; a point p is inside where
// n . p <= 0 for every unit normal n), and the cone inside which the lens does not fold (tangent
// of its half-angle; infinity: everywhere). Nothing where the image border does not undistort.
struct ViewPlanes {
  std::array<Eigen::Vector3d, 4> normals;
  double unfolded_tan = std::numeric_limits<double>::infinity();
};

std::optional<ViewPlanes> view_planes(const Camera& camera) {
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
  ViewPlanes out;
  out.normals = {Eigen::Vector3d(1.0, 0.0, -hi.x()).normalized(), Eigen::Vector3d(-1.0, 0.0, lo.x()).normalized(),
                 Eigen::Vector3d(0.0, 1.0, -hi.y()).normalized(), Eigen::Vector3d(0.0, -1.0, lo.y()).normalized()};
  // Tangential terms (a fraction of a percent in calibrated lenses) move the fold a little: the
  // cone stops short of it by a tenth.
  out.unfolded_tan = 0.9 * fold_radius(k.distortion);
  return out;
}

}  // namespace

CameraVisibility::CameraVisibility(std::span<const Camera> cameras, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  const Eigen::Vector3d size = hi - lo;
  if (!(size.allFinite() && size.minCoeff() > 0.0)) return;
  lo_ = lo;
  // Cubes of the volume's share, grown until the grid fits kMaxCells (a long thin box has cells as
  // wide as its length allows).
  cell_m_ = std::max(std::cbrt(size.prod() / kMaxCells), size.maxCoeff() / kMaxCells);
  if (!(std::isfinite(cell_m_) && cell_m_ > 0.0)) return;
  const auto fit = [&] {
    double cells = 1.0;
    for (int a = 0; a < 3; ++a) {
      const double n = std::max(1.0, std::ceil(size[a] / cell_m_));
      cells *= n;
      dims_[static_cast<std::size_t>(a)] = static_cast<int>(std::min(n, static_cast<double>(kMaxCells)));
    }
    return cells <= kMaxCells;
  };
  while (!fit()) cell_m_ *= 1.05;
  sets_.assign(static_cast<std::size_t>(dims_[0] * dims_[1] * dims_[2]), 0);

  // A cell's bounding sphere, a hair wider for the rounding of a point's place in the grid.
  const double radius = 0.5 * std::sqrt(3.0) * cell_m_ * (1.0 + 1e-9) + 1e-12;
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
          if (!(centre.z() + radius > 1e-3)) continue;
          bool inside = true;
          for (const Eigen::Vector3d& n : planes->normals) inside = inside && n.dot(centre) <= radius;
          // Outside the view, but not wholly inside the cone where the lens does not fold: a
          // point there may still be distorted into the image, and the camera is kept.
          const double cos_cone = 1.0 / std::sqrt(1.0 + planes->unfolded_tan * planes->unfolded_tan);
          const bool in_unfolded = !std::isfinite(planes->unfolded_tan) ||
                                   centre.head<2>().norm() * cos_cone - centre.z() * planes->unfolded_tan * cos_cone <= -radius;
          if (inside || !in_unfolded) set |= bit;
        }
      }
    }
  }
}

}  // namespace rhot
