#include "tracking/filter/OneEuroFilter.h"

namespace rhot {

Rigid3d PoseFilter::filter(const Rigid3d& pose, double time_s) {
  Rigid3d out;
  out.translation = translation_.filter(pose.translation, time_s);
  if (!pose.rotation.coeffs().allFinite() || !std::isfinite(time_s) || !(pose.rotation.norm() > 0.5)) {
    out.rotation = rotation_.value_or(Eigen::Quaterniond::Identity());
    return out;
  }
  const Eigen::Quaterniond q = pose.rotation.normalized();
  if (!rotation_) {
    rotation_ = q;
    time_s_ = time_s;
    angular_speed_ = 0.0;
    out.rotation = q;
    return out;
  }
  const double dt = time_s - time_s_;
  if (!(dt > 0.0)) {
    out.rotation = *rotation_;
    return out;
  }
  const double speed = rotation_->angularDistance(q) / dt;
  angular_speed_ += one_euro_alpha(rotation_settings_.d_cutoff_hz, dt) * (speed - angular_speed_);
  const double cutoff = rotation_settings_.min_cutoff_hz + rotation_settings_.beta * angular_speed_;
  rotation_ = rotation_->slerp(one_euro_alpha(cutoff, dt), q).normalized();
  time_s_ = time_s;
  out.rotation = *rotation_;
  return out;
}

}  // namespace rhot
