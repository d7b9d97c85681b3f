#include "tracking/hand/FingerFit.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>

#include "tracking/hand/HandSolver.h"

namespace rhot {

namespace {

using Params = Eigen::Vector4d;  // abduction, then the three flexions
// On the stack: a fit allocates nothing.
using Residuals = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 3 * kMaxFingerPoints + 1, 1>;
using Jacobian = Eigen::Matrix<double, Eigen::Dynamic, 4, 0, 3 * kMaxFingerPoints + 1, 4>;

FingerAngles angles_of(const Params& q) { return FingerAngles{q(0), {q(1), q(2), q(3)}}; }
Params params_of(const FingerAngles& a) { return {a.abduction_rad, a.flexion_rad[0], a.flexion_rad[1], a.flexion_rad[2]}; }

// A finger posed at q in its own plane: forward (F, turned by the abduction), down (D, toward the
// palm) and the plane's normal N = F x D; each bone's heading (the flexions summed up to it). A point
// on bone b with offset (x, y, z) in that bone's frame (HandLayout.h: -Z along the bone, +Y the back
// of the finger, so Y = sin(h) F - cos(h) D, Z = -cos(h) F - sin(h) D, X = -N) is at
//   root + a F + b D + c N,  a = sum_{i<j} l_i cos h_i + y sin h - z cos h,
//                            b = sum_{i<j} l_i sin h_i - y cos h - z sin h,  c = -x,
// with j its joint (0 root .. 3 tip) and h the heading of bone min(j, 2).
struct Pose {
  Eigen::Vector3d forward, down, normal;
  std::array<double, 3> cos_h{}, sin_h{};

  Pose(const FingerChain& chain, const Params& q) {
    const Eigen::Vector3d lateral = chain.rest_direction.cross(chain.up);
    forward = std::cos(q(0)) * chain.rest_direction + std::sin(q(0)) * lateral;
    down = -chain.up;
    normal = forward.cross(down);
    double h = 0.0;
    for (std::size_t k = 0; k < 3; ++k) {
      h += q(static_cast<Eigen::Index>(k + 1));
      cos_h[k] = std::cos(h);
      sin_h[k] = std::sin(h);
    }
  }

  // The point's (a, b, c) in the plane.
  Eigen::Vector3d in_plane(const FingerChain& chain, const FingerPoint& p) const {
    const auto j = static_cast<std::size_t>(p.joint);
    const std::size_t bone = std::min<std::size_t>(j, 2);
    double a = p.offset_m.y() * sin_h[bone] - p.offset_m.z() * cos_h[bone];
    double b = -p.offset_m.y() * cos_h[bone] - p.offset_m.z() * sin_h[bone];
    for (std::size_t i = 0; i < j; ++i) {
      a += chain.length_m[i] * cos_h[i];
      b += chain.length_m[i] * sin_h[i];
    }
    return {a, b, -p.offset_m.x()};
  }

  Eigen::Vector3d at(const FingerChain& chain, const FingerPoint& p) const {
    const Eigen::Vector3d abc = in_plane(chain, p);
    return chain.root_m + abc.x() * forward + abc.y() * down + abc.z() * normal;
  }
};

// The finite points to fit, and the coupling's weight.
struct Problem {
  const FingerChain& chain;
  std::array<FingerPoint, kMaxFingerPoints> point_store{};
  std::size_t count = 0;
  double coupling_m;

  std::span<const FingerPoint> points() const { return {point_store.data(), count}; }
  Eigen::Index rows() const { return static_cast<Eigen::Index>(3 * count) + (chain.limits.coupling > 0.0 ? 1 : 0); }

  // The residuals: each point's miss times the square root of its weight, then the coupling's.
  void residuals(const Params& q, Residuals& r) const {
    const Pose pose(chain, q);
    for (std::size_t i = 0; i < count; ++i) {
      const FingerPoint& p = point_store[i];
      r.segment<3>(static_cast<Eigen::Index>(3 * i)) = std::sqrt(p.weight) * (pose.at(chain, p) - p.at_m);
    }
    if (chain.limits.coupling > 0.0) r(r.size() - 1) = coupling_m * (q(3) - chain.limits.coupling * q(2));
  }

