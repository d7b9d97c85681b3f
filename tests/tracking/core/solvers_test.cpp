#include "tracking/core/Solvers.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

namespace rhot {
namespace {

Eigen::Matrix3d random_symmetric(std::mt19937& rng, double log10_spread) {
  // R diag(values) R^T with eigenvalues over log10_spread decades and either sign.
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const Eigen::Quaterniond q = Eigen::Quaterniond{unit(rng), unit(rng), unit(rng), unit(rng)}.normalized();
  Eigen::Vector3d values;
  for (int i = 0; i < 3; ++i) {
    const double magnitude = std::pow(10.0, log10_spread * 0.5 * (unit(rng) + 1.0));
    values(i) = unit(rng) < -0.8 ? -magnitude : magnitude;
  }
  const Eigen::Matrix3d r = q.toRotationMatrix();
  return r * values.asDiagonal() * r.transpose();
}

// The closed form agrees with the iterative solver (ascending, each eigenvalue to 1e-10 of the
// largest) over random matrices whose eigenvalues span up to six decades, and to 1e-7 where two
// eigenvalues are (nearly) equal: a double root of the cubic is found to about the square root of
// the machine epsilon. The Matrix3d and packed forms give the same values.
TEST(SymmetricEigenvaluesDirect, AgreeWithTheIterativeSolver) {
  std::mt19937 rng(7);
  for (int n = 0; n < 2000; ++n) {
    const Eigen::Matrix3d m = random_symmetric(rng, n % 7);
    const Eigen::Vector3d expected = symmetric_eigenvalues(m);
    const Eigen::Vector3d direct = symmetric_eigenvalues_direct(m);
    const std::array<double, 3> packed = symmetric_eigenvalues_packed({m(0, 0), m(0, 1), m(0, 2), m(1, 1), m(1, 2), m(2, 2)});
    const double largest = expected.cwiseAbs().maxCoeff();
    const double gap = std::min(expected(1) - expected(0), expected(2) - expected(1));
    const double tolerance = (gap > 1e-3 * largest ? 1e-10 : 1e-7) * largest;
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(direct(i), expected(i), tolerance) << n << " " << i << "\n" << m;
      EXPECT_EQ(packed[static_cast<std::size_t>(i)], direct(i));
    }
  }
}

TEST(SymmetricEigenvaluesDirect, RepeatedAndDegenerateEigenvalues) {
  const std::array<double, 3> identity = symmetric_eigenvalues_packed({2.5, 0, 0, 2.5, 0, 2.5});
  EXPECT_EQ(identity, (std::array<double, 3>{2.5, 2.5, 2.5}));
  const std::array<double, 3> zero = symmetric_eigenvalues_packed({0, 0, 0, 0, 0, 0});
  EXPECT_EQ(zero, (std::array<double, 3>{0, 0, 0}));
  // Rank one (parallel rays in the planner): two zero eigenvalues, the third the trace.
  const Eigen::Vector3d d = Eigen::Vector3d(1, 2, 3).normalized();
  const Eigen::Matrix3d rank_one = 4.0 * d * d.transpose();
  const Eigen::Vector3d v = symmetric_eigenvalues_direct(rank_one);
  EXPECT_NEAR(v(0), 0.0, 1e-7);  // a double root again
  EXPECT_NEAR(v(1), 0.0, 1e-7);
  EXPECT_NEAR(v(2), 4.0, 1e-12);
  // A double eigenvalue: diag(1, 3, 3) rotated.
  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, -1, 2).normalized()).toRotationMatrix();
  const Eigen::Vector3d pair = symmetric_eigenvalues_direct(Eigen::Matrix3d(r * Eigen::Vector3d(1, 3, 3).asDiagonal() * r.transpose()));
  EXPECT_NEAR(pair(0), 1.0, 1e-12);
  EXPECT_NEAR(pair(1), 3.0, 1e-7);  // a double root of the cubic: sqrt(eps) accuracy
  EXPECT_NEAR(pair(2), 3.0, 1e-7);
}

TEST(SymmetricEigenvaluesDirect, NaNOrInfinityInGivesNaNOut) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const std::array<double, 6>& m : {std::array<double, 6>{1, nan, 0, 1, 0, 1}, std::array<double, 6>{nan, 0, 0, 1, 0, 1},
                                         std::array<double, 6>{1, 0, 0, 1, std::numeric_limits<double>::infinity(), 1}}) {
    for (const double x : symmetric_eigenvalues_packed(m)) EXPECT_TRUE(std::isnan(x));
  }
}

