#include "tracking/sim/Realism.h"

#include <cmath>
#include <numbers>
#include <random>

#include <Eigen/Geometry>

#include "tracking/sim/SimulatedRig.h"

namespace rhot {

std::expected<void, std::string> WorldSettings::check() const {
  if (!std::isfinite(calib_error_px) || calib_error_px < 0.0 || calib_error_px > 20.0) {
    return std::unexpected("--calib-error-px: expected 0 to 20 pixels, got " + std::to_string(calib_error_px));
  }
  if (auto ok = rig_settings(1).check(); !ok) return std::unexpected(ok.error());
  return {};
}

SimulatedRigSettings WorldSettings::rig_settings(unsigned seed, double rate_hz) const {
  SimulatedRigSettings s;
  s.sigma_px = sigma_px;
  s.dropout = dropout;
  s.strays = strays;
  s.marker_diameter_m = marker_diameter_m;
  s.camera_skew_s = camera_skew_s;
  s.seed = seed;
  s.rate_hz = rate_hz;
  return s;
}

std::expected<WorldSettings, std::string> world_named(std::string_view name) {
  WorldSettings w;
  if (name == "ideal") return w;
  if (name == "realistic") {
    w.sigma_px = 0.5;
    w.dropout = 0.02;
    w.strays = 3;
    w.marker_diameter_m = 0.006;
    w.camera_skew_s = 0.002;
    w.calib_error_px = 0.3;
    w.independent_hands = true;
    w.occluding_bodies = true;
    return w;
  }
  return std::unexpected("--world: expected ideal or realistic, got \"" + std::string(name) + "\"");
}

namespace {

// Points spread through the rig's volume (else a metre around where the cameras look).
std::vector<Eigen::Vector3d> volume_points(const CameraRig& rig, unsigned seed) {
  Eigen::Vector3d centre(0, 1, 0);
  Eigen::Vector3d size(1, 1, 1);
  if (rig.volume) {
    centre = rig.volume->centre_m;
    size = rig.volume->size_m;
  } else if (!rig.cameras.empty()) {
    centre.setZero();
    for (const Camera& c : rig.cameras) centre += c.centre_world() + c.cam_from_world.rotation.conjugate() * Eigen::Vector3d(0, 0, 1.0);
    centre /= static_cast<double>(rig.cameras.size());
  }
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  std::vector<Eigen::Vector3d> out;
  for (int k = 0; k < 200; ++k) out.push_back(centre + Eigen::Vector3d{u(rng) * size.x(), u(rng) * size.y(), u(rng) * size.z()});
  return out;
}

}  // namespace

double rig_difference_px(const CameraRig& truth, const CameraRig& other, unsigned seed) {
  double sum = 0.0;
  long n = 0;
  const std::vector<Eigen::Vector3d> points = volume_points(truth, seed);
  for (std::size_t c = 0; c < truth.cameras.size() && c < other.cameras.size(); ++c) {
    for (const Eigen::Vector3d& p : points) {
      const auto a = truth.cameras[c].project(p);
      const auto b = other.cameras[c].project(p);
      if (!a || !b || !truth.cameras[c].in_image(*a)) continue;
      sum += (*a - *b).squaredNorm();
      ++n;
    }
  }
  return n > 0 ? std::sqrt(sum / static_cast<double>(n)) : 0.0;
}

CameraRig perturbed_rig(const CameraRig& truth, double rms_px, unsigned seed) {
  if (rms_px <= 0.0) return truth;
  // One random direction of error per camera (turn, shift, focal), then scaled: for small errors
  // the pixels move in proportion.
  std::mt19937_64 rng(seed * 104729u + 17u);
  std::normal_distribution<double> g(0.0, 1.0);
  struct Nudge {
    Eigen::Vector3d turn_rad, shift_m;
    double focal;
  };
  std::vector<Nudge> nudges;
  for (std::size_t c = 0; c < truth.cameras.size(); ++c) {
    nudges.push_back({Eigen::Vector3d{g(rng), g(rng), g(rng)} * 1e-3, Eigen::Vector3d{g(rng), g(rng), g(rng)} * 1e-3, g(rng) * 1e-3});
  }
  const auto apply = [&](double scale) {
    CameraRig out = truth;
    for (std::size_t c = 0; c < out.cameras.size(); ++c) {
      Camera& cam = out.cameras[c];
      const Nudge& n = nudges[c];
      const Eigen::Vector3d turn = scale * n.turn_rad;
      if (turn.norm() > 0.0)
        cam.cam_from_world.rotation =
            (Eigen::Quaterniond(Eigen::AngleAxisd(turn.norm(), turn.normalized())) * cam.cam_from_world.rotation).normalized();
      cam.cam_from_world.translation += scale * n.shift_m;
      cam.intrinsics.fx *= 1.0 + scale * n.focal;
      cam.intrinsics.fy *= 1.0 + scale * n.focal;
    }
    return out;
  };
  const double unit = rig_difference_px(truth, apply(1.0), seed);
  if (!(unit > 0.0)) return truth;
  return apply(rms_px / unit);
}

std::vector<Occluder> hand_bone_occluders(const Rigid3d& world_from_hand, const HandPose& pose) {
  std::vector<Occluder> out;
  for (int j = 0; j < kHandJointCount; ++j) {
    const auto parent = joint_parent(static_cast<HandJoint>(j));
    if (!parent) continue;
    out.push_back({world_from_hand * pose.position_m[static_cast<std::size_t>(*parent)],
                   world_from_hand * pose.position_m[static_cast<std::size_t>(j)], 0.8 * pose.radius_m[static_cast<std::size_t>(j)]});
  }
  return out;
}

HandPose independent_hand(const HandPose& model, unsigned seed) {
  std::mt19937_64 rng(seed * 7727u + 3u);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double user = 1.0 + 0.06 * u(rng);  // the whole hand
  HandPose out = model;
  for (int j = 0; j < kHandJointCount; ++j) {
    const auto parent = joint_parent(static_cast<HandJoint>(j));
    const double bone = user * (1.0 + 0.04 * u(rng));  // each bone its own, within about +-10 % in all
    const auto uj = static_cast<std::size_t>(j);
    if (!parent) {
      out.position_m[uj] = model.position_m[uj] * user;
    } else {
      const auto up = static_cast<std::size_t>(*parent);
      out.position_m[uj] = out.position_m[up] + bone * (model.position_m[uj] - model.position_m[up]);
    }
    out.radius_m[uj] = model.radius_m[uj] * user;
  }
  return out;
}

std::array<FingerAngles, kFingerCount> independent_angles(const std::array<FingerAngles, kFingerCount>& angles, unsigned seed) {
  std::mt19937_64 rng(seed * 6151u + 5u);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::array<FingerAngles, kFingerCount> out = angles;
  for (std::size_t f = 0; f < kFingerCount; ++f) {
    const double dip = 1.0 + 0.35 * u(rng);
    const double shift = 5.0 * std::numbers::pi / 180.0 * u(rng);
    if (f == 0) continue;  // the thumb has no coupled hinge; its own angles stand
    out[f].flexion_rad[2] *= dip;
    out[f].flexion_rad[0] += shift;
  }
  return out;
}

bool hand_confused(const Eigen::Vector3d& reported_wrist, const Eigen::Vector3d& true_wrist, const Eigen::Vector3d& other_true_wrist) {
  const double own = (reported_wrist - true_wrist).norm();
  return own > 0.010 && (reported_wrist - other_true_wrist).norm() < own;
}

}  // namespace rhot