  // Their derivatives by the four angles: as the abduction turns, F -> -N and N -> F, so a point
  // moves by -a N + c F; as flexion k turns, every heading from bone k on turns with it.
  void jacobian(const Params& q, Jacobian& jac) const {
    const Pose pose(chain, q);
    jac.setZero();
    for (std::size_t i = 0; i < count; ++i) {
      const FingerPoint& p = point_store[i];
      const auto j = static_cast<std::size_t>(p.joint);
      const std::size_t bone = std::min<std::size_t>(j, 2);
      const Eigen::Vector3d abc = pose.in_plane(chain, p);
      const double w = std::sqrt(p.weight);
      const auto row = static_cast<Eigen::Index>(3 * i);
      jac.block<3, 1>(row, 0) = w * (-abc.x() * pose.normal + abc.z() * pose.forward);
      for (std::size_t k = 0; k < 3; ++k) {
        double da = 0.0, db = 0.0;
        for (std::size_t m = k; m < j; ++m) {
          da -= chain.length_m[m] * pose.sin_h[m];
          db += chain.length_m[m] * pose.cos_h[m];
        }
        if (k <= bone) {
          da += p.offset_m.y() * pose.cos_h[bone] + p.offset_m.z() * pose.sin_h[bone];
          db += p.offset_m.y() * pose.sin_h[bone] - p.offset_m.z() * pose.cos_h[bone];
        }
        jac.block<3, 1>(row, static_cast<Eigen::Index>(k + 1)) = w * (da * pose.forward + db * pose.down);
      }
    }
    if (chain.limits.coupling > 0.0) {
      jac(jac.rows() - 1, 2) = -coupling_m * chain.limits.coupling;
      jac(jac.rows() - 1, 3) = coupling_m;
    }
  }