// rotation_between is Eigen's FromTwoVectors: it takes the first direction onto the second, for
// any lengths, for the same and for opposite directions (a half turn), and is a unit quaternion.
TEST(RotationBetween, TakesTheFirstDirectionOntoTheSecond) {
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  const auto random_vector = [&] { return Eigen::Vector3d{normal(rng), normal(rng), normal(rng)}; };
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d from = random_vector(), to = 3.0 * random_vector();
    const Eigen::Quaterniond q = rotation_between(from, to);
    EXPECT_NEAR(q.norm(), 1.0, 1e-12);
    EXPECT_LT((q * from.normalized() - to.normalized()).norm(), 1e-12) << i;
  }
  const Eigen::Vector3d a(0.3, -1.2, 0.5);
  EXPECT_LT(rotation_between(a, 2.0 * a).angularDistance(Eigen::Quaterniond::Identity()), 1e-12);
  const Eigen::Quaterniond half = rotation_between(a, -a);
  EXPECT_NEAR(half.angularDistance(Eigen::Quaterniond::Identity()), std::numbers::pi, 1e-9);
  EXPECT_LT((half * a + a).norm(), 1e-12);
}

// Points and a rotation from standard normal draws (braced lists: drawn left to right).
Eigen::Matrix3Xd normal_points(std::mt19937& rng, Eigen::Index count) {
  std::normal_distribution<double> normal;
  Eigen::Matrix3Xd points(3, count);
  for (Eigen::Index i = 0; i < count; ++i) points.col(i) = Eigen::Vector3d{normal(rng), normal(rng), normal(rng)};
  return points;
}

Eigen::Quaterniond normal_rotation(std::mt19937& rng) {
  std::normal_distribution<double> normal;
  return Eigen::Quaterniond{normal(rng), normal(rng), normal(rng), normal(rng)}.normalized();
}

// umeyama_transform is Umeyama's fit: a rigid motion (and a scale, when asked) of points comes
// back exactly.
TEST(UmeyamaTransform, GivesBackTheMotionThatMovedThePoints) {
  std::mt19937 rng(11);
  const Eigen::Matrix3Xd from = normal_points(rng, 6);
  const Eigen::Quaterniond q = normal_rotation(rng);
  const Eigen::Vector3d t(0.4, -2.0, 1.5);
  for (const double scale : {1.0, 2.5}) {
    const Eigen::Matrix3Xd to = ((scale * q.toRotationMatrix()) * from).colwise() + t;
    const Eigen::Matrix4d m = umeyama_transform(from, to, scale != 1.0);
    EXPECT_LT((m.topLeftCorner<3, 3>() - scale * q.toRotationMatrix()).norm(), 1e-10) << scale;
    EXPECT_LT((m.topRightCorner<3, 1>() - t).norm(), 1e-10) << scale;
  }
}

// Where no motion fits exactly (noisy points, and points mirrored, for which the best orthogonal
// fit is a reflection), it is Eigen::umeyama's least-squares fit to rounding, and a rotation.
TEST(UmeyamaTransform, IsEigensFitToRoundingForNoisyAndMirroredPoints) {
  std::mt19937 rng(12);
  const Eigen::Matrix3Xd from = normal_points(rng, 9);
  const Eigen::Quaterniond q = normal_rotation(rng);
  const Eigen::Matrix3Xd noisy =
      ((1.7 * q.toRotationMatrix()) * from).colwise() + Eigen::Vector3d(1.0, 0.5, -3.0) + 0.2 * normal_points(rng, from.cols());
  const Eigen::Matrix3Xd mirrored = Eigen::Vector3d(-1.0, 1.0, 1.0).asDiagonal() * from;
  for (const Eigen::Matrix3Xd* to : {&noisy, &mirrored}) {
    for (const bool with_scale : {false, true}) {
      const Eigen::Matrix4d m = umeyama_transform(from, *to, with_scale);
      const Eigen::Matrix4d eigen = Eigen::umeyama(from, *to, with_scale);
      EXPECT_LT((m - eigen).norm(), 1e-12) << "mirrored " << (to == &mirrored) << ", scale " << with_scale << "\n" << m << "\n" << eigen;
      const Eigen::Matrix3d r = m.topLeftCorner<3, 3>() / std::cbrt(m.topLeftCorner<3, 3>().determinant());
      EXPECT_LT((r.transpose() * r - Eigen::Matrix3d::Identity()).norm(), 1e-12);
      EXPECT_GT((m.topLeftCorner<3, 3>().determinant()), 0.0);
    }
  }
}

}  // namespace
}  // namespace rhot
