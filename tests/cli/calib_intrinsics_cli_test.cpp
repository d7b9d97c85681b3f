// Runs the real rhot-calib intrinsics and rhot-calib simulate board.

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "tests/support/TempDir.h"
#include <nlohmann/json.hpp>

#include "tests/support/RunCommand.h"
#include "tracking/camera/RigFile.h"

namespace {

namespace fs = std::filesystem;
using rhot::test::run_program;

fs::path intrinsics_dir() { return rhot::test::fresh_test_dir("rhot_calib_intrinsics_cli"); }

std::string read(const fs::path& file) {
  std::ifstream in(file);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(CalibIntrinsicsCli, HelpNamesEveryOption) {
  auto r = run_program("rhot-calib", "intrinsics --help", "2>&1");
  EXPECT_EQ(r.exit_code, 0);
  for (const char* option : {"--board", "--out", "--name", "--pictures", "--json", "--fix-k3", "--free-k3", "--no-leave-one-out",
                             "chess:COLSxROWS", "charuco:COLSxROWS:SQUARE_MM:MARKER_MM", "inner corners"}) {
    EXPECT_NE(r.output.find(option), std::string::npos) << option << "\n" << r.output;
  }
  r = run_program("rhot-calib", "simulate board --help", "2>&1");
  EXPECT_EQ(r.exit_code, 0);
  for (const char* option : {"--out", "--board", "--views", "--size", "--fx", "--fy", "--cx", "--cy", "--k1", "--k2", "--p1", "--p2",
                             "--k3", "--noise", "--blur", "--seed", "--json"}) {
    EXPECT_NE(r.output.find(option), std::string::npos) << option << "\n" << r.output;
  }
}

TEST(CalibIntrinsicsCli, SimulatedBoardPicturesGiveBackTheCamera) {
  const fs::path dir = intrinsics_dir();
  auto r = run_program(
      "rhot-calib",
      "simulate board --out " + (dir / "pictures").string() + " --views 12 --size 960x540 --fx 760 --cx 486.5 --cy 265 --k1 -0.12", "2>&1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("rendering board 12/12: board_11.png"), std::string::npos) << r.output;
  ASSERT_TRUE(fs::exists(dir / "pictures" / "board_11.png"));
  const auto truth = rhot::load_rig(dir / "pictures" / "truth.yaml");
  ASSERT_TRUE(truth.has_value()) << truth.error();
  const rhot::CameraIntrinsics& t = truth->cameras.at(0).intrinsics;
  EXPECT_EQ(t.fx, 760.0);
  EXPECT_EQ(t.distortion[0], -0.12);

  // A folder of pictures; the report on stdout, progress on stderr.
  const fs::path log = dir / "stderr.txt";
  r = run_program(
      "rhot-calib",
      "intrinsics --board chess:9x6:25 " + (dir / "pictures").string() + " --out " + (dir / "out" / "cam0.yaml").string() + " --json",
      "2>" + log.string());
  ASSERT_EQ(r.exit_code, 0) << r.output << read(log);
  const std::string progress = read(log);
  EXPECT_NE(progress.find("detecting corners 1/12: board_00.png"), std::string::npos) << progress;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  const double fx = j.at("fx").get<double>();
  std::printf("fx %.3f (truth %.1f): error %.4f %%, rms %.4f px, leave-one-out %.4f px\n", fx, t.fx, 100 * std::abs(fx / t.fx - 1),
              j.at("rms_px").get<double>(), j.at("leave_one_out_rms_px").get<double>());
  EXPECT_NEAR(fx, t.fx, 0.001 * t.fx);
  EXPECT_NEAR(j.at("fy").get<double>(), t.fy, 0.001 * t.fy);
  EXPECT_NEAR(j.at("cx").get<double>(), t.cx, 1.0);
  EXPECT_NEAR(j.at("cy").get<double>(), t.cy, 1.0);
  EXPECT_NEAR(j.at("dist").at(0).get<double>(), -0.12, 0.01);
  EXPECT_EQ(j.at("views_used").get<int>(), 12);
  EXPECT_EQ(j.at("views").size(), 12u);
  EXPECT_EQ(j.at("worst_views").size(), 3u);
  EXPECT_LT(j.at("rms_px").get<double>(), 0.2);
  EXPECT_TRUE(j.at("warnings").empty()) << j.at("warnings").dump();
  EXPECT_EQ(j.at("board").get<std::string>(), "chess:9x6:25");

  // The camera file is a one-camera rig with what the report says, and the picture is beside it.
  const auto cam = rhot::load_rig(dir / "out" / "cam0.yaml");
  ASSERT_TRUE(cam.has_value()) << cam.error();
  ASSERT_EQ(cam->cameras.size(), 1u);
  EXPECT_EQ(cam->cameras[0].name, "cam0");
  EXPECT_NEAR(cam->cameras[0].intrinsics.fx, fx, 1e-6 * fx);
  EXPECT_EQ(cam->cameras[0].intrinsics.width_px, 960);
  EXPECT_TRUE(fs::exists(dir / "out" / "cam0_intrinsics.png"));
}

// Pictures of a 9 x 6 board with --board chess:10x7:25 (the squares counted, not the inner corners):
// the reason comes after the first three pictures, not after a long search through every one.
TEST(CalibIntrinsicsCli, AWrongBoardSizeIsSaidAfterTheFirstPictures) {
  const fs::path dir = intrinsics_dir();
  auto r = run_program("rhot-calib", "simulate board --out " + (dir / "pictures").string() + " --views 5 --size 960x540 --fx 760", "2>&1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = run_program("rhot-calib", "intrinsics --board chess:10x7:25 " + (dir / "pictures").string() + " --out " + (dir / "cam.yaml").string(),
                  "2>&1");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("detecting corners 3/5: board_02.png\n"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("detecting corners 4/5"), std::string::npos) << r.output;
  const std::string error =
      "rhot-calib: error: board chess:10x7:25 not found in any of the first 3 of 5 images, so the others were not searched; is the "
      "board's size right? chess COLSxROWS counts inner corners (a board of 10 x 7 squares is chess:9x6)\n";
  ASSERT_GE(r.output.size(), error.size());
  EXPECT_EQ(r.output.substr(r.output.size() - error.size()), error) << r.output;
  EXPECT_FALSE(fs::exists(dir / "cam.yaml"));
}

TEST(CalibIntrinsicsCli, BadInputIsRefusedWithTheReason) {
  const fs::path dir = intrinsics_dir();
  auto r = run_program("rhot-calib", "intrinsics --board chess:9x6 x.png --out " + (dir / "cam.yaml").string(), "2>&1");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.output, "rhot-calib: error: board \"chess:9x6\": expected chess:COLSxROWS:SQUARE_MM (e.g. chess:9x6:25)\n");
  r = run_program("rhot-calib", "intrinsics --board chess:9x6:25 " + (dir / "nope.png").string() + " --out " + (dir / "cam.yaml").string(),
                  "2>&1");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.output, "rhot-calib: error: " + (dir / "nope.png").string() + ": no such file\n") << "found missing before any detection";
  r = run_program("rhot-calib", "intrinsics --board chess:9x6:25 --out " + (dir / "cam.yaml").string(), "2>&1");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.output, "rhot-calib: error: no images: give the pictures of the board (files, or folders of them)\n");
  r = run_program("rhot-calib", "simulate board --out " + dir.string() + " --size 12", "2>&1");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.output,
            "rhot-calib: error: simulate board: --size must be WIDTHxHEIGHT in pixels, each 64 to 4096 (e.g. 1280x720), got \"12\"\n");
  EXPECT_FALSE(fs::exists(dir / "cam.yaml"));
}

}  // namespace
