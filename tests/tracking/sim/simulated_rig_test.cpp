#include "tracking/sim/SimulatedRig.h"

#include <cmath>

#include <gtest/gtest.h>

#include "tracking/camera/RigFile.h"

namespace rhot {
namespace {

CameraRig rig(const char* name) {
  auto r = load_rig(std::filesystem::path(RHOT_ASSET_DIR) / "rigs" / name);
  EXPECT_TRUE(r.has_value()) << (r ? "" : r.error());
  return r.value_or(CameraRig{});
}

std::vector<Trajectory> desk_markers(int n, unsigned seed) { return random_trajectories(n, {-0.4, 0.8, -0.85}, {0.4, 1.4, -0.05}, seed); }

TEST(SimulatedRig, SameSeedSameFrames) {
  SimulatedRigSettings s;
  s.dropout = 0.1;
  s.seed = 5;
  SimulatedRig a(rig("seated-4.yaml"), desk_markers(20, 3), s);
  SimulatedRig b(rig("seated-4.yaml"), desk_markers(20, 3), s);
  for (int f = 0; f < 5; ++f) {
    const RigFrame fa = a.next();
    const RigFrame fb = b.next();
    ASSERT_EQ(fa.cameras.size(), fb.cameras.size());
    for (std::size_t c = 0; c < fa.cameras.size(); ++c) {
      ASSERT_EQ(fa.cameras[c].detections.size(), fb.cameras[c].detections.size());
      for (std::size_t d = 0; d < fa.cameras[c].detections.size(); ++d) {
        EXPECT_EQ(fa.cameras[c].detections[d].pixel, fb.cameras[c].detections[d].pixel);
      }
    }
  }
}

TEST(SimulatedRig, NoiseHasTheRequestedSigmaAndDropoutItsRate) {
  SimulatedRigSettings s;
  s.sigma_px = 0.3;
  s.dropout = 0.1;
  SimulatedRig sim(rig("seated-4.yaml"), desk_markers(50, 1), s);
  double sum2 = 0.0;
  long n = 0;
  long visible = 0;
  for (int f = 0; f < 200; ++f) {
    const RigFrame frame = sim.next();
    for (const CameraFrame& cf : frame.cameras) {
      for (std::size_t m = 0; m < frame.truth_position_m.size(); ++m) visible += sim.visible(cf.camera, frame.truth_position_m[m]) ? 1 : 0;
      for (const Detection& d : cf.detections) {
        const Eigen::Vector2d truth = *sim.rig().cameras[static_cast<std::size_t>(cf.camera)].project(
            frame.truth_position_m[static_cast<std::size_t>(d.truth_marker)]);
        sum2 += (d.pixel - truth).squaredNorm();
        n += 2;
      }
    }
  }
  // Tens of thousands of samples: sigma within 2 %, dropout within 1 percentage point.
  EXPECT_NEAR(std::sqrt(sum2 / static_cast<double>(n)), 0.3, 0.006);
  EXPECT_NEAR(1.0 - static_cast<double>(n / 2) / static_cast<double>(visible), 0.1, 0.01);
}

TEST(SimulatedRig, OccludersHideMarkersFromCamerasBehindThem) {
  const CameraRig r = rig("seated-4.yaml");
  Trajectory fixed;
  fixed.centre_m = {0.0, 1.1, -0.45};
  SimulatedRigSettings s;
  s.sigma_px = 0.0;
  SimulatedRig sim(r, {fixed}, s);
  for (int c = 0; c < 4; ++c) EXPECT_TRUE(sim.visible(c, fixed.centre_m));
  // A 3 cm ball 10 cm in front of the marker toward camera 0 hides it from camera 0 only.
  const Eigen::Vector3d toward0 = (r.cameras[0].centre_world() - fixed.centre_m).normalized();
  sim.set_occluders({Occluder{fixed.centre_m + 0.1 * toward0, fixed.centre_m + 0.1 * toward0, 0.03}});
  const RigFrame frame = sim.next();
  EXPECT_TRUE(frame.cameras[0].detections.empty());
  for (int c = 1; c < 4; ++c) EXPECT_EQ(frame.cameras[static_cast<std::size_t>(c)].detections.size(), 1u);
  // A capsule the marker sits on (its surface 0.5 mm away, its axis across the line of sight) does
  // not hide it from the camera on its side.
  const Eigen::Vector3d across = toward0.cross(Eigen::Vector3d::UnitY()).normalized() * 0.05;
  sim.set_occluders({Occluder{fixed.centre_m - toward0 * 0.0205 - across, fixed.centre_m - toward0 * 0.0205 + across, 0.02}});
  EXPECT_TRUE(sim.visible(0, fixed.centre_m));
}

// A world that puts one marker at a place that moves with time, behind a ball at t >= 1 s.
class BallWorld final : public SimulatedWorld {
 public:
  explicit BallWorld(Eigen::Vector3d toward_camera0) : toward0_(std::move(toward_camera0)) {}
  WorldSnapshot at(double t_s) override {
    asked.push_back(t_s);
    const Eigen::Vector3d marker(0.1 * t_s, 1.1, -0.45);
    WorldSnapshot w;
    w.markers_m = {marker};
    if (t_s >= 1.0) w.occluders = {Occluder{marker + 0.1 * toward0_, marker + 0.1 * toward0_, 0.03}};
    return w;
  }
  std::vector<double> asked;

