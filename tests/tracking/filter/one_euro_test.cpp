#include "tracking/filter/OneEuroFilter.h"

#include <random>

#include <gtest/gtest.h>

namespace rhot {
namespace {

TEST(OneEuroFilter, AConstantInputStaysConstant) {
  OneEuroFilter<3> f;
  const Eigen::Vector3d x(0.1, 1.2, -0.4);
  for (int i = 0; i < 200; ++i) EXPECT_EQ(f.filter(x, i / 90.0), x) << i;
}

TEST(OneEuroFilter, AStepConvergesAndFasterWithMoreBeta) {
  OneEuroFilter<1> slow({1.0, 0.0, 1.0});
  OneEuroFilter<1> fast({1.0, 50.0, 1.0});
  Eigen::Matrix<double, 1, 1> zero(0.0), step(0.05);
  slow.filter(zero, 0.0);
  fast.filter(zero, 0.0);
  double slow_at_50ms = 0, fast_at_50ms = 0;
  double previous = 0.0;
  for (int i = 1; i <= 180; ++i) {
    const double t = i / 90.0;
    const double s = slow.filter(step, t)(0);
    const double q = fast.filter(step, t)(0);
    EXPECT_GE(s, previous) << "no overshoot, no ringing";
    EXPECT_LE(s, 0.05);
    previous = s;
    if (i == 5) {
      slow_at_50ms = s;
      fast_at_50ms = q;
    }
  }
  EXPECT_NEAR(previous, 0.05, 0.05 * 1e-4) << "within 0.01 % after 2 s";
  // With beta 0 it is a plain 1 Hz low-pass: 1 - (1 - alpha)^5 of the step after 5 samples.
  const double alpha = one_euro_alpha(1.0, 1.0 / 90.0);
  EXPECT_NEAR(slow_at_50ms, 0.05 * (1.0 - std::pow(1.0 - alpha, 5)), 1e-12);
  EXPECT_GT(fast_at_50ms, 2.0 * slow_at_50ms) << "speed raises the cutoff";
}

TEST(OneEuroFilter, StillJitterIsCutToAThird) {
  OneEuroFilter<3> f;
  std::mt19937_64 rng(1);
  std::normal_distribution<double> noise(0.0, 0.0003);
  double sum2 = 0.0;
  int n = 0;
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector3d out = f.filter(Eigen::Vector3d{noise(rng), noise(rng), noise(rng)}, i / 90.0);
    if (i < 200) continue;
    sum2 += out.squaredNorm() / 3.0;
    ++n;
  }
  EXPECT_LT(std::sqrt(sum2 / n), 0.0001) << "0.3 mm of jitter per axis becomes under 0.1 mm";
}

TEST(OneEuroFilter, BadSamplesChangeNothing) {
  OneEuroFilter<3> f;
  const Eigen::Vector3d x(1, 2, 3);
  f.filter(x, 0.0);
  EXPECT_EQ(f.filter(Eigen::Vector3d(std::nan(""), 0, 0), 0.1), x);
  EXPECT_EQ(f.filter(Eigen::Vector3d(std::numeric_limits<double>::infinity(), 0, 0), 0.2), x);
  EXPECT_EQ(f.filter(Eigen::Vector3d(5, 5, 5), 0.0), x) << "time did not advance";
  EXPECT_EQ(f.filter(x, 0.3), x);
  OneEuroFilter<3> empty;
  EXPECT_TRUE(empty.filter(Eigen::Vector3d(std::nan(""), 0, 0), 0.0).allFinite());
}

TEST(PoseFilter, ConstantPoseStaysAndARotationStepConverges) {
  PoseFilter f;
  Rigid3d a;
  a.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()));
  a.translation = {0.1, 1.0, -0.3};
  for (int i = 0; i < 20; ++i) {
    const Rigid3d out = f.filter(a, i / 90.0);
    EXPECT_LT(out.rotation.angularDistance(a.rotation), 1e-12);
    EXPECT_EQ(out.translation, a.translation);
  }
  Rigid3d b = a;
  b.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(1.3, Eigen::Vector3d::UnitY()));
  Rigid3d out;
  for (int i = 20; i < 200; ++i) out = f.filter(b, i / 90.0);
  EXPECT_LT(out.rotation.angularDistance(b.rotation), 1e-3);
  Rigid3d bad = b;
  bad.rotation.coeffs().setConstant(std::nan(""));
  EXPECT_TRUE(f.filter(bad, 3.0).is_finite());
}

// The filter keeps the time of its last sample (HandTracker starts it afresh after a gap from it),
// so that a copy of the filter, put back, has its clock with it.
TEST(PoseFilter, KnowsWhenItLastTookASample) {
  PoseFilter f;
  EXPECT_FALSE(f.last_sample_s().has_value());
  f.filter(Rigid3d{}, 1.0);
  f.filter(Rigid3d{}, 1.5);
  EXPECT_EQ(f.last_sample_s(), 1.5);
  Rigid3d bad;
  bad.rotation.coeffs().setConstant(std::nan(""));
  f.filter(bad, 2.0);
  EXPECT_EQ(f.last_sample_s(), 1.5) << "a bad sample is not taken";
  const PoseFilter saved = f;
  f.filter(Rigid3d{}, 2.5);
  f = saved;
  EXPECT_EQ(f.last_sample_s(), 1.5);
  f.reset();
  EXPECT_FALSE(f.last_sample_s().has_value());
}

TEST(MovingAverage, MeansTheLastFiveSamples) {
  MovingAverage<1> m;
  using V = Eigen::Matrix<double, 1, 1>;
  EXPECT_EQ(m.filter(V(1.0))(0), 1.0);
  EXPECT_EQ(m.filter(V(3.0))(0), 2.0);
  for (double v : {5.0, 7.0, 9.0}) m.filter(V(v));
  EXPECT_EQ(m.filter(V(11.0))(0), (3.0 + 5 + 7 + 9 + 11) / 5);
  EXPECT_EQ(m.filter(V(std::nan("")))(0), (3.0 + 5 + 7 + 9 + 11) / 5) << "a NaN sample is skipped";
}

}  // namespace
}  // namespace rhot
