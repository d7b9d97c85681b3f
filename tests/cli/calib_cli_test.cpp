// Runs the real rhot-calib: a simulated wand session through `wand`, the world from a simulated
// L-frame, two rigs merged, and the errors a user sees for bad input.

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "tracking/media/Media.h"
#include "tests/support/TempDir.h"
#include <nlohmann/json.hpp>

#include <Eigen/Geometry>

#include "tests/support/RunCommand.h"
#include "tracking/calib/Detections.h"
#include "tracking/camera/RigFile.h"
#include "tracking/net/ChildProcess.h"
#include "tracking/net/NodeSource.h"
#include "tracking/detect/ColourModel.h"
#include "tracking/sim/SyntheticImages.h"

#include <opencv2/core.hpp>

namespace {

namespace fs = std::filesystem;

rhot::test::CommandRun calib(const std::string& args) { return rhot::test::run_program("rhot-calib", args, "2>&1"); }
// stdout only: the JSON report.
rhot::test::CommandRun calib_json(const std::string& args) { return rhot::test::run_program("rhot-calib", args, "2>/dev/null"); }

fs::path temp_dir() { return rhot::test::fresh_test_dir("rhot_calib_cli"); }

std::string asset(const std::string& path) { return std::string(RHOT_ASSET_DIR) + "/" + path; }

// A rig's cameras as a user's files from `rhot-calib intrinsics`: one file per camera, each at the
// origin looking along +Z, so that `wand` finds every pose from the wave alone and never starts
// from the truth it is checked against. Returns the files for --intrinsics, space-separated.
std::string intrinsics_files(const std::string& rig_file, const fs::path& dir) {
  const auto rig = rhot::load_rig(rig_file);
  EXPECT_TRUE(rig) << rig.error();
  std::string files;
  if (!rig) return files;
  for (const rhot::Camera& c : rig->cameras) {
    rhot::CameraRig one;
    one.name = c.name;
    one.cameras.push_back(rhot::Camera{c.name, c.intrinsics, rhot::Rigid3d::identity()});
    const fs::path file = dir / (c.name + "_intrinsics.yaml");
    const auto saved = rhot::save_rig(one, file);
    EXPECT_TRUE(saved) << saved.error();
    files += (files.empty() ? "" : " ") + file.string();
  }
  return files;
}

TEST(CalibCli, HelpListsTheSubcommands) {
  const auto r = calib("--help");
  EXPECT_EQ(r.exit_code, 0);
  for (const char* sub : {"intrinsics", "wand", "world", "merge", "colours", "simulate"}) {
    EXPECT_NE(r.output.find(sub), std::string::npos) << sub << " missing from:\n" << r.output;
  }
  const auto wand = calib("wand --help");
  EXPECT_EQ(wand.exit_code, 0);
  for (const char* option : {"--intrinsics", "--detections", "--wand-mm", "--wand-markers", "--refine", "--json", "--out"}) {
    EXPECT_NE(wand.output.find(option), std::string::npos) << option << " missing from:\n" << wand.output;
  }
}

TEST(CalibCli, SimulatedWandSessionToAMetricRigAndItsWorld) {
  const fs::path dir = temp_dir();
  const std::string truth = asset("rigs/stereo-2.yaml");
  const auto sim = calib("simulate wand --rig " + truth + " --frames 600 --wand-mm 300 --seed 4 --out " + (dir / "wand.csv").string());
  ASSERT_EQ(sim.exit_code, 0) << sim.output;
  const auto wand = calib_json("wand --intrinsics " + intrinsics_files(truth, dir) + " --detections " + (dir / "wand.csv").string() +
                               " --wand-mm 300 --json --out " + (dir / "rig.yaml").string());
  ASSERT_EQ(wand.exit_code, 0) << wand.output;
  const nlohmann::json j = nlohmann::json::parse(wand.output);
  EXPECT_TRUE(j["metric"].get<bool>());
  EXPECT_LT(j["rms_px"].get<double>(), 0.5);
  // stereo-2's two cameras triangulate each end to about 1 mm: the true rig itself measures this
  // wave's wand at 1.5 mm RMS (rhot-eval wand --rig assets/rigs/stereo-2.yaml --length-mm 300).
  EXPECT_LT(j["wand_rms_mm"].get<double>(), 1.8);
  EXPECT_LT(std::abs(j["wand_mean_mm"].get<double>()), 0.1);
  ASSERT_EQ(j["cameras"].size(), 2u);
  ASSERT_EQ(j["graph"].size(), 1u);
  EXPECT_GT(j["graph"][0]["shared_points"].get<int>(), 500);
  for (const auto& p : j["pictures"]) EXPECT_TRUE(fs::is_regular_file(p.get<std::string>())) << p;
  EXPECT_EQ(j["pictures"].size(), 3u);  // two cameras' residuals and the rig from above
  // The rig file reads back, with the report's figures beside the cameras.
  const auto rig = rhot::load_rig(dir / "rig.yaml");
  ASSERT_TRUE(rig) << rig.error();
  std::ifstream text(dir / "rig.yaml");
  std::stringstream buffer;
  buffer << text.rdbuf();
  const std::string yaml = buffer.str();
  EXPECT_NE(yaml.find("calibration:"), std::string::npos);
  EXPECT_NE(yaml.find("wand_rms_mm:"), std::string::npos);

  // The world from an L-frame lying at the truth's origin: the cameras land where the truth has them.
  // A 400 x 250 mm L-frame on a stand in front of the cameras (y = 0.9 m), its corner at
  // x = -0.12, z = -0.25.
  const auto frame = calib("simulate lframe --rig " + truth + " --lframe-mm 400,250 --at-m -0.12,0.9,-0.25 --seed 5 --out " +
                           (dir / "lframe.csv").string());
  ASSERT_EQ(frame.exit_code, 0) << frame.output;
  const auto world = calib_json("world --lframe --lframe-mm 400,250 --rig " + (dir / "rig.yaml").string() + " --detections " +
                                (dir / "lframe.csv").string() + " --json --out " + (dir / "world.yaml").string());
  ASSERT_EQ(world.exit_code, 0) << world.output;
  const nlohmann::json w = nlohmann::json::parse(world.output);
  EXPECT_LT(w["rms_mm"].get<double>(), 2.0);
  const auto placed = rhot::load_rig(dir / "world.yaml");
  const auto truth_rig = rhot::load_rig(truth);
  ASSERT_TRUE(placed && truth_rig);
  // The frame's own pose is known only as well as its three markers: with two cameras, ~1 mm
  // over a 250 mm arm, 0.2 degrees, which moves cameras 0.5 m away by a few millimetres.
  const Eigen::Vector3d corner(-0.12, 0.9, -0.25);
  const double lever_m = (truth_rig->cameras[0].centre_world() - corner).norm();
  const double allowed_m = 0.002 + lever_m * 2.0 * (w["rms_mm"].get<double>() / 250.0);
  for (std::size_t c = 0; c < truth_rig->cameras.size(); ++c) {
    EXPECT_LT((placed->cameras[c].centre_world() - (truth_rig->cameras[c].centre_world() - corner)).norm(), allowed_m) << c;
  }
  EXPECT_LT(allowed_m, 0.012);
}

TEST(CalibCli, RecordsAWaveFromImageSequencesAndCalibratesFromIt) {
  // The whole path from images: simulated camera images of one marker, the blob detector through
  // `record`, then `wand` (not metric without a wand: compared with the truth up to scale). Drawing
  // and reading back the images is most of this test's time (two 1024 x 768 noisy PNGs a frame):
  // 80 frames, whose 155 detections still put the thresholds below 4 to 10 times what they measure.
  const fs::path dir = temp_dir();
  const std::string truth = asset("rigs/stereo-2.yaml");
  const auto sim = calib("simulate wand --rig " + truth + " --markers 1 --frames 80 --rate-hz 8 --seed 3 --out " +
                         (dir / "truth.csv").string() + " --images " + (dir / "images").string());
  ASSERT_EQ(sim.exit_code, 0) << sim.output;
  const std::string source = "video:" + (dir / "images" / "cam0_%04d.png").string() + "," + (dir / "images" / "cam1_%04d.png").string();
  const auto record = calib("record --rig " + truth + " --source " + source + " --out " + (dir / "recorded.csv").string());
  ASSERT_EQ(record.exit_code, 0) << record.output;
  EXPECT_NE(record.output.find("of 80 frames"), std::string::npos) << record.output;
  const std::string intrinsics = intrinsics_files(truth, dir);
  const auto wand = calib_json("wand --intrinsics " + intrinsics + " --detections " + (dir / "recorded.csv").string() + " --json --out " +
                               (dir / "rig.yaml").string());
  ASSERT_EQ(wand.exit_code, 0) << wand.output;
  const nlohmann::json j = nlohmann::json::parse(wand.output);
  EXPECT_FALSE(j["metric"].get<bool>());
  EXPECT_LT(j["rms_px"].get<double>(), 0.5);
  // The same wave calibrated from the simulation's own detections: the images and the blob
  // detector add little, and both are near the truth up to scale (the second camera's rotation
  // relative to the first; 80 positions of one marker pin it to about 0.15 degrees). Measured:
  // 0.007 degrees between the two, 0.13 degrees from the truth (0.005 and 0.08 with the
  // noise images drawn before 2026-11-26; 160 frames: 0.002 and 0.11).
  const auto direct = calib("wand --intrinsics " + intrinsics + " --detections " + (dir / "truth.csv").string() + " --out " +
                            (dir / "direct.yaml").string());
  ASSERT_EQ(direct.exit_code, 0) << direct.output;
  const auto rig = rhot::load_rig(dir / "rig.yaml");
  const auto direct_rig = rhot::load_rig(dir / "direct.yaml");
  const auto truth_rig = rhot::load_rig(truth);
  ASSERT_TRUE(rig && direct_rig && truth_rig);
  const auto relative = [](const rhot::CameraRig& r) {
    return r.cameras[1].cam_from_world.rotation * r.cameras[0].cam_from_world.rotation.conjugate();
  };
  const auto degrees = [](const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) { return a.angularDistance(b) * 180.0 / M_PI; };
  EXPECT_LT(degrees(relative(*rig), relative(*direct_rig)), 0.05);
  EXPECT_LT(degrees(relative(*rig), relative(*truth_rig)), 0.3);
  const auto bad = calib("record --rig " + truth + " --source video:" + (dir / "none_%04d.png").string() + " --out x.csv");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.output.find("rhot-calib: error: "), std::string::npos) << bad.output;
}

