#include "tracking/hand/HandSolver.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <Eigen/Geometry>

namespace rhot {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

HandJoint joint_at(int index) { return static_cast<HandJoint>(index); }

}  // namespace

std::array<HandJoint, 4> chain_joints(Finger finger) {
  if (finger == Finger::kThumb)
    return {HandJoint::kThumbMetacarpal, HandJoint::kThumbProximal, HandJoint::kThumbDistal, HandJoint::kThumbTip};
  const int base = static_cast<int>(HandJoint::kIndexProximal) + 5 * (static_cast<int>(finger) - 1);
  return {joint_at(base), joint_at(base + 1), joint_at(base + 2), joint_at(base + 3)};
}

std::array<FingerChain, kFingerCount> hand_chains(const HandPose& skeleton, HandSide side) {
  std::array<FingerChain, kFingerCount> chains;
  for (int f = 0; f < kFingerCount; ++f) {
    const auto joints = chain_joints(static_cast<Finger>(f));
    const auto at = [&](HandJoint j) { return skeleton.position_m[static_cast<std::size_t>(j)]; };
    FingerChain& c = chains[static_cast<std::size_t>(f)];
    c.root_m = at(joints[0]);
    // The rest direction: the metacarpal's for a finger; for the thumb, its metacarpal bone's.
    const Eigen::Vector3d from = f == 0 ? at(HandJoint::kThumbMetacarpal) : at(joint_at(static_cast<int>(joints[0]) - 1));
    const Eigen::Vector3d to = f == 0 ? at(HandJoint::kThumbProximal) : at(joints[0]);
    c.rest_direction = (to - from).normalized();
    // The flexion plane: where the skeleton's own joints bend (toward the palm), else straight down.
    Eigen::Vector3d bend = Eigen::Vector3d::Zero();
    for (std::size_t k = 1; k < 4; ++k) {
      const Eigen::Vector3d v = at(joints[k]) - c.root_m;
      bend += v - v.dot(c.rest_direction) * c.rest_direction;
    }
    if (bend.norm() < 0.002 || bend.dot(Eigen::Vector3d::UnitY()) > 0.0) bend = -Eigen::Vector3d::UnitY();
    bend -= bend.dot(c.rest_direction) * c.rest_direction;
    c.up = -bend.normalized();
    for (std::size_t k = 0; k < 3; ++k) c.length_m[k] = (at(joints[k + 1]) - at(joints[k])).norm();
    // Both hands flex toward the palm (-Y); positive abduction is toward +X, the little finger's
    // side on a right hand and the thumb's on a left one (the limits are symmetric).
    (void)side;
    // The fingers' last joints extend a little past straight (15 degrees, pressed on a surface),
    // and the middle finger abducts as the others do. Seed 002 allows neither (its middle finger's
    // abduction fixed), and on a real take (../shared/data/glove-take) that put seen middle
    // fingertips 10.9 mm off on average, where these limits reach them within 1.8 mm. Knuckles
    // extending too (to -30 degrees) gained nothing there and let simulated fingers fold back.
    if (f != static_cast<int>(Finger::kThumb)) c.limits.flexion_min_rad = {0.0, 0.0, -15.0 * kDeg};
    if (f == static_cast<int>(Finger::kThumb)) {
      c.limits.abduction_max_rad = 45.0 * kDeg;
      c.limits.flexion_min_rad = {-20.0 * kDeg, -20.0 * kDeg, -20.0 * kDeg};
      c.limits.flexion_max_rad = {60.0 * kDeg, 60.0 * kDeg, 80.0 * kDeg};
    }
  }
  return chains;
}

void update_pinch(Gesture& pinch, double gap_m, bool tips_seen, const GestureSettings& g) {
  if (!std::isfinite(gap_m)) return;
  pinch.activation = std::clamp((g.pinch_zero_m - gap_m) / (g.pinch_zero_m - g.pinch_on_m), 0.0, 1.0);
  if (gap_m < g.pinch_on_m && tips_seen) pinch.active = true;
  if (gap_m > g.pinch_off_m) pinch.active = false;
}

void update_grip(Gesture& grip, double curl, const GestureSettings& g) {
  if (!std::isfinite(curl)) return;
  grip.activation = std::clamp(curl / g.grip_on, 0.0, 1.0);
  if (curl > g.grip_on) grip.active = true;
  if (curl < g.grip_off) grip.active = false;
}

