#include "tracking/camera/Camera.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>

namespace rhot {
namespace {

Camera wide_camera() {
  Camera c;
  c.name = "test";
  c.intrinsics = {1280, 720, 910.0, 905.0, 641.0, 358.0, {-0.21, 0.08, 0.001, -0.0015, -0.012}};
  c.cam_from_world = cam_from_world_look_at({0.5, 1.8, 0.4}, {0.0, 1.0, -0.5});
  return c;
}

TEST(Camera, ProjectionMatchesOpenCv) {
  const Camera c = wide_camera();
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-0.4, 0.4);
  const Eigen::Matrix3d r = c.cam_from_world.rotation.toRotationMatrix();
  cv::Mat rvec;
  cv::Rodrigues(cv::Matx33d(r(0, 0), r(0, 1), r(0, 2), r(1, 0), r(1, 1), r(1, 2), r(2, 0), r(2, 1), r(2, 2)), rvec);
  const cv::Vec3d tvec(c.cam_from_world.translation.x(), c.cam_from_world.translation.y(), c.cam_from_world.translation.z());
  const cv::Matx33d k(c.intrinsics.fx, 0, c.intrinsics.cx, 0, c.intrinsics.fy, c.intrinsics.cy, 0, 0, 1);
  const cv::Vec<double, 5> d(c.intrinsics.distortion.data());
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d p{u(rng), 1.0 + u(rng), -0.5 + u(rng)};
    std::vector<cv::Point2d> expected;
    cv::projectPoints(std::vector<cv::Point3d>{{p.x(), p.y(), p.z()}}, rvec, tvec, k, d, expected);
    const auto pixel = c.project(p);
    ASSERT_TRUE(pixel.has_value());
    EXPECT_NEAR(pixel->x(), expected[0].x, 1e-7);
    EXPECT_NEAR(pixel->y(), expected[0].y, 1e-7);
  }
}

TEST(Camera, JacobianMatchesFiniteDifferences) {
  const Camera c = wide_camera();
  const Eigen::Vector3d p(0.1, 1.1, -0.3);
  Eigen::Matrix<double, 2, 3> j;
  ASSERT_TRUE(c.project(p, j).has_value());
  for (int a = 0; a < 3; ++a) {
    Eigen::Vector3d h = Eigen::Vector3d::Zero();
    h(a) = 1e-6;
    const Eigen::Vector2d numeric = (*c.project(p + h) - *c.project(p - h)) / 2e-6;
    EXPECT_NEAR((numeric - j.col(a)).norm(), 0.0, 1e-3) << "column " << a;
  }
}

TEST(Camera, UndistortInvertsProjection) {
  const Camera c = wide_camera();
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(0, 1, -0.5), Eigen::Vector3d(0.2, 0.9, -0.4), Eigen::Vector3d(-0.3, 1.2, -0.8)}) {
    const auto pixel = c.project(p);
    ASSERT_TRUE(pixel.has_value());
    ASSERT_TRUE(c.in_image(*pixel));
    // The ray through the pixel passes through the point.
    const Eigen::Vector3d o = c.centre_world();
    const Eigen::Vector3d d = c.ray_world(*pixel);
    EXPECT_NEAR(d.norm(), 1.0, 1e-12);
    EXPECT_LT(((p - o) - (p - o).dot(d) * d).norm(), 1e-9);
  }
}

