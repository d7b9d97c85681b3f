// Runs the real rhot-demo executable and checks its exit status, output and statistics file.

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/support/RunCommand.h"

namespace {

namespace fs = std::filesystem;

using DemoRun = rhot::test::CommandRun;

// env_prefix: e.g. "env -u DISPLAY" to run the demo in a changed environment. Output: stdout and
// stderr together.
DemoRun run_demo(const std::string& args, const std::string& env_prefix = "") {
  return rhot::test::run_program("rhot-demo", args, "2>&1", env_prefix);
}

fs::path temp_dir() {
  const fs::path d = fs::path(::testing::TempDir()) / "rhot_demo_cli" / ::testing::UnitTest::GetInstance()->current_test_info()->name();
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

TEST(DemoCli, HelpListsTheOptions) {
  const DemoRun r = run_demo("--help");
  EXPECT_EQ(r.exit_code, 0);
  for (const char* option : {"--scene", "--headless", "--frames", "--stats"}) {
    EXPECT_NE(r.output.find(option), std::string::npos) << option << " missing from:\n" << r.output;
  }
}

TEST(DemoCli, RunsTheDefaultSceneHeadlessAndWritesStatistics) {
  const fs::path stats = temp_dir() / "stats.json";
  const DemoRun r = run_demo("--headless --frames 90 --eye 160x176 --stats " + stats.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("vulkan validation"), std::string::npos) << "debug builds validate; no message allowed:\n" << r.output;
  std::ifstream in(stats);
  ASSERT_TRUE(in.good()) << r.output;
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["frames"], 90);
  EXPECT_DOUBLE_EQ(j["budget_ms"].get<double>(), 11.1);
  EXPECT_TRUE(j.contains("p50_ms"));
  EXPECT_TRUE(j.contains("p99_ms"));
  EXPECT_TRUE(j.contains("budget_miss_fraction"));
  ASSERT_TRUE(j["stages"].contains("transforms"));
  EXPECT_LE(j["stages"]["transforms"]["p50_ms"].get<double>(), j["max_ms"].get<double>());
}

TEST(DemoCli, FallsBackToHeadlessWithoutADisplay) {
  const DemoRun r = run_demo("--frames 5", "env -u DISPLAY -u WAYLAND_DISPLAY");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("no display found"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("5 frames"), std::string::npos) << r.output;
}

TEST(DemoCli, CapturesBothEyesAsPng) {
  const fs::path dir = temp_dir();
  const DemoRun eyes = run_demo("--headless --frames 2 --eye 64x48 --capture " + (dir / "eyes").string());
  ASSERT_EQ(eyes.exit_code, 0) << eyes.output;
  for (const char* name : {"frame_000000_left.png", "frame_000000_right.png", "frame_000001_left.png", "frame_000001_right.png"}) {
    EXPECT_TRUE(fs::is_regular_file(dir / "eyes" / name)) << name;
  }
  const DemoRun sbs = run_demo("--headless --frames 1 --eye 64x48 --capture-layout side-by-side --capture " + (dir / "sbs").string());
  ASSERT_EQ(sbs.exit_code, 0) << sbs.output;
  // A PNG's IHDR holds width and height as big-endian 32-bit numbers at bytes 16 and 20.
  std::ifstream png(dir / "sbs" / "frame_000000.png", std::ios::binary);
  ASSERT_TRUE(png.good());
  std::array<unsigned char, 24> header{};
  png.read(reinterpret_cast<char*>(header.data()), header.size());
  EXPECT_EQ((header[16] << 24) | (header[17] << 16) | (header[18] << 8) | header[19], 128) << "two 64-pixel eyes side by side";
  EXPECT_EQ((header[20] << 24) | (header[21] << 16) | (header[22] << 8) | header[23], 48);
}

TEST(DemoCli, BadRendererOptionsAreReported) {
  const DemoRun size = run_demo("--headless --frames 1 --eye 64by48");
  EXPECT_EQ(size.exit_code, 1);
  EXPECT_NE(size.output.find("--eye: expected WIDTHxHEIGHT in pixels, such as 1080x1200, got \"64by48\""), std::string::npos)
      << size.output;
  const DemoRun device = run_demo("--headless --frames 1 --device warp-drive");
  EXPECT_EQ(device.exit_code, 1);
  EXPECT_NE(device.output.find("cannot start the renderer: no Vulkan device matches \"warp-drive\""), std::string::npos) << device.output;
}

TEST(DemoCli, NoVulkanDriverIsAClearError) {
  // Point the Vulkan loader at a driver list that does not exist: as on a machine with no driver.
  const DemoRun r = run_demo("--headless --frames 1", "env VK_ICD_FILENAMES=/nonexistent/icd.json VK_DRIVER_FILES=/nonexistent/icd.json");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("cannot start the renderer: "), std::string::npos) << r.output;
  EXPECT_TRUE(r.output.find("VK_ERROR_INCOMPATIBLE_DRIVER (no Vulkan driver installed?)") != std::string::npos ||
              r.output.find("no Vulkan device found") != std::string::npos)
      << r.output;
}

