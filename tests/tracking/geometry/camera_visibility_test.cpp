// CameraVisibility: a camera left out of a point's set never sees the point, and the sets do
// leave cameras out.

#include <filesystem>
#include <limits>
#include <numbers>
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
    // Cameras that cannot see the point are left out: at least a fifth of all pairs.
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

// Points on rays through the image's border and corners, at any depth: the view's edge, where a
// pyramid or a sphere drawn too tight would leave the camera out.
TEST(CameraVisibility, PointsOnTheImagesBorderKeepTheirCamera) {
  const auto rig = load_rig(std::filesystem::path(RHOT_ASSET_DIR) / "rigs" / "room-8.yaml");
  ASSERT_TRUE(rig.has_value()) << (rig ? "" : rig.error());
  const TrackingVolume v = rig->volume.value();
  const CameraVisibility visibility(rig->cameras, v.centre_m - v.size_m, v.centre_m + v.size_m);
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  long asked = 0;
  for (std::size_t c = 0; c < rig->cameras.size(); ++c) {
    const Camera& camera = rig->cameras[c];
    const double w = camera.intrinsics.width_px - 0.5, h = camera.intrinsics.height_px - 0.5;
    for (int n = 0; n < 2000; ++n) {
      // A pixel on the border (a corner one time in eight), a depth of 0.2 to 8 m.
      const double t = u(rng);
      const int edge = n % 4;
      Eigen::Vector2d pixel = edge == 0   ? Eigen::Vector2d{-0.5 + t * (w + 0.5), -0.5}
                              : edge == 1 ? Eigen::Vector2d{-0.5 + t * (w + 0.5), h - 1e-6}
                              : edge == 2 ? Eigen::Vector2d{-0.5, -0.5 + t * (h + 0.5)}
                                          : Eigen::Vector2d{w - 1e-6, -0.5 + t * (h + 0.5)};
      if (n % 8 == 0) pixel = {n % 16 == 0 ? -0.5 : w - 1e-6, n % 32 == 0 ? -0.5 : h - 1e-6};
      const Eigen::Vector3d p = camera.centre_world() + (0.2 + 7.8 * u(rng)) * camera.ray_world(pixel);
      const auto back = camera.project(p);
      if (!back || !camera.in_image(*back)) continue;  // rounded off the image
      ++asked;
      EXPECT_TRUE(CameraVisibility::contains(visibility.cameras_at(p), c)) << "camera " << c << ", pixel " << pixel.transpose();
    }
  }
  EXPECT_GT(asked, 8000);
}

// A lens whose radial distortion folds back (k2 < 0, as a calibration often gives): points 65 to
// 67 degrees off its axis, far outside its view, are distorted back into its image, and the camera
// must stay in their sets.
TEST(CameraVisibility, ALensThatFoldsKeepsThePointsItFoldsIntoItsImage) {
  CameraRig rig;
  Camera camera;
  camera.intrinsics = {640, 480, 520.0, 520.0, 320.0, 240.0, {0.02, -0.04, 0.0, 0.0, 0.0}};
  camera.cam_from_world = cam_from_world_look_at({0.0, 1.5, 3.0}, {0.0, 1.0, 0.0});
  rig.cameras.push_back(camera);
  const CameraVisibility visibility(rig.cameras, {-4.0, -1.0, -4.0}, {4.0, 4.0, 6.0});
  const Rigid3d world_from_cam = camera.cam_from_world.inverse();
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  long folded = 0;
  for (int n = 0; n < 4000; ++n) {
    const double r = 2.0 + 0.5 * u(rng), angle = 2.0 * std::numbers::pi * u(rng), z = 0.1 + 0.6 * u(rng);
    const Eigen::Vector3d p = world_from_cam * Eigen::Vector3d{r * std::cos(angle) * z, r * std::sin(angle) * z, z};
    const auto pixel = camera.project(p);
    if (!pixel || !camera.in_image(*pixel)) continue;
    ++folded;
    EXPECT_TRUE(CameraVisibility::contains(visibility.cameras_at(p), 0)) << "a folded point at r " << r;
  }
  EXPECT_GT(folded, 100) << "points distorted back into the image";
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