// One camera node serving both cameras' image sequences (given second camera first, so that each
// device's camera number counts), detected side by side on two threads:
// `record` through it (a real rhot-node on loopback) gets, in every frame, both cameras'
// detections of one and the same image pair, exactly as detecting the images here does.
TEST(CalibCli, ANodeServesTwoCamerasDetectedOnTwoThreadsAsTheImagesAreDetectedHere) {
  const fs::path dir = temp_dir();
  const std::string truth = asset("rigs/stereo-2.yaml");
  const auto sim = calib("simulate wand --rig " + truth + " --markers 1 --frames 60 --rate-hz 8 --seed 4 --out " +
                         (dir / "truth.csv").string() + " --images " + (dir / "images").string());
  ASSERT_EQ(sim.exit_code, 0) << sim.output;
  const std::string cam0 = (dir / "images" / "cam0_%04d.png").string(), cam1 = (dir / "images" / "cam1_%04d.png").string();
  const auto here = calib("record --rig " + truth + " --source video:" + cam0 + "," + cam1 + " --out " + (dir / "here.csv").string());
  ASSERT_EQ(here.exit_code, 0) << here.output;
  const auto ports = rhot::free_tcp_port_pairs(1);
  ASSERT_TRUE(ports.has_value()) << ports.error();
  const std::string endpoint = "tcp://127.0.0.1:" + std::to_string(ports->front());
  // The node's 60 image pairs at 15 Hz take 4 s; the recording (Ctrl-C after 5 s) holds the frames
  // that came once it had connected and set the node's clock.
  auto node = rhot::ChildProcess::spawn({std::string(RHOT_BINARY_DIR) + "/rhot-node", "--publish", endpoint, "--insecure", "--device",
                                         cam1 + "," + cam0, "--rig", truth, "--camera", "1,0", "--threads", "2", "--rate-hz", "15"},
                                        (dir / "node.log").string());
  ASSERT_TRUE(node.has_value()) << node.error();
  const auto recorded = rhot::test::run_program(
      "rhot-calib", "record --rig " + truth + " --source nodes:" + endpoint + " --insecure --out " + (dir / "node.csv").string(), "2>&1",
      "timeout --preserve-status -s INT 5");
  ASSERT_EQ(recorded.exit_code, 0) << recorded.output;
  EXPECT_EQ(node->wait(30.0), 0) << "the node ends with its images";
  const auto local = rhot::read_detections_csv(dir / "here.csv");
  const auto remote = rhot::read_detections_csv(dir / "node.csv");
  ASSERT_TRUE(local && remote);
  // A frame's two pixels (camera 0's, camera 1's); one marker, so at most one detection a camera.
  using Pair = std::array<Eigen::Vector2d, 2>;
  const auto pairs = [](const rhot::Detections& d) {
    std::vector<Pair> out;
    for (const rhot::DetectionFrame& f : d.frames) {
      Pair p{Eigen::Vector2d::Constant(-1), Eigen::Vector2d::Constant(-1)};
      for (const rhot::MarkerObservation& o : f.observations) p[static_cast<std::size_t>(o.camera)] = o.pixel;
      if (p[0].x() >= 0 && p[1].x() >= 0) out.push_back(p);
    }
    return out;
  };
  const std::vector<Pair> seen_here = pairs(*local), seen_by_node = pairs(*remote);
  ASSERT_GE(seen_by_node.size(), 15u) << recorded.output;
  for (const Pair& p : seen_by_node) {
    const bool same =
        std::ranges::any_of(seen_here, [&p](const Pair& q) { return (p[0] - q[0]).norm() < 1e-3 && (p[1] - q[1]).norm() < 1e-3; });
    EXPECT_TRUE(same) << "camera 0 at " << p[0].transpose() << ", camera 1 at " << p[1].transpose() << ": no image pair gives both";
  }
  // The node's flags: one camera of the rig a device.
  const auto mismatched = rhot::test::run_program(
      "rhot-node", "--publish " + endpoint + " --insecure --device " + cam0 + "," + cam1 + " --rig " + truth + " --camera 1", "2>&1",
      "timeout 20");
  EXPECT_EQ(mismatched.exit_code, 1);
  EXPECT_NE(mismatched.output.find("--camera: 1 cameras of --rig named for 2 devices: one camera a --device, in the same order"),
            std::string::npos)
      << mismatched.output;
  const auto twice = rhot::test::run_program(
      "rhot-node", "--publish " + endpoint + " --insecure --device " + cam0 + "," + cam1 + " --rig " + truth + " --camera 1,1", "2>&1",
      "timeout 20");
  EXPECT_EQ(twice.exit_code, 1);
  EXPECT_NE(twice.output.find("--camera: camera 1 is named twice: each device is another camera of the rig"), std::string::npos)
      << twice.output;
}