TEST(DemoCli, BadSceneExitsNonZeroWithTheError) {
  const fs::path dir = temp_dir();
  const fs::path scene = dir / "bad.json";
  std::ofstream(scene) << R"({"entities": [{"name": "box", "mesh": {"shape": "box", "size_m": [1, 1, 1]},
                                             "body": {"type": "dynamic", "mass_kg": -2}}]})";
  const DemoRun r = run_demo("--headless --frames 1 --scene " + scene.string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("cannot load scene: " + scene.string() +
                          ": /entities/0/body/mass_kg: expected a mass greater than 0 kg for a dynamic body, got -2"),
            std::string::npos)
      << r.output;
}

TEST(DemoCli, MissingSceneAndBadFlagsAreReported) {
  const DemoRun missing = run_demo("--headless --scene /nonexistent/scene.json");
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.output.find("/nonexistent/scene.json: scene file not found"), std::string::npos) << missing.output;

  const DemoRun bad_flag = run_demo("--frames lots");
  EXPECT_NE(bad_flag.exit_code, 0);
  EXPECT_NE(bad_flag.output.find("--frames"), std::string::npos) << bad_flag.output;

  // A number the flag's range lets through but no simulation can use: a clear error, no abort.
  const DemoRun nan_sigma = run_demo("--headless --sigma nan");
  EXPECT_EQ(nan_sigma.exit_code, 1) << nan_sigma.output;
  EXPECT_NE(nan_sigma.output.find("sigma: the simulated pixel noise must be a number from 0 to 50 pixels, got nan"), std::string::npos)
      << nan_sigma.output;

  const DemoRun nan_rate = run_demo("--headless --rate-hz nan");
  EXPECT_EQ(nan_rate.exit_code, 1) << nan_rate.output;
  EXPECT_NE(nan_rate.output.find("rate_hz must be from 1 to 10000, got nan"), std::string::npos) << nan_rate.output;

  const DemoRun unknown = run_demo("--fly");
  EXPECT_NE(unknown.exit_code, 0);
  EXPECT_NE(unknown.output.find("--fly"), std::string::npos) << unknown.output;
}

}  // namespace

namespace {

// The demo on coloured markers: colour cameras drawn by the renderer on the stereo pair, the
// colour detector, matching by colour, the colour hand layouts; and a bad colour file refused.
TEST(DemoCli, RunsWithColourMarkersOnSimulatedColourCameras) {
  const fs::path stats = temp_dir() / "stats.json";
  const DemoRun r = run_demo("--headless --markers colour --frames 45 --eye 160x176 --stats " + stats.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("colour cameras ("), std::string::npos) << "the source's summary:\n" << r.output;
  std::ifstream in(stats);
  ASSERT_TRUE(in.good()) << r.output;
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["frames"], 45);

  const fs::path bad = temp_dir() / "bad_colours.json";
  std::ofstream(bad) << R"({"format": "rhot-marker-colours", "version": 1, "colours": [{"name": "teal", "hue_deg": 180,
      "hue_tolerance_deg": 20, "min_saturation": 0.5, "min_value": 0.2}]})";
  const DemoRun refused = run_demo("--headless --markers colour --frames 5 --colours " + bad.string());
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_NE(refused.output.find(
                bad.string() +
                ": /colours/0/name: expected a marker colour (red, orange, yellow, green, cyan, blue, purple, magenta), got \"teal\""),
            std::string::npos)
      << refused.output;
  const DemoRun without = run_demo("--headless --frames 5 --colours " + bad.string());
  EXPECT_NE(without.exit_code, 0);
  EXPECT_NE(without.output.find("--colours: a colour model needs --markers colour"), std::string::npos) << without.output;
}

}  // namespace
