#pragma once
// Smoothing for tracked positions and poses.
//
// The 1-euro filter (Casiez, Roussel, Vogel, CHI 2012): a low-pass filter whose cutoff rises with
// speed, so a still hand does not jitter and a moving one does not lag. Per sample:
//   dx = (x - x_prev_filtered) / dt, smoothed at d_cutoff;
//   cutoff = min_cutoff + beta * |dx|;  x_filtered = x_prev_filtered + alpha(cutoff) (x - x_prev_filtered),
//   alpha(fc) = 1 / (1 + 1 / (2 pi fc dt)).
// Defaults are for positions in metres at 90 Hz: min_cutoff 1 Hz keeps 0.3 mm of jitter under
// 0.1 mm when still; beta 20 s/m raises the cutoff to 11 Hz at 0.5 m/s; d_cutoff 1 Hz.
//
// And seed 000's 5-point moving average as the plain alternative.
//
// Non-finite samples are ignored (the last output is returned, the state is kept), and a sample
// whose time does not advance replaces nothing: a bad frame cannot poison the filter.

#include <array>
#include <cmath>
#include <numbers>
#include <optional>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "tracking/core/Rigid3.h"

namespace rhot {

struct OneEuroSettings {
  double min_cutoff_hz = 1.0;
  double beta = 20.0;  // per (unit per second) of speed
  double d_cutoff_hz = 1.0;
};

inline double one_euro_alpha(double cutoff_hz, double dt_s) {
  const double tau = 1.0 / (2.0 * std::numbers::pi * cutoff_hz);
  return 1.0 / (1.0 + tau / dt_s);
}

template <int N>
class OneEuroFilter {
 public:
  using Vector = Eigen::Matrix<double, N, 1>;

  explicit OneEuroFilter(OneEuroSettings settings = {}) : settings_(settings) {}

  Vector filter(const Vector& x, double time_s) {
    if (!x.allFinite() || !std::isfinite(time_s)) return last_.value_or(Vector::Zero());
    if (!last_) {
      last_ = x;
      derivative_.setZero();
      time_s_ = time_s;
      return x;
    }
    const double dt = time_s - time_s_;
    if (!(dt > 0.0)) return *last_;
    const Vector dx = (x - *last_) / dt;
    derivative_ += one_euro_alpha(settings_.d_cutoff_hz, dt) * (dx - derivative_);
    const double cutoff = settings_.min_cutoff_hz + settings_.beta * derivative_.norm();
    *last_ += one_euro_alpha(cutoff, dt) * (x - *last_);
    time_s_ = time_s;
    return *last_;
  }
  void reset() { last_.reset(); }
  const std::optional<Vector>& last() const { return last_; }

 private:
  OneEuroSettings settings_;
  std::optional<Vector> last_;
  Vector derivative_ = Vector::Zero();
  double time_s_ = 0.0;
};

// A rigid pose: the translation through a 1-euro filter, the rotation slerped toward each sample
// by the alpha its angular speed calls for (beta per radian per second; defaults min 1 Hz, beta 2).
class PoseFilter {
 public:
  explicit PoseFilter(OneEuroSettings translation = {}, OneEuroSettings rotation = {1.0, 2.0, 1.0})
      : translation_(translation), rotation_settings_(rotation) {}

  Rigid3d filter(const Rigid3d& pose, double time_s);
  // When the last sample it took was (none before the first, or after reset()).
  std::optional<double> last_sample_s() const { return rotation_ ? std::optional<double>(time_s_) : std::nullopt; }
  void reset() {
    translation_.reset();
    rotation_.reset();
  }

 private:
  OneEuroFilter<3> translation_;
  OneEuroSettings rotation_settings_;
  std::optional<Eigen::Quaterniond> rotation_;
  double angular_speed_ = 0.0;
  double time_s_ = 0.0;
};

// The mean of the last `kWindow` samples (fewer at the start). Non-finite samples are ignored.
template <int N, int kWindow = 5>
class MovingAverage {
 public:
  using Vector = Eigen::Matrix<double, N, 1>;

  Vector filter(const Vector& x) {
    if (x.allFinite()) {
      samples_[static_cast<std::size_t>(next_ % kWindow)] = x;
      ++next_;
    }
    const int count = std::min(next_, kWindow);
    if (count == 0) return Vector::Zero();
    Vector sum = Vector::Zero();
    for (int i = 0; i < count; ++i) sum += samples_[static_cast<std::size_t>(i)];
    return sum / static_cast<double>(count);
  }
  void reset() { next_ = 0; }

 private:
  std::array<Vector, kWindow> samples_{};
  int next_ = 0;
};

}  // namespace rhot
