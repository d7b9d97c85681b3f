#include "tracking/rigid/TriangleTracker.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <vector>

#include <Eigen/Geometry>

#include "tracking/core/Solvers.h"
#include "tracking/rigid/RigidFit.h"

namespace rhot {

namespace {

// The markers each edge joins: 0-1, 1-2, 0-2.
constexpr std::array<std::array<int, 2>, 3> kEdgeMarkers{{{0, 1}, {1, 2}, {0, 2}}};

double point_sigma(std::span<const double> sigma_m, int p, double fallback) {
  const auto i = static_cast<std::size_t>(p);
  return i < sigma_m.size() && std::isfinite(sigma_m[i]) && sigma_m[i] > 1e-6 ? sigma_m[i] : fallback;
}

}  // namespace

TriangleTracker::TriangleTracker(const std::array<Eigen::Vector3d, 3>& markers_m, TriangleTrackerSettings settings)
    : markers_m_(markers_m), settings_(settings) {
  for (std::size_t e = 0; e < 3; ++e) {
    edge_m_[e] =
        (markers_m_[static_cast<std::size_t>(kEdgeMarkers[e][0])] - markers_m_[static_cast<std::size_t>(kEdgeMarkers[e][1])]).norm();
  }
}

double TriangleTracker::edge_separation_m() const {
  return std::min({std::abs(edge_m_[0] - edge_m_[1]), std::abs(edge_m_[1] - edge_m_[2]), std::abs(edge_m_[0] - edge_m_[2])});
}

bool TriangleTracker::edge_fits(int edge, std::span<const Eigen::Vector3d> points, std::span<const double> sigma_m, int a, int b) const {
  const double sa = point_sigma(sigma_m, a, settings_.point_sigma_m);
  const double sb = point_sigma(sigma_m, b, settings_.point_sigma_m);
  // The distance's noise: each point's per-axis deviation along the line between them.
  const double tolerance = settings_.edge_tolerance_m + settings_.gate_sigmas * std::sqrt(sa * sa + sb * sb);
  const double d = (points[static_cast<std::size_t>(a)] - points[static_cast<std::size_t>(b)]).norm();
  return std::abs(d - edge_m_[static_cast<std::size_t>(edge)]) <= tolerance;
}

// Every assignment of points to the three markers whose edges all fit, cheapest first (the
// kMaxMatches cheapest). Followed (`predicted`), each marker's points are those within the follow gate of its
// predicted place and the cost is the squared distance from the prediction; found anew, every point
// is a candidate and the cost is the edges' squared misfit.
std::vector<TriangleTracker::Match> TriangleTracker::matches(std::span<const Eigen::Vector3d> points, std::span<const double> sigma_m,
                                                             const std::array<Eigen::Vector3d, 3>* predicted) const {
  std::array<std::vector<int>, 3> near;
  for (int p = 0; p < static_cast<int>(points.size()); ++p) {
    const Eigen::Vector3d& at = points[static_cast<std::size_t>(p)];
    if (!at.allFinite()) continue;
    for (std::size_t k = 0; k < 3; ++k) {
      if (predicted == nullptr || (at - (*predicted)[k]).norm() <= settings_.follow_gate_m) near[k].push_back(p);
    }
  }
  std::vector<Match> out;
  for (const int a : near[0]) {
    for (const int b : near[1]) {
      if (b == a || !edge_fits(0, points, sigma_m, a, b)) continue;
      for (const int c : near[2]) {
        if (c == a || c == b || !edge_fits(2, points, sigma_m, a, c) || !edge_fits(1, points, sigma_m, b, c)) continue;
        Match m{{a, b, c}, 0.0};
        for (std::size_t k = 0; k < 3; ++k) {
          const Eigen::Vector3d& at = points[static_cast<std::size_t>(m.point[k])];
          if (predicted != nullptr) {
            m.cost += (at - (*predicted)[k]).squaredNorm();
          } else {
            const auto [i, j] = kEdgeMarkers[k];
            const double d = (points[static_cast<std::size_t>(m.point[static_cast<std::size_t>(i)])] -
                              points[static_cast<std::size_t>(m.point[static_cast<std::size_t>(j)])])
                                 .norm();
            m.cost += (d - edge_m_[k]) * (d - edge_m_[k]);
          }
        }
        out.push_back(m);
      }
    }
  }
  std::ranges::sort(out, {}, &Match::cost);
  if (out.size() > kMaxMatches) out.resize(kMaxMatches);
  return out;
}

// One marker missing while followed: the best-fitting pair near its predicted place, the
// prediction turned by the least rotation that lays the pair's edge along the points'.
std::optional<Rigid3d> TriangleTracker::place_by_two(const Rigid3d& predicted, std::span<const Eigen::Vector3d> points,
                                                     std::span<const double> sigma_m) {
  std::array<Eigen::Vector3d, 3> q;
  for (std::size_t k = 0; k < 3; ++k) q[k] = predicted * markers_m_[k];
  double best_cost = std::numeric_limits<double>::infinity();
  int best_edge = -1, best_a = -1, best_b = -1;
  for (int e = 0; e < 3; ++e) {
    const auto [i, j] = kEdgeMarkers[static_cast<std::size_t>(e)];
    for (int a = 0; a < static_cast<int>(points.size()); ++a) {
      const Eigen::Vector3d& pa = points[static_cast<std::size_t>(a)];
      if (!pa.allFinite() || (pa - q[static_cast<std::size_t>(i)]).norm() > settings_.follow_gate_m) continue;
      for (int b = 0; b < static_cast<int>(points.size()); ++b) {
        const Eigen::Vector3d& pb = points[static_cast<std::size_t>(b)];
        if (b == a || !pb.allFinite() || (pb - q[static_cast<std::size_t>(j)]).norm() > settings_.follow_gate_m) continue;
        if (!edge_fits(e, points, sigma_m, a, b)) continue;
        const double cost = (pa - q[static_cast<std::size_t>(i)]).squaredNorm() + (pb - q[static_cast<std::size_t>(j)]).squaredNorm();
        if (cost < best_cost) {
          best_cost = cost;
          best_edge = e;
          best_a = a;
          best_b = b;
        }
      }
    }
  }
  if (best_edge < 0) return std::nullopt;
  const auto [i, j] = kEdgeMarkers[static_cast<std::size_t>(best_edge)];
  const Eigen::Vector3d& pa = points[static_cast<std::size_t>(best_a)];
  const Eigen::Vector3d& pb = points[static_cast<std::size_t>(best_b)];
  Rigid3d pose;
  pose.rotation =
      (rotation_between(q[static_cast<std::size_t>(j)] - q[static_cast<std::size_t>(i)], pb - pa) * predicted.rotation).normalized();
  const Eigen::Vector3d mid_body = 0.5 * (markers_m_[static_cast<std::size_t>(i)] + markers_m_[static_cast<std::size_t>(j)]);
  pose.translation = 0.5 * (pa + pb) - pose.rotation * mid_body;
  if (!pose.translation.allFinite() || !pose.rotation.coeffs().allFinite()) return std::nullopt;
  out_.point[static_cast<std::size_t>(i)] = best_a;
  out_.point[static_cast<std::size_t>(j)] = best_b;
  out_.markers_seen = 2;
  return pose;
}

void TriangleTracker::seen_at(double time_s, const Rigid3d& pose) {
  const double dt = time_s - last_seen_s_;
  if (out_.followed && dt > 1e-6) {
    // Smoothed over about two frames: one frame's noise divided by a 90 Hz step is metres a second.
    const Eigen::Vector3d v = (pose.translation - out_.world_from_body.translation) / dt;
    out_.velocity_m_s = 0.5 * (out_.velocity_m_s + v);
  } else {
    out_.velocity_m_s.setZero();
  }
  out_.world_from_body = pose;
  out_.seen = true;
  out_.followed = true;
  last_seen_s_ = time_s;
}

const TrackedTriangle& TriangleTracker::update(double time_s, std::span<const Eigen::Vector3d> points_world,
                                               std::span<const double> sigma_m) {
  out_.seen = false;
  out_.point = {-1, -1, -1};
  out_.markers_seen = 0;
  if (time_s < last_seen_s_ || time_s < pending_time_s_) {
    // Time ran backwards (a replay started over): nothing followed or pending holds.
    confirmed_ = false;
    pending_.clear();
    last_seen_s_ = pending_time_s_ = time_s;
  }
  out_.followed = confirmed_ && time_s - last_seen_s_ <= settings_.lost_after_s;
  if (out_.followed) {
    Rigid3d predicted = out_.world_from_body;
    predicted.translation += out_.velocity_m_s * (time_s - last_seen_s_);
    std::array<Eigen::Vector3d, 3> q;
    for (std::size_t k = 0; k < 3; ++k) q[k] = predicted * markers_m_[k];
    const std::vector<Match> found = matches(points_world, sigma_m, &q);
    if (!found.empty()) {
      if (const auto fit = fit_rigid(markers_m_, places(points_world, found.front()))) {
        out_.point = found.front().point;
        out_.markers_seen = 3;
        seen_at(time_s, fit->to_from_from);
        return out_;
      }
    }
    if (const auto two = place_by_two(predicted, points_world, sigma_m)) seen_at(time_s, *two);
    return out_;
  }
  // Found anew: every match continues the candidate it stays near (each of its points within the
  // follow gate of the last frame's) or starts one; a candidate that comes back confirm_frames
  // frames in a row is the body, unless another has lasted two frames or more beside it (a second
  // glove, or three markers of it and another's: nothing tells them apart).
  confirmed_ = false;
  if (time_s - pending_time_s_ > settings_.lost_after_s) pending_.clear();  // not frames in a row
  pending_time_s_ = time_s;
  const auto near = [&](const std::array<Eigen::Vector3d, 3>& a, const std::array<Eigen::Vector3d, 3>& b) {
    for (std::size_t k = 0; k < 3; ++k) {
      if ((a[k] - b[k]).norm() > settings_.follow_gate_m) return false;
    }
    return true;
  };
  std::vector<Pending> next;
  for (const Match& m : matches(points_world, sigma_m, nullptr)) {
    Pending p{places(points_world, m), m.point, 1};
    // A near-copy of a cheaper match (a doubled point) is that match, not a rival.
    if (std::ranges::any_of(next, [&](const Pending& cheaper) { return near(cheaper.at, p.at); })) continue;
    for (const Pending& before : pending_) {
      if (near(p.at, before.at)) p.frames = std::max(p.frames, before.frames + 1);
    }
    next.push_back(p);
  }
  pending_ = std::move(next);
  const Pending* confirmed = nullptr;
  int lasting = 0;
  for (const Pending& p : pending_) {
    lasting += p.frames >= 2 ? 1 : 0;
    if (p.frames >= settings_.confirm_frames && (confirmed == nullptr || p.frames > confirmed->frames)) confirmed = &p;
  }
  if (confirmed == nullptr || lasting > 1) return out_;
  const auto fit = fit_rigid(markers_m_, confirmed->at);
  if (!fit) return out_;
  confirmed_ = true;
  out_.point = confirmed->point;
  out_.markers_seen = 3;
  pending_.clear();
  seen_at(time_s, fit->to_from_from);
  return out_;
}

std::array<Eigen::Vector3d, 3> TriangleTracker::places(std::span<const Eigen::Vector3d> points, const Match& m) {
  std::array<Eigen::Vector3d, 3> at;
  for (std::size_t k = 0; k < 3; ++k) at[k] = points[static_cast<std::size_t>(m.point[k])];
  return at;
}

}  // namespace rhot
