#include "tracking/geometry/EpipolarIndex.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <Eigen/Geometry>

#include "base/Capacity.h"
#include "base/Check.h"

namespace rhot {

namespace {

// Query windows are widened by this (radians) so that rounding never loses a point on the edge:
// the exact test decides.
constexpr double kAngleMargin = 1e-9;

int bucket_of(double theta, int buckets) { return std::clamp(static_cast<int>(theta / std::numbers::pi * buckets), 0, buckets - 1); }

}  // namespace

double EpipolarIndex::angle(const Eigen::Vector3d& line) const {
  double theta = std::atan2(line.dot(v_), line.dot(u_));
  if (theta < 0.0) theta += std::numbers::pi;
  return theta >= std::numbers::pi ? 0.0 : theta;
}

void EpipolarIndex::build(const Eigen::Vector3d& epipole, std::span<const Eigen::Vector2d> normalised, std::span<const char> skip) {
  RHOT_PRECONDITION(epipole.squaredNorm() > 0.0 && epipole.allFinite(), "EpipolarIndex: a finite, non-zero epipole");
  RHOT_PRECONDITION(skip.empty() || skip.size() == normalised.size(), "EpipolarIndex: one skip flag per point");
  e_ = epipole.normalized();
  // u: orthogonal to e, from the axis least aligned with it; v completes the basis.
  Eigen::Index least = 0;
  e_.cwiseAbs().minCoeff(&least);
  u_ = e_.cross(Eigen::Vector3d::Unit(least)).normalized();
  v_ = e_.cross(u_);

  points_.clear();
  near_.clear();
  for (Tier& tier : tiers_) {
    tier.theta.clear();
    tier.member.clear();
  }
  for (std::size_t k = 0; k < normalised.size(); ++k) {
    if (!skip.empty() && skip[k] != 0) continue;
    const Eigen::Vector3d x = normalised[k].homogeneous();
    const auto p = static_cast<int>(points_.size());
    points_.push_back({static_cast<int>(k), x});
    const Eigen::Vector3d through = e_.cross(x);  // the line through the epipole and x
    const double s = through.norm();              // |x orthogonal to e|
    if (!(s >= kNearEpipole)) {
      near_.push_back(p);
      continue;
    }
    int t = 0;
    double s_min = kNearEpipole * 4.0;
    while (t + 1 < kTiers && s >= s_min) {
      ++t;
      s_min *= 4.0;
    }
    tiers_[static_cast<std::size_t>(t)].theta.push_back(angle(through));
    tiers_[static_cast<std::size_t>(t)].member.push_back(p);
  }
  // Each tier: about one point a bucket, its points sorted into buckets by angle (counting sort).
  double s_min = kNearEpipole;
  for (std::size_t t = 0; t < kTiers; ++t, s_min *= 4.0) {
    Tier& tier = tiers_[t];
    tier.s_min = s_min;
    const std::vector<int>& member = tier.member;
    const int buckets = std::max(1, static_cast<int>(member.size()));
    reserve_room(tier.start, static_cast<std::size_t>(buckets) + 1);
    reserve_room(tier.fill, static_cast<std::size_t>(buckets));
    reserve_room(tier.bucket, member.size());
    reserve_room(tier.items, member.size());
    tier.start.assign(static_cast<std::size_t>(buckets) + 1, 0);
    tier.bucket.resize(member.size());
    for (std::size_t m = 0; m < member.size(); ++m) {
      tier.bucket[m] = bucket_of(tier.theta[m], buckets);
      ++tier.start[static_cast<std::size_t>(tier.bucket[m]) + 1];
    }
    for (std::size_t b = 1; b < tier.start.size(); ++b) tier.start[b] += tier.start[b - 1];
    tier.items.assign(member.size(), 0);
    tier.fill.assign(tier.start.begin(), tier.start.end() - 1);
    for (std::size_t m = 0; m < member.size(); ++m) {
      tier.items[static_cast<std::size_t>(tier.fill[static_cast<std::size_t>(tier.bucket[m])]++)] = member[m];
    }
  }
}

void EpipolarIndex::query(const Eigen::Vector3d& line, double tolerance, std::vector<int>& out) const {
  out.clear();
  const auto test = [&](int p) {
    const Point& point = points_[static_cast<std::size_t>(p)];
    if (std::abs(line.dot(point.x)) <= tolerance) out.push_back(point.index);
  };
  for (const int p : near_) test(p);
  // The line's part in the pencil (its part along e is rounding).
  const double lu = line.dot(u_), lv = line.dot(v_);
  const double l_norm = std::hypot(lu, lv);
  const double theta = angle(line);
  for (const Tier& tier : tiers_) {
    if (tier.items.empty()) continue;
    const int buckets = static_cast<int>(tier.start.size()) - 1;
    // |sin(d theta)| <= tolerance / (|l| s) <= tolerance / (|l| s_min) for every point of the tier.
    const double ratio = l_norm > 0.0 ? tolerance / (l_norm * tier.s_min) : 2.0;
    const double window = ratio >= 1.0 ? std::numbers::pi : std::asin(ratio) + kAngleMargin;
    const int lo = static_cast<int>(std::floor((theta - window) / std::numbers::pi * buckets));
    const int hi = static_cast<int>(std::floor((theta + window) / std::numbers::pi * buckets));
    if (2.0 * window >= std::numbers::pi || hi - lo + 1 >= buckets) {
      for (const int p : tier.items) test(p);
      continue;
    }
    for (int b = lo; b <= hi; ++b) {
      const auto w = static_cast<std::size_t>(((b % buckets) + buckets) % buckets);  // angles wrap at pi
      for (int i = tier.start[w]; i < tier.start[w + 1]; ++i) test(tier.items[static_cast<std::size_t>(i)]);
    }
  }
  std::sort(out.begin(), out.end());
}

}  // namespace rhot
