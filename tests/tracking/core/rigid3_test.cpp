#include "tracking/core/Rigid3.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

namespace rhot {
namespace {

Rigid3d example() {
  Rigid3d t;
  t.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()));
  t.translation = {0.1, -0.2, 0.3};
  return t;
}

TEST(Rigid3d, InverseUndoesTheTransform) {
  const Rigid3d cam_from_world = example();
  const Eigen::Vector3d p_world(0.5, 1.0, -2.0);
  const Eigen::Vector3d p_cam = cam_from_world * p_world;
  EXPECT_LT((cam_from_world.inverse() * p_cam - p_world).norm(), 1e-12);
}

TEST(Rigid3d, CompositionMatchesMatrixProduct) {
  const Rigid3d c_from_b = example();
  Rigid3d b_from_a;
  b_from_a.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(-1.2, Eigen::Vector3d::UnitY()));
  b_from_a.translation = {2, 0, -1};
  const Eigen::Matrix4d expected = c_from_b.matrix() * b_from_a.matrix();
  EXPECT_LT(((c_from_b * b_from_a).matrix() - expected).norm(), 1e-12);
}

TEST(Rigid3d, NonFiniteIsDetected) {
  Rigid3d t = example();
  EXPECT_TRUE(t.is_finite());
  t.translation.y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(t.is_finite());
  t = example();
  t.rotation.w() = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(t.is_finite());
}

}  // namespace
}  // namespace rhot
