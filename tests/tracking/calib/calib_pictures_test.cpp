// Calibration pictures: coverage counted on the grid, pictures written at the promised size.

#include "tracking/media/Media.h"
#include "tracking/calib/CalibPictures.h"

#include <cmath>
#include <filesystem>

#include <gtest/gtest.h>

#include "tracking/camera/RigFile.h"

namespace {

namespace fs = std::filesystem;

TEST(CalibPictures, CoverageCountsGridCellsWithAPoint) {
  // 1600 x 1600: cells of 100 px. Three cells hit (two points share one), one point off the image.
  const std::vector<Eigen::Vector2d> pixels{{50, 50}, {60, 70}, {150, 50}, {1599, 1599}, {1700, 10}, {std::nan(""), 3}};
  EXPECT_DOUBLE_EQ(rhot::image_coverage(1600, 1600, pixels), 3.0 / 256.0);
  EXPECT_DOUBLE_EQ(rhot::image_coverage(1600, 1600, {}), 0.0);
}

TEST(CalibPictures, ResidualAndTopViewPicturesAreWritten) {
  const fs::path dir = fs::path(::testing::TempDir()) / "rhot_calib_pictures";
  fs::create_directories(dir);
  std::vector<rhot::ResidualSample> samples;
  for (int i = 0; i < 100; ++i) samples.push_back({{i * 25.0, i * 7.0}, {0.3, -0.2}, i % 10 != 0});
  ASSERT_TRUE(rhot::write_residual_picture(dir / "residuals.png", 2560, 1440, samples, 50.0, "cam"));
  const cv::Mat residuals = rhot::read_image((dir / "residuals.png"), rhot::ImageRead::kColour).value_or(cv::Mat());
  EXPECT_EQ(residuals.cols, 1280);  // halved until at most 1280 wide
  EXPECT_EQ(residuals.rows, 720);
  const auto rig = rhot::load_rig(std::string(RHOT_ASSET_DIR) + "/rigs/room-8.yaml");
  ASSERT_TRUE(rig) << rig.error();
  ASSERT_TRUE(rhot::write_rig_top_view(dir / "top.png", *rig, {{0, 1, 0}, {0.5, 1, 0.5}}, "room-8"));
  const cv::Mat top = rhot::read_image((dir / "top.png"), rhot::ImageRead::kColour).value_or(cv::Mat());
  EXPECT_EQ(top.cols, 800);
  const auto bad = rhot::write_residual_picture(dir / "no-such-folder" / "x.png", 640, 480, samples, 1.0, "x");
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error().rfind((dir / "no-such-folder" / "x.png").string() + ": cannot write the image", 0), 0u) << bad.error();
}

}  // namespace
