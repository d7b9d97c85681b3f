#include "tracking/hand/FingerIK.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <Eigen/Geometry>

namespace rhot {

namespace {

double finite_or_zero(double v) { return std::isfinite(v) ? v : 0.0; }

// The largest abduction the ellipse allows at this root flexion.
double abduction_limit(const FingerLimits& l, double flexion) {
  if (l.abduction_max_rad <= 0.0) return 0.0;
  const double f_max = l.flexion_max_rad[0];
  if (flexion <= 0.0 || f_max <= 0.0) return l.abduction_max_rad;
  const double r = std::min(1.0, flexion / f_max);
  return l.abduction_max_rad * std::sqrt(std::max(0.0, 1.0 - r * r));
}

// The finger's plane for an abduction: its forward axis and its "down" (flexion) axis.
void plane_axes(const FingerChain& c, double abduction, Eigen::Vector3d& forward, Eigen::Vector3d& down) {
  const Eigen::Vector3d lateral = c.rest_direction.cross(c.up);
  forward = std::cos(abduction) * c.rest_direction + std::sin(abduction) * lateral;
  down = -c.up;
}

// Planar forward kinematics: joint positions (x forward, y down) from the three flexions.
std::array<Eigen::Vector2d, 4> planar_forward(const std::array<double, 3>& length, const std::array<double, 3>& flexion) {
  std::array<Eigen::Vector2d, 4> p;
  p[0] = Eigen::Vector2d::Zero();
  double heading = 0.0;
  for (std::size_t i = 0; i < 3; ++i) {
    heading += flexion[i];
    p[i + 1] = p[i] + length[i] * Eigen::Vector2d(std::cos(heading), std::sin(heading));
  }
  return p;
}

double angle_of(const Eigen::Vector2d& v) { return std::atan2(v.y(), v.x()); }

double wrap(double a) {
  while (a > std::numbers::pi) a -= 2 * std::numbers::pi;
  while (a < -std::numbers::pi) a += 2 * std::numbers::pi;
  return a;
}

}  // namespace

FingerAngles clamp_to_limits(const FingerLimits& l, FingerAngles a) {
  for (std::size_t i = 0; i < 3; ++i)
    a.flexion_rad[i] = std::clamp(finite_or_zero(a.flexion_rad[i]), l.flexion_min_rad[i], l.flexion_max_rad[i]);
  const double limit = abduction_limit(l, a.flexion_rad[0]);
  a.abduction_rad = std::clamp(finite_or_zero(a.abduction_rad), -limit, limit);
  return a;
}

bool within_limits(const FingerLimits& l, const FingerAngles& a, double tol) {
  for (std::size_t i = 0; i < 3; ++i) {
    if (!(a.flexion_rad[i] >= l.flexion_min_rad[i] - tol && a.flexion_rad[i] <= l.flexion_max_rad[i] + tol)) return false;
  }
  return std::abs(a.abduction_rad) <= abduction_limit(l, a.flexion_rad[0]) + tol;
}

std::array<Eigen::Vector3d, 4> finger_forward(const FingerChain& c, const FingerAngles& a) {
  Eigen::Vector3d forward, down;
  plane_axes(c, a.abduction_rad, forward, down);
  const auto planar = planar_forward(c.length_m, a.flexion_rad);
  std::array<Eigen::Vector3d, 4> out;
  for (std::size_t i = 0; i < 4; ++i) out[i] = c.root_m + planar[i].x() * forward + planar[i].y() * down;
  return out;
}

namespace {

IkResult fabrik_from(const FingerChain& c, const Eigen::Vector3d& target, const FingerAngles& start, const IkSettings& s) {
  IkResult r;
  r.angles = clamp_to_limits(c.limits, start);
  if (!target.allFinite()) {
    r.tip_error_m = 0.0;
    return r;
  }
  const FingerLimits& l = c.limits;
  const Eigen::Vector3d lateral = c.rest_direction.cross(c.up);
  const Eigen::Vector3d to_target = target - c.root_m;
  std::array<double, 3> flexion = r.angles.flexion_rad;
  double abduction = r.angles.abduction_rad;
  // The chain lies in one plane through the up axis, so the target's direction in the palm plane
  // is the abduction (its opposite when the finger curls back past its knuckle), limited by the
  // ellipse for the current root flexion.
  double along = to_target.dot(c.rest_direction);
  double across = to_target.dot(lateral);
  if (along < 0.0) {
    along = -along;
    across = -across;
  }
  const bool aim = std::hypot(along, across) > 1e-6;
  const double wanted_abduction = aim ? std::atan2(across, along) : abduction;
  double plane_abduction = std::numeric_limits<double>::quiet_NaN();
  Eigen::Vector2d goal = Eigen::Vector2d::Zero();
  double off_plane2 = 0.0;  // squared distance of the target from the finger's plane
  std::array<Eigen::Vector2d, 4> p = planar_forward(c.length_m, flexion);
  for (int it = 0; it < s.max_iterations; ++it) {
    r.iterations = it + 1;
    const double limit = abduction_limit(l, flexion[0]);
    abduction = std::clamp(wanted_abduction, -limit, limit);
    if (abduction != plane_abduction) {
      Eigen::Vector3d forward, down;
      plane_axes(c, abduction, forward, down);
      goal = {to_target.dot(forward), to_target.dot(down)};
      off_plane2 = std::max(0.0, to_target.squaredNorm() - goal.squaredNorm());
      plane_abduction = abduction;
    }
    // Backward pass from the target, forward pass from the root with each hinge clamped.
    p[3] = goal;
    for (int i = 2; i >= 0; --i) {
      const Eigen::Vector2d d = p[static_cast<std::size_t>(i)] - p[static_cast<std::size_t>(i) + 1];
      const double n = d.norm();
      p[static_cast<std::size_t>(i)] = p[static_cast<std::size_t>(i) + 1] + (n > 1e-12 ? Eigen::Vector2d(d / n) : Eigen::Vector2d(-1, 0)) *
                                                                                c.length_m[static_cast<std::size_t>(i)];
    }
    double heading = 0.0;
    Eigen::Vector2d at = Eigen::Vector2d::Zero();
    for (std::size_t i = 0; i < 3; ++i) {
      const Eigen::Vector2d d = p[i + 1] - at;
      const double wanted = d.norm() > 1e-12 ? angle_of(d) : heading;
      flexion[i] = std::clamp(wrap(wanted - heading), l.flexion_min_rad[i], l.flexion_max_rad[i]);
      heading += flexion[i];
      at += c.length_m[i] * Eigen::Vector2d(std::cos(heading), std::sin(heading));
      p[i + 1] = at;
    }
    // The last hinge follows the middle one (DIP = 2/3 PIP): keep their sum, split it.
    if (l.coupling > 0.0) {
      const double sum = flexion[1] + flexion[2];
      flexion[1] = std::clamp(sum / (1.0 + l.coupling), l.flexion_min_rad[1], l.flexion_max_rad[1]);
      flexion[2] = std::clamp(l.coupling * flexion[1], l.flexion_min_rad[2], l.flexion_max_rad[2]);
      const double h1 = flexion[0] + flexion[1];
      const double h2 = h1 + flexion[2];
      p[2] = p[1] + c.length_m[1] * Eigen::Vector2d(std::cos(h1), std::sin(h1));
      p[3] = p[2] + c.length_m[2] * Eigen::Vector2d(std::cos(h2), std::sin(h2));
    }
    r.tip_error_m = std::sqrt((p[3] - goal).squaredNorm() + off_plane2);
    if (r.tip_error_m < s.tolerance_m) break;
  }
  r.angles = clamp_to_limits(l, FingerAngles{abduction, flexion});
  r.tip_error_m = (finger_forward(c, r.angles)[3] - target).norm();
  return r;
}

}  // namespace

IkResult solve_fabrik(const FingerChain& c, const Eigen::Vector3d& target, const FingerAngles& start, const IkSettings& s) {
  IkResult r = fabrik_from(c, target, start, s);
  // Hinges that may also extend (the thumb's) can leave FABRIK bent the wrong way from a poor
  // start; once it has stalled far from the target, try again from the middle of the ranges.
  if (r.tip_error_m > 10.0 * s.tolerance_m && target.allFinite()) {
    FingerAngles middle;
    for (std::size_t k = 0; k < 3; ++k) middle.flexion_rad[k] = 0.5 * (c.limits.flexion_min_rad[k] + c.limits.flexion_max_rad[k]);
    const IkResult again = fabrik_from(c, target, middle, s);
    if (again.tip_error_m < r.tip_error_m) r = IkResult{again.angles, again.tip_error_m, r.iterations + again.iterations};
  }
  return r;
}

IkResult solve_dls(const FingerChain& c, const Eigen::Vector3d& target, const FingerAngles& start, const IkSettings& s, double damping) {
  IkResult r;
  r.angles = clamp_to_limits(c.limits, start);
  if (!target.allFinite()) return r;
  const double coupling = c.limits.coupling;
  auto tip = [&](const Eigen::Vector3d& q) {
    FingerAngles a{q(0), {q(1), q(2), coupling * q(2)}};
    return finger_forward(c, a)[3];
  };
  Eigen::Vector3d q(r.angles.abduction_rad, r.angles.flexion_rad[0], r.angles.flexion_rad[1]);
  for (int it = 0; it < s.max_iterations; ++it) {
    r.iterations = it + 1;
    const Eigen::Vector3d here = tip(q);
    const Eigen::Vector3d e = target - here;
    r.tip_error_m = e.norm();
    if (r.tip_error_m < s.tolerance_m) break;
    Eigen::Matrix3d j;
    for (int k = 0; k < 3; ++k) {
      Eigen::Vector3d dq = Eigen::Vector3d::Zero();
      dq(k) = 1e-6;
      j.col(k) = (tip(q + dq) - here) / 1e-6;
    }
    const Eigen::Vector3d step = (j.transpose() * j + damping * damping * Eigen::Matrix3d::Identity()).ldlt().solve(j.transpose() * e);
    if (!step.allFinite()) break;
    q += step;
    const FingerAngles clamped = clamp_to_limits(c.limits, FingerAngles{q(0), {q(1), q(2), coupling * q(2)}});
    q = Eigen::Vector3d(clamped.abduction_rad, clamped.flexion_rad[0], clamped.flexion_rad[1]);
  }
  r.angles = clamp_to_limits(c.limits, FingerAngles{q(0), {q(1), q(2), coupling * q(2)}});
  r.tip_error_m = (finger_forward(c, r.angles)[3] - target).norm();
  return r;
}

}  // namespace rhot