TEST(Camera, NewtonUndistortionAgreesWithOpenCvOverTheWholeImage) {
  // The wide lens above and the shipped rigs' lenses: every 8th pixel of the image, undistorted
  // both ways, agree to 1e-10 (normalised), and distorting the answer gives the pixel back.
  for (const CameraIntrinsics& k :
       {wide_camera().intrinsics, CameraIntrinsics{1280, 720, 700.0, 700.0, 639.5, 359.5, {-0.08, 0.015, 0, 0, 0}},
        CameraIntrinsics{640, 480, 630.0, 630.0, 319.5, 239.5, {0.02, -0.04, 0, 0, 0}}}) {
    const cv::Matx33d m(k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1);
    const cv::Vec<double, 5> d(k.distortion.data());
    int compared = 0;
    for (int y = 0; y < k.height_px; y += 8) {
      for (int x = 0; x < k.width_px; x += 8) {
        std::vector<cv::Point2d> out;
        cv::undistortPoints(std::vector<cv::Point2d>{{double(x), double(y)}}, out, m, d, cv::noArray(), cv::noArray(),
                            cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 200, 1e-15));
        const Eigen::Vector2d distorted((x - k.cx) / k.fx, (y - k.cy) / k.fy);
        const auto mine = undistort_normalised(k.distortion, distorted);
        ASSERT_TRUE(mine.has_value()) << x << ", " << y;
        EXPECT_NEAR(mine->x(), out[0].x, 1e-10) << x << ", " << y;
        EXPECT_NEAR(mine->y(), out[0].y, 1e-10) << x << ", " << y;
        EXPECT_LT((distort_normalised(k.distortion, *mine) - distorted).norm(), 1e-13);
        ++compared;
      }
    }
    EXPECT_GT(compared, 4000);
  }
}

TEST(Camera, NewtonUndistortionRefusesWhereTheModelFoldsOver) {
  // Strong barrel distortion folds over beyond r^2 = 1 / (3 |k1|): no answer there, and none for
  // non-finite input, rather than a wrong one.
  const std::array<double, 5> k{-0.6, 0.0, 0.0, 0.0, 0.0};
  EXPECT_FALSE(undistort_normalised(k, Eigen::Vector2d(0.9, 0.0)).has_value());
  EXPECT_FALSE(undistort_normalised(k, Eigen::Vector2d(std::nan(""), 0.0)).has_value());
  const auto inside = undistort_normalised(k, Eigen::Vector2d(0.2, 0.1));
  ASSERT_TRUE(inside.has_value());
  EXPECT_LT((distort_normalised(k, *inside) - Eigen::Vector2d(0.2, 0.1)).norm(), 1e-13);
}

TEST(Camera, BehindTheCameraDoesNotProject) {
  const Camera c = wide_camera();
  EXPECT_FALSE(c.project(c.centre_world() - (c.cam_from_world.rotation.conjugate() * Eigen::Vector3d::UnitZ())).has_value());
  EXPECT_FALSE(c.in_image({-1.0, 10.0}));
  EXPECT_FALSE(c.in_image({10.0, 719.6}));
  EXPECT_TRUE(c.in_image({-0.4, 719.4}));
}

TEST(Camera, LookAtPointsTheOpticalAxisAtTheTarget) {
  const Rigid3d cam_from_world = cam_from_world_look_at({1, 2, 3}, {0, 1, -1});
  const Eigen::Vector3d target_cam = cam_from_world * Eigen::Vector3d(0, 1, -1);
  EXPECT_NEAR(target_cam.x(), 0.0, 1e-12);
  EXPECT_NEAR(target_cam.y(), 0.0, 1e-12);
  EXPECT_GT(target_cam.z(), 0.0);
  // World up appears toward the top of the image (negative image y).
  EXPECT_LT((cam_from_world * Eigen::Vector3d(0, 2, -1)).y(), 0.0);
}

// Straight down, where world up is along the optical axis: world +Z is up in the image instead.
TEST(Camera, LookAtStraightDownKeepsAnUpright) {
  const Rigid3d cam_from_world = cam_from_world_look_at({1, 5, 2}, {1, 0, 2});
  ASSERT_TRUE(cam_from_world.rotation.coeffs().allFinite());
  const Eigen::Vector3d floor_cam = cam_from_world * Eigen::Vector3d(1, 0, 2);
  EXPECT_NEAR(floor_cam.x(), 0.0, 1e-12);
  EXPECT_NEAR(floor_cam.y(), 0.0, 1e-12);
  EXPECT_NEAR(floor_cam.z(), 5.0, 1e-12);
  EXPECT_NEAR((cam_from_world * Eigen::Vector3d(1, 0, 3)).y(), -1.0, 1e-12);
}

}  // namespace
}  // namespace rhot