  double points_rms(const Residuals& r) const {
    double weights = 0.0;
    for (const FingerPoint& p : points()) weights += p.weight;
    const double squares = r.head(static_cast<Eigen::Index>(3 * count)).squaredNorm();
    return weights > 0.0 ? std::sqrt(squares / weights) : 0.0;
  }
};

Params clamp_params(const FingerLimits& limits, const Params& q) { return params_of(clamp_to_limits(limits, angles_of(q))); }

// Each angle's range at q: the flexions' own, the abduction's at q's root flexion (the ellipse).
std::array<std::pair<double, double>, 4> angle_bounds(const FingerLimits& limits, const Params& q) {
  FingerAngles widest = angles_of(q);
  widest.abduction_rad = 1e3;
  const double abduction = clamp_to_limits(limits, widest).abduction_rad;
  return {{{-abduction, abduction},
           {limits.flexion_min_rad[0], limits.flexion_max_rad[0]},
           {limits.flexion_min_rad[1], limits.flexion_max_rad[1]},
           {limits.flexion_min_rad[2], limits.flexion_max_rad[2]}}};
}

// Levenberg-Marquardt from `start`, each step clamped into the limits (a projected step: one that
// would leave them stops at their edge).
FingerFit levenberg_marquardt(const Problem& problem, const FingerAngles& start, const FingerFitSettings& s) {
  const Eigen::Index n = problem.rows();
  Params q = clamp_params(problem.chain.limits, params_of(start));
  Residuals r(n), trial_r(n);
  problem.residuals(q, r);
  double cost = r.squaredNorm();
  double lambda = 1e-3;
  FingerFit out;
  Jacobian jacobian(n, 4);
  for (int it = 0; it < s.max_iterations; ++it) {
    out.iterations = it + 1;
    problem.jacobian(q, jacobian);
    Eigen::Matrix4d jtj = jacobian.transpose() * jacobian;
    Params gradient = jacobian.transpose() * r;
    // An angle at its limit that the descent would push further stays there this step (its row and
    // column out of the system): a clamped step along it would gain nothing and stall the others.
    const std::array<std::pair<double, double>, 4> bounds = angle_bounds(problem.chain.limits, q);
    for (int k = 0; k < 4; ++k) {
      const auto [low, high] = bounds[static_cast<std::size_t>(k)];
      const bool held = (q(k) <= low + 1e-12 && gradient(k) > 0.0) || (q(k) >= high - 1e-12 && gradient(k) < 0.0);
      if (!held) continue;
      jtj.row(k).setZero();
      jtj.col(k).setZero();
      jtj(k, k) = 1.0;
      gradient(k) = 0.0;
    }
    bool improved = false;
    double moved = 0.0;
    const double cost_before = cost;
    for (int attempt = 0; attempt < 6 && !improved; ++attempt) {
      Eigen::Matrix4d a = jtj;
      a.diagonal() += lambda * (jtj.diagonal() + Params::Constant(1e-12));
      const Params step = a.ldlt().solve(-gradient);
      if (!step.allFinite()) break;
      const Params next = clamp_params(problem.chain.limits, q + step);
      problem.residuals(next, trial_r);
      const double trial_cost = trial_r.squaredNorm();
      if (trial_cost < cost) {
        moved = (next - q).cwiseAbs().maxCoeff();
        q = next;
        r = trial_r;
        cost = trial_cost;
        lambda = std::max(1e-9, 0.3 * lambda);
        improved = true;
      } else {
        lambda *= 10.0;
      }
    }
    // Converged once a near Gauss-Newton step (little damping) barely moves (a step kept small by
    // heavy damping after rejected tries is not convergence), or a step gains almost nothing (a
    // point out of reach: the nearest pose is found, the miss stays).
    if (!improved || (moved < s.tolerance_rad && lambda <= 1e-2) || cost > (1.0 - 1e-6) * cost_before) break;
  }
  out.angles = angles_of(q);
  out.rms_m = problem.points_rms(r);
  return out;
}

}  // namespace

FingerFitSettings finger_fit_settings(Finger finger) {
  FingerFitSettings s;
  if (finger == Finger::kThumb) s.coupling_m = 0.0;
  return s;
}

FingerPoint finger_point(const LayoutMarker& marker, const Eigen::Vector3d& at_m, double weight) {
  const auto joints = chain_joints(finger_of_bone(marker.bone));
  FingerPoint p;
  p.joint = static_cast<int>(std::min<std::ptrdiff_t>(3, std::find(joints.begin(), joints.end(), marker.bone) - joints.begin()));
  p.offset_m = marker.offset_m;
  p.at_m = at_m;
  p.weight = weight;
  return p;
}

Eigen::Vector3d finger_point_at(const FingerChain& chain, const FingerAngles& angles, const FingerPoint& point) {
  FingerPoint p = point;
  p.joint = std::clamp(p.joint, 0, 3);
  return Pose(chain, params_of(angles)).at(chain, p);
}

FingerFit fit_finger(const FingerChain& chain, std::span<const FingerPoint> points, const FingerAngles& start, const FingerFitSettings& s) {
  Problem problem{chain, {}, 0, s.coupling_m};
  for (const FingerPoint& p : points) {
    if (problem.count < kMaxFingerPoints && p.at_m.allFinite() && p.offset_m.allFinite() && std::isfinite(p.weight) && p.weight > 0.0 &&
        p.joint >= 0 && p.joint <= 3)
      problem.point_store[problem.count++] = p;
  }
  if (problem.count == 0) return FingerFit{clamp_to_limits(chain.limits, start), 0.0, 0};
  FingerFit best = levenberg_marquardt(problem, start, s);
  if (best.rms_m <= s.restart_m) return best;
  // A poor fit from the last pose: again from FABRIK's pose toward the tip joint where the most
  // distal point puts it (its offset turned as in the last pose), unless that point is out of the
  // finger's reach, where no start would do better (a skeleton too small for its user's markers).
  const auto distal = std::ranges::max_element(problem.points(), {}, &FingerPoint::joint);
  double reach = distal->offset_m.norm();
  for (int k = 0; k < std::min(distal->joint, 3); ++k) reach += chain.length_m[static_cast<std::size_t>(k)];
  if ((distal->at_m - chain.root_m).norm() > reach) return best;
  const FingerAngles from = clamp_to_limits(chain.limits, start);
  const Eigen::Vector3d tip = distal->at_m - (finger_point_at(chain, from, *distal) - finger_forward(chain, from)[3]);
  IkSettings fabrik;
  fabrik.max_iterations = 30;
  const FingerFit again = levenberg_marquardt(problem, solve_fabrik(chain, tip, from, fabrik).angles, s);
  const int iterations = best.iterations + again.iterations;
  if (again.rms_m < best.rms_m) best = again;
  best.iterations = iterations;
  return best;
}

}  // namespace rhot