 private:
  Eigen::Vector3d toward0_;
};

TEST(SimulatedRig, AWorldHandedToItIsPhotographedAtTheTimeAsked) {
  const CameraRig r = rig("seated-4.yaml");
  SimulatedRigSettings s;
  s.sigma_px = 0.0;
  SimulatedRig sim(r, {}, s);
  FrameSource& source = sim;
  const Eigen::Vector3d toward0 = (r.cameras[0].centre_world() - Eigen::Vector3d(0.05, 1.1, -0.45)).normalized();
  auto world = std::make_shared<BallWorld>(toward0);
  sim.set_world(world);
  const auto early = source.next(0.5);
  ASSERT_TRUE(early.has_value());
  EXPECT_EQ(world->asked, std::vector<double>{0.5});
  ASSERT_EQ(early->truth_position_m.size(), 1u);
  EXPECT_EQ(early->truth_position_m[0], Eigen::Vector3d(0.05, 1.1, -0.45));
  EXPECT_EQ(early->time_s, 0.5);
  for (const CameraFrame& cf : early->cameras) {
    ASSERT_EQ(cf.detections.size(), 1u) << "camera " << cf.camera;
    const Eigen::Vector2d truth = *r.cameras[static_cast<std::size_t>(cf.camera)].project(early->truth_position_m[0]);
    EXPECT_LT((cf.detections[0].pixel - truth).norm(), 1e-9);
  }
  // At 1 s the world's own occluder (the ball) hides the marker from camera 0: the rig took it.
  const auto late = source.next(1.0);
  ASSERT_TRUE(late.has_value());
  EXPECT_TRUE(late->cameras[0].detections.empty());
  EXPECT_EQ(late->cameras[1].detections.size(), 1u);
}

TEST(SimulatedRig, CamerasSeeOnlyWhatIsInTheirImageAndStampTheirOwnTime) {
  Trajectory behind;
  behind.centre_m = {0.0, 1.0, 5.0};  // behind the seated user, out of every front camera's view
  SimulatedRigSettings s;
  s.camera_skew_s = 0.002;
  SimulatedRig sim(rig("seated-4.yaml"), {behind}, s);
  sim.next();
  const RigFrame f = sim.next();
  EXPECT_TRUE(f.cameras[0].detections.empty());
  EXPECT_TRUE(f.cameras[1].detections.empty());
  EXPECT_DOUBLE_EQ(f.time_s, 1.0 / 90.0);
  EXPECT_DOUBLE_EQ(f.cameras[3].timestamp_s, 1.0 / 90.0 + 0.006);
}

TEST(SimulatedRig, OverlappingBlobsMergeIntoOneDetectionOfTheNearerMarker) {
  const CameraRig r = rig("seated-4.yaml");
  const Eigen::Vector3d near{0.0, 1.1, -0.45};
  const Eigen::Vector3d along = (near - r.cameras[0].centre_world()).normalized();
  const Eigen::Vector3d side = along.cross(Eigen::Vector3d::UnitY()).normalized();
  Trajectory far_one;  // behind `near` as camera 0 sees it, offset sideways by about a pixel
  far_one.centre_m = near + 0.2 * along + 0.001 * side;
  Trajectory near_one;
  near_one.centre_m = near;
  SimulatedRigSettings s;
  s.sigma_px = 0.0;
  s.merge_distance_px = 3.0;
  SimulatedRig sim(r, {far_one, near_one}, s);
  const RigFrame frame = sim.next();
  const Camera& c0 = r.cameras[0];
  const Eigen::Vector2d p_far = *c0.project(far_one.centre_m);
  const Eigen::Vector2d p_near = *c0.project(near_one.centre_m);
  ASSERT_GT((p_far - p_near).norm(), 0.2);
  ASSERT_LT((p_far - p_near).norm(), 3.0);
  ASSERT_EQ(frame.cameras[0].detections.size(), 1u);
  EXPECT_EQ(frame.cameras[0].detections[0].truth_marker, 1) << "credited to the marker nearer the camera";
  EXPECT_LT((frame.cameras[0].detections[0].pixel - 0.5 * (p_far + p_near)).norm(), 1e-9);
  for (std::size_t c = 1; c < 4; ++c) EXPECT_EQ(frame.cameras[c].detections.size(), 2u) << "camera " << c << " sees them apart";
  s.merge_distance_px = 0.0;
  EXPECT_EQ(SimulatedRig(r, {far_one, near_one}, s).next().cameras[0].detections.size(), 2u) << "merging off";
}

TEST(SimulatedRig, WandEndsStayTheirLengthApartInsideTheBox) {
  const Eigen::Vector3d lo(-0.5, 0.6, -0.95);
  const Eigen::Vector3d hi(0.5, 1.6, 0.05);
  const auto ends = wand_trajectories(0.195, lo, hi);
  for (double t = 0.0; t < 60.0; t += 0.37) {
    const Eigen::Vector3d a = ends[0].at(t);
    const Eigen::Vector3d b = ends[1].at(t);
    EXPECT_NEAR((a - b).norm(), 0.195, 1e-12);
    for (int i = 0; i < 3; ++i) {
      EXPECT_GE(a(i), lo(i) - 1e-9);
      EXPECT_LE(a(i), hi(i) + 1e-9);
    }
  }
}

}  // namespace
}  // namespace rhot
