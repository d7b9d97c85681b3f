// Rendered board pictures against the camera model they were rendered with: OpenCV finds the
// corners where the model projects them.

#include "tracking/media/Media.h"
#include "tracking/sim/BoardImages.h"

#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "tracking/calib/CalibPictures.h"
#include "tracking/calib/Intrinsics.h"

namespace rhot {
namespace {

namespace fs = std::filesystem;

fs::path board_dir() {
  const fs::path d = fs::path(::testing::TempDir()) / "rhot_board_images" / ::testing::UnitTest::GetInstance()->current_test_info()->name();
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

CameraIntrinsics camera(int width, int height) {
  CameraIntrinsics k;
  k.width_px = width;
  k.height_px = height;
  k.fx = 0.8 * width;
  k.fy = 0.8 * width;
  k.cx = 0.5 * width + 3.2;
  k.cy = 0.5 * height - 2.1;
  k.distortion = {-0.2, 0.08, 0.001, -0.0007, 0.0};
  return k;
}

BoardLayout chess(int cols, int rows, double square_m) {
  BoardLayout layout;
  layout.cols = cols;
  layout.rows = rows;
  layout.spacing_m = square_m;
  return layout;
}

std::optional<Eigen::Vector2d> project(const CameraIntrinsics& k, const Rigid3d& camera_from_board, const Eigen::Vector3d& p_board) {
  return Camera{"c", k, camera_from_board}.project(p_board);
}

bool in_image(const CameraIntrinsics& k, const Eigen::Vector2d& pixel) { return Camera{"c", k, Rigid3d::identity()}.in_image(pixel); }

TEST(BoardImages, OpenCvFindsTheCornersWhereTheModelProjectsThem) {
  const fs::path dir = board_dir();
  const CameraIntrinsics k = camera(1024, 768);
  const BoardLayout layout = chess(9, 6, 0.025);
  const std::vector<Rigid3d> poses = board_poses(k, layout, 4, 3);
  ASSERT_EQ(poses.size(), 4u);
  const BoardSpec spec = *parse_board_spec("chess:9x6:25");
  const std::vector<Eigen::Vector3d> truth_board = board_points_m(layout);
  double worst_px = 0.0, sum_sq = 0.0;
  int count = 0;
  for (std::size_t v = 0; v < poses.size(); ++v) {
    const fs::path file = dir / ("b" + std::to_string(v) + ".png");
    ASSERT_TRUE(rhot::write_image(file.string(), render_board(k, poses[v], layout)).has_value());
    const auto view = detect_board(file, spec);
    ASSERT_TRUE(view.has_value()) << view.error();
    ASSERT_EQ(view->corners_px.size(), 54u) << "view " << v;
    for (const Eigen::Vector2d& corner : view->corners_px) {
      // The detector may number a board from either end; compare with the nearest true corner.
      double nearest = 1e300;
      for (const Eigen::Vector3d& p : truth_board) nearest = std::min(nearest, (*project(k, poses[v], p) - corner).norm());
      worst_px = std::max(worst_px, nearest);
      sum_sq += nearest * nearest;
      ++count;
    }
  }
  std::printf("corner error: rms %.4f px, worst %.4f px over %d corners\n", std::sqrt(sum_sq / count), worst_px, count);
  EXPECT_LT(worst_px, 0.1);
  EXPECT_LT(std::sqrt(sum_sq / count), 0.05);
}

TEST(BoardImages, PixelsShowTheBoardThroughTheDistortion) {
  const CameraIntrinsics k = camera(640, 480);
  const BoardLayout layout = chess(5, 4, 0.04);
  // Tilted and off to the side, where the distortion moves pixels most.
  Rigid3d camera_from_board;
  camera_from_board.rotation = Eigen::AngleAxisd(0.5, Eigen::Vector3d(0.6, 0.8, 0.0));
  camera_from_board.translation = Eigen::Vector3d(0.05, 0.0, 0.6);
  BoardRenderSettings settings;
  const cv::Mat image = render_board(k, camera_from_board, layout, settings);
  ASSERT_EQ(image.cols, 640);
  ASSERT_EQ(image.rows, 480);
  ASSERT_EQ(image.type(), CV_8UC1);
  const auto grey_at = [&](const Eigen::Vector3d& p_board) {
    const Eigen::Vector2d pixel = *project(k, camera_from_board, p_board);
    EXPECT_TRUE(in_image(k, pixel)) << p_board.transpose();
    if (!in_image(k, pixel)) return std::uint8_t{0};
    return image.at<std::uint8_t>(static_cast<int>(std::lround(pixel.y())), static_cast<int>(std::lround(pixel.x())));
  };
  // Square centres: (-1, -1) is black, its neighbours white; the margin is white.
  EXPECT_EQ(grey_at({-0.02, -0.02, 0}), 25);
  EXPECT_EQ(grey_at({0.02, -0.02, 0}), 225);
  EXPECT_EQ(grey_at({0.02, 0.02, 0}), 25);
  EXPECT_EQ(grey_at({0.18, 0.14, 0}), 225) << "the far corner square (4, 3)";
  EXPECT_EQ(grey_at({-0.06, 0.05, 0}), 225) << "margin";
  EXPECT_EQ(grey_at({-0.12, 0.05, 0}), 110) << "beyond the board: background";
  // An edge pixel is a blend.
  const Eigen::Vector2d edge = *project(k, camera_from_board, {0.0, 0.06, 0});
  const int x = static_cast<int>(std::lround(edge.x())), y = static_cast<int>(std::lround(edge.y()));
  EXPECT_GT(image.at<std::uint8_t>(y, x), 25);
  EXPECT_LT(image.at<std::uint8_t>(y, x), 225);
}

TEST(BoardImages, PosesKeepTheWholeBoardInViewAndVaryTiltAndPlace) {
  const CameraIntrinsics k = camera(1280, 720);
  const BoardLayout layout = chess(9, 6, 0.025);
  const std::vector<Rigid3d> poses = board_poses(k, layout, 15, 1);
  ASSERT_EQ(poses.size(), 15u);
  const auto [lo, hi] = board_extent_m(layout);
  std::vector<Eigen::Vector2d> corners;
  double min_tilt = 1e9, max_tilt = 0.0;
  for (const Rigid3d& pose : poses) {
    for (const Eigen::Vector3d& p : {Eigen::Vector3d(lo.x(), lo.y(), 0), Eigen::Vector3d(hi.x(), lo.y(), 0),
                                     Eigen::Vector3d(lo.x(), hi.y(), 0), Eigen::Vector3d(hi.x(), hi.y(), 0)}) {
      const auto pixel = project(k, pose, p);
      ASSERT_TRUE(pixel.has_value());
      EXPECT_TRUE(in_image(k, *pixel)) << pixel->transpose();
    }
    for (const Eigen::Vector3d& p : board_points_m(layout)) corners.push_back(*project(k, pose, p));
    const double tilt = std::acos(std::abs((pose.rotation * Eigen::Vector3d::UnitZ()).z())) * 180.0 / std::numbers::pi;
    min_tilt = std::min(min_tilt, tilt);
    max_tilt = std::max(max_tilt, tilt);
  }
  EXPECT_GE(min_tilt, 9.9);
  EXPECT_LE(max_tilt, 45.1);
  EXPECT_GT(max_tilt - min_tilt, 20.0);
  EXPECT_GT(image_coverage(k.width_px, k.height_px, corners), 0.55) << "the boards together cover most of the image";
  // The same seed, the same poses; another seed, others.
  const std::vector<Rigid3d> again = board_poses(k, layout, 15, 1);
  const std::vector<Rigid3d> other = board_poses(k, layout, 15, 2);
  EXPECT_TRUE(again[7].translation == poses[7].translation);
  EXPECT_FALSE(other[7].translation == poses[7].translation);
  // Nothing asked, or no camera to fit the board in: no poses.
  EXPECT_TRUE(board_poses(k, layout, 0, 1).empty());
  EXPECT_TRUE(board_poses(CameraIntrinsics{}, layout, 5, 1).empty());
}

TEST(BoardImages, NoiseAndBlurAreSeededAndChecked) {
  const CameraIntrinsics k = camera(320, 240);
  const BoardLayout layout = chess(4, 3, 0.03);
  const Rigid3d pose = board_poses(k, layout, 1, 5).at(0);
  BoardRenderSettings settings;
  settings.noise_sigma = 3.0;
  settings.blur_sigma_px = 1.0;
  settings.seed = 9;
  const cv::Mat a = render_board(k, pose, layout, settings);
  const cv::Mat b = render_board(k, pose, layout, settings);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  settings.seed = 10;
  const cv::Mat c = render_board(k, pose, layout, settings);
  EXPECT_GT(cv::norm(a, c, cv::NORM_INF), 0.0);
  // The background far from the board: its spread is the noise's.
  // The noise: the difference from the same picture without it (rounding adds 1/12 grey level^2).
  BoardRenderSettings quiet = settings;
  quiet.noise_sigma = 0.0;
  cv::Mat difference;
  cv::subtract(a, render_board(k, pose, layout, quiet), difference, cv::noArray(), CV_64F);
  cv::Scalar mean, sigma;
  cv::meanStdDev(difference, mean, sigma);
  EXPECT_NEAR(mean[0], 0.0, 0.05);
  EXPECT_NEAR(sigma[0], std::sqrt(9.0 + 1.0 / 6.0), 0.1);

  settings.noise_sigma = -1.0;
  EXPECT_EQ(settings.check().error(), "noise_sigma: expected 0 to 100 grey levels, got -1");
  BoardLayout bad = layout;
  bad.cols = 1;
  EXPECT_EQ(bad.check().error(), "cols: expected 2 to 1000, got 1");
  bad = layout;
  bad.pattern = BoardPattern::texture;
  EXPECT_EQ(bad.check().error(), "texture: expected an 8-bit grey picture (CV_8UC1)");
}

}  // namespace
}  // namespace rhot
