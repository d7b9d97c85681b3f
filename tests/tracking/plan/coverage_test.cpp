#include "tracking/plan/Coverage.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "tracking/geometry/Triangulation.h"

namespace rhot {
namespace {

// A camera at `position` looking at `target`: 1000 x 1000 pixels, f = 500 px (90 degrees across),
// no distortion, so its footprint at distance d straight ahead is a 2d x 2d square.
Camera square_camera(const std::string& name, const Eigen::Vector3d& position, const Eigen::Vector3d& target) {
  Camera c;
  c.name = name;
  c.intrinsics = {1000, 1000, 500.0, 500.0, 499.5, 499.5, {0, 0, 0, 0, 0}};
  c.cam_from_world = cam_from_world_look_at(position, target);
  return c;
}

// Looking straight down (a hair off vertical, which look_at cannot do exactly) from 5 m onto a
// 1 cm slab on the floor: each camera covers a 10 x 10 m square of the slab.
CameraRig two_ceiling_cameras(double apart_m) {
  CameraRig rig;
  rig.cameras.push_back(square_camera("a", {-0.5 * apart_m, 5.0, 0.0}, {-0.5 * apart_m, 0.0, 1e-6}));
  rig.cameras.push_back(square_camera("b", {0.5 * apart_m, 5.0, 0.0}, {0.5 * apart_m, 0.0, 1e-6}));
  return rig;
}

TEST(Coverage, FractionsSeenAreTheFootprintsOverlapsOverTheVolume) {
  // Footprints 10 x 10 m, 4 m apart along X, on a 20 x 20 m floor: seen by one or more 14 x 10 of
  // 400 m^2, by both 6 x 10.
  const CameraRig rig = two_ceiling_cameras(4.0);
  const TrackingVolume slab{{0, 0.005, 0}, {20, 0.01, 20}};
  CoverageSettings s;
  s.grid_step_m = 0.05;
  const auto report = evaluate_coverage(rig, slab, s);
  ASSERT_TRUE(report.has_value()) << report.error();
  EXPECT_EQ(report->grid.nx, 400);
  EXPECT_EQ(report->grid.nz, 400);
  EXPECT_NEAR(report->coverage_1, 140.0 / 400.0, 0.005);
  EXPECT_NEAR(report->coverage_2, 60.0 / 400.0, 0.005);
  EXPECT_EQ(report->coverage_3, 0.0);
}

TEST(Coverage, PredictedCovarianceIsTheCramerRaoBound) {
  CameraRig rig = two_ceiling_cameras(2.0);
  rig.cameras.push_back(square_camera("c", {0.0, 3.0, 4.0}, {0.0, 1.0, 0.0}));
  const std::vector<CameraProjection> cameras = camera_projections(rig);
  const Eigen::Vector3d p(0.3, 1.2, -0.2);
  const std::vector<int> seeing = cameras_seeing(cameras, p);
  ASSERT_EQ(seeing, (std::vector<int>{0, 1, 2}));
  const auto predicted = predicted_covariance(cameras, seeing, p, 0.3);
  const auto bound = crlb_covariance(rig, p, seeing, 0.3);
  ASSERT_TRUE(predicted && bound);
  EXPECT_LT((*predicted - *bound).norm(), 1e-9 * bound->norm());
  EXPECT_FALSE(predicted_covariance(cameras, std::vector<int>{0}, p, 0.3).has_value());
}

// The prediction is what triangulating noisy detections gives: markers spread through a volume,
// projected with 0.3 px of noise into the cameras that see them, refined by Gauss-Newton; the
// median and 95th percentile of their 3D errors agree with the prediction within 5 %.
TEST(Coverage, PredictedErrorQuantilesAreWhatTriangulationMeasures) {
  CameraRig rig;
  rig.cameras.push_back(square_camera("0", {-3, 2.5, -3}, {0, 1, 0}));
  rig.cameras.push_back(square_camera("1", {3, 2.5, -3}, {0, 1, 0}));
  rig.cameras.push_back(square_camera("2", {3, 2.5, 3}, {0, 1, 0}));
  rig.cameras.push_back(square_camera("3", {-3, 2.5, 3}, {0, 1, 0}));
  rig.cameras.push_back(square_camera("4", {0, 4.0, 0.5}, {0, 1, 0}));
  const TrackingVolume volume{{0, 1, 0}, {3, 1.6, 3}};
  const auto report = evaluate_coverage(rig, volume, {});
  ASSERT_TRUE(report.has_value()) << report.error();
  EXPECT_GT(report->coverage_2, 0.99);

  const std::vector<CameraProjection> cameras = camera_projections(rig);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> unit(-0.5, 0.5);
  std::normal_distribution<double> noise(0.0, 0.3);
  std::vector<double> errors_mm;
  while (errors_mm.size() < 20000) {
    const Eigen::Vector3d p = volume.centre_m + volume.size_m.cwiseProduct(Eigen::Vector3d{unit(rng), unit(rng), unit(rng)});
    std::vector<Observation> seen;
    for (const int c : cameras_seeing(cameras, p)) {
      seen.push_back({c, *cameras[static_cast<std::size_t>(c)].project(p) + Eigen::Vector2d{noise(rng), noise(rng)}});
    }
    if (seen.size() < 2) continue;
    const auto t = refine_point(cameras, seen, p, 10);
    ASSERT_TRUE(t.has_value());
    errors_mm.push_back(1000.0 * (t->position_world - p).norm());
  }
  const auto at = [&](double q) {
    const auto k = static_cast<std::size_t>(q * static_cast<double>(errors_mm.size() - 1));
    std::nth_element(errors_mm.begin(), errors_mm.begin() + static_cast<std::ptrdiff_t>(k), errors_mm.end());
    return errors_mm[k];
  };
  const double median = at(0.5), p95 = at(0.95);
  EXPECT_NEAR(report->predicted_median_mm / median, 1.0, 0.05) << report->predicted_median_mm << " against " << median;
  EXPECT_NEAR(report->predicted_p95_mm / p95, 1.0, 0.05) << report->predicted_p95_mm << " against " << p95;
  EXPECT_GT(report->predicted_max_mm, p95);
}

// One camera: coverage by one, no point triangulated, so no error is predicted (not 0 mm).
TEST(Coverage, NoPointSeenByTwoPredictsNoError) {
  CameraRig rig;
  rig.cameras.push_back(square_camera("a", {0.0, 5.0, 0.0}, {0.0, 0.0, 1e-6}));
  const auto report = evaluate_coverage(rig, {{0, 0.5, 0}, {2, 1, 2}});
  ASSERT_TRUE(report.has_value()) << report.error();
  EXPECT_EQ(report->coverage_1, 1.0);
  EXPECT_EQ(report->coverage_2, 0.0);
  EXPECT_TRUE(std::isnan(report->predicted_median_mm));
  EXPECT_TRUE(std::isnan(report->predicted_p95_mm));
  EXPECT_TRUE(std::isnan(report->predicted_max_mm));
}

TEST(Coverage, BadInputIsRefusedWithTheReason) {
  const CameraRig rig = two_ceiling_cameras(1.0);
  const TrackingVolume box{{0, 1, 0}, {1, 1, 1}};
  EXPECT_EQ(evaluate_coverage(CameraRig{}, box).error(), "the rig has no cameras");
  EXPECT_EQ(evaluate_coverage(rig, {{0, 1, 0}, {1, 0, 1}}).error(), "volume: every side must be positive and finite");
  EXPECT_EQ(evaluate_coverage(rig, {{0, std::numeric_limits<double>::quiet_NaN(), 0}, {1, 1, 1}}).error(),
            "volume: its centre must be finite");
  CoverageSettings s;
  s.sigma_px = 0.0;
  EXPECT_EQ(evaluate_coverage(rig, box, s).error(), "sigma: must be positive");
  s = {};
  s.grid_step_m = 1e-7;
  EXPECT_EQ(evaluate_coverage(rig, box, s).error(), "grid step: too fine for the volume (over 50 million points)");
}

}  // namespace
}  // namespace rhot
