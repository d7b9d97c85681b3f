// The world frame from an L-frame or floor points: a rig calibrated in some other frame (here the
// truth moved by a known similarity) brought back to the truth's world.

#include "tracking/calib/WorldFrame.h"

#include <cmath>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "tracking/calib/Similarity.h"
#include "tracking/camera/RigFile.h"
#include "tracking/sim/CalibrationSessions.h"

namespace {

rhot::CameraRig seated() {
  auto rig = rhot::load_rig(std::string(RHOT_ASSET_DIR) + "/rigs/seated-4.yaml");
  EXPECT_TRUE(rig) << rig.error();
  return *rig;
}

// The truth as a wand calibration would leave it: in another frame (and scale).
rhot::CameraRig moved(const rhot::CameraRig& truth, double scale) {
  rhot::Similarity3 s;
  s.scale = scale;
  s.rotation = Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.3, 1.0, -0.2).normalized()).toRotationMatrix();
  s.translation = {0.4, -1.2, 2.5};
  rhot::CameraRig out = truth;
  for (rhot::Camera& c : out.cameras) c = rhot::transform_camera(c, s);
  out.volume.reset();
  return out;
}

void expect_same_cameras(const rhot::CameraRig& a, const rhot::CameraRig& b, double mm, double deg) {
  ASSERT_EQ(a.cameras.size(), b.cameras.size());
  for (std::size_t c = 0; c < a.cameras.size(); ++c) {
    EXPECT_LT((a.cameras[c].centre_world() - b.cameras[c].centre_world()).norm() * 1000.0, mm) << a.cameras[c].name;
    EXPECT_LT(a.cameras[c].cam_from_world.rotation.angularDistance(b.cameras[c].cam_from_world.rotation) * 180.0 / M_PI, deg)
        << a.cameras[c].name;
  }
}

// The truth's cameras described in the world an L-frame (or floor point) at world_from_frame defines.
rhot::CameraRig in_frame(const rhot::CameraRig& truth, const rhot::Rigid3d& world_from_frame) {
  rhot::Similarity3 frame_from_world;
  frame_from_world.rotation = world_from_frame.rotation.conjugate().toRotationMatrix();
  frame_from_world.translation = -(frame_from_world.rotation * world_from_frame.translation);
  rhot::CameraRig out = truth;
  for (rhot::Camera& c : out.cameras) c = rhot::transform_camera(c, frame_from_world);
  return out;
}

// seated-4 looks at a desk: its cameras do not see the room's floor, so the frame lies on the desk,
// at the bottom of the tracked volume.
rhot::Rigid3d on_the_desk() {
  rhot::Rigid3d t;
  t.translation = {-0.2, 0.65, -0.2};
  return t;
}

rhot::SessionNoise noise(unsigned seed) {
  rhot::SessionNoise n;
  n.rig.sigma_px = 0.3;
  n.rig.seed = seed;
  return n;
}

TEST(WorldFrame, AnLFrameOnTheFloorGivesBackTheTruthsWorld) {
  const rhot::CameraRig truth = seated();
  const rhot::LFrame frame;  // 500 x 300 mm, three markers
  const rhot::Detections d = rhot::simulate_lframe_session(truth, frame, on_the_desk(), 60, noise(1));
  const auto result = rhot::world_from_lframe(moved(truth, 1.0), d, frame, false);
  ASSERT_TRUE(result) << result.error();
  expect_same_cameras(result->rig, in_frame(truth, on_the_desk()), 2.0, 0.3);
  EXPECT_LT(result->report.rms_mm, 1.0);
  EXPECT_LT(std::abs(result->report.angle_error_deg), 0.3);
  EXPECT_DOUBLE_EQ(result->report.scale, 1.0);
  ASSERT_EQ(result->report.marker_residual_mm.size(), 3u);
}

TEST(WorldFrame, AFourMarkerFrameTurnedAndMovedDefinesItsOwnWorld) {
  const rhot::CameraRig truth = seated();
  rhot::LFrame frame;
  frame.middle_m = 0.2;
  frame.height_m = 0.01;
  rhot::Rigid3d world_from_frame;
  world_from_frame.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitY()));
  world_from_frame.translation = {-0.05, 0.65, -0.1};
  const rhot::Detections d = rhot::simulate_lframe_session(truth, frame, world_from_frame, 60, noise(2));
  const auto result = rhot::world_from_lframe(moved(truth, 1.0), d, frame, false);
  ASSERT_TRUE(result) << result.error();
  expect_same_cameras(result->rig, in_frame(truth, world_from_frame), 2.0, 0.3);
  EXPECT_EQ(result->report.marker_residual_mm.size(), 4u);
}