HandSolver::HandSolver(HandSide side, const HandPose& skeleton, GestureSettings gestures)
    : chains_(hand_chains(skeleton, side)), gestures_(gestures) {
  state_.pose = skeleton;
  // Relaxed: the skeleton's own pose (a relaxed open hand for the reference skeleton).
  for (int f = 0; f < kFingerCount; ++f) {
    const auto joints = chain_joints(static_cast<Finger>(f));
    IkSettings s;
    s.max_iterations = 50;
    relaxed_[static_cast<std::size_t>(f)] =
        solve_fabrik(chains_[static_cast<std::size_t>(f)], skeleton.position_m[static_cast<std::size_t>(joints[3])], {}, s).angles;
  }
  state_.angles = relaxed_;
  state_.confidence.fill(0.0);
}

FingerAngles angles_from_bones(const FingerChain& c, const std::array<Eigen::Vector3d, 3>& b) {
  const Eigen::Vector3d lateral = c.rest_direction.cross(c.up);
  double along = b[0].dot(c.rest_direction);
  double across = b[0].dot(lateral);
  if (along < 0.0) {
    along = -along;
    across = -across;
  }
  FingerAngles a;
  a.abduction_rad = std::atan2(across, along);
  const Eigen::Vector3d forward = std::cos(a.abduction_rad) * c.rest_direction + std::sin(a.abduction_rad) * lateral;
  const Eigen::Vector3d down = -c.up;
  double previous = 0.0;
  for (std::size_t k = 0; k < 3; ++k) {
    const double heading = std::atan2(b[k].dot(down), b[k].dot(forward));
    double d = heading - previous;
    while (d > std::numbers::pi) d -= 2 * std::numbers::pi;
    while (d < -std::numbers::pi) d += 2 * std::numbers::pi;
    a.flexion_rad[k] = d;
    previous = heading;
  }
  return clamp_to_limits(c.limits, a);
}

namespace {

bool finite_angles(const FingerAngles& a) {
  return std::isfinite(a.abduction_rad) && std::ranges::all_of(a.flexion_rad, [](double v) { return std::isfinite(v); });
}

}  // namespace

const HandState& HandSolver::update(double time_s, const std::array<std::optional<Eigen::Vector3d>, kFingerCount>& tips,
                                    const std::array<std::optional<FingerAngles>, kFingerCount>& measured,
                                    const std::array<std::optional<Eigen::Vector3d>, kFingerCount>& predicted) {
  std::array<FingerEvidence, kFingerCount> fingers{};
  for (std::size_t f = 0; f < kFingerCount; ++f) {
    // The first evidence that is there and finite: measured bones, the tip, its prediction.
    FingerEvidence& e = fingers[f];
    if (measured[f] && finite_angles(*measured[f])) {
      e.kind = FingerEvidence::Kind::kMeasured;
      e.angles = *measured[f];
    } else if (tips[f] && tips[f]->allFinite()) {
      e.kind = FingerEvidence::Kind::kTip;
      e.tip_m = *tips[f];
    } else if (predicted[f] && predicted[f]->allFinite()) {
      e.kind = FingerEvidence::Kind::kPredictedTip;
      e.tip_m = *predicted[f];
    }
  }
  return update(time_s, fingers);
}

namespace {

// A finger's flexion rate: its three hinges' together (rad/s).
double closing_of(const FingerAngles& rate) { return rate.flexion_rad[0] + rate.flexion_rad[1] + rate.flexion_rad[2]; }

// Each seen finger's flexion rate against the others' mean, added to the coupling's exponentially
// weighted sums (HandSolver::coupling).
void learn_coupling(double dt, double closing_sum, int closing_count, const std::array<bool, kFingerCount>& seen,
                    const std::array<FingerAngles, kFingerCount>& rate, std::array<double, kFingerCount>& xy,
                    std::array<double, kFingerCount>& xx) {
  const double forget = std::exp(-dt / HandSolver::kCouplingMemory_s);
  for (std::size_t fi = 0; fi < kFingerCount; ++fi) {
    if (!seen[fi]) continue;
    const double own = closing_of(rate[fi]);
    const double others = (closing_sum - own) / (closing_count - 1);
    xy[fi] = forget * xy[fi] + dt * own * others;
    xx[fi] = forget * xx[fi] + dt * others * others;
  }
}

// Evidence that is not finite is none.
FingerEvidence::Kind usable(const FingerEvidence& e) {
  switch (e.kind) {
    case FingerEvidence::Kind::kTip:
    case FingerEvidence::Kind::kPredictedTip:
      return e.tip_m.allFinite() ? e.kind : FingerEvidence::Kind::kHidden;
    case FingerEvidence::Kind::kFitted:
    case FingerEvidence::Kind::kMeasured:
    case FingerEvidence::Kind::kPredictedFit:
      return finite_angles(e.angles) ? e.kind : FingerEvidence::Kind::kHidden;
    case FingerEvidence::Kind::kHidden:
      break;
  }
  return FingerEvidence::Kind::kHidden;
}

}  // namespace

