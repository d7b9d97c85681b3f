#pragma once
// One camera's detections indexed by the epipolar line of another camera through them, so that
// the detections near an epipolar line are found without testing every detection against it.
//
// Every epipolar line of camera i in camera j passes through the epipole e (camera i's centre as
// seen from camera j, at infinity when it lies in camera j's focal plane). In homogeneous
// coordinates the lines through e are the vectors orthogonal to e: a plane with an orthonormal
// basis {u, v}, in which a line has an angle theta. A point x (homogeneous, (x, y, 1)) whose part
// orthogonal to e has length s lies off a line l through e by
//     |l . x| = |l| s |sin(theta_l - theta_x)|,
// theta_x being the angle of the line through e and x. So the points within a tolerance of l are
// among those whose angle is within asin(tolerance / (|l| s)) of theta_l. The points are kept in
// tiers of s (each four times the last) and, within a tier, in buckets of angle: a query visits
// the few buckets its window covers in each tier and tests only their points. Points with s
// below kNearEpipole (next to the epipole, on every line) are always tested. Nothing here
// depends on where the epipole is: inside the image, outside it, or at infinity.
//
// Building costs one atan2 per point; a query, one per line plus the points it tests, against a
// dot product with every point for a scan. Worth it when many lines are asked about.

#include <array>
#include <span>
#include <vector>

#include <Eigen/Core>

namespace rhot {

class EpipolarIndex {
 public:
  // Points nearer the epipole than this (s, in normalised image units) are tested by every query.
  static constexpr double kNearEpipole = 0.01;

  // Indexes normalised[k] for every k with skip[k] == 0 (skip may be empty: index all).
  // epipole: homogeneous, non-zero. Replaces what was indexed before.
  void build(const Eigen::Vector3d& epipole, std::span<const Eigen::Vector2d> normalised, std::span<const char> skip);

  // The indices k of the indexed points with |line . (x_k, y_k, 1)| <= tolerance, ascending,
  // written to out (cleared first). line: a line through the epipole (line . epipole = 0 up to
  // rounding), homogeneous coefficients (a, b, c) of a x + b y + c = 0.
  void query(const Eigen::Vector3d& line, double tolerance, std::vector<int>& out) const;

  std::size_t size() const { return points_.size(); }

 private:
  static constexpr int kTiers = 4;
  struct Tier {
    double s_min = 0.0;      // every point of the tier is at least this far from the epipole
    std::vector<int> start;  // bucket b holds items[start[b] .. start[b + 1])
    std::vector<int> items;  // indices into points_
    // build's own, kept so that an index built pair after pair allocates nothing once it has seen
    // its largest counts: the tier's points (indices into points_), their angles and buckets.
    std::vector<int> member;
    std::vector<double> theta;
    std::vector<int> bucket, fill;
  };
  struct Point {
    int index = 0;
    Eigen::Vector3d x{0, 0, 1};
  };
  // theta in [0, pi) of the line with homogeneous coefficients (in the basis u, v).
  double angle(const Eigen::Vector3d& line) const;

  Eigen::Vector3d e_{0, 0, 1}, u_{1, 0, 0}, v_{0, 1, 0};
  std::vector<Point> points_;
  std::vector<int> near_;  // indices into points_ of the points next to the epipole
  std::array<Tier, kTiers> tiers_;
};

}  // namespace rhot
