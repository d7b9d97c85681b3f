// Coloured markers on simulated colour cameras drawn by the real renderer (lavapipe where there
// is no GPU): the colour detector against the identity images' truth with the scene's clutter and
// another light, and the demo end to end, in process and from PNG sequences written by
// rhot-simvideo --colour and read back through --source video:.

#include "engine/sim/ColourCameras.h"

#include <cstdio>
#include <filesystem>

#include <gtest/gtest.h>

#include "engine/scene/SceneLoader.h"
#include "engine/sim/Demo.h"
#include "tests/support/RunCommand.h"
#include "tracking/camera/RigFile.h"
#include "tracking/core/MarkerColour.h"
#include "tracking/source/VideoSource.h"

namespace rhot {
namespace {

namespace fs = std::filesystem;

SceneDesc demo_scene() {
  auto scene = load_scene_file(std::string(RHOT_ASSET_DIR) + "/scenes/default.json");
  EXPECT_TRUE(scene.has_value());
  return scene.value_or(SceneDesc{});
}

CameraRig stereo_640() {
  auto rig = load_rig(std::string(RHOT_ASSET_DIR) + "/rigs/stereo-640.yaml");
  EXPECT_TRUE(rig.has_value());
  return rig.value_or(CameraRig{});
}

struct Score {
  int visible = 0, found = 0, wrong_colour = 0, false_detections = 0, centroid_n = 0;
  double centroid_sum2 = 0.0;
  double rate() const { return visible ? static_cast<double>(found) / visible : 0.0; }
  double rms() const { return centroid_n ? std::sqrt(centroid_sum2 / centroid_n) : 0.0; }
};

// Detections against the identity image's truth: a marker visible by 20 pixels or more is found
// by a detection of its colour within its radius + 1 px; centroids of markers 90 % visible.
void score(const std::vector<Detection>& dets, const std::vector<MarkerView>& views, const ColourShot& shot, Score& s) {
  std::vector<bool> used(dets.size(), false);
  for (std::size_t m = 0; m < shot.markers.size(); ++m) {
    const MarkerView& v = views[m];
    if (!v.in_front || v.visible_px < 20) continue;
    ++s.visible;
    const double reach = std::sqrt(v.disc_px / 3.14159265) + 1.0;
    int best = -1;
    double best_d = reach;
    for (std::size_t d = 0; d < dets.size(); ++d) {
      const double dist = (dets[d].pixel - v.pixel).norm();
      if (dist < best_d) best_d = dist, best = static_cast<int>(d);
    }
    if (best < 0) continue;
    used[static_cast<std::size_t>(best)] = true;
    ++s.found;
    if (dets[static_cast<std::size_t>(best)].colour != shot.markers[m].colour) ++s.wrong_colour;
    if (v.visible_px >= 0.9 * v.disc_px) {
      s.centroid_sum2 += best_d * best_d;
      ++s.centroid_n;
    }
  }
  for (std::size_t d = 0; d < dets.size(); ++d) {
    if (used[d]) continue;
    bool near = false;
    for (std::size_t m = 0; m < shot.markers.size() && !near; ++m) {
      near = views[m].in_front && views[m].visible_px > 0 &&
             (dets[d].pixel - views[m].pixel).norm() < std::sqrt(views[m].disc_px / 3.14159265) + 2.0;
    }
    if (!near) ++s.false_detections;
  }
}

// Frames of the demo's world photographed by the stereo pair, each image detected whole.
Score detect_over_frames(ColourCameras& cameras, DemoWorld& world, const ColourModel& model, int frames) {
  ColourDetector detector(model);
  Score s;
  for (int f = 0; f < frames; ++f) {
    const double t = 0.5 + f / 15.0;  // every sixth frame of the script's first seconds
    const ColourShot shot = world.colour_shot(world.at(t));
    const auto images = cameras.render(shot, static_cast<std::uint64_t>(f));
    const auto views = cameras.marker_visibility(shot);
    for (std::size_t c = 0; c < images.size(); ++c) {
      const auto dets = detector.detect(images[c]);
      EXPECT_TRUE(dets.has_value());
      if (dets) score(*dets, views[c], shot, s);
    }
  }
  return s;
}

TEST(ColourCameras, RenderedMarkersAreFoundAmongTheScenesObjectsUnderDaylightAndAWarmLamp) {
  const SceneDesc scene = demo_scene();
  auto sim = make_demo_simulation(scene, RHOT_ASSET_DIR, {}, 0, true);
  ASSERT_TRUE(sim.has_value()) << sim.error();
  // The model's white reference from the scene under daylight, as rhot-calib colours takes it.
  ColourModel model = default_colour_model();
  {
    auto daylight = ColourCameras::create(stereo_640(), scene);
    ASSERT_TRUE(daylight.has_value()) << daylight.error();
    const auto images = (*daylight)->render(sim->world->colour_shot(sim->world->at(0.5)), 0);
    model.white_reference = median_colour(images[0]);
    const Score s = detect_over_frames(**daylight, *sim->world, model, 6);
    std::printf("daylight: %d of %d visible found, %d wrong colour, %d false, %.3f px\n", s.found, s.visible, s.wrong_colour,
                s.false_detections, s.rms());
    // Measured: 279 of 302 visible markers found (0.92: the misses are markers half hidden by their
    // own finger, or touching another of their colour), none of a wrong colour, none false, 0.22 px.
    EXPECT_GE(s.visible, 100);
    EXPECT_GE(s.rate(), 0.88);
    EXPECT_EQ(s.wrong_colour, 0);
    EXPECT_EQ(s.false_detections, 0);
    EXPECT_LT(s.rms(), 0.3);
  }
  ColourCameraSettings warm;
  warm.kelvin = 3500.0;
  auto lamp = ColourCameras::create(stereo_640(), scene, warm);
  ASSERT_TRUE(lamp.has_value()) << lamp.error();
  const Score s = detect_over_frames(**lamp, *sim->world, model, 6);
  std::printf("3500 K: %d of %d visible found, %d wrong colour, %d false, %.3f px\n", s.found, s.visible, s.wrong_colour,
              s.false_detections, s.rms());
  EXPECT_GE(s.rate(), 0.88);
  EXPECT_EQ(s.wrong_colour, 0);
  EXPECT_EQ(s.false_detections, 0);
  EXPECT_LT(s.rms(), 0.3);
}

TEST(ColourCameras, CamerasOfDifferentSizesAreRefused) {
  CameraRig rig = stereo_640();
  rig.cameras[1].intrinsics.width_px = 320;
  const auto cameras = ColourCameras::create(rig, demo_scene());
  ASSERT_FALSE(cameras.has_value());
  EXPECT_EQ(cameras.error(), "colour cameras: every camera must have one image size; \"right\" is 320x480, \"left\" 640x480");
  ColourCameraSettings bad;
  bad.kelvin = 100.0;
  const auto refused = ColourCameras::create(stereo_640(), demo_scene(), bad);
  ASSERT_FALSE(refused.has_value());
  EXPECT_EQ(refused.error(), "colour cameras: kelvin: expected 1500 to 15000 K, got 100.000000");
}

struct HandErrors {
  int frames = 0, seen = 0;
  double tip_mean_m = 0.0;
};

// Both hands' fingertips against the script's, as tracked by the demo's live tracking.
HandErrors track_fingertips(LiveTracking& p, const DemoScript& script, int frames) {
  HandErrors e;
  double sum = 0.0;
  long tips = 0;
  for (int f = 0; f < frames; ++f) {
    const double t = f / 90.0;
    p.read_source(t);
    if (p.ended()) break;
    p.match();
    p.track_stars(t);
    p.track_hands(t);
    ++e.frames;
    for (std::size_t h = 0; h < 2; ++h) {
      const TrackedHand& tracked = p.tracked_hand(h == 0 ? HandSide::kLeft : HandSide::kRight);
      if (!tracked.hand_seen) continue;
      ++e.seen;
      const HandTruth truth = script.at(t).hands[h];
      for (int k = 0; k < kFingerCount; ++k) {
        const auto tip = static_cast<std::size_t>(chain_joints(static_cast<Finger>(k))[3]);
        sum += (tracked.joints_world[tip] - truth.world_from_hand * truth.pose.position_m[tip]).norm();
        ++tips;
      }
    }
  }
  e.tip_mean_m = tips ? sum / static_cast<double>(tips) : 0.0;
  return e;
}

TEST(ColourDemo, RenderedColourImagesWrittenAndReadBackTrackTheHandsAsInProcess) {
  constexpr int kFrames = 45;
  const fs::path dir = fs::path(::testing::TempDir()) / "rhot_colour_video";
  fs::remove_all(dir);
  const auto written =
      test::run_program("rhot-simvideo", "--colour --out " + dir.string() + " --frames " + std::to_string(kFrames), "2>&1");
  ASSERT_EQ(written.exit_code, 0) << written.output;
  EXPECT_NE(written.output.find("--source video:"), std::string::npos) << written.output;

  const SceneDesc scene = demo_scene();
  const DemoScript script(scene);
  DemoSettings video;
  video.asset_dir = RHOT_ASSET_DIR;
  video.colour_markers = true;
  for (int c = 0; c < 2; ++c) video.video_devices.push_back((dir / ("cam" + std::to_string(c) + "_%04d.png")).string());
  auto from_images = Demo::create(scene, nullptr, video);
  ASSERT_TRUE(from_images.has_value()) << from_images.error();
  const HandErrors v = track_fingertips(*(*from_images)->live(), script, kFrames + 5);

  DemoSettings live;
  live.asset_dir = RHOT_ASSET_DIR;
  live.colour_markers = true;
  auto in_process = Demo::create(scene, nullptr, live);
  ASSERT_TRUE(in_process.has_value()) << in_process.error();
  const HandErrors s = track_fingertips(*(*in_process)->live(), script, kFrames);
  std::printf("fingertips: from PNG files %.2f mm (%d hand frames seen), in process %.2f mm (%d)\n", 1000.0 * v.tip_mean_m, v.seen,
              1000.0 * s.tip_mean_m, s.seen);

  EXPECT_EQ(v.frames, kFrames);
  EXPECT_GE(v.seen, 2 * kFrames * 80 / 100);
  // The target: fingertips within 5 mm on average through the whole pipeline (seed 002: 2 cm).
  EXPECT_LT(v.tip_mean_m, 0.005);
  EXPECT_NEAR(v.tip_mean_m, s.tip_mean_m, 0.0002) << "the same rendered images, through PNG files or not";
  const auto* source = dynamic_cast<const VideoSource*>(&(*from_images)->live()->source());
  ASSERT_NE(source, nullptr);
  for (const VideoCameraStats& st : source->stats()) EXPECT_EQ(st.bad_images + st.failed_reads, 0u);
}

TEST(ColourDemo, ColourMarkersThroughCameraNodesAreRefused) {
  DemoSettings settings;
  settings.asset_dir = RHOT_ASSET_DIR;
  settings.colour_markers = true;
  settings.node_endpoints = {"tcp://127.0.0.1:5601"};
  const auto demo = Demo::create(demo_scene(), nullptr, settings);
  ASSERT_FALSE(demo.has_value());
  EXPECT_EQ(demo.error(), "colour markers through camera nodes: the node protocol (version 1) carries no colour");
}

}  // namespace
}  // namespace rhot
