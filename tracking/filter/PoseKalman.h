#pragma once
// A rigid body's pose over time: a constant-velocity Kalman filter on position and orientation,
// fed measured poses with their covariance, that says how sure it is.
//
// State: position p and orientation q (world from body), linear velocity v and angular velocity w
// (world frame). The orientation's uncertainty is a small rotation d in the world frame, the true
// orientation being exp(d) q (an error-state filter), so the covariance is 12 x 12 over
// (p, d, v, w). Between measurements the body keeps its velocities, and unforeseen accelerations
// (white noise) make the prediction less sure the longer it runs. A measurement is a pose with
// its 6 x 6 covariance over (p, d): from a rigid fit, rigid_fit_covariance in RigidFit.h.
//
// A measurement far from the prediction (Mahalanobis distance against the sum of both
// covariances) is not the body (a wrong correspondence of its markers) or the body did what the
// model does not foresee; the caller decides which (mahalanobis2), and either updates the filter or
// starts it again (reset).

#include <limits>

#include <Eigen/Core>

#include "tracking/core/Rigid3.h"

namespace rhot {

struct PoseKalmanSettings {
  // What the body may do that the model does not foresee: white-noise accelerations of these
  // spectral densities' square roots (m s^-1.5 and rad s^-1.5), so that over a prediction of dt
  // seconds the velocity's uncertainty grows by density * sqrt(dt) (at 90 Hz by 0.53 m/s and
  // 2.1 rad/s a frame): an object carried by a hand. Larger follows quicker moves with less
  // smoothing; measured in docs/PERFORMANCE.md ("Stars that never lie").
  double acceleration_density = 5.0;
  double angular_acceleration_density = 20.0;
  // What is known of the velocities when the filter starts (one standard deviation).
  double start_speed_m_s = 1.0;
  double start_turn_rate_rad_s = 6.0;
  // A measurement whose squared Mahalanobis distance from the prediction exceeds this (6 degrees
  // of freedom: 1 in 100 by chance) is weighed as if its covariance were that much larger
  // (Huber's weighting): one fit pulled off by a merged or half-hidden marker moves the pose less.
  double robust_chi2 = 16.8;
};

class PoseKalman {
 public:
  explicit PoseKalman(PoseKalmanSettings settings = {}) : settings_(settings) {}

  // Starts again at a measured pose with its covariance, with velocities as given (their
  // uncertainty the settings' start values).
  void reset(double time_s, const Rigid3d& pose, const Matrix6d& covariance, const Eigen::Vector3d& velocity_m_s = Eigen::Vector3d::Zero(),
             const Eigen::Vector3d& angular_velocity_rad_s = Eigen::Vector3d::Zero());
  bool started() const { return started_; }

  // The pose foreseen at time_s (>= the last measurement's time) and its covariance.
  Rigid3d predict(double time_s) const;
  Matrix6d predicted_covariance(double time_s) const;
  // The squared Mahalanobis distance of a measurement from the prediction at time_s (chi-square
  // with 6 degrees of freedom when it is the body).
  double mahalanobis2(double time_s, const Rigid3d& measured, const Matrix6d& covariance) const;
  // Folds in a measurement at time_s (>= the last) unless its squared Mahalanobis distance exceeds
  // gate_chi2 (the gate and the update share one propagation and one factorisation). Non-finite
  // input is ignored.
  struct Update {
    double mahalanobis2 = std::numeric_limits<double>::infinity();  // 0 where the filter starts here
    bool applied = false;
  };
  Update update(double time_s, const Rigid3d& measured, const Matrix6d& covariance,
                double gate_chi2 = std::numeric_limits<double>::infinity());

  // The state at the last measurement.
  double time_s() const { return time_s_; }
  const Rigid3d& pose() const { return pose_; }
  const Eigen::Vector3d& velocity_m_s() const { return velocity_; }
  const Eigen::Vector3d& angular_velocity_rad_s() const { return angular_velocity_; }
  Matrix6d pose_covariance() const { return covariance_.topLeftCorner<6, 6>(); }

 private:
  using Matrix12d = Eigen::Matrix<double, 12, 12>;
  using Vector6d = Eigen::Matrix<double, 6, 1>;
  Matrix12d propagated(double dt) const;
  Vector6d residual(const Rigid3d& predicted, const Rigid3d& measured) const;

  PoseKalmanSettings settings_;
  bool started_ = false;
  double time_s_ = 0.0;
  Rigid3d pose_;
  Eigen::Vector3d velocity_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d angular_velocity_ = Eigen::Vector3d::Zero();
  Matrix12d covariance_ = Matrix12d::Identity();
};

// How far `estimate` is from `reference`: the position difference and the world-frame rotation
// vector taking reference to estimate (angle in [-pi, pi]), the space PoseKalman's covariance is in.
Eigen::Matrix<double, 6, 1> pose_error(const Rigid3d& estimate, const Rigid3d& reference);

// The largest standard deviation of a 3 x 3 covariance (the square root of its largest
// eigenvalue): how far off, along its worst direction, the estimate may be.
double largest_sigma(const Eigen::Matrix3d& covariance);

}  // namespace rhot
