#include "tracking/camera/RigFile.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

namespace rhot {
namespace {

namespace fs = std::filesystem;

fs::path rig_asset(const char* name) { return fs::path(RHOT_ASSET_DIR) / "rigs" / name; }

fs::path temp(const std::string& name) {
  const fs::path d = fs::path(::testing::TempDir()) / "rhot_rig_test";
  fs::create_directories(d);
  return d / name;
}

TEST(RigFile, ShippedRigsLoadAndSeeTheirVolume) {
  struct Expect {
    const char* file;
    std::size_t cameras;
    Eigen::Vector3d centre;
    Eigen::Vector3d size;
  };
  for (const Expect& e : {Expect{"seated-4.yaml", 4, {0, 1.1, -0.45}, {1, 1, 1}}, Expect{"room-8.yaml", 8, {0, 1.0, 0.0}, {3, 1.6, 3}},
                          Expect{"stereo-2.yaml", 2, {0, 1.0, -0.45}, {0.6, 0.6, 0.6}}}) {
    const auto rig = load_rig(rig_asset(e.file));
    ASSERT_TRUE(rig.has_value()) << rig.error();
    EXPECT_EQ(rig->cameras.size(), e.cameras) << e.file;
    ASSERT_TRUE(rig->volume.has_value()) << e.file;
    EXPECT_EQ(rig->volume->centre_m, e.centre) << e.file;
    EXPECT_EQ(rig->volume->size_m, e.size) << e.file;
    for (const Camera& c : rig->cameras) {
      const auto pixel = c.project(e.centre);
      ASSERT_TRUE(pixel.has_value()) << e.file << " " << c.name;
      EXPECT_TRUE(c.in_image(*pixel)) << e.file << " " << c.name << " does not see the volume's centre";
    }
  }
}

TEST(RigFile, SeatedRigCoversTheWholeCubeWithAtLeastTwoCameras) {
  const auto rig = load_rig(rig_asset("seated-4.yaml"));
  ASSERT_TRUE(rig.has_value()) << rig.error();
  for (double x = -0.5; x <= 0.5; x += 0.25) {
    for (double y = 0.6; y <= 1.6; y += 0.25) {
      for (double z = -0.95; z <= 0.05; z += 0.25) {
        int seen = 0;
        for (const Camera& c : rig->cameras) {
          const auto p = c.project({x, y, z});
          seen += (p && c.in_image(*p)) ? 1 : 0;
        }
        EXPECT_GE(seen, 2) << "(" << x << ", " << y << ", " << z << ")";
      }
    }
  }
}

TEST(RigFile, SaveThenLoadIsExactAndOpenCvCanReadIt) {
  const auto rig = load_rig(rig_asset("seated-4.yaml"));
  ASSERT_TRUE(rig.has_value());
  const fs::path out = temp("copy.yaml");
  ASSERT_TRUE(save_rig(*rig, out).has_value());
  const auto back = load_rig(out);
  ASSERT_TRUE(back.has_value()) << back.error();
  ASSERT_EQ(back->cameras.size(), rig->cameras.size());
  for (std::size_t i = 0; i < rig->cameras.size(); ++i) {
    EXPECT_EQ(back->cameras[i].name, rig->cameras[i].name);
    EXPECT_EQ(back->cameras[i].intrinsics.fx, rig->cameras[i].intrinsics.fx);
    EXPECT_LT((back->cameras[i].centre_world() - rig->cameras[i].centre_world()).norm(), 1e-12);
  }
  ASSERT_TRUE(back->volume.has_value());
  EXPECT_EQ(back->volume->centre_m, rig->volume->centre_m);
  EXPECT_EQ(back->volume->size_m, rig->volume->size_m);
  // Plain OpenCV reads the matrices.
  cv::FileStorage fs(out.string(), cv::FileStorage::READ);
  cv::Mat k;
  fs["cameras"][0]["camera_matrix"] >> k;
  EXPECT_EQ(k.rows, 3);
  EXPECT_DOUBLE_EQ(k.at<double>(0, 0), rig->cameras[0].intrinsics.fx);
}

// Writes the seated rig with one substitution applied to its text.
std::string error_after(const std::string& pattern, const std::string& replacement) {
  std::ifstream in(rig_asset("seated-4.yaml"));
  std::ostringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  const std::string changed = std::regex_replace(text, std::regex(pattern), replacement, std::regex_constants::format_first_only);
  EXPECT_NE(changed, text) << "pattern " << pattern << " did not match";
  const fs::path p = temp("bad.yaml");
  std::ofstream(p) << changed;
  const auto r = load_rig(p);
  return r ? std::string("loaded") : r.error().substr(p.string().size() + 2);
}

TEST(RigFile, MalformedAndInconsistentRigsAreRefusedWithTheField) {
  EXPECT_EQ(load_rig(temp("none.yaml")).error(), temp("none.yaml").string() + ": rig file not found");
  EXPECT_EQ(error_after("image_width: 1280", "image_width: wide"), "cameras[0] (\"front-left\").image_width: expected an integer");
  EXPECT_EQ(error_after("image_height: 720", "image_height: -720"),
            "cameras[0] (\"front-left\").image_width/image_height: expected 1 to 65536 pixels, got 1280x-720");
  EXPECT_EQ(error_after("data: \\[ 900.0, 0.0, 639.5", "data: [ -900.0, 0.0, 639.5"),
            "cameras[0] (\"front-left\").camera_matrix: focal lengths fx and fy must be positive");
  EXPECT_EQ(error_after("data: \\[ 900.0, 0.0, 639.5", "data: [ 900.0, 0.0, 6390.5"),
            "cameras[0] (\"front-left\").camera_matrix: the principal point (6390.500000, 359.500000) lies outside the "
            "1280x720 image");
  EXPECT_EQ(error_after("rows: 1\n         cols: 5\n         dt: d\n         data: \\[ -0.05, 0.01, 0.0, 0.0, 0.0 \\]",
                        "rows: 1\n         cols: 4\n         dt: d\n         data: [ -0.05, 0.01, 0.0, 0.0 ]"),
            "cameras[0] (\"front-left\").distortion_coefficients: expected 1x5, got 1x4");
  EXPECT_EQ(error_after("data: \\[ -0.728199992693", "data: [ -0.9"),
            "cameras[0] (\"front-left\").rotation: not a rotation matrix (expected orthonormal with determinant +1)");
  EXPECT_EQ(error_after("data: \\[ 0.308414114552", "data: [ .nan"),
            "cameras[0] (\"front-left\").translation: contains a value that is not finite");
  EXPECT_EQ(error_after("name: \"front-right\"", "name: \"front-left\""),
            "cameras[1] (\"front-left\").name: duplicate name \"front-left\"");
  EXPECT_EQ(error_after("      translation: !!opencv-matrix", "      translatoin: !!opencv-matrix"),
            "cameras[0] (\"front-left\").translation: missing");
  EXPECT_EQ(error_after("cameras:", "kameras:"), "cameras: missing");
  EXPECT_EQ(error_after("volume_size:", "volume_sighs:"), "volume_size: missing (volume_centre needs it)");
  EXPECT_EQ(error_after("volume_centre:", "volume_center:"), "volume_centre: missing (volume_size needs it)");
  EXPECT_EQ(error_after("data: \\[ 1.0, 1.0, 1.0 \\]", "data: [ 1.0, -1.0, 1.0 ]"), "volume_size: every side must be positive and finite");
  EXPECT_EQ(error_after("data: \\[ 1.0, 1.0, 1.0 \\]", "data: [ 1.0, 1.0 ]"), "volume_size: expected an !!opencv-matrix of 3x1 numbers");
  EXPECT_EQ(error_after("data: \\[ 0.0, 1.1, -0.45 \\]", "data: [ 0.0, .inf, -0.45 ]"),
            "volume_centre: contains a value that is not finite");
  const auto junk = error_after("%YAML:1.0", "{{{ not yaml");
  EXPECT_NE(junk, "loaded");
}

// A rig file of `count` cameras of seated-4's model, all turned alike (the identity rotation): the
// first at the origin and each next one 10 cm further along -X, or all at the origin with
// `at_origin`; without any rotation and translation where `poses` is false.
std::string rig_text(std::size_t count, bool at_origin, bool poses = true) {
  std::ostringstream y;
  y << "%YAML:1.0\n---\nrig_name: \"generated\"\ncameras:\n";
  for (std::size_t i = 0; i < count; ++i) {
    y << "   -\n      name: \"cam" << i << "\"\n      image_width: 1280\n      image_height: 720\n"
      << "      camera_matrix: !!opencv-matrix\n         rows: 3\n         cols: 3\n         dt: d\n"
      << "         data: [ 900.0, 0.0, 639.5, 0.0, 900.0, 359.5, 0.0, 0.0, 1.0 ]\n"
      << "      distortion_coefficients: !!opencv-matrix\n         rows: 1\n         cols: 5\n         dt: d\n"
      << "         data: [ -0.05, 0.01, 0.0, 0.0, 0.0 ]\n";
    if (!poses) continue;
    y << "      rotation: !!opencv-matrix\n         rows: 3\n         cols: 3\n         dt: d\n"
      << "         data: [ 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0 ]\n"
      << "      translation: !!opencv-matrix\n         rows: 3\n         cols: 1\n         dt: d\n"
      << "         data: [ " << (at_origin ? 0.0 : 0.1 * static_cast<double>(i)) << ", 0.0, 0.0 ]\n";
  }
  return y.str();
}

fs::path write_rig_text(const std::string& name, const std::string& text) {
  const fs::path p = temp(name);
  std::ofstream(p) << text;
  return p;
}

TEST(RigFile, EveryShippedRigIsWithinTheCameraCap) {
  std::size_t largest = 0;
  for (const fs::directory_entry& e : fs::directory_iterator(fs::path(RHOT_ASSET_DIR) / "rigs")) {
    if (e.path().extension() != ".yaml") continue;
    const auto rig = load_rig(e.path());
    ASSERT_TRUE(rig.has_value()) << rig.error();
    largest = std::max(largest, rig->cameras.size());
  }
  EXPECT_EQ(largest, 54u) << "seed-wiimote-54.yaml";
  EXPECT_LT(largest, kMaxRigCameras);
}

TEST(RigFile, MoreCamerasThanTheCapAreRefusedWhenLoadedOrSaved) {
  const fs::path most = write_rig_text("most.yaml", rig_text(kMaxRigCameras, false));
  const auto loaded = load_rig(most);
  ASSERT_TRUE(loaded.has_value()) << loaded.error();
  EXPECT_EQ(loaded->cameras.size(), 256u);

  const fs::path too_many = write_rig_text("too_many.yaml", rig_text(kMaxRigCameras + 1, false));
  EXPECT_EQ(load_rig(too_many).error(), too_many.string() + ": cameras: a rig may have at most 256 cameras, got 257");
  EXPECT_EQ(load_rig_intrinsics(too_many).error(), too_many.string() + ": cameras: a rig may have at most 256 cameras, got 257");

  CameraRig rig = *loaded;
  Camera extra = rig.cameras.back();
  extra.name = "one-too-many";
  extra.cam_from_world.translation.x() -= 0.1;
  rig.cameras.push_back(extra);
  EXPECT_EQ(check_rig(rig).error(), "cameras: a rig may have at most 256 cameras, got 257");
  const fs::path out = temp("not_saved.yaml");
  EXPECT_EQ(save_rig(rig, out).error(), out.string() + ": not saved: cameras: a rig may have at most 256 cameras, got 257");
}

// One file of every camera's intrinsics, each camera at the origin as `rhot-calib intrinsics`
// writes it: not a rig to track with, but read for its intrinsics it is whole.
TEST(RigFile, ReadForIntrinsicsOnlyTheCamerasPosesAreIgnored) {
  const fs::path at_origin = write_rig_text("at_origin.yaml", rig_text(3, true));
  EXPECT_EQ(load_rig(at_origin).error(),
            at_origin.string() + ": cameras[1] (\"cam1\").translation: same position as cameras[0] (\"cam0\")");
  const auto intrinsics = load_rig_intrinsics(at_origin);
  ASSERT_TRUE(intrinsics.has_value()) << intrinsics.error();
  ASSERT_EQ(intrinsics->cameras.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    const Camera& c = intrinsics->cameras[i];
    EXPECT_EQ(c.name, "cam" + std::to_string(i));
    EXPECT_EQ(c.intrinsics.width_px, 1280);
    EXPECT_EQ(c.intrinsics.fx, 900.0);
    EXPECT_EQ(c.intrinsics.cy, 359.5);
    EXPECT_EQ(c.intrinsics.distortion[0], -0.05);
    EXPECT_TRUE(c.cam_from_world.translation.isZero());
    EXPECT_TRUE(c.cam_from_world.rotation.isApprox(Eigen::Quaterniond::Identity()));
  }
  EXPECT_TRUE(check_rig_intrinsics(*intrinsics).has_value());
  EXPECT_FALSE(check_rig(*intrinsics).has_value());

  // No poses at all.
  const fs::path no_poses = write_rig_text("no_poses.yaml", rig_text(2, true, false));
  EXPECT_EQ(load_rig(no_poses).error(), no_poses.string() + ": cameras[0] (\"cam0\").rotation: missing");
  ASSERT_TRUE(load_rig_intrinsics(no_poses).has_value()) << load_rig_intrinsics(no_poses).error();

  // The intrinsics themselves are checked as ever.
  std::string text = rig_text(2, true);
  text.replace(text.find("900.0"), 5, "-900.0");
  const fs::path bad = write_rig_text("bad_intrinsics.yaml", text);
  EXPECT_EQ(load_rig_intrinsics(bad).error(),
            bad.string() + ": cameras[0] (\"cam0\").camera_matrix: focal lengths fx and fy must be positive");
}

}  // namespace
}  // namespace rhot
