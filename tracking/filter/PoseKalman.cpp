#include "tracking/filter/PoseKalman.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

namespace rhot {

namespace {

// exp of a rotation vector.
Eigen::Quaterniond exp_rotation(const Eigen::Vector3d& v) {
  const double angle = v.norm();
  return angle > 1e-12 ? Eigen::Quaterniond(Eigen::AngleAxisd(angle, v / angle)) : Eigen::Quaterniond::Identity();
}

bool finite(const Rigid3d& pose, const Matrix6d& covariance) { return pose.is_finite() && covariance.allFinite(); }

}  // namespace

void PoseKalman::reset(double time_s, const Rigid3d& pose, const Matrix6d& covariance, const Eigen::Vector3d& velocity_m_s,
                       const Eigen::Vector3d& angular_velocity_rad_s) {
  if (!finite(pose, covariance) || !velocity_m_s.allFinite() || !angular_velocity_rad_s.allFinite() || !std::isfinite(time_s)) return;
  started_ = true;
  time_s_ = time_s;
  pose_ = pose;
  pose_.rotation.normalize();
  velocity_ = velocity_m_s;
  angular_velocity_ = angular_velocity_rad_s;
  covariance_.setZero();
  covariance_.topLeftCorner<6, 6>() = 0.5 * (covariance + covariance.transpose());
  covariance_.block<3, 3>(6, 6) = Eigen::Matrix3d::Identity() * settings_.start_speed_m_s * settings_.start_speed_m_s;
  covariance_.block<3, 3>(9, 9) = Eigen::Matrix3d::Identity() * settings_.start_turn_rate_rad_s * settings_.start_turn_rate_rad_s;
}

Rigid3d PoseKalman::predict(double time_s) const {
  const double dt = std::max(0.0, time_s - time_s_);
  Rigid3d p = pose_;
  p.translation += velocity_ * dt;
  p.rotation = (exp_rotation(angular_velocity_ * dt) * p.rotation).normalized();
  return p;
}

PoseKalman::Matrix12d PoseKalman::propagated(double dt) const {
  // F = [I dt; 0 I] over (pose, velocities), six by six: F P F^T by blocks. Q: white-noise
  // acceleration, per axis q [dt^3/3, dt^2/2; dt^2/2, dt].
  const Matrix6d xx = covariance_.topLeftCorner<6, 6>(), xv = covariance_.topRightCorner<6, 6>(),
                 vv = covariance_.bottomRightCorner<6, 6>();
  Matrix12d p;
  p.topLeftCorner<6, 6>() = xx + dt * (xv + xv.transpose()) + dt * dt * vv;
  p.topRightCorner<6, 6>() = xv + dt * vv;
  p.bottomLeftCorner<6, 6>() = p.topRightCorner<6, 6>().transpose();
  p.bottomRightCorner<6, 6>() = vv;
  const double qa = settings_.acceleration_density * settings_.acceleration_density;
  const double qw = settings_.angular_acceleration_density * settings_.angular_acceleration_density;
  for (int axis = 0; axis < 6; ++axis) {
    const double q = axis < 3 ? qa : qw;
    p(axis, axis) += q * dt * dt * dt / 3.0;
    p(axis, 6 + axis) += q * dt * dt / 2.0;
    p(6 + axis, axis) += q * dt * dt / 2.0;
    p(6 + axis, 6 + axis) += q * dt;
  }
  return p;
}

Matrix6d PoseKalman::predicted_covariance(double time_s) const { return propagated(std::max(0.0, time_s - time_s_)).topLeftCorner<6, 6>(); }

Eigen::Matrix<double, 6, 1> pose_error(const Rigid3d& estimate, const Rigid3d& reference) {
  Eigen::Matrix<double, 6, 1> e;
  e.head<3>() = estimate.translation - reference.translation;
  const Eigen::AngleAxisd turn((estimate.rotation * reference.rotation.conjugate()).normalized());
  e.tail<3>() = turn.axis() * (turn.angle() > std::numbers::pi ? turn.angle() - 2.0 * std::numbers::pi : turn.angle());
  return e;
}

PoseKalman::Vector6d PoseKalman::residual(const Rigid3d& predicted, const Rigid3d& measured) const {
  return pose_error(measured, predicted);
}

double PoseKalman::mahalanobis2(double time_s, const Rigid3d& measured, const Matrix6d& covariance) const {
  if (!started_ || !finite(measured, covariance)) return std::numeric_limits<double>::infinity();
  const Vector6d r = residual(predict(time_s), measured);
  const Eigen::LDLT<Matrix6d> s(predicted_covariance(time_s) + covariance);
  if (s.info() != Eigen::Success) return std::numeric_limits<double>::infinity();
  return r.dot(s.solve(r));
}

PoseKalman::Update PoseKalman::update(double time_s, const Rigid3d& measured, const Matrix6d& covariance, double gate_chi2) {
  if (!finite(measured, covariance) || !std::isfinite(time_s)) return {};
  if (!started_) {
    reset(time_s, measured, covariance);
    return {0.0, true};
  }
  const double dt = std::max(0.0, time_s - time_s_);
  const Rigid3d predicted = predict(time_s);
  const Matrix12d p = propagated(dt);
  const Vector6d r = residual(predicted, measured);
  Matrix6d weighed = covariance;
  Eigen::LDLT<Matrix6d> ldlt(p.topLeftCorner<6, 6>() + weighed);
  if (ldlt.info() != Eigen::Success) return {};
  const double d2 = r.dot(ldlt.solve(r));
  if (d2 > gate_chi2) return {d2, false};
  if (d2 > settings_.robust_chi2) {
    weighed *= d2 / settings_.robust_chi2;
    ldlt.compute(p.topLeftCorner<6, 6>() + weighed);
    if (ldlt.info() != Eigen::Success) return {d2, false};
  }
  // K = P H^T S^-1 with H = [I 0]: P's first six columns.
  const Eigen::Matrix<double, 12, 6> k = ldlt.solve(p.leftCols<6>().transpose()).transpose();
  const Eigen::Matrix<double, 12, 1> dx = k * r;
  if (!dx.allFinite()) return {d2, false};
  pose_.translation = predicted.translation + dx.segment<3>(0);
  pose_.rotation = (exp_rotation(dx.segment<3>(3)) * predicted.rotation).normalized();
  velocity_ += dx.segment<3>(6);
  angular_velocity_ += dx.segment<3>(9);
  // P - K S K^T (K is the gain for S, so this equals the Joseph form), made symmetric again.
  const Matrix6d s = p.topLeftCorner<6, 6>() + weighed;
  covariance_ = p - k * s * k.transpose();
  covariance_ = 0.5 * (covariance_ + covariance_.transpose());
  time_s_ = std::max(time_s_, time_s);
  return {d2, true};
}

double largest_sigma(const Eigen::Matrix3d& covariance) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(covariance, Eigen::EigenvaluesOnly);
  return std::sqrt(std::max(0.0, eig.eigenvalues().maxCoeff()));
}

}  // namespace rhot