TEST(CalibCli, BadInputGetsOneLineNamingIt) {
  const fs::path dir = temp_dir();
  { std::ofstream(dir / "broken.csv") << "frame,camera,x,y\n0,0,1,2\n0,1,three,4\n"; }
  const auto broken = calib("wand --intrinsics " + asset("rigs/stereo-2.yaml") + " --detections " + (dir / "broken.csv").string() +
                            " --out " + (dir / "rig.yaml").string());
  EXPECT_EQ(broken.exit_code, 1);
  EXPECT_EQ(broken.output, "rhot-calib: error: " + (dir / "broken.csv").string() + ":3: x: expected a finite number, got \"three\"\n");
  EXPECT_FALSE(fs::exists(dir / "rig.yaml"));
  const auto refine = calib("wand --intrinsics " + asset("rigs/stereo-2.yaml") + " --detections " + (dir / "broken.csv").string() +
                            " --refine focal,zoom --out " + (dir / "rig.yaml").string());
  EXPECT_EQ(refine.exit_code, 1);
  EXPECT_NE(refine.output.find("rhot-calib: error: --refine: expected focal, principal or k1, got \"zoom\""), std::string::npos)
      << refine.output;
  const auto no_mode =
      calib("world --rig " + asset("rigs/stereo-2.yaml") + " --detections " + (dir / "broken.csv").string() + " --out x.yaml");
  EXPECT_EQ(no_mode.exit_code, 1);
  EXPECT_EQ(no_mode.output, "rhot-calib: error: give one of --lframe and --floor\n");
  const auto missing = calib("merge " + asset("rigs/stereo-2.yaml") + " " + (dir / "none.yaml").string() + " --out x.yaml");
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_EQ(missing.output, "rhot-calib: error: " + (dir / "none.yaml").string() + ": rig file not found\n");
}

