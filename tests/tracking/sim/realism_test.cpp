// The realistic world's parts against what they promise: strays, merging by projected size, box
// occluders, the calibration error's size, users' own hands, and the settings' checks.

#include "tracking/sim/Realism.h"

#include <cmath>
#include <map>

#include <gtest/gtest.h>

#include "tracking/camera/RigFile.h"
#include "tracking/geometry/Matching.h"
#include "tracking/sim/SimulatedRig.h"

namespace rhot {
namespace {

CameraRig seated() {
  auto r = load_rig(std::filesystem::path(RHOT_ASSET_DIR) / "rigs" / "seated-4.yaml");
  EXPECT_TRUE(r.has_value()) << (r ? "" : r.error());
  return r.value_or(CameraRig{});
}

Trajectory fixed_at(const Eigen::Vector3d& p) {
  Trajectory t;
  t.centre_m = p;
  return t;
}

TEST(Realism, StraysAreHalfLampsThatStayPutAndHalfFlickerAnywhere) {
  SimulatedRigSettings s;
  s.strays = 6;
  s.sigma_px = 0.0;
  SimulatedRig sim(seated(), {}, s);
  std::map<std::pair<long, long>, int> seen;  // stray pixels (rounded) over 20 frames, camera 0
  for (int f = 0; f < 20; ++f) {
    const RigFrame frame = sim.next();
    for (const CameraFrame& cf : frame.cameras) {
      ASSERT_EQ(cf.detections.size(), 6u) << "camera " << cf.camera;
      for (const Detection& d : cf.detections) {
        EXPECT_EQ(d.truth_marker, -1);
        EXPECT_TRUE(sim.rig().cameras[static_cast<std::size_t>(cf.camera)].in_image(d.pixel));
        if (cf.camera == 0) ++seen[{std::lround(d.pixel.x()), std::lround(d.pixel.y())}];
      }
    }
  }
  int lamps = 0;
  for (const auto& [pixel, frames] : seen) lamps += frames == 20 ? 1 : 0;
  EXPECT_EQ(lamps, 3) << "three lamps in every frame";
  EXPECT_EQ(seen.size(), 3u + 3u * 20u) << "the other three somewhere new each frame";
}

TEST(Realism, MarkersMergeWhenTheirProjectedDiscsOverlapNotOtherwise) {
  const CameraRig rig = seated();
  const Eigen::Vector3d centre(0.0, 1.1, -0.45);
  // 5 mm apart: 6 mm markers overlap in every camera (they touch at 6 mm); 4 mm markers at about
  // a metre are some 3.5 px wide and 4.4 px apart: they stay apart.
  for (const auto& [diameter, merged] : {std::pair{0.006, true}, {0.004, false}}) {
    SimulatedRigSettings s;
    s.sigma_px = 0.0;
    s.marker_diameter_m = diameter;
    SimulatedRig sim(rig, {fixed_at(centre), fixed_at(centre + Eigen::Vector3d(0.005, 0, 0))}, s);
    const RigFrame frame = sim.next();
    for (const CameraFrame& cf : frame.cameras) {
      const Camera& cam = rig.cameras[static_cast<std::size_t>(cf.camera)];
      const double apart = (*cam.project(centre) - *cam.project(centre + Eigen::Vector3d(0.005, 0, 0))).norm();
      const double depth = (cam.cam_from_world * centre).z();
      const double sum_radii = cam.intrinsics.fx * diameter / depth;
      if (std::abs(apart - sum_radii) < 0.3) continue;  // too near the edge to call
      EXPECT_EQ(cf.detections.size(), apart < sum_radii ? 1u : 2u) << "camera " << cf.camera << " diameter " << diameter;
      if (merged) {
        EXPECT_LT(apart, sum_radii);
      }
    }
  }
}

TEST(Realism, ABoxHidesWhatIsBehindItAndNothingBeside) {
  const Occluder table = Occluder::box({0, 0.7, -0.4}, Eigen::Quaterniond::Identity(), {0.6, 0.02, 0.4});
  EXPECT_TRUE(table.blocks({0, 1.5, -0.4}, {0, 0.5, -0.4}));       // straight down through it
  EXPECT_FALSE(table.blocks({0, 1.5, -0.4}, {0, 0.73, -0.4}));     // stops above it
  EXPECT_FALSE(table.blocks({0.7, 1.5, -0.4}, {0.7, 0.5, -0.4}));  // beside it
  const Occluder turned =
      Occluder::box({0, 0, 0}, Eigen::Quaterniond(Eigen::AngleAxisd(0.25 * 3.14159265358979, Eigen::Vector3d::UnitY())), {0.1, 0.1, 0.1});
  EXPECT_TRUE(turned.blocks({0.13, 0, -1}, {0.13, 0, 1}));  // within the turned box's corner (reaches 0.141)
  EXPECT_FALSE(turned.blocks({0.15, 0, -1}, {0.15, 0, 1}));
}

TEST(Realism, ThePerturbedRigIsOffByTheRequestedReprojectionErrorAndTheTrackerSeesIt) {
  const CameraRig truth = seated();
  for (const unsigned seed : {1u, 2u}) {
    for (const double px : {0.3, 1.0}) {
      const CameraRig off = perturbed_rig(truth, px, seed);
      EXPECT_NEAR(rig_difference_px(truth, off), px, 0.05 * px) << "seed " << seed;
      EXPECT_NEAR(rig_difference_px(truth, off, 99), px, 0.15 * px) << "other points, seed " << seed;
    }
  }
  EXPECT_EQ(rig_difference_px(truth, perturbed_rig(truth, 0.0, 1)), 0.0);
  // Detections from the true rig triangulated with one 0.5 px off: the residuals show more noise
  // than the same detections through the true rig.
  SimulatedRigSettings s;
  s.sigma_px = 0.2;
  SimulatedRig sim(truth, random_trajectories(60, {-0.4, 0.7, -0.9}, {0.4, 1.5, 0.0}, 3), s);
  const RigFrame frame = sim.next();
  const double honest = *estimate_pixel_sigma(match_and_triangulate(truth, frame));
  const double fooled = *estimate_pixel_sigma(match_and_triangulate(perturbed_rig(truth, 0.5, 1), frame));
  EXPECT_LT(honest, 0.3);
  EXPECT_GT(fooled, honest + 0.07);  // measured: 0.26 px through the true rig, 0.36 px through the one off
}

TEST(Realism, AUsersHandHasItsOwnBonesWithinTenPercentAndItsOwnFingerHinges) {
  const HandPose model = reference_open_hand(HandSide::kRight);
  for (const unsigned seed : {1u, 2u, 3u}) {
    const HandPose user = independent_hand(model, seed);
    double smallest = 10.0, largest = 0.0;
    for (int j = 0; j < kHandJointCount; ++j) {
      const auto parent = joint_parent(static_cast<HandJoint>(j));
      if (!parent) continue;
      const auto uj = static_cast<std::size_t>(j), up = static_cast<std::size_t>(*parent);
      const double ratio = (user.position_m[uj] - user.position_m[up]).norm() / (model.position_m[uj] - model.position_m[up]).norm();
      smallest = std::min(smallest, ratio);
      largest = std::max(largest, ratio);
    }
    EXPECT_GE(smallest, 0.9 - 1e-9) << "seed " << seed;
    EXPECT_LE(largest, 1.1 + 1e-9) << "seed " << seed;
    EXPECT_GT(largest - smallest, 0.02) << "bones differ from one another, seed " << seed;
  }
  std::array<FingerAngles, kFingerCount> angles{};
  for (FingerAngles& a : angles) a.flexion_rad = {0.6, 0.9, 0.6};  // the solver's DIP = 2/3 PIP
  const auto user = independent_angles(angles, 4);
  int off_rule = 0;
  for (std::size_t f = 1; f < kFingerCount; ++f) off_rule += std::abs(user[f].flexion_rad[2] - 0.6) > 0.01 ? 1 : 0;
  EXPECT_GE(off_rule, 3) << "most fingers' last hinge leave the coupling rule";
}

TEST(Realism, NamedWorldsAndTheirChecks) {
  const auto realistic = world_named("realistic");
  ASSERT_TRUE(realistic.has_value());
  EXPECT_EQ(realistic->sigma_px, 0.5);
  EXPECT_EQ(realistic->strays, 3);
  EXPECT_EQ(realistic->calib_error_px, 0.3);
  EXPECT_TRUE(realistic->independent_hands);
  EXPECT_EQ(world_named("kind").error(), "--world: expected ideal or realistic, got \"kind\"");
  WorldSettings w;
  w.calib_error_px = std::nan("");
  EXPECT_EQ(w.check().error(), "--calib-error-px: expected 0 to 20 pixels, got nan");
  w = WorldSettings{};
  w.strays = -1;
  EXPECT_EQ(w.check().error(), "strays: expected 0 to 1000 stray detections per camera, got -1.000000");
}

}  // namespace
}  // namespace rhot
