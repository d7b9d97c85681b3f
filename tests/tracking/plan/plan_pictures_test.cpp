// The plan's pictures: camera labels in the top view that never cover one another, and slice
// captions that say the height asked for.

#include "tracking/plan/PlanPictures.h"

#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "tracking/camera/RigFile.h"

namespace rhot {
namespace {

namespace fs = std::filesystem;

// Every two placed boxes apart, every placed box inside the picture.
void expect_apart_and_inside(const std::vector<std::optional<LabelBox>>& labels, const Eigen::Vector2d& picture_px) {
  for (std::size_t a = 0; a < labels.size(); ++a) {
    if (!labels[a]) continue;
    EXPECT_GE(labels[a]->min_px.minCoeff(), 0.0) << a;
    EXPECT_LE(labels[a]->max_px.x(), picture_px.x()) << a;
    EXPECT_LE(labels[a]->max_px.y(), picture_px.y()) << a;
    for (std::size_t b = a + 1; b < labels.size(); ++b) {
      if (labels[b]) {
        EXPECT_FALSE(labels[a]->overlaps(*labels[b])) << "labels " << a << " and " << b;
      }
    }
  }
}

TEST(PlanPictures, LabelsOfCamerasInOnePlaceGoAroundItWithoutOverlapping) {
  const Eigen::Vector2d picture(400, 300);
  const std::vector<Eigen::Vector2d> points(5, Eigen::Vector2d(100, 100));
  const std::vector<Eigen::Vector2d> sizes(5, Eigen::Vector2d(60, 12));
  const auto labels = place_labels(points, sizes, picture);
  ASSERT_EQ(labels.size(), 5u);
  for (const auto& l : labels) EXPECT_TRUE(l.has_value());
  expect_apart_and_inside(labels, picture);
  // The first takes the usual place, to the right of its point.
  EXPECT_EQ(labels[0]->min_px, Eigen::Vector2d(106, 86));
  EXPECT_EQ(labels[0]->max_px, Eigen::Vector2d(166, 98));

  // At the picture's right edge a label goes to the left.
  const auto edge = place_labels({Eigen::Vector2d(390, 100)}, {Eigen::Vector2d(60, 12)}, picture);
  ASSERT_TRUE(edge[0].has_value());
  EXPECT_LT(edge[0]->max_px.x(), 390.0);

  // More labels than there is room for: some are left out, the rest still apart, and none covers
  // another point.
  std::vector<Eigen::Vector2d> crowd;
  for (int i = 0; i < 40; ++i) crowd.emplace_back(200 + 3 * (i % 5), 150 + 3 * (i / 5));
  const auto crowded = place_labels(crowd, std::vector<Eigen::Vector2d>(crowd.size(), Eigen::Vector2d(60, 12)), picture);
  std::size_t shown = 0;
  for (std::size_t i = 0; i < crowded.size(); ++i) {
    if (!crowded[i]) continue;
    ++shown;
    for (std::size_t p = 0; p < crowd.size(); ++p) {
      if (p != i) {
        EXPECT_FALSE(crowded[i]->overlaps({crowd[p] - Eigen::Vector2d(4, 4), crowd[p] + Eigen::Vector2d(4, 4)})) << i << " " << p;
      }
    }
  }
  EXPECT_GT(shown, 0u);
  EXPECT_LT(shown, crowd.size());
  expect_apart_and_inside(crowded, picture);
}

// A ring of 12 cameras 30 cm across on a 3 m ceiling (cameras the old labels, each to the right
// of its dot, drew over one another), and the shipped 32-camera stage: no two labels overlap.
TEST(PlanPictures, TheTopViewsCameraLabelsNeverOverlap) {
  CameraRig ring;
  const auto stage = load_rig(fs::path(RHOT_ASSET_DIR) / "rigs" / "stage-32.yaml");
  ASSERT_TRUE(stage.has_value()) << stage.error();
  for (int i = 0; i < 12; ++i) {
    Camera c = stage->cameras[0];
    c.name = "ceiling-" + std::to_string(i);
    const double a = 2.0 * std::numbers::pi * i / 12.0;
    // Looking straight down from (0.15 cos a, 3, 0.15 sin a): camera +Z is world -Y.
    c.cam_from_world.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(-std::numbers::pi / 2, Eigen::Vector3d::UnitX()));
    c.cam_from_world.translation = -(c.cam_from_world.rotation * Eigen::Vector3d(0.15 * std::cos(a), 3.0, 0.15 * std::sin(a)));
    ring.cameras.push_back(c);
  }
  const TrackingVolume room{Eigen::Vector3d(0, 1, 0), Eigen::Vector3d(3, 2, 3)};
  for (const auto& [rig, volume] : {std::pair{ring, room}, std::pair{*stage, *stage->volume}}) {
    const auto labels = plan_top_view_labels(rig, volume);
    ASSERT_TRUE(labels.has_value()) << labels.error();
    ASSERT_EQ(labels->size(), rig.cameras.size());
    expect_apart_and_inside(*labels, Eigen::Vector2d(1e9, 1e9));
  }
  const auto stage_labels = plan_top_view_labels(*stage, *stage->volume);
  for (const auto& l : *stage_labels) EXPECT_TRUE(l.has_value()) << "room for every label of a spread-out rig";

  const fs::path file = fs::path(::testing::TempDir()) / "rhot_plan_ring_top.png";
  ASSERT_TRUE(write_plan_top_view(file, ring, room).has_value());
  EXPECT_TRUE(fs::exists(file));
}

// A 2 m volume cut into 0.12 m rows from 0.04 m: 1.80 m lies between rows 1.72 and 1.84.
TEST(PlanPictures, ASliceCaptionSaysTheHeightAskedForAndTheRowShown) {
  CoverageGrid grid;
  grid.origin_m = Eigen::Vector3d(-1.45, 0.04, -1.45);
  grid.step_m = Eigen::Vector3d(0.1, 0.12, 0.1);
  grid.nx = grid.nz = 30;
  grid.ny = 17;
  EXPECT_EQ(slice_height_caption(grid, 1.80), "height 1.80 m (the grid's nearest row: 1.84 m)");
  EXPECT_EQ(slice_height_caption(grid, 1.84), "height 1.84 m");
  EXPECT_EQ(slice_height_caption(grid, 3.0), "height 3.00 m (the grid's nearest row: 1.96 m)");
  EXPECT_EQ(slice_height_caption(grid, -1.0), "height -1.00 m (the grid's nearest row: 0.04 m)");
}

}  // namespace
}  // namespace rhot
