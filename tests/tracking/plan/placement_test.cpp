#include "tracking/plan/Placement.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tracking/camera/RigFile.h"

namespace rhot {
namespace {

Camera webcam() {
  Camera c;
  c.intrinsics = {1280, 720, 900.0, 900.0, 639.5, 359.5, {-0.05, 0.01, 0, 0, 0}};
  return c;
}

// Seed 000's Wiimote: 1024 x 768, 1360 px (about 41 x 31 degrees), no distortion.
Camera wiimote() {
  Camera c;
  c.intrinsics = {1024, 768, 1360.0, 1360.0, 511.5, 383.5, {0, 0, 0, 0, 0}};
  return c;
}

TEST(Placement, SixWebcamsAroundARoomSeeNearlyAllOfItWithThree) {
  const TrackingVolume room{{0, 1, 0}, {3, 2, 3}};
  PlanSettings s;
  s.cameras = 6;
  s.ceiling_m = 2.6;
  const auto plan = plan_rig(webcam(), room, s);
  ASSERT_TRUE(plan.has_value()) << plan.error();
  ASSERT_EQ(plan->rig.cameras.size(), 6u);
  EXPECT_GT(plan->candidates, 100);
  ASSERT_TRUE(plan->rig.volume.has_value());
  EXPECT_EQ(plan->rig.volume->size_m, room.size_m);
  // Coverage counts views only: one error sample a point (the quantiles go unused) gives the same
  // fractions as the default 16.
  const auto report = evaluate_coverage(plan->rig, room, {.samples_per_point = 1});
  ASSERT_TRUE(report.has_value()) << report.error();
  EXPECT_GT(report->coverage_3, 0.95);
  EXPECT_GT(report->coverage_2, 0.99);
  // Every camera stays on its mount (the ceiling at 2.6 m over the footprint widened by 0.5 m, or
  // a wall 0.5 m outside the volume between its top and the ceiling), no two share a place, and
  // each sees part of the volume.
  const std::vector<CameraProjection> cameras = camera_projections(plan->rig);
  for (std::size_t c = 0; c < plan->rig.cameras.size(); ++c) {
    const Camera& cam = plan->rig.cameras[c];
    const Eigen::Vector3d o = cam.centre_world();
    EXPECT_LE(std::max(std::abs(o.x()), std::abs(o.z())), 2.0 + 1e-9) << cam.name;
    if (cam.name.starts_with("ceiling")) {
      EXPECT_NEAR(o.y(), 2.6, 1e-9) << cam.name;
    } else {
      EXPECT_NEAR(std::max(std::abs(o.x()), std::abs(o.z())), 2.0, 1e-9) << cam.name << " is not on a wall";
      EXPECT_GE(o.y(), 2.0 - 1e-9) << cam.name;
      EXPECT_LE(o.y(), 2.6 + 1e-9) << cam.name;
    }
    for (std::size_t d = 0; d < c; ++d) EXPECT_GT((plan->rig.cameras[d].centre_world() - o).norm(), 1e-3) << cam.name;
    EXPECT_FALSE(cameras_seeing(std::span(&cameras[c], 1), room.centre_m).empty() &&
                 cameras_seeing(std::span(&cameras[c], 1), room.centre_m - Eigen::Vector3d(0, 0.9, 0)).empty() &&
                 cameras_seeing(std::span(&cameras[c], 1), room.centre_m + Eigen::Vector3d(1.4, -0.9, 1.4)).empty() &&
                 cameras_seeing(std::span(&cameras[c], 1), room.centre_m + Eigen::Vector3d(-1.4, -0.9, -1.4)).empty())
        << cam.name << " looks at nothing of the volume";
  }
  // The rig file round trip keeps it.
  const std::filesystem::path file = std::filesystem::path(::testing::TempDir()) / "planned-room.yaml";
  ASSERT_TRUE(save_rig(plan->rig, file).has_value());
  const auto loaded = load_rig(file);
  ASSERT_TRUE(loaded.has_value()) << loaded.error();
  EXPECT_EQ(loaded->cameras.size(), 6u);
  ASSERT_TRUE(loaded->volume.has_value());
  EXPECT_LT((loaded->volume->centre_m - room.centre_m).norm(), 1e-12);
}

// Seed 000's 4.6 x 4.6 x 2 m case: 10 Wiimotes, ceiling at 7 m. The plan sees at least as much of
// the volume with two and with three cameras as the seed's parallel arrangement (shipped as
// assets/rigs/seed-wiimote-10.yaml), and its worst predicted error at 0.3 px is at most a
// quarter of the arrangement's (6.5 against 32 mm when this was written).
TEST(Placement, TenWiimotesOnTheCeilingCoverTheSeedsVolumeAtLeastAsWellAsItsArrangement) {
  const auto seed = load_rig(std::filesystem::path(RHOT_ASSET_DIR) / "rigs" / "seed-wiimote-10.yaml");
  ASSERT_TRUE(seed.has_value()) << seed.error();
  ASSERT_TRUE(seed->volume.has_value());
  PlanSettings s;
  s.cameras = 10;
  s.mount = Mount::kCeiling;
  s.ceiling_m = 7.0;
  const auto plan = plan_rig(wiimote(), *seed->volume, s);
  ASSERT_TRUE(plan.has_value()) << plan.error();
  const auto ours = evaluate_coverage(plan->rig, *seed->volume);
  const auto theirs = evaluate_coverage(*seed, *seed->volume);
  ASSERT_TRUE(ours && theirs);
  EXPECT_GE(ours->coverage_2, theirs->coverage_2);
  EXPECT_GE(ours->coverage_3, theirs->coverage_3);
  EXPECT_LT(ours->predicted_max_mm, 0.25 * theirs->predicted_max_mm);
  for (const Camera& c : plan->rig.cameras) EXPECT_NEAR(c.centre_world().y(), 7.0, 1e-9) << c.name;
}

TEST(Placement, AnErrorTargetIsMetWithAsFewCamerasAsItTakes) {
  const TrackingVolume room{{0, 1, 0}, {3, 2, 3}};
  PlanSettings s;
  s.max_error_mm = 6.0;
  s.ceiling_m = 2.6;
  // The planner reports each count it tries, after improving it: "N cameras: C % seen by 3 or
  // more, worst predicted error E mm".
  struct Tried {
    int cameras = 0;
    double seen_percent = 0.0;
    double worst_mm = 0.0;
  };
  std::vector<Tried> tried;
  const auto plan = plan_rig(webcam(), room, s, [&](const std::string& line) {
    Tried t;
    int views = 0;
    if (std::sscanf(line.c_str(), "%d cameras: %lf %% seen by %d or more, worst predicted error %lf mm", &t.cameras, &t.seen_percent,
                    &views, &t.worst_mm) == 4) {
      tried.push_back(t);
    }
  });
  ASSERT_TRUE(plan.has_value()) << plan.error();
  const auto report =
      evaluate_coverage(plan->rig, room, {.sigma_px = 0.3, .grid_step_m = 0.0, .max_points = 20000, .samples_per_point = 1, .seed = 1});
  ASSERT_TRUE(report.has_value());
  EXPECT_LE(report->predicted_max_mm, 6.0);
  const auto seen = static_cast<double>(std::count_if(report->views.begin(), report->views.end(), [](int v) { return v >= 3; }));
  EXPECT_GE(seen / static_cast<double>(report->views.size()), 0.99);
  // Six when this was written (the planner's best five reached 6.27 mm, its six 4.85 mm); eight
  // webcams (room-8's) give 7 mm placed as in room-8.
  EXPECT_EQ(plan->rig.cameras.size(), 6u);
  // As few as it takes: one camera fewer, placed as well as the planner could, missed the target
  // (it saw all of the volume, but its worst predicted error was 6.27 mm).
  const int n = static_cast<int>(plan->rig.cameras.size());
  const auto fewer = std::find_if(tried.begin(), tried.end(), [&](const Tried& t) { return t.cameras == n - 1; });
  ASSERT_NE(fewer, tried.end()) << "no progress line for " << n - 1 << " cameras";
  EXPECT_GT(fewer->worst_mm, 6.0) << fewer->seen_percent << " % seen by three";
  ASSERT_FALSE(tried.empty());
  EXPECT_EQ(tried.back().cameras, n);
  EXPECT_LE(tried.back().worst_mm, 6.0);
}

TEST(Placement, BadInputIsRefusedWithTheReason) {
  const TrackingVolume room{{0, 1, 0}, {3, 2, 3}};
  PlanSettings s;
  s.cameras = 4;
  EXPECT_EQ(plan_rig(Camera{}, room, s).error(), "camera model: needs a positive image size and focal length");
  EXPECT_EQ(plan_rig(webcam(), {{0, 0.5, 0}, {3, 2, 3}}, s).error(), "volume: reaches 0.50 m below the floor (Y = 0)");
  EXPECT_EQ(plan_rig(webcam(), {{0, 1, 0}, {3, 0, 3}}, s).error(), "volume: every side must be positive and finite");
  EXPECT_EQ(plan_rig(webcam(), {{0, 1, 0}, {3000, 2, 3}}, s).error(), "volume: sides of up to 1000 m");
  EXPECT_EQ(plan_rig(webcam(), {{0, 1, 0}, {1000, 1e-4, 1000}}, s).error(),
            "volume: too thin for its length and width (over 4 million grid points): plan it in parts");
  PlanSettings low = s;
  low.ceiling_m = 1.5;
  EXPECT_EQ(plan_rig(webcam(), room, low).error(), "ceiling: 1.50 m is not above the volume's top (2.00 m)");
  PlanSettings neither = s;
  neither.cameras = 0;
  EXPECT_EQ(plan_rig(webcam(), room, neither).error(), "give a number of cameras or a maximum error");
  // Refused only after trying every count up to 8 (no bound says so sooner): a search lattice of
  // 300 points instead of 3,000 makes that cheap, and the rig of each count is still judged on the
  // fine grid, which must see 99 % of the room by three for this reason (rather than "see at most").
  PlanSettings impossible;
  impossible.max_error_mm = 0.001;
  impossible.max_cameras = 8;
  impossible.grid_points = 300;
  EXPECT_EQ(
      plan_rig(webcam(), room, impossible).error().rfind("max error: 0.00 mm cannot be reached with up to 8 cameras of this model", 0), 0u)
      << plan_rig(webcam(), room, impossible).error();
  // A camera whose principal point lies far outside its image: it sees only what is nearly
  // beside it, so no pose looking at the volume sees any of it.
  Camera pinhole;
  pinhole.intrinsics = {640, 480, 500.0, 500.0, 1e5, 1e5, {0, 0, 0, 0, 0}};
  EXPECT_EQ(plan_rig(pinhole, room, s).error(),
            "volume: no camera position on the chosen mounts sees any of it (camera model or ceiling?)");
}

}  // namespace
}  // namespace rhot
