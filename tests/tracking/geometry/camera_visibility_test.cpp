// CameraVisibility: a camera left out of a point's set never sees the point, and the sets do
// leave cameras out.

#include <filesystem>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "tracking/camera/RigFile.h"
#include "tracking/geometry/CameraVisibility.h"

namespace rhot {
namespace {

struct Tally {
  long seen = 0;     // (point, camera) pairs where the camera sees the point
  long missed = 0;   // ... and the point's set leaves the camera out: must stay 0
  long skipped = 0;  // pairs the set leaves out
  long pairs = 0;
};

// Random points over the grid's box, every camera asked.
Tally check(const CameraRig& rig, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int points, unsigned seed) {
  const CameraVisibility visibility(rig.cameras, lo, hi);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Tally t;
  for (int n = 0; n < points; ++n) {
    const Eigen::Vector3d p = lo + Eigen::Vector3d{u(rng), u(rng), u(rng)}.cwiseProduct(hi - lo);
    const CameraVisibility::CameraSet set = visibility.cameras_at(p);
    for (std::size_t c = 0; c < rig.cameras.size(); ++c) {
      ++t.pairs;
      const auto pixel = rig.cameras[c].project(p);
      const bool sees = pixel && rig.cameras[c].in_image(*pixel);
      const bool kept = CameraVisibility::contains(set, c);
      t.seen += sees ? 1 : 0;
      t.missed += (sees && !kept) ? 1 : 0;
      t.skipped += kept ? 0 : 1;
    }
  }
  return t;
}

TEST(CameraVisibility, NoCameraThatSeesAPointIsLeftOutOnTheStageAndTheRoom) {
  for (const char* name : {"stage-32.yaml", "room-8.yaml"}) {
    SCOPED_TRACE(name);
    const auto rig = load_rig(std::filesystem::path(RHOT_ASSET_DIR) / "rigs" / name);
    ASSERT_TRUE(rig.has_value()) << (rig ? "" : rig.error());
    const TrackingVolume v = rig->volume.value();
    // The volume twice over, as matching's seeds may lie.
    const Tally t = check(*rig, v.centre_m - v.size_m, v.centre_m + v.size_m, 4000, 3);
    EXPECT_EQ(t.missed, 0) << "of " << t.seen << " views";
    // Cameras that cannot see the point are left out: on the stage, at least a fifth of all pairs.
    EXPECT_GT(t.skipped, t.pairs / 5) << t.skipped << " of " << t.pairs << " left out, " << t.seen << " seen";
  }
}

TEST(CameraVisibility, AStronglyDistortedWideCameraKeepsEveryPointItSees) {
  CameraRig rig;
  Camera wide;
  // A wide webcam's barrel distortion: at the image corners, points 20 % further out than a
  // pinhole would put them.
  wide.intrinsics = {1280, 720, 600.0, 600.0, 650.0, 350.0, {-0.28, 0.08, 0.001, -0.002, 0.0}};
  wide.cam_from_world = cam_from_world_look_at({0.0, 2.0, 2.0}, {0.3, 0.5, 0.0});
  rig.cameras.push_back(wide);
  const Tally t = check(rig, {-3.0, -1.0, -3.0}, {3.0, 3.0, 3.0}, 20000, 5);
  EXPECT_GT(t.seen, 2000);
  EXPECT_EQ(t.missed, 0) << "of " << t.seen << " views";
  EXPECT_GT(t.skipped, t.pairs / 4);
}

// A lens model that folds back (its image corners are beyond what the model can reach): the
// camera's border does not undistort, so it is never left out.
TEST(CameraVisibility, ACameraWhoseBorderDoesNotUndistortIsNeverLeftOut) {
  CameraRig rig;
  Camera folded;
  folded.intrinsics = {1280, 720, 420.0, 420.0, 650.0, 350.0, {-0.32, 0.12, 0.0, 0.0, -0.02}};
  folded.cam_from_world = cam_from_world_look_at({0.0, 2.0, 2.0}, {0.3, 0.5, 0.0});
  rig.cameras.push_back(folded);
  const Tally t = check(rig, {-3.0, -1.0, -3.0}, {3.0, 3.0, 3.0}, 2000, 7);
  EXPECT_EQ(t.skipped, 0);
}

TEST(CameraVisibility, APointOutsideTheGridOrNotANumberHasEveryCamera) {
  const auto rig = load_rig(std::filesystem::path(RHOT_ASSET_DIR) / "rigs" / "room-8.yaml");
  ASSERT_TRUE(rig.has_value()) << (rig ? "" : rig.error());
  const CameraVisibility visibility(rig->cameras, {-1.0, 0.0, -1.0}, {1.0, 2.0, 1.0});
  EXPECT_EQ(visibility.cameras_at({5.0, 1.0, 0.0}), CameraVisibility::kAllCameras);
  EXPECT_EQ(visibility.cameras_at({0.0, -0.5, 0.0}), CameraVisibility::kAllCameras);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(visibility.cameras_at({nan, 1.0, 0.0}), CameraVisibility::kAllCameras);
  EXPECT_EQ(CameraVisibility().cameras_at({0.0, 1.0, 0.0}), CameraVisibility::kAllCameras);
  // An empty or inverted box makes no grid.
  EXPECT_EQ(CameraVisibility(rig->cameras, {1.0, 0.0, 0.0}, {-1.0, 1.0, 1.0}).cameras_at({0.0, 0.5, 0.5}), CameraVisibility::kAllCameras);
  // Cameras past the 64th are never left out.
  EXPECT_TRUE(CameraVisibility::contains(0, 64));
  EXPECT_FALSE(CameraVisibility::contains(0, 63));
}

}  // namespace
}  // namespace rhot