TEST(WorldFrame, RescalesARigCalibratedWithoutAWand) {
  const rhot::CameraRig truth = seated();
  const rhot::LFrame frame;
  const rhot::Detections d = rhot::simulate_lframe_session(truth, frame, on_the_desk(), 60, noise(3));
  const rhot::CameraRig half = moved(truth, 0.5);
  const auto refused = rhot::world_from_lframe(half, d, frame, false);
  ASSERT_FALSE(refused);
  EXPECT_EQ(refused.error().rfind("the points found do not fit the L-frame", 0), 0u) << refused.error();
  const auto result = rhot::world_from_lframe(half, d, frame, true);
  ASSERT_TRUE(result) << result.error();
  EXPECT_NEAR(result->report.scale, 2.0, 0.01);
  expect_same_cameras(result->rig, in_frame(truth, on_the_desk()), 5.0, 0.3);
}

TEST(WorldFrame, RefusesAFrameWithMissingMarkers) {
  const rhot::CameraRig truth = seated();
  rhot::LFrame four;
  four.middle_m = 0.2;
  const rhot::Detections d = rhot::simulate_lframe_session(truth, rhot::LFrame{}, on_the_desk(), 30, noise(4));
  const auto result = rhot::world_from_lframe(truth, d, four, false);
  ASSERT_FALSE(result);
  EXPECT_EQ(
      result.error(),
      "the L-frame has 4 markers, but 3 points stayed still in at least half of the 30 frames; is the frame in view of two cameras or "
      "more, and nothing else still in view?");
  rhot::LFrame bad;
  bad.short_m = 0.5;
  EXPECT_EQ(rhot::world_from_lframe(truth, d, bad, false).error(),
            "L-frame: expected arms of 5 cm to 5 m with the long arm at least 5 % longer than the short one, got 500.0 mm and 500.0 mm");
}

TEST(WorldFrame, FloorPointsSetUpTheOriginAndX) {
  const rhot::CameraRig truth = seated();
  // Four places on the desk (y = 0.65 is its surface).
  const std::vector<Eigen::Vector3d> places{{-0.3, 0.65, 0.0}, {0.3, 0.65, 0.0}, {0.2, 0.65, -0.7}, {-0.3, 0.65, -0.8}};
  const rhot::Detections d = rhot::simulate_floor_session(truth, places, 0.02, 30, noise(5));
  const auto result = rhot::world_from_floor_points(moved(truth, 1.0), d, 0.02);
  ASSERT_TRUE(result) << result.error();
  // The new world: origin at the first place, +X towards the second.
  rhot::Rigid3d world_from_floor;
  world_from_floor.translation = places[0];
  expect_same_cameras(result->rig, in_frame(truth, world_from_floor), 3.0, 0.3);
  EXPECT_LT(result->report.rms_mm, 1.0);
  ASSERT_EQ(result->report.measured_world.size(), 4u);
  EXPECT_NEAR(result->report.measured_world[1].x(), 0.6, 0.003);
}

TEST(WorldFrame, FloorPointsOnALineAreRefused) {
  const rhot::CameraRig truth = seated();
  const std::vector<Eigen::Vector3d> places{{-0.3, 0.65, -0.4}, {0.0, 0.65, -0.4}, {0.3, 0.65, -0.4}};
  const rhot::Detections d = rhot::simulate_floor_session(truth, places, 0.0, 20, noise(6));
  EXPECT_EQ(rhot::world_from_floor_points(truth, d, 0.0).error(),
            "floor points: the places lie on one line; touch the floor at three corners of a wide triangle");
}

}  // namespace

namespace {

TEST(WorldFrame, AMirroredFrameIsRefusedNotTurnedUpsideDown) {
  // Laid with the short arm to the left: the same as the frame turned over about its long arm.
  const rhot::CameraRig truth = seated();
  rhot::Rigid3d mirrored = on_the_desk();
  mirrored.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ()));
  const rhot::Detections d = rhot::simulate_lframe_session(truth, rhot::LFrame{}, mirrored, 60, noise(8));
  const auto result = rhot::world_from_lframe(moved(truth, 1.0), d, rhot::LFrame{}, false);
  ASSERT_FALSE(result);
  EXPECT_EQ(
      result.error(),
      "the L-frame reads as mirrored: with it, the cameras would be below the floor; lay it with the short arm to the right of the long "
      "arm (seen from above, the long arm pointing away from you)");
}

TEST(WorldFrame, TheTrackedVolumeTurnsWithTheWorld) {
  rhot::Similarity3 quarter_turn;
  quarter_turn.rotation = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const rhot::TrackingVolume box{{1, 0, 0}, {2, 1, 0.5}};
  const rhot::TrackingVolume turned = rhot::transform_volume(box, quarter_turn);
  EXPECT_LT((turned.centre_m - Eigen::Vector3d(0, 0, -1)).norm(), 1e-12);
  EXPECT_LT((turned.size_m - Eigen::Vector3d(0.5, 1, 2)).norm(), 1e-12);
}

}  // namespace
