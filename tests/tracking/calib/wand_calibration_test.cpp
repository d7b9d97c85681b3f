// The wand calibration against the simulated rig's truth: camera centres and rotations after a
// similarity alignment, residuals against what the pixel noise allows, the wand's length, and the
// bad inputs it must refuse with a message. The calibration is handed the cameras' intrinsics
// only (every pose at the origin), never the truth it is measured against.

#include "tracking/calib/WandCalibration.h"

#include <cmath>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "tests/tracking/calib/CalibTestSupport.h"

#include "tracking/calib/Similarity.h"
#include "tracking/camera/RigFile.h"
#include "tracking/sim/CalibrationSessions.h"

namespace {

rhot::CameraRig load(const std::string& name) {
  auto rig = rhot::load_rig(std::string(RHOT_ASSET_DIR) + "/rigs/" + name + ".yaml");
  EXPECT_TRUE(rig) << rig.error();
  return *rig;
}

// The cameras as a user's intrinsics-only files give them (`rhot-calib intrinsics` writes each at
// the origin, looking along +Z): the calibration must find every pose from the wave alone.
using rhot::test::without_poses;

struct Agreement {
  double centre_rms_mm = 0.0;
  double rotation_max_deg = 0.0;
  double scale = 1.0;
};

// The estimate moved onto the truth by the similarity that best maps its camera centres.
Agreement compare(const rhot::CameraRig& estimate, const rhot::CameraRig& truth) {
  std::vector<Eigen::Vector3d> from, to;
  for (std::size_t c = 0; c < truth.cameras.size(); ++c) {
    from.push_back(estimate.cameras[c].centre_world());
    to.push_back(truth.cameras[c].centre_world());
  }
  const auto fit = rhot::fit_similarity(from, to, true);
  EXPECT_TRUE(fit);
  Agreement a;
  a.scale = fit->scale;
  double sq = 0;
  for (std::size_t c = 0; c < truth.cameras.size(); ++c) {
    const rhot::Camera moved = rhot::transform_camera(estimate.cameras[c], *fit);
    sq += (moved.centre_world() - truth.cameras[c].centre_world()).squaredNorm();
    a.rotation_max_deg = std::max(a.rotation_max_deg,
                                  moved.cam_from_world.rotation.angularDistance(truth.cameras[c].cam_from_world.rotation) * 180.0 / M_PI);
  }
  a.centre_rms_mm = std::sqrt(sq / static_cast<double>(truth.cameras.size())) * 1000.0;
  return a;
}

// What Gaussian noise of sigma per axis leaves after a least-squares fit: the residual vector's
// RMS norm is sigma sqrt(2) sqrt(1 - parameters / residuals).
double noise_floor_px(const rhot::WandReport& r, double sigma, int cameras) {
  int observations = 0;
  for (const auto& c : r.cameras) observations += c.inliers;
  const double parameters = 3.0 * r.points + 6.0 * cameras - 7.0;
  return sigma * std::sqrt(2.0) * std::sqrt(1.0 - parameters / (2.0 * observations));
}

rhot::Detections wand_session(const rhot::CameraRig& rig, int frames, double sigma, unsigned seed, double dropout = 0.0,
                              double strays = 0.0, double outliers = 0.0) {
  rhot::WandSession session;
  session.frames = frames;
  session.wand_length_m = 0.5;
  const rhot::TrackingVolume box = rhot::session_box(rig);
  session.box_centre_m = box.centre_m;
  session.box_size_m = box.size_m;
  rhot::SessionNoise noise;
  noise.rig.sigma_px = sigma;
  noise.rig.seed = seed;
  noise.rig.dropout = dropout;
  noise.strays = strays;
  noise.outliers = outliers;
  return rhot::simulate_wand_session(rig, session, noise);
}

TEST(WandCalibration, SeatedFourFromAWandMatchesTheTruth) {
  const rhot::CameraRig truth = load("seated-4");
  const rhot::Detections d = wand_session(truth, 1000, 0.3, 3);
  rhot::WandSettings settings;
  settings.wand_length_m = 0.5;
  const auto result = rhot::calibrate_wand(without_poses(truth), d, settings);
  ASSERT_TRUE(result) << result.error();
  const Agreement a = compare(result->rig, truth);
  EXPECT_LT(a.centre_rms_mm, 1.0);
  EXPECT_LT(a.rotation_max_deg, 0.03);
  EXPECT_NEAR(a.scale, 1.0, 0.001) << "the wand's scale";
  const rhot::WandReport& r = result->report;
  EXPECT_TRUE(r.metric);
  // The length error per frame is the ends' triangulation noise: within 10 % of the true rig's.
  const double truth_wand_rms = rhot::wand_length_rms_mm(truth, d, 0.5);
  EXPECT_LE(r.wand_rms_mm, 1.1 * truth_wand_rms);
  EXPECT_LT(std::abs(r.wand_mean_mm), 0.05);
  EXPECT_GT(r.wand_frames, 500);
  const double floor = noise_floor_px(r, 0.3, 4);
  EXPECT_NEAR(r.rms_px, floor, 0.1 * floor);
  ASSERT_EQ(r.cameras.size(), 4u);
  for (const auto& c : r.cameras) {
    EXPECT_NEAR(c.rms_px, floor, 0.1 * floor) << c.name;
    EXPECT_GT(c.frames_seen, 300) << c.name;
  }
  // Until `world`, the world is camera 0's in rhot's axes: camera 0 at the origin looking along -Z.
  EXPECT_LT(result->rig.cameras[0].centre_world().norm(), 1e-9);
  const Eigen::Vector3d forward = result->rig.cameras[0].cam_from_world.rotation.conjugate() * Eigen::Vector3d::UnitZ();
  EXPECT_NEAR(forward.z(), -1.0, 1e-9);
  EXPECT_TRUE(rhot::check_rig(result->rig));
}

TEST(WandCalibration, RoomEightWithDropoutStraysAndOutliers) {
  const rhot::CameraRig truth = load("room-8");
  const rhot::Detections d = wand_session(truth, 1000, 0.3, 5, 0.1, 0.05, 0.01);
  rhot::WandSettings settings;
  settings.wand_length_m = 0.5;
  const auto result = rhot::calibrate_wand(without_poses(truth), d, settings);
  ASSERT_TRUE(result) << result.error();
  const Agreement a = compare(result->rig, truth);
  EXPECT_LT(a.centre_rms_mm, 1.0);
  EXPECT_LT(a.rotation_max_deg, 0.03);
  const rhot::WandReport& r = result->report;
  // The same session without the strays and outliers (they come from a random stream of their
  // own), triangulated with the true rig.
  EXPECT_LE(r.wand_rms_mm, 1.1 * rhot::wand_length_rms_mm(truth, wand_session(truth, 1000, 0.3, 5, 0.1), 0.5));
  EXPECT_GT(r.outliers, 0) << "1 % of detections were displaced by 3 to 30 px";
  const double floor = noise_floor_px(r, 0.3, 8);
  EXPECT_NEAR(r.rms_px, floor, 0.1 * floor);
  // The graph: room-8's cameras face each other across the room; every one shares points with
  // several others.
  std::vector<int> degree(8, 0);
  for (const auto& e : r.graph) {
    if (e.shared_points < 15) continue;
    ++degree[static_cast<std::size_t>(e.a)];
    ++degree[static_cast<std::size_t>(e.b)];
  }
  for (int c = 0; c < 8; ++c) EXPECT_GE(degree[static_cast<std::size_t>(c)], 2) << truth.cameras[static_cast<std::size_t>(c)].name;
}

TEST(WandCalibration, OneMarkerWithoutAWandIsRightUpToScale) {
  const rhot::CameraRig truth = load("seated-4");
  rhot::WandSession session;
  session.frames = 800;
  session.markers = 1;
  session.box_centre_m = truth.volume->centre_m;
  session.box_size_m = truth.volume->size_m;
  rhot::SessionNoise noise;
  noise.rig.seed = 9;
  noise.strays = 0.05;  // a stray blob makes its camera's frame ambiguous: dropped, not guessed
  const rhot::Detections d = rhot::simulate_wand_session(truth, session, noise);
  const auto result = rhot::calibrate_wand(without_poses(truth), d, rhot::WandSettings{});
  ASSERT_TRUE(result) << result.error();
  EXPECT_FALSE(result->report.metric);
  EXPECT_GT(result->report.ambiguous, 0);
  ASSERT_FALSE(result->report.warnings.empty());
  EXPECT_NE(result->report.warnings.back().find("not metric"), std::string::npos);
  const Agreement a = compare(result->rig, truth);
  EXPECT_LT(a.centre_rms_mm, 1.0);
  EXPECT_LT(a.rotation_max_deg, 0.03);
  const double floor = noise_floor_px(result->report, 0.3, 4);
  EXPECT_NEAR(result->report.rms_px, floor, 0.1 * floor);
}

TEST(WandCalibration, RefinesAFocalLengthThatWasWrong) {
  const rhot::CameraRig truth = load("seated-4");
  const rhot::Detections d = wand_session(truth, 800, 0.3, 11);
  rhot::CameraRig start = without_poses(truth);
  for (std::size_t c = 0; c < start.cameras.size(); ++c) {
    const double wrong = c % 2 == 0 ? 1.03 : 0.97;
    start.cameras[c].intrinsics.fx *= wrong;
    start.cameras[c].intrinsics.fy *= wrong;
  }
  rhot::WandSettings settings;
  settings.wand_length_m = 0.5;
  settings.refine_focal = true;
  const auto result = rhot::calibrate_wand(start, d, settings);
  ASSERT_TRUE(result) << result.error();
  for (std::size_t c = 0; c < truth.cameras.size(); ++c) {
    EXPECT_NEAR(result->rig.cameras[c].intrinsics.fx / truth.cameras[c].intrinsics.fx, 1.0, 0.003) << truth.cameras[c].name;
  }
  EXPECT_LT(compare(result->rig, truth).centre_rms_mm, 2.0);
}

TEST(WandCalibration, RefusesDetectionsOffTheImage) {
  const rhot::CameraRig truth = load("seated-4");
  rhot::Detections d = wand_session(truth, 200, 0.3, 1);
  d.frames[5].observations[0].pixel = {1400.0, 100.0};
  const int camera = d.frames[5].observations[0].camera;
  const auto result = rhot::calibrate_wand(without_poses(truth), d, rhot::WandSettings{});
  ASSERT_FALSE(result);
  EXPECT_EQ(result.error(), "camera " + std::to_string(camera) + " (\"" + truth.cameras[static_cast<std::size_t>(camera)].name +
                                "\"): 1 detections lie outside its 1280x720 image (first: frame " + std::to_string(d.frames[5].frame) +
                                " at (1400.0, 100.0)); are the detections' cameras in the rig's order?");
}

TEST(WandCalibration, RefusesACameraTheRigLacksAndTooFewFrames) {
  const rhot::CameraRig truth = load("stereo-2");
  rhot::Detections d = wand_session(truth, 200, 0.3, 1);
  d.frames[0].observations.push_back({4, {10, 10}, 0});
  d.camera_count = 5;
  EXPECT_EQ(rhot::calibrate_wand(without_poses(truth), d, rhot::WandSettings{}).error(),
            "the detections name camera 4 but the rig has only 2 cameras (0 to 1)");
  d.camera_count = 2;  // understated: the observation itself is checked
  EXPECT_EQ(rhot::calibrate_wand(without_poses(truth), d, rhot::WandSettings{}).error(),
            "frame " + std::to_string(d.frames[0].frame) + ": a detection names camera 4 but the rig has cameras 0 to 1");
  const rhot::Detections few = wand_session(truth, 10, 0.3, 1);
  EXPECT_EQ(rhot::calibrate_wand(without_poses(truth), few, rhot::WandSettings{}).error(),
            "too few frames: 20 marker positions were seen by two cameras or more (need 30)");
}

TEST(WandCalibration, NamesTheCamerasAGraphInPiecesCannotConnect) {
  const rhot::CameraRig truth = load("seated-4");
  rhot::Detections d = wand_session(truth, 600, 0.3, 2);
  // Cameras 0 and 1 only ever see the marker when 2 and 3 do not, and the other way round.
  for (rhot::DetectionFrame& f : d.frames) {
    const bool front = f.frame % 2 == 0;
    std::erase_if(f.observations, [front](const rhot::MarkerObservation& o) { return (o.camera < 2) != front; });
  }
  const auto result = rhot::calibrate_wand(without_poses(truth), d, rhot::WandSettings{});
  ASSERT_FALSE(result);
  EXPECT_EQ(result.error(),
            "the cameras do not form one connected graph (an edge needs 15 shared points): groups {front-left, front-right} {back-left, "
            "back-right}; wave where cameras of different groups see the marker at once, or calibrate the groups apart and merge them");
}

TEST(WandCalibration, RefusesAPlanarWave) {
  const rhot::CameraRig truth = load("seated-4");
  rhot::WandSession session;
  session.frames = 600;
  session.box_centre_m = truth.volume->centre_m;
  session.box_size_m = {1.0, 0.0, 1.0};  // the wand stays level at one height
  const rhot::Detections d = rhot::simulate_wand_session(truth, session, rhot::SessionNoise{});
  const auto result = rhot::calibrate_wand(without_poses(truth), d, rhot::WandSettings{});
  ASSERT_FALSE(result);
  EXPECT_EQ(result.error().rfind("the wave is nearly planar", 0), 0u) << result.error();
}

TEST(WandCalibration, SaysWhenTwoCameraStreamsAreSwapped) {
  // Two cameras of different lenses: their detections swapped against the rig's order.
  rhot::CameraRig truth = load("seated-4");
  truth.cameras[1].intrinsics.fx = truth.cameras[1].intrinsics.fy = 600.0;
  truth.cameras[1].intrinsics.distortion = {-0.2, 0.05, 0, 0, 0};
  const rhot::Detections d = wand_session(truth, 600, 0.3, 4);
  rhot::Detections swapped = d;
  for (rhot::DetectionFrame& f : swapped.frames) {
    for (rhot::MarkerObservation& o : f.observations) {
      if (o.camera == 1 || o.camera == 2) o.camera = 3 - o.camera;
    }
  }
  rhot::WandSettings settings;
  settings.wand_length_m = 0.5;
  ASSERT_TRUE(rhot::calibrate_wand(without_poses(truth), d, settings));
  const auto result = rhot::calibrate_wand(without_poses(truth), swapped, settings);
  ASSERT_FALSE(result);
  EXPECT_NE(result.error().find("are the detections' camera streams in the rig's order"), std::string::npos) << result.error();
}

TEST(WandCalibration, SettingsAreChecked) {
  rhot::WandSettings s;
  s.wand_length_m = std::nan("");
  EXPECT_EQ(s.check().error(), "wand length: expected 1 mm to 10 m, got nan mm");
  s.wand_length_m = 10.0;
  EXPECT_TRUE(s.check());
  s.wand_length_m = 10.001;
  EXPECT_EQ(s.check().error(), "wand length: expected 1 mm to 10 m, got 10001.000 mm");
  s.wand_length_m = 0.5;
  s.marker_b = 0;
  EXPECT_EQ(s.check().error(), "wand markers: expected two different non-negative ids");
}

}  // namespace
