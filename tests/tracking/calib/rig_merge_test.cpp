// Merging two rigs calibrated apart through their shared cameras.

#include "tracking/calib/RigMerge.h"

#include <cmath>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "tests/tracking/calib/CalibTestSupport.h"

#include "tracking/calib/WandCalibration.h"
#include "tracking/camera/RigFile.h"
#include "tracking/sim/CalibrationSessions.h"

namespace {

rhot::CameraRig room() {
  auto rig = rhot::load_rig(std::string(RHOT_ASSET_DIR) + "/rigs/room-8.yaml");
  EXPECT_TRUE(rig) << rig.error();
  return *rig;
}

rhot::CameraRig subset(const rhot::CameraRig& rig, std::initializer_list<int> cameras, const rhot::Similarity3& moved_by) {
  rhot::CameraRig out;
  out.name = rig.name;
  for (const int c : cameras) out.cameras.push_back(rhot::transform_camera(rig.cameras[static_cast<std::size_t>(c)], moved_by));
  return out;
}

// The cameras as a user's intrinsics-only files give them (each at the origin, looking along +Z),
// so that each wand calibration finds its poses from its wave alone.
using rhot::test::without_poses;

const rhot::Camera* find(const rhot::CameraRig& rig, const std::string& name) {
  for (const auto& c : rig.cameras) {
    if (c.name == name) return &c;
  }
  return nullptr;
}

// The merged rig against the truth after the similarity that best maps its camera centres onto
// the truth's: every camera present, metric (scale within 0.2 %), centres within 2 mm RMS.
void expect_matches_truth_up_to_frame(const rhot::CameraRig& merged, const rhot::CameraRig& truth) {
  std::vector<Eigen::Vector3d> from, to;
  for (const rhot::Camera& t : truth.cameras) {
    const rhot::Camera* m = find(merged, t.name);
    ASSERT_NE(m, nullptr) << t.name;
    from.push_back(m->centre_world());
    to.push_back(t.centre_world());
  }
  const auto fit = rhot::fit_similarity(from, to, true);
  ASSERT_TRUE(fit);
  EXPECT_NEAR(fit->scale, 1.0, 0.002);
  double sq = 0;
  for (std::size_t i = 0; i < from.size(); ++i) sq += (fit->apply(from[i]) - to[i]).squaredNorm();
  EXPECT_LT(std::sqrt(sq / static_cast<double>(from.size())) * 1000.0, 2.0);
}

TEST(RigMerge, TwoHalvesOfARoomJoinThroughTwoSharedCameras) {
  const rhot::CameraRig truth = room();
  rhot::Similarity3 b_frame;
  b_frame.scale = 1.7;  // B was calibrated in other units, in another frame
  b_frame.rotation = Eigen::AngleAxisd(-1.1, Eigen::Vector3d(0.2, 1.0, 0.1).normalized()).toRotationMatrix();
  b_frame.translation = {3.0, 0.2, -1.0};
  const rhot::CameraRig a = subset(truth, {0, 1, 2, 3, 4}, rhot::Similarity3{});
  const rhot::CameraRig b = subset(truth, {3, 4, 5, 6, 7}, b_frame);
  const auto merged = rhot::merge_rigs(a, b, rhot::MergeSettings{});
  ASSERT_TRUE(merged) << merged.error();
  EXPECT_EQ(merged->rig.cameras.size(), 8u);
  EXPECT_EQ(merged->report.shared_cameras, (std::vector<std::string>{truth.cameras[3].name, truth.cameras[4].name}));
  EXPECT_NEAR(merged->report.a_from_b.scale, 1.0 / 1.7, 1e-9);
  EXPECT_LT(merged->report.centre_rms_mm, 1e-6);
  for (const rhot::Camera& t : truth.cameras) {
    const rhot::Camera* m = find(merged->rig, t.name);
    ASSERT_NE(m, nullptr) << t.name;
    EXPECT_LT((m->centre_world() - t.centre_world()).norm(), 1e-9) << t.name;
    EXPECT_LT(m->cam_from_world.rotation.angularDistance(t.cam_from_world.rotation), 1e-9) << t.name;
  }
  EXPECT_FALSE(merged->report.adjusted);
}

TEST(RigMerge, TwoWandSessionsMergedAndAdjustedTogether) {
  // Each half calibrated from its own wave (which the other half's cameras partly see too), then
  // merged and bundle-adjusted over both sessions.
  const rhot::CameraRig truth = room();
  const rhot::CameraRig a_truth = subset(truth, {0, 1, 2, 3, 4}, rhot::Similarity3{});
  const rhot::CameraRig b_truth = subset(truth, {3, 4, 5, 6, 7}, rhot::Similarity3{});
  rhot::WandSession session;
  session.frames = 600;
  session.box_centre_m = truth.volume->centre_m;
  session.box_size_m = truth.volume->size_m;
  rhot::SessionNoise noise;
  noise.rig.seed = 21;
  const rhot::Detections da = rhot::simulate_wand_session(a_truth, session, noise);
  noise.rig.seed = 22;
  const rhot::Detections db = rhot::simulate_wand_session(b_truth, session, noise);
  rhot::WandSettings settings;
  settings.wand_length_m = 0.5;
  const auto a = rhot::calibrate_wand(without_poses(a_truth), da, settings);
  ASSERT_TRUE(a) << a.error();
  const auto b = rhot::calibrate_wand(without_poses(b_truth), db, settings);
  ASSERT_TRUE(b) << b.error();
  const auto merged = rhot::merge_rigs(a->rig, b->rig, rhot::MergeSettings{}, &da, &db);
  ASSERT_TRUE(merged) << merged.error();
  EXPECT_TRUE(merged->report.adjusted);
  EXPECT_LT(merged->report.rms_px, 0.5);
  // Each half's shared cameras were placed from its own wave: before the joint adjustment their two
  // estimates differ by the halves' errors, a few millimetres at the room's 3 to 6 m distances.
  EXPECT_GT(merged->report.centre_rms_mm, 0.0);
  EXPECT_LT(merged->report.centre_rms_mm, 30.0);
  // Against the truth, after aligning A's frame (camera 0's) to the truth's.
  expect_matches_truth_up_to_frame(merged->rig, truth);
}

// The detections of `cameras` only, renumbered 0, 1, ... in that order.
rhot::Detections only(const rhot::Detections& d, const std::vector<int>& cameras) {
  rhot::Detections out;
  out.camera_count = static_cast<int>(cameras.size());
  for (const rhot::DetectionFrame& f : d.frames) {
    rhot::DetectionFrame g{f.frame, {}};
    for (const rhot::MarkerObservation& o : f.observations) {
      for (std::size_t i = 0; i < cameras.size(); ++i) {
        if (cameras[i] == o.camera) g.observations.push_back({static_cast<int>(i), o.pixel, o.marker});
      }
    }
    if (!g.observations.empty()) out.frames.push_back(std::move(g));
  }
  return out;
}

TEST(RigMerge, RigsSharingNoCameraJoinThroughOneWaveBothSaw) {
  // One wave through the room; the two halves (no camera in common) calibrated apart from their
  // own cameras' detections, then joined through the wand positions both reconstructed.
  const rhot::CameraRig truth = room();
  rhot::WandSession session;
  session.frames = 800;
  session.box_centre_m = truth.volume->centre_m;
  session.box_size_m = truth.volume->size_m;
  rhot::SessionNoise noise;
  noise.rig.seed = 31;
  const rhot::Detections all = rhot::simulate_wand_session(truth, session, noise);
  const rhot::Detections da = only(all, {0, 1, 2, 3});
  const rhot::Detections db = only(all, {4, 5, 6, 7});
  rhot::WandSettings settings;
  settings.wand_length_m = 0.5;
  const auto a = rhot::calibrate_wand(without_poses(subset(truth, {0, 1, 2, 3}, rhot::Similarity3{})), da, settings);
  ASSERT_TRUE(a) << a.error();
  const auto b = rhot::calibrate_wand(without_poses(subset(truth, {4, 5, 6, 7}, rhot::Similarity3{})), db, settings);
  ASSERT_TRUE(b) << b.error();
  const auto merged = rhot::merge_rigs(a->rig, b->rig, rhot::MergeSettings{}, &da, &db);
  ASSERT_TRUE(merged) << merged.error();
  EXPECT_TRUE(merged->report.shared_cameras.empty());
  EXPECT_GT(merged->report.shared_points, 500);
  // Two independent triangulations of each point, by four cameras 2 to 4 m away each: their
  // difference is a few millimetres; the joint adjustment below settles the rig far better.
  EXPECT_LT(merged->report.point_rms_mm, 5.0);
  EXPECT_TRUE(merged->report.adjusted);
  // Against the truth, after aligning A's frame (camera 0's) to the truth's.
  expect_matches_truth_up_to_frame(merged->rig, truth);
}

TEST(RigMerge, RefusesRigsWithoutASharedCameraOrWithDifferentLenses) {
  const rhot::CameraRig truth = room();
  const rhot::CameraRig a = subset(truth, {0, 1, 2}, rhot::Similarity3{});
  const rhot::CameraRig b = subset(truth, {3, 4, 5}, rhot::Similarity3{});
  EXPECT_EQ(
      rhot::merge_rigs(a, b, {}).error(),
      "merge: the rigs share no camera (cameras are matched by name); calibrate so that at least one camera is in both waves, or give "
      "both sessions' detections of one wave both rigs saw (the same frame numbers)");
  rhot::CameraRig b2 = subset(truth, {2, 3, 4}, rhot::Similarity3{});
  b2.cameras[0].intrinsics.fx *= 1.2;
  EXPECT_EQ(rhot::merge_rigs(a, b2, {}).error(),
            "merge: camera \"" + truth.cameras[2].name +
                "\" is in both rigs with different intrinsics (image size, focal length or principal point differ by more than 1 %)");
}

}  // namespace
