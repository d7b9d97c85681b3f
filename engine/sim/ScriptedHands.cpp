#include "engine/sim/ScriptedHands.h"

#include <Eigen/Geometry>

#include "tracking/sim/HandMotions.h"

namespace rhot {

namespace {

FingerAngles angles(double abduction, double mcp, double pip, double dip) { return FingerAngles{abduction, {mcp, pip, dip}}; }

std::size_t tip_of(int finger) { return static_cast<std::size_t>(chain_joints(static_cast<Finger>(finger))[3]); }

}  // namespace

GraspPose make_grasp(HandSide side, double width_m, double squeeze_m, int fingers) {
  GraspPose g;
  g.side = side;
  g.skeleton = reference_open_hand(side);
  g.chains = hand_chains(g.skeleton, side);
  const auto relaxed = HandSolver(side, g.skeleton).state().angles;
  // From open (thumb out, fingers nearly straight) toward a pinch where the thumb and index tips
  // meet; the grasping fingers close along that path until their tips, less their radii, are
  // `squeeze_m` inside the object's width on each side.
  g.open = {angles(-0.6, -0.3, 0.0, 0.0), angles(0.0, 0.1, 0.1, 0.07), angles(0.0, 0.1, 0.1, 0.07), relaxed[3], relaxed[4]};
  std::array<FingerAngles, kFingerCount> pinch{angles(0.55, 0.45, 0.35, 0.35), angles(-0.1, 0.75, 0.85, 0.57), relaxed[2], relaxed[3],
                                               relaxed[4]};
  if (fingers >= 2) pinch[2] = angles(0.0, 0.75, 0.85, 0.57);
  // Abduction turns toward the chain's lateral axis (+X of the hand frame for both hands): the
  // angles above are a right hand's, a left hand mirrors them.
  if (side == HandSide::kLeft) {
    for (std::size_t f = 0; f < 3; ++f) {
      g.open[f].abduction_rad = -g.open[f].abduction_rad;
      pinch[f].abduction_rad = -pinch[f].abduction_rad;
    }
  }
  const auto along = [&](double s) {
    std::array<FingerAngles, kFingerCount> a;
    for (std::size_t f = 0; f < kFingerCount; ++f) {
      a[f].abduction_rad = g.open[f].abduction_rad + s * (pinch[f].abduction_rad - g.open[f].abduction_rad);
      for (std::size_t k = 0; k < 3; ++k)
        a[f].flexion_rad[k] = g.open[f].flexion_rad[k] + s * (pinch[f].flexion_rad[k] - g.open[f].flexion_rad[k]);
      a[f] = clamp_to_limits(g.chains[f].limits, a[f]);
    }
    return a;
  };
  const double radii = g.skeleton.radius_m[tip_of(0)] + g.skeleton.radius_m[tip_of(1)];
  const double wanted = std::max(0.0, width_m + radii - 2.0 * squeeze_m);
  const auto gap = [&](double s) {
    const HandPose p = hand_pose_from_angles(g.skeleton, g.chains, along(s));
    return (p.position_m[tip_of(1)] - p.position_m[tip_of(0)]).norm();
  };
  double lo = 0.0, hi = 1.0;  // the gap shrinks along the path
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    (gap(mid) > wanted ? lo : hi) = mid;
  }
  g.closed = along(hi);
  g.reach_error_m = std::abs(gap(hi) - wanted);
  const HandPose closed = hand_pose_from_angles(g.skeleton, g.chains, g.closed);
  g.grip_point = 0.5 * (closed.position_m[tip_of(0)] + closed.position_m[tip_of(1)]);
  g.grip_axis = (closed.position_m[tip_of(1)] - closed.position_m[tip_of(0)]).normalized();
  return g;
}

HandPose GraspPose::pose(double closure) const {
  const double s = std::clamp(closure, 0.0, 1.0);
  std::array<FingerAngles, kFingerCount> a;
  for (std::size_t f = 0; f < kFingerCount; ++f) {
    a[f].abduction_rad = open[f].abduction_rad + s * (closed[f].abduction_rad - open[f].abduction_rad);
    for (std::size_t k = 0; k < 3; ++k)
      a[f].flexion_rad[k] = open[f].flexion_rad[k] + s * (closed[f].flexion_rad[k] - open[f].flexion_rad[k]);
    a[f] = clamp_to_limits(chains[f].limits, a[f]);
  }
  return hand_pose_from_angles(skeleton, chains, a);
}

Rigid3d GraspPose::place(const Eigen::Vector3d& centre, const Eigen::Vector3d& axis) const {
  // Hand basis: grip axis, palm normal (-Y) square to it, their cross; world basis alike.
  const auto basis = [](const Eigen::Vector3d& a, const Eigen::Vector3d& down) {
    Eigen::Matrix3d m;
    const Eigen::Vector3d x = a.normalized();
    const Eigen::Vector3d y = (down - down.dot(x) * x).normalized();
    m.col(0) = x;
    m.col(1) = y;
    m.col(2) = x.cross(y);
    return m;
  };
  const Eigen::Matrix3d hand = basis(grip_axis, -Eigen::Vector3d::UnitY());
  const Eigen::Matrix3d world = basis(axis, -Eigen::Vector3d::UnitY());
  Rigid3d r;
  r.rotation = Eigen::Quaterniond(world * hand.transpose()).normalized();
  r.translation = centre - r.rotation * grip_point;
  return r;
}

HandPose pointing_hand(HandSide side) {
  const HandPose skeleton = reference_open_hand(side);
  const auto chains = hand_chains(skeleton, side);
  const std::array<FingerAngles, kFingerCount> a{angles(0.4, 0.5, 0.6, 0.6), angles(0.0, 0.0, 0.0, 0.0), angles(0.0, 1.4, 1.6, 1.07),
                                                 angles(0.0, 1.4, 1.6, 1.07), angles(0.0, 1.4, 1.6, 1.07)};
  std::array<FingerAngles, kFingerCount> clamped;
  for (std::size_t f = 0; f < kFingerCount; ++f) clamped[f] = clamp_to_limits(chains[f].limits, a[f]);
  return hand_pose_from_angles(skeleton, chains, clamped);
}

}  // namespace rhot