TEST(CalibCli, MergesTwoRigsThroughASharedCamera) {
  const fs::path dir = temp_dir();
  const auto room = rhot::load_rig(asset("rigs/room-8.yaml"));
  ASSERT_TRUE(room);
  rhot::CameraRig a, b;
  for (int c = 0; c < 5; ++c) a.cameras.push_back(room->cameras[static_cast<std::size_t>(c)]);
  for (int c = 4; c < 8; ++c) b.cameras.push_back(room->cameras[static_cast<std::size_t>(c)]);
  ASSERT_TRUE(rhot::save_rig(a, dir / "a.yaml"));
  ASSERT_TRUE(rhot::save_rig(b, dir / "b.yaml"));
  const auto merged =
      calib_json("merge " + (dir / "a.yaml").string() + " " + (dir / "b.yaml").string() + " --json --out " + (dir / "ab.yaml").string());
  ASSERT_EQ(merged.exit_code, 0) << merged.output;
  const nlohmann::json j = nlohmann::json::parse(merged.output);
  EXPECT_EQ(j["cameras"], 8);
  EXPECT_EQ(j["shared_cameras"].size(), 1u);
  EXPECT_LT(j["centre_rms_mm"].get<double>(), 1e-6);
  const auto ab = rhot::load_rig(dir / "ab.yaml");
  ASSERT_TRUE(ab) << ab.error();
  EXPECT_EQ(ab->cameras.size(), 8u);
}

}  // namespace

