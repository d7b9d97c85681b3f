#include "engine/runtime/Latency.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <nlohmann/json.hpp>

#include "base/Check.h"

namespace rhot {

VsyncClock::VsyncClock(double period_s, double anchor_s) : period_s_(period_s), anchor_s_(anchor_s) {
  RHOT_PRECONDITION(std::isfinite(period_s) && period_s > 0.0 && std::isfinite(anchor_s), "VsyncClock: a finite period > 0 and anchor");
}

double VsyncClock::next_at_or_after(double t_s) const {
  if (!(t_s > anchor_s_)) return anchor_s_;
  // A nanosecond's grace: a time computed as a vsync itself stays on it.
  const double periods = std::ceil((t_s - anchor_s_) / period_s_ - 1e-9 / period_s_);
  return anchor_s_ + periods * period_s_;
}

LatencyStats::LatencyStats(std::size_t window) : window_(std::max<std::size_t>(window, 1)) {}

void LatencyStats::push(Series& s, double ms) {
  s.window.push_back(ms);
  if (s.window.size() > window_) s.window.pop_front();
  s.sum += ms;
  s.max = std::max(s.max, ms);
}

void LatencyStats::record(const FrameMoments& m) {
  RHOT_PRECONDITION(std::isfinite(m.capture_s) && std::isfinite(m.display_s) && m.capture_s <= m.pose_s && m.pose_s <= m.submit_s &&
                        m.submit_s <= m.display_s,
                    "LatencyStats::record: capture <= pose <= submit <= display, finite");
  ++frames_;
  push(tracking_, 1e3 * (m.pose_s - m.capture_s));
  push(render_, 1e3 * (m.submit_s - m.pose_s));
  push(motion_to_photon_, 1e3 * (m.display_s - m.capture_s));
}

TimingSummary LatencyStats::summary(const Series& s) const {
  TimingSummary t;
  t.count = frames_;
  if (frames_ == 0) return t;
  t.mean_ms = s.sum / static_cast<double>(frames_);
  t.max_ms = s.max;
  const std::vector<double> samples(s.window.begin(), s.window.end());
  t.p50_ms = percentile(samples, 0.5);
  t.p99_ms = percentile(samples, 0.99);
  return t;
}

nlohmann::json LatencyStats::to_json() const {
  const auto one = [](const TimingSummary& t) {
    return nlohmann::json{{"p50", t.p50_ms}, {"p99", t.p99_ms}, {"mean", t.mean_ms}, {"max", t.max_ms}};
  };
  return {{"frames", frames_},
          {"tracking_ms", one(tracking())},
          {"render_ms", one(render())},
          {"motion_to_photon_ms", one(motion_to_photon())}};
}

MotionPredictor::MotionPredictor(std::size_t points, int frames, double max_speed_m_s)
    : points_(points), frames_(frames), max_speed_m_s_(max_speed_m_s), velocity_(points, Eigen::Vector3d::Zero()) {
  RHOT_PRECONDITION(points > 0 && frames >= 2 && max_speed_m_s > 0.0, "MotionPredictor: points > 0, frames >= 2, max_speed > 0");
}

void MotionPredictor::reset() {
  times_.clear();
  history_.clear();
  std::fill(velocity_.begin(), velocity_.end(), Eigen::Vector3d::Zero());
}

void MotionPredictor::update(double t_s, std::span<const Eigen::Vector3d> positions, bool seen) {
  RHOT_PRECONDITION(positions.size() == points_, "MotionPredictor::update: one position per point");
  bool usable = seen && std::isfinite(t_s);
  for (const Eigen::Vector3d& p : positions) usable = usable && p.allFinite();
  if (!usable) {
    reset();
    return;
  }
  if (!times_.empty()) {
    const double dt = t_s - times_.back();
    if (dt <= 0.0) {
      reset();  // time went back (a replay restarted) or stood still: a new history
    } else {
      const std::vector<Eigen::Vector3d>& last = history_.back();
      for (std::size_t i = 0; i < points_; ++i) {
        if ((positions[i] - last[i]).norm() > max_speed_m_s_ * dt) {
          reset();  // a jump, not a motion (the hand found afresh)
          break;
        }
      }
    }
  }
  times_.push_back(t_s);
  history_.emplace_back(positions.begin(), positions.end());
  if (times_.size() > static_cast<std::size_t>(frames_)) {
    times_.pop_front();
    history_.pop_front();
  }
  const std::size_t n = times_.size();
  if (n < 2) {
    std::fill(velocity_.begin(), velocity_.end(), Eigen::Vector3d::Zero());
    return;
  }
  double mean_t = 0.0;
  for (const double t : times_) mean_t += t;
  mean_t /= static_cast<double>(n);
  double stt = 0.0;
  for (const double t : times_) stt += (t - mean_t) * (t - mean_t);
  for (std::size_t i = 0; i < points_; ++i) {
    Eigen::Vector3d mean_x = Eigen::Vector3d::Zero();
    for (const auto& frame : history_) mean_x += frame[i];
    mean_x /= static_cast<double>(n);
    Eigen::Vector3d stx = Eigen::Vector3d::Zero();
    for (std::size_t k = 0; k < n; ++k) stx += (times_[k] - mean_t) * (history_[k][i] - mean_x);
    velocity_[i] = stx / stt;
  }
}

Eigen::Vector3d MotionPredictor::velocity(std::size_t point) const {
  RHOT_PRECONDITION(point < points_, "MotionPredictor::velocity: no such point");
  return velocity_[point];
}

std::vector<Eigen::Vector3d> MotionPredictor::predict(std::span<const Eigen::Vector3d> positions, double horizon_s) const {
  RHOT_PRECONDITION(positions.size() == points_, "MotionPredictor::predict: one position per point");
  std::vector<Eigen::Vector3d> out(positions.begin(), positions.end());
  if (!(horizon_s > 0.0)) return out;
  const double h = std::min(horizon_s, kMaxPredictionHorizon_s);
  for (std::size_t i = 0; i < points_; ++i) out[i] += h * velocity_[i];
  return out;
}

PoseMotion::PoseMotion(int frames, double max_speed_m_s, double max_turn_rad_s)
    : origin_(1, frames, max_speed_m_s), max_turn_rad_s_(max_turn_rad_s) {}

void PoseMotion::update(double t_s, const Rigid3d& world_from_object, bool seen) {
  const bool usable =
      seen && std::isfinite(t_s) && world_from_object.translation.allFinite() && world_from_object.rotation.coeffs().allFinite();
  const std::array<Eigen::Vector3d, 1> origin{world_from_object.translation};
  origin_.update(t_s, origin, usable);
  angular_velocity_.setZero();
  if (!usable) {
    last_rotation_.reset();
    return;
  }
  const Eigen::Quaterniond q = world_from_object.rotation.normalized();
  const double dt = t_s - last_t_s_;
  if (last_rotation_ && dt > 0.0) {
    // The turn from the last orientation to this one, as a world-frame rotation vector.
    const Eigen::AngleAxisd turn(q * last_rotation_->conjugate());
    double angle = turn.angle();
    if (angle > std::numbers::pi) angle -= 2.0 * std::numbers::pi;  // the short way round
    const Eigen::Vector3d omega = turn.axis() * (angle / dt);
    if (omega.allFinite() && omega.norm() <= max_turn_rad_s_) angular_velocity_ = omega;
  }
  last_rotation_ = q;
  last_t_s_ = t_s;
}

Rigid3d PoseMotion::predict(const Rigid3d& world_from_object, double horizon_s) const {
  if (!(horizon_s > 0.0)) return world_from_object;
  const double h = std::min(horizon_s, kMaxPredictionHorizon_s);
  const std::array<Eigen::Vector3d, 1> origin{world_from_object.translation};
  Rigid3d out = world_from_object;
  // Slower than the fit's own noise (a still object's star jitters about a millimetre): still.
  if (origin_.velocity(0).norm() >= kStillSpeed_m_s) out.translation = origin_.predict(origin, h)[0];
  const double angle = angular_velocity_.norm() >= kStillTurn_rad_s ? angular_velocity_.norm() * h : 0.0;
  if (angle > 0.0)
    out.rotation = (Eigen::Quaterniond(Eigen::AngleAxisd(angle, angular_velocity_.normalized())) * out.rotation).normalized();
  return out;
}

}  // namespace rhot