double HandSolver::coupling(Finger finger) const {
  const auto fi = static_cast<std::size_t>(finger);
  // Scaled to seconds of evidence: the sums are in (rad/s)^2 x s, the prior in (rad/s)^2 x 1 s.
  return (coupling_xy_[fi] + kCouplingPrior_rad2_s2) / (coupling_xx_[fi] + kCouplingPrior_rad2_s2);
}

const HandState& HandSolver::update(double time_s, const std::array<FingerEvidence, kFingerCount>& fingers) {
  using Kind = FingerEvidence::Kind;
  const double dt = started_ && std::isfinite(time_s) && time_s > time_s_ ? time_s - time_s_ : 0.0;
  if (std::isfinite(time_s)) time_s_ = std::max(time_s_, time_s);
  started_ = true;
  state_.confidence[static_cast<std::size_t>(HandJoint::kPalm)] = 1.0;
  state_.confidence[static_cast<std::size_t>(HandJoint::kWrist)] = 1.0;
  // The seen fingers first: measured bones win, else their fit or IK to the tip; how fast each one bends.
  const std::array<FingerAngles, kFingerCount> before = state_.angles;
  std::array<Kind, kFingerCount> kind{};
  for (std::size_t fi = 0; fi < kFingerCount; ++fi) kind[fi] = usable(fingers[fi]);
  std::array<bool, kFingerCount> bones_seen{};
  double closing_sum = 0.0;  // the seen fingers' flexion rates (sum of the three hinges), rad/s
  int closing_count = 0;
  for (std::size_t fi = 0; fi < kFingerCount; ++fi) {
    const FingerChain& chain = chains_[fi];
    bones_seen[fi] = kind[fi] == Kind::kMeasured;
    const bool seen = kind[fi] == Kind::kMeasured || kind[fi] == Kind::kFitted || kind[fi] == Kind::kTip;
    state_.tip_seen[fi] = seen;
    if (!seen) continue;
    FingerAngles& a = state_.angles[fi];
    a = kind[fi] == Kind::kTip ? solve_fabrik(chain, fingers[fi].tip_m, a).angles : clamp_to_limits(chain.limits, fingers[fi].angles);
    last_seen_s_[fi] = time_s_;
    if (dt <= 0.0) continue;
    // The finger's own motion, smoothed over a few frames (for when it is hidden next).
    FingerAngles& r = rate_[fi];
    r.abduction_rad = 0.5 * r.abduction_rad + 0.5 * (a.abduction_rad - before[fi].abduction_rad) / dt;
    double closing = 0.0;
    for (std::size_t k = 0; k < 3; ++k) {
      r.flexion_rad[k] = 0.5 * r.flexion_rad[k] + 0.5 * (a.flexion_rad[k] - before[fi].flexion_rad[k]) / dt;
      closing += r.flexion_rad[k];
    }
    closing_sum += closing;
    ++closing_count;
  }
  if (dt > 0.0 && closing_count > 1) learn_coupling(dt, closing_sum, closing_count, state_.tip_seen, rate_, coupling_xy_, coupling_xx_);
  // Hidden fingers: with other fingers seen, each bends as they do (a hand closes and opens as a
  // whole: a grasp, a release); with none seen, it goes on as it last moved, slowing, holds, and
  // only after kHold_s eases toward relaxed.
  for (std::size_t fi = 0; fi < kFingerCount; ++fi) {
    if (state_.tip_seen[fi]) continue;
    const FingerChain& chain = chains_[fi];
    FingerAngles& a = state_.angles[fi];
    FingerAngles& r = rate_[fi];
    const double unseen_s = time_s_ - last_seen_s_[fi];
    predicted_[fi] = kind[fi] == Kind::kPredictedTip || kind[fi] == Kind::kPredictedFit;
    if (predicted_[fi]) {
      // Where the hand's other markers say this tip is; its rate kept for when the prediction stops.
      const FingerAngles from = a;
      a = kind[fi] == Kind::kPredictedTip ? solve_fabrik(chain, fingers[fi].tip_m, a).angles
                                          : clamp_to_limits(chain.limits, fingers[fi].angles);
      if (dt > 0.0) {
        r.abduction_rad = (a.abduction_rad - from.abduction_rad) / dt;
        for (std::size_t k = 0; k < 3; ++k) r.flexion_rad[k] = (a.flexion_rad[k] - from.flexion_rad[k]) / dt;
      }
    } else if (closing_count > 0) {
      // The others' mean flexion rate, times this finger's learnt coupling to them, shared over
      // its hinges by their ranges.
      const double closing = coupling(static_cast<Finger>(fi)) * closing_sum / closing_count;
      double range = 0.0;
      for (std::size_t k = 0; k < 3; ++k) range += chain.limits.flexion_max_rad[k] - chain.limits.flexion_min_rad[k];
      for (std::size_t k = 0; k < 3; ++k) {
        r.flexion_rad[k] = closing * (chain.limits.flexion_max_rad[k] - chain.limits.flexion_min_rad[k]) / range;
        a.flexion_rad[k] += dt * r.flexion_rad[k];
      }
      r.abduction_rad = 0.0;
    } else if (unseen_s <= kHold_s) {
      const double slow = std::exp(-dt / kCoast_s);
      a.abduction_rad += dt * r.abduction_rad;
      for (std::size_t k = 0; k < 3; ++k) a.flexion_rad[k] += dt * r.flexion_rad[k];
      r.abduction_rad *= slow;
      for (double& v : r.flexion_rad) v *= slow;
    } else {
      // Ease toward relaxed: the remaining difference shrinks by exp(-dt / T) each frame.
      const double keep = std::exp(-dt / kRelaxTime_s);
      a.abduction_rad = relaxed_[fi].abduction_rad + keep * (a.abduction_rad - relaxed_[fi].abduction_rad);
      for (std::size_t k = 0; k < 3; ++k)
        a.flexion_rad[k] = relaxed_[fi].flexion_rad[k] + keep * (a.flexion_rad[k] - relaxed_[fi].flexion_rad[k]);
      r = FingerAngles{};
    }
    a = clamp_to_limits(chain.limits, a);
    estimated_[fi] = closing_count > 0;
  }
  for (int f = 0; f < kFingerCount; ++f) {
    const auto fi = static_cast<std::size_t>(f);
    const auto joints = chain_joints(static_cast<Finger>(f));
    const bool seen = state_.tip_seen[fi];
    const auto p = finger_forward(chains_[fi], state_.angles[fi]);
    const double unseen_s = time_s_ - last_seen_s_[fi];
    const double confidence = seen             ? 0.9
                              : predicted_[fi] ? kPredictedConfidence
                              : estimated_[fi] ? kEstimatedConfidence
                                               : 0.9 * std::exp(-unseen_s / kRelaxTime_s);
    for (std::size_t k = 0; k < 4; ++k) {
      // The thumb's metacarpal joint moves with the CMC; the fingers' knuckles are fixed by the hand frame.
      state_.pose.position_m[static_cast<std::size_t>(joints[k])] = p[k];
      state_.confidence[static_cast<std::size_t>(joints[k])] =
          (k == 0 && f != 0) || bones_seen[fi] ? 1.0 : (k == 3 && seen ? 1.0 : confidence);
    }
    if (f != 0) state_.confidence[static_cast<std::size_t>(joints[0]) - 1] = 1.0;  // the metacarpal joint
  }

  // Gestures.
  const auto at = [&](HandJoint j) { return state_.pose.position_m[static_cast<std::size_t>(j)]; };
  const auto radius = [&](HandJoint j) { return state_.pose.radius_m[static_cast<std::size_t>(j)]; };
  const double gap =
      (at(HandJoint::kThumbTip) - at(HandJoint::kIndexTip)).norm() - radius(HandJoint::kThumbTip) - radius(HandJoint::kIndexTip);
  update_pinch(state_.pinch, gap, state_.tip_seen[0] && state_.tip_seen[1], gestures_);
  double curl = 0.0;
  for (int f = 2; f < kFingerCount; ++f) {
    const FingerAngles& a = state_.angles[static_cast<std::size_t>(f)];
    const FingerLimits& l = chains_[static_cast<std::size_t>(f)].limits;
    curl += (a.flexion_rad[0] + a.flexion_rad[1] + a.flexion_rad[2]) / (l.flexion_max_rad[0] + l.flexion_max_rad[1] + l.flexion_max_rad[2]);
  }
  update_grip(state_.grip, curl / 3.0, gestures_);
  return state_;
}

}  // namespace rhot
