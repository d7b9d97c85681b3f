#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "tracking/filter/PoseKalman.h"

namespace rhot {
namespace {

constexpr double kRate = 90.0;

Eigen::Quaterniond exp_rotation(const Eigen::Vector3d& v) {
  return v.norm() > 1e-12 ? Eigen::Quaterniond(Eigen::AngleAxisd(v.norm(), v.normalized())) : Eigen::Quaterniond::Identity();
}

// The pose error (estimate against truth) over (position, world-frame rotation).
Eigen::Matrix<double, 6, 1> error(const Rigid3d& estimate, const Rigid3d& truth) { return pose_error(estimate, truth); }

// A measurement of `truth` drawn from the covariance diag(sp^2 x3, sr^2 x3).
Rigid3d measure(const Rigid3d& truth, double sp, double sr, std::mt19937_64& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  Rigid3d m = truth;
  m.translation += sp * Eigen::Vector3d{g(rng), g(rng), g(rng)};
  m.rotation = (exp_rotation(sr * Eigen::Vector3d{g(rng), g(rng), g(rng)}) * truth.rotation).normalized();
  return m;
}

struct FilterRun {
  double filtered_rms_position = 0, filtered_rms_rotation = 0, measured_rms_position = 0, measured_rms_rotation = 0, nees_mean = 0;
};

// 900 frames of a body moving as `truth_at` says, measured with 1.5 mm and 3 degrees of noise per
// axis (a small star at 0.7 px); errors counted after the first half second.
template <typename Truth>
FilterRun run(Truth truth_at, unsigned seed, const PoseKalmanSettings& settings) {
  std::mt19937_64 rng(seed);
  const double sp = 0.0015, sr = 3.0 * std::numbers::pi / 180.0;
  Matrix6d r = Matrix6d::Zero();
  r.topLeftCorner<3, 3>() = Eigen::Matrix3d::Identity() * sp * sp;
  r.bottomRightCorner<3, 3>() = Eigen::Matrix3d::Identity() * sr * sr;
  PoseKalman filter(settings);
  FilterRun out;
  int n = 0;
  for (int f = 0; f < 900; ++f) {
    const double t = f / kRate;
    const Rigid3d truth = truth_at(t);
    const Rigid3d m = measure(truth, sp, sr, rng);
    filter.update(t, m, r);
    if (f < 45) continue;
    const auto e = error(filter.pose(), truth), em = error(m, truth);
    out.filtered_rms_position += e.head<3>().squaredNorm();
    out.filtered_rms_rotation += e.tail<3>().squaredNorm();
    out.measured_rms_position += em.head<3>().squaredNorm();
    out.measured_rms_rotation += em.tail<3>().squaredNorm();
    out.nees_mean += e.dot(filter.pose_covariance().ldlt().solve(e));
    ++n;
  }
  for (double* v : {&out.filtered_rms_position, &out.filtered_rms_rotation, &out.measured_rms_position, &out.measured_rms_rotation})
    *v = std::sqrt(*v / n);
  out.nees_mean /= n;
  return out;
}

TEST(PoseKalman, AConstantMotionIsFollowedWithLessNoiseThanItsMeasurementsAndAnHonestCovariance) {
  for (const unsigned seed : {1u, 2u, 3u}) {
    const auto truth_at = [](double t) {
      Rigid3d p;
      p.translation = Eigen::Vector3d(0.1, 0.2, 0.9) + t * Eigen::Vector3d(0.3, -0.1, 0.05);
      p.rotation = exp_rotation(t * Eigen::Vector3d(0.5, 1.0, -0.8)) * Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()));
      return p;
    };
    // Little unforeseen acceleration: the filter averages over many frames.
    const FilterRun r = run(truth_at, seed, PoseKalmanSettings{.acceleration_density = 0.02, .angular_acceleration_density = 1.0});
    EXPECT_LT(r.filtered_rms_position, 0.5 * r.measured_rms_position) << "seed " << seed;
    EXPECT_LT(r.filtered_rms_rotation, 0.5 * r.measured_rms_rotation) << "seed " << seed;
    // The model holds (constant velocity) and its process noise adds uncertainty the motion does not
    // use: the covariance errs on the safe side, never below the errors (NEES 6 when exact).
    EXPECT_LT(r.nees_mean, 6.5) << "seed " << seed;
    EXPECT_GT(r.nees_mean, 1.0) << "seed " << seed;
  }
}