namespace {

// Colours learned from drawn images of the six markers held up on a cluttered table: a colour file
// that loads with every colour, and its picture; and the errors a user sees.
TEST(CalibCli, LearnsTheMarkerColoursFromImagesAndDrawsWhatItClassifies) {
  const fs::path dir = temp_dir();
  std::string images;
  for (unsigned seed = 1; seed <= 3; ++seed) {
    std::vector<rhot::ColourMarkerDrawing> held_up;
    int i = 0;
    for (const int colour : {0, 2, 3, 4, 5, 7}) {
      held_up.push_back({{80.0 + 90.0 * i, 120.0 + 40.0 * seed}, 8.0, colour});
      held_up.push_back({{80.0 + 90.0 * i, 330.0 - 30.0 * seed}, 7.0, colour});
      ++i;
    }
    rhot::ColourImageSettings settings;
    settings.seed = seed;
    const fs::path file = dir / ("held_up_" + std::to_string(seed) + ".png");
    ASSERT_TRUE(rhot::write_image(file.string(), rhot::draw_colour_markers(640, 480, held_up, settings)).has_value());
    images += " " + file.string();
  }
  const fs::path out = dir / "colours.json";
  const auto r = calib_json("colours" + images + " --out " + out.string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << calib("colours" + images + " --out " + out.string()).output;
  const auto report = nlohmann::json::parse(r.output);
  EXPECT_EQ(report["colours"].size(), 6u) << r.output;
  EXPECT_EQ(report["markers_in_test_image"], 12) << r.output;
  const auto model = rhot::load_colour_model(out);
  ASSERT_TRUE(model.has_value()) << model.error().to_string();
  EXPECT_EQ(model->classes.size(), 6u);
  EXPECT_TRUE(model->white_reference.has_value());
  EXPECT_TRUE(fs::exists(dir / "colours_classes.png"));

  const auto unknown = calib("colours" + images + " --out " + out.string() + " --expect red,teal");
  EXPECT_EQ(unknown.exit_code, 1);
  EXPECT_NE(
      unknown.output.find("--expect: \"teal\" is not a marker colour (red, orange, yellow, green, cyan, blue, purple, magenta, or any)"),
      std::string::npos)
      << unknown.output;
  const auto missing = calib("colours" + images + " --out " + out.string() + " --expect red,orange");
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.output.find("no blobs of orange found: is the marker in view and lit?"), std::string::npos) << missing.output;
  const auto none = calib("colours --out " + out.string());
  EXPECT_EQ(none.exit_code, 1);
  EXPECT_NE(none.output.find("give images, or --source video:DEV to take frames from cameras"), std::string::npos) << none.output;
}

// The cameras of `rig` written as one intrinsics file: every camera at the origin, as `intrinsics`
// writes each camera, gathered into one file by hand (docs/calibration.md: "or one rig file
// holding every camera").
void write_cameras_at_origin(const rhot::CameraRig& rig, const fs::path& file) {
  cv::FileStorage fs(file.string(), cv::FileStorage::WRITE | cv::FileStorage::FORMAT_YAML);
  fs << "rig_name"
     << "intrinsics"
     << "cameras"
     << "[";
  for (const rhot::Camera& c : rig.cameras) {
    const rhot::CameraIntrinsics& k = c.intrinsics;
    fs << "{"
       << "name" << c.name << "image_width" << k.width_px << "image_height" << k.height_px << "camera_matrix"
       << cv::Mat(cv::Matx33d(k.fx, 0.0, k.cx, 0.0, k.fy, k.cy, 0.0, 0.0, 1.0)) << "distortion_coefficients"
       << cv::Mat(cv::Matx<double, 1, 5>(k.distortion[0], k.distortion[1], k.distortion[2], k.distortion[3], k.distortion[4])) << "rotation"
       << cv::Mat(cv::Matx33d::eye()) << "translation" << cv::Mat(cv::Matx31d(0.0, 0.0, 0.0)) << "}";
  }
  fs << "]";
}

// `wand --intrinsics` reads only the cameras' intrinsics: one file of every camera at the origin
// used to be refused ("cameras[1] (\"right\").translation: same position as cameras[0]").
TEST(CalibCli, WandTakesOneFileOfEveryCamerasIntrinsicsWhateverItsPoses) {
  const fs::path dir = temp_dir();
  const std::string truth = asset("rigs/stereo-2.yaml");
  const auto truth_rig = rhot::load_rig(truth);
  ASSERT_TRUE(truth_rig) << truth_rig.error();
  const fs::path intrinsics = dir / "intrinsics.yaml";
  write_cameras_at_origin(*truth_rig, intrinsics);
  ASSERT_EQ(rhot::load_rig(intrinsics).error(),
            intrinsics.string() + ": cameras[1] (\"right\").translation: same position as cameras[0] (\"left\")")
      << "not a rig to track with";
  const auto sim = calib("simulate wand --rig " + truth + " --frames 600 --wand-mm 300 --seed 4 --out " + (dir / "wand.csv").string());
  ASSERT_EQ(sim.exit_code, 0) << sim.output;
  const auto wand = calib("wand --intrinsics " + intrinsics.string() + " --detections " + (dir / "wand.csv").string() +
                          " --wand-mm 300 --out " + (dir / "rig.yaml").string());
  ASSERT_EQ(wand.exit_code, 0) << wand.output;
  const auto rig = rhot::load_rig(dir / "rig.yaml");
  ASSERT_TRUE(rig) << rig.error();
  ASSERT_EQ(rig->cameras.size(), 2u);
  EXPECT_EQ(rig->cameras[0].name, "left");
  EXPECT_EQ(rig->cameras[1].name, "right");
}

// docs/calibration.md's walk-through on two cameras: each camera's intrinsics from its board
// pictures, the files `intrinsics` writes read by `wand`, and the world from an L-frame on a stand
// 0.9 m up with --height-mm 900, which keeps Y = 0 on the floor: every camera at the truth's height.
// Without it the stand is taken for the floor and every camera comes out 0.9 m too low above it.
TEST(CalibCli, TheWalkThroughChainsIntrinsicsIntoWandAndKeepsTheFloor) {
  const fs::path dir = temp_dir();
  const std::string truth = asset("rigs/stereo-2.yaml");  // 1024 x 768, fx 1280 px, no distortion
  std::string cameras;
  for (int i = 0; i < 2; ++i) {
    const std::string boards = (dir / ("boards/cam" + std::to_string(i))).string();
    const std::string cam = (dir / ("calib/cam" + std::to_string(i) + ".yaml")).string();
    const auto board = calib("simulate board --size 1024x768 --fx 1280 --k1 0 --k2 0 --p1 0 --p2 0 --views 10 --seed " +
                             std::to_string(i + 1) + " --out " + boards);
    ASSERT_EQ(board.exit_code, 0) << board.output;
    const auto found = calib("intrinsics --board chess:9x6:25 " + boards + " --out " + cam + " --no-leave-one-out");
    ASSERT_EQ(found.exit_code, 0) << found.output;
    cameras += " " + cam;
  }
  const auto sim = calib("simulate wand --rig " + truth + " --frames 600 --wand-mm 300 --seed 4 --out " + (dir / "wand.csv").string());
  ASSERT_EQ(sim.exit_code, 0) << sim.output;
  const auto wand = calib("wand --intrinsics" + cameras + " --detections " + (dir / "wand.csv").string() + " --wand-mm 300 --out " +
                          (dir / "rig.yaml").string());
  ASSERT_EQ(wand.exit_code, 0) << wand.output;
  const auto frame = calib("simulate lframe --rig " + truth + " --lframe-mm 400,250 --at-m -0.12,0.9,-0.25 --seed 5 --out " +
                           (dir / "lframe.csv").string());
  ASSERT_EQ(frame.exit_code, 0) << frame.output;
  const auto truth_rig = rhot::load_rig(truth);
  ASSERT_TRUE(truth_rig) << truth_rig.error();
  for (const double height_mm : {900.0, 0.0}) {
    const fs::path out = dir / (height_mm > 0.0 ? "world.yaml" : "world_on_the_stand.yaml");
    const auto world = calib("world --lframe --lframe-mm 400,250 --height-mm " + std::to_string(height_mm) + " --rig " +
                             (dir / "rig.yaml").string() + " --detections " + (dir / "lframe.csv").string() + " --out " + out.string());
    ASSERT_EQ(world.exit_code, 0) << world.output;
    const auto placed = rhot::load_rig(out);
    ASSERT_TRUE(placed) << placed.error();
    ASSERT_EQ(placed->cameras.size(), 2u);
    EXPECT_EQ(placed->cameras[0].name, "cam0");
    for (std::size_t c = 0; c < 2; ++c) {
      EXPECT_NEAR(placed->cameras[c].centre_world().y(), truth_rig->cameras[c].centre_world().y() - (0.9 - height_mm / 1000.0), 0.012)
          << "camera " << c << " with --height-mm " << height_mm;
    }
  }
}

}  // namespace
