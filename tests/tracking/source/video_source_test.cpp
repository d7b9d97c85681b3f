// The video source on image sequences written into a temporary folder: images drawn from the
// simulated rig's detections (sigma 0, so each drawn spot sits exactly at its marker's projection),
// read back through OpenCV's CAP_IMAGES and the blob detector, matched and triangulated.

#include "tracking/media/Media.h"
#include "tracking/source/VideoSource.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "tracking/camera/RigFile.h"
#include "tracking/geometry/Matching.h"
#include "tracking/sim/SimulatedRig.h"
#include "tracking/sim/SyntheticImages.h"

namespace rhot {
namespace {

namespace fs = std::filesystem;

CameraRig seated_rig() {
  auto r = load_rig(fs::path(RHOT_ASSET_DIR) / "rigs" / "seated-4.yaml");
  EXPECT_TRUE(r.has_value()) << (r ? "" : r.error());
  return r.value_or(CameraRig{});
}

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::path(::testing::TempDir()) / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string frame_file(const fs::path& dir, std::size_t camera, int frame) {
  char name[64];
  std::snprintf(name, sizeof(name), "cam%zu_%04d.png", camera, frame);
  return (dir / name).string();
}

std::vector<std::string> patterns(const fs::path& dir, std::size_t cameras) {
  std::vector<std::string> out;
  for (std::size_t c = 0; c < cameras; ++c) out.push_back((dir / ("cam" + std::to_string(c) + "_%04d.png")).string());
  return out;
}

// Simulates `frames` frames of 20 markers in front of the rig and writes each camera's image.
std::vector<RigFrame> write_sequence(const CameraRig& rig, const fs::path& dir, int frames) {
  SimulatedRigSettings s;
  s.sigma_px = 0.0;
  SimulatedRig sim(rig, random_trajectories(20, {-0.4, 0.8, -0.85}, {0.4, 1.4, -0.05}, 4), s);
  std::vector<RigFrame> truth;
  for (int f = 0; f < frames; ++f) {
    truth.push_back(sim.next());
    for (std::size_t c = 0; c < rig.cameras.size(); ++c) {
      SyntheticImageSettings draw;
      draw.noise_sigma = 2.0;
      draw.seed = static_cast<std::uint64_t>(f * 16) + c;
      EXPECT_TRUE(
          rhot::write_image(frame_file(dir, c, f), draw_blobs(rig.cameras[c].intrinsics, truth.back().cameras[c], draw)).has_value());
    }
  }
  return truth;
}

// Whether no other detection of the camera lies within 8 px (two spots closer than about 5.4 px merge).
bool isolated(const CameraFrame& frame, const Detection& d) {
  return std::none_of(frame.detections.begin(), frame.detections.end(),
                      [&](const Detection& o) { return &o != &d && (o.pixel - d.pixel).norm() < 8.0; });
}

TEST(VideoSource, ImageSequencesGiveTheTrueDetectionsWhichTriangulateToTheTrueMarkers) {
  const CameraRig rig = seated_rig();
  const fs::path dir = fresh_dir("rhot_video_source_sequence");
  constexpr int kFrames = 4;
  const std::vector<RigFrame> truth = write_sequence(rig, dir, kFrames);
  VideoSourceSettings settings;
  settings.rate_hz = 60.0;
  auto source = VideoSource::open(rig, patterns(dir, rig.cameras.size()), settings);
  ASSERT_TRUE(source.has_value()) << source.error();

  double worst_pixel = 0.0, worst_point_m = 0.0;
  int isolated_count = 0, points_checked = 0;
  for (int f = 0; f < kFrames; ++f) {
    auto frame = source->next();
    ASSERT_TRUE(frame.has_value()) << f;
    EXPECT_EQ(frame->index, static_cast<std::uint64_t>(f));
    EXPECT_DOUBLE_EQ(frame->time_s, f / 60.0);
    ASSERT_EQ(frame->cameras.size(), rig.cameras.size());
    EXPECT_TRUE(frame->truth_position_m.empty());
    const RigFrame& t = truth[static_cast<std::size_t>(f)];
    for (std::size_t c = 0; c < rig.cameras.size(); ++c) {
      EXPECT_EQ(frame->cameras[c].camera, static_cast<int>(c));
      EXPECT_DOUBLE_EQ(frame->cameras[c].timestamp_s, f / 60.0);
      for (const Detection& d : t.cameras[c].detections) {
        if (!isolated(t.cameras[c], d)) continue;
        ++isolated_count;
        double best = 1e9;
        for (const Detection& v : frame->cameras[c].detections) best = std::min(best, (v.pixel - d.pixel).norm());
        worst_pixel = std::max(worst_pixel, best);
      }
    }
    // Every marker whose spots are isolated in at least two cameras triangulates next to its truth.
    const std::vector<MatchedPoint> points = match_and_triangulate(rig, *frame);
    for (std::size_t m = 0; m < t.truth_position_m.size(); ++m) {
      int seen = 0;
      for (const CameraFrame& cf : t.cameras) {
        for (const Detection& d : cf.detections) seen += d.truth_marker == static_cast<int>(m) && isolated(cf, d) ? 1 : 0;
      }
      if (seen < 2) continue;
      double best = 1e9;
      for (const MatchedPoint& p : points) best = std::min(best, (p.point.position_world - t.truth_position_m[m]).norm());
      worst_point_m = std::max(worst_point_m, best);
      ++points_checked;
    }
  }
  EXPECT_GT(isolated_count, 100);
  EXPECT_GT(points_checked, 40);
  EXPECT_LT(worst_pixel, 0.06) << "measured 0.045 px (306 spots, noise 2 grey levels)";
  EXPECT_LT(worst_point_m, 1e-4) << "measured 0.058 mm (80 markers)";
  EXPECT_FALSE(source->next().has_value()) << "the sequence is over";
  EXPECT_TRUE(source->ended());
  for (const VideoCameraStats& s : source->stats()) {
    EXPECT_EQ(s.frames, static_cast<std::uint64_t>(kFrames));
    EXPECT_EQ(s.bad_images + s.failed_reads, 0u);
  }
}

TEST(VideoSource, ABadImageFromOneCameraCostsThatCameraThatFrameOnly) {
  const CameraRig rig = seated_rig();
  const fs::path dir = fresh_dir("rhot_video_source_bad_image");
  write_sequence(rig, dir, 3);
  // Camera 1's second image becomes 16-bit (CAP_IMAGES reads it unchanged), camera 2's the wrong size.
  ASSERT_TRUE(rhot::write_image(frame_file(dir, 1, 1), cv::Mat(720, 1280, CV_16UC1, cv::Scalar(1000))).has_value());
  ASSERT_TRUE(rhot::write_image(frame_file(dir, 2, 1), cv::Mat(240, 320, CV_8UC1, cv::Scalar(0))).has_value());
  auto source = VideoSource::open(rig, patterns(dir, rig.cameras.size()));
  ASSERT_TRUE(source.has_value()) << source.error();
  for (int f = 0; f < 3; ++f) {
    const auto frame = source->next();
    ASSERT_TRUE(frame.has_value()) << f;
    EXPECT_FALSE(frame->cameras[0].detections.empty());
    EXPECT_EQ(frame->cameras[1].detections.empty(), f == 1) << f;
    EXPECT_EQ(frame->cameras[2].detections.empty(), f == 1) << f;
  }
  EXPECT_FALSE(source->next().has_value());
  const auto& stats = source->stats();
  EXPECT_EQ(stats[0].bad_images, 0u);
  EXPECT_EQ(stats[1].bad_images, 1u);
  EXPECT_EQ(stats[1].frames, 2u);
  EXPECT_EQ(stats[1].last_problem,
            "frame 1: \"" + patterns(dir, 4)[1] +
                "\": blob detector: 1280x720 image of type CV_16UC1, expected 8-bit grey (CV_8UC1) or BGR (CV_8UC3)");
  EXPECT_EQ(stats[2].bad_images, 1u);
  EXPECT_EQ(stats[2].last_problem, "frame 1: \"" + patterns(dir, 4)[2] + "\" gave a 320x240 image, the rig calibrates it at 1280x720");
}

TEST(VideoSource, OneCameraEndingEarlyCountsAsFailedReadsUntilAllEnd) {
  const CameraRig rig = seated_rig();
  const fs::path dir = fresh_dir("rhot_video_source_short");
  write_sequence(rig, dir, 3);
  fs::remove(frame_file(dir, 3, 2));
  auto source = VideoSource::open(rig, patterns(dir, rig.cameras.size()));
  ASSERT_TRUE(source.has_value()) << source.error();
  for (int f = 0; f < 3; ++f) {
    const auto frame = source->next();
    ASSERT_TRUE(frame.has_value()) << f;
    EXPECT_EQ(frame->cameras[3].delivered, f < 2) << "a camera with no image this frame delivered none: " << f;
    EXPECT_TRUE(frame->cameras[0].delivered) << f;
  }
  EXPECT_FALSE(source->next().has_value());
  EXPECT_EQ(source->stats()[3].frames, 2u);
  EXPECT_EQ(source->stats()[3].failed_reads, 1u);
  EXPECT_EQ(source->stats()[3].last_problem, "frame 2: no image from \"" + patterns(dir, 4)[3] + "\"");
}

TEST(VideoSource, WrongDeviceCountUnopenableDeviceAndWrongImageSizeAreErrors) {
  const CameraRig rig = seated_rig();
  EXPECT_EQ(VideoSource::open(rig, {"a.png", "b.png"}).error(),
            "video source: 2 devices for a rig of 4 cameras (one per camera, in rig order)");
  EXPECT_EQ(VideoSource::open(rig, {"a.png"}).error(), "video source: 1 device for a rig of 4 cameras (one per camera, in rig order)");

  const fs::path dir = fresh_dir("rhot_video_source_errors");
  write_sequence(rig, dir, 1);
  std::vector<std::string> devices = patterns(dir, rig.cameras.size());
  devices[2] = (dir / "missing_%04d.png").string();
  EXPECT_EQ(VideoSource::open(rig, devices).error(),
            "video source: camera 2 (" + rig.cameras[2].name + "): cannot open \"" + devices[2] + "\"");

  // A file that exists but is no image: opened by no backend, or opened with no frame to give.
  devices = patterns(dir, rig.cameras.size());
  devices[1] = (dir / "not_a_video.avi").string();
  std::ofstream(devices[1]) << "not a video";
  const std::string garbage = VideoSource::open(rig, devices).error();
  EXPECT_TRUE(garbage == "video source: camera 1 (" + rig.cameras[1].name + "): cannot open \"" + devices[1] + "\"" ||
              garbage == "video source: camera 1 (" + rig.cameras[1].name + "): \"" + devices[1] + "\" gives no image")
      << garbage;

  const fs::path small = fresh_dir("rhot_video_source_small");
  ASSERT_TRUE(rhot::write_image((small / "cam_0000.png").string(), cv::Mat(240, 320, CV_8UC1, cv::Scalar(0))).has_value());
  devices = patterns(dir, rig.cameras.size());
  devices[3] = (small / "cam_%04d.png").string();
  EXPECT_EQ(VideoSource::open(rig, devices).error(), "video source: camera 3 (" + rig.cameras[3].name + "): \"" + devices[3] +
                                                         "\" gives 320x240 images, the rig calibrates it at 1280x720");
}

TEST(VideoSource, DeviceListsSplitAtCommas) {
  EXPECT_EQ(parse_video_devices("0,1").value(), (std::vector<std::string>{"0", "1"}));
  EXPECT_EQ(parse_video_devices("cams/a_%04d.png").value(), (std::vector<std::string>{"cams/a_%04d.png"}));
  EXPECT_EQ(parse_video_devices("0,,1").error(),
            "video source: empty device in \"0,,1\" (expected DEV[,DEV...], one per camera: an index such as 0, or a file)");
  EXPECT_FALSE(parse_video_devices("").has_value());
}

}  // namespace
}  // namespace rhot