TEST(PoseKalman, AHandsWaveWithinTheSettingsAccelerationsKeepsTheCovarianceHonest) {
  // Swinging 10 cm at 1 Hz (4 m/s^2 at the ends) and turning +-1 rad at 0.7 Hz (19 rad/s^2).
  for (const unsigned seed : {4u, 5u, 6u}) {
    const auto truth_at = [](double t) {
      Rigid3d p;
      p.translation = Eigen::Vector3d(0.0, 0.0, 1.0) + 0.1 * std::sin(2 * std::numbers::pi * t) * Eigen::Vector3d(1, 0.5, 0).normalized();
      p.rotation = exp_rotation(std::sin(2 * std::numbers::pi * 0.7 * t) * Eigen::Vector3d(0, 1, 0));
      return p;
    };
    // The defaults: an object carried by a hand.
    const FilterRun r = run(truth_at, seed, PoseKalmanSettings{});
    EXPECT_LT(r.filtered_rms_position, r.measured_rms_position) << "seed " << seed;
    EXPECT_LT(r.filtered_rms_rotation, r.measured_rms_rotation) << "seed " << seed;
    EXPECT_LT(r.nees_mean, 7.5) << "seed " << seed;
  }
}

TEST(PoseKalman, AMeasurementTwoCentimetresOffIsFarOutsideThePredictionAndTheTrueOneInside) {
  std::mt19937_64 rng(7);
  Matrix6d r = Matrix6d::Identity() * 1e-6;  // 1 mm, 1 mrad
  PoseKalman filter(PoseKalmanSettings{.acceleration_density = 0.2, .angular_acceleration_density = 1.0});
  Rigid3d truth;
  for (int f = 0; f < 90; ++f) {
    truth.translation = Eigen::Vector3d(0.2 * f / kRate, 0, 1);
    filter.update(f / kRate, measure(truth, 0.001, 0.001, rng), r);
  }
  truth.translation = Eigen::Vector3d(0.2 * 90 / kRate, 0, 1);
  const double t = 90 / kRate;
  EXPECT_LT(filter.mahalanobis2(t, measure(truth, 0.001, 0.001, rng), r), 36.0);
  Rigid3d off = truth;
  off.translation.x() += 0.02;
  EXPECT_GT(filter.mahalanobis2(t, off, r), 100.0);
  Rigid3d turned = truth;
  turned.rotation = exp_rotation(Eigen::Vector3d(0, 0, 0.3));
  EXPECT_GT(filter.mahalanobis2(t, turned, r), 100.0);

  // A gated update returns the same distance, and leaves the filter as it was where it is over.
  const double d2 = filter.mahalanobis2(t, off, r);
  const Rigid3d before = filter.pose();
  const PoseKalman::Update refused = filter.update(t, off, r, 36.0);
  EXPECT_DOUBLE_EQ(refused.mahalanobis2, d2);
  EXPECT_FALSE(refused.applied);
  EXPECT_EQ(filter.pose().translation, before.translation);
  EXPECT_LT(filter.time_s(), t);
  const Rigid3d on = measure(truth, 0.001, 0.001, rng);
  const double d2_on = filter.mahalanobis2(t, on, r);
  EXPECT_LT(d2_on, 36.0);
  const PoseKalman::Update folded = filter.update(t, on, r, 36.0);
  EXPECT_DOUBLE_EQ(folded.mahalanobis2, d2_on);
  EXPECT_TRUE(folded.applied);
  EXPECT_DOUBLE_EQ(filter.time_s(), t);
}

TEST(PoseKalman, NonFiniteInputIsIgnored) {
  PoseKalman filter;
  Rigid3d p;
  p.translation = Eigen::Vector3d(0, 0, 1);
  const Matrix6d r = Matrix6d::Identity() * 1e-6;
  filter.update(0.0, p, r);
  Rigid3d bad = p;
  bad.translation.x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(filter.update(0.1, bad, r).applied);
  Matrix6d bad_r = r;
  bad_r(0, 0) = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(filter.update(0.2, p, bad_r).applied);
  const PoseKalman::Update nan_time = filter.update(std::numeric_limits<double>::quiet_NaN(), p, r);
  EXPECT_FALSE(nan_time.applied);
  EXPECT_EQ(nan_time.mahalanobis2, std::numeric_limits<double>::infinity());
  EXPECT_TRUE(filter.pose().is_finite());
  EXPECT_TRUE(filter.pose_covariance().allFinite());
  EXPECT_DOUBLE_EQ(filter.time_s(), 0.0);
  EXPECT_EQ(filter.mahalanobis2(0.1, bad, r), std::numeric_limits<double>::infinity());
}

TEST(PoseKalman, LargestSigmaIsTheWorstDirectionsStandardDeviation) {
  Eigen::Matrix3d c = Eigen::Vector3d(1e-6, 9e-6, 4e-6).asDiagonal();
  const Eigen::Matrix3d rot = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  EXPECT_NEAR(largest_sigma(rot * c * rot.transpose()), 3e-3, 1e-12);
}

}  // namespace
}  // namespace rhot
