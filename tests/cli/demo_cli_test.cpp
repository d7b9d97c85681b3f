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
  // The stages are the frame: their mean times add up to the frame's, less only the few
  // microseconds between them (measured: 99.96 %), and no stage ever takes longer than its frame.
  double stages_ms = 0.0;
  for (const auto& [name, stage] : j["stages"].items()) {
    stages_ms += stage["mean_ms"].get<double>();
    EXPECT_LE(stage["max_ms"].get<double>(), j["max_ms"].get<double>()) << name;
  }
  EXPECT_LE(stages_ms, j["mean_ms"].get<double>());
  EXPECT_GT(stages_ms, 0.9 * j["mean_ms"].get<double>());
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

  const DemoRun threads = run_demo("--headless --threads -1");
  EXPECT_EQ(threads.exit_code, 1) << threads.output;
  EXPECT_NE(threads.output.find("--threads: Value -1 not in range 0 to 256"), std::string::npos) << threads.output;

  const DemoRun unknown = run_demo("--fly");
  EXPECT_NE(unknown.exit_code, 0);
  EXPECT_NE(unknown.output.find("--fly"), std::string::npos) << unknown.output;
}

// CLI11 read "-1" as the largest 64-bit number and saturated a number too large to it: a headless
// run that never ended. Such counts are refused before anything starts.
TEST(DemoCli, FrameCountsOutsideTheAllowedRangeAreRefused) {
  for (const std::string frames : {"-1", "99999999999999999999999", "100000001", "1e3"}) {
    const DemoRun r = run_demo("--headless --frames " + frames);
    EXPECT_EQ(r.exit_code, 1) << frames << ":\n" << r.output;
    EXPECT_NE(r.output.find("--frames: expected a whole number of frames from 0 to 100000000 (0: until closed), got " + frames),
              std::string::npos)
        << r.output;
  }
}

// Bad flags exit with status 1, as every other failure does, not with CLI11's own codes (105, 109).
TEST(DemoCli, BadFlagsExitWithStatusOne) {
  EXPECT_EQ(run_demo("--fly").exit_code, 1);
  EXPECT_EQ(run_demo("--frames lots").exit_code, 1);
  EXPECT_EQ(run_demo("--headless --log-level loud").exit_code, 1);
  EXPECT_EQ(run_demo("--help").exit_code, 0);
}

// Errors (and everything else the demo says) go to stderr; stdout stays empty.
TEST(DemoCli, ErrorsGoToStandardError) {
  const DemoRun stdout_only = rhot::test::run_program("rhot-demo", "--headless --scene /nonexistent/scene.json", "2>/dev/null");
  EXPECT_EQ(stdout_only.exit_code, 1);
  EXPECT_EQ(stdout_only.output, "");
  const DemoRun stderr_only = rhot::test::run_program("rhot-demo", "--headless --scene /nonexistent/scene.json", "2>&1 >/dev/null");
  EXPECT_EQ(stderr_only.exit_code, 1);
  EXPECT_NE(stderr_only.output.find("/nonexistent/scene.json: scene file not found"), std::string::npos) << stderr_only.output;
}

// A --stats file that cannot be written is refused before the run, not reported after it.
TEST(DemoCli, AStatsFileThatCannotBeWrittenIsRefusedBeforeTheRun) {
  const DemoRun missing = run_demo("--headless --frames 30 --eye 64x64 --stats /nonexistent/folder/stats.json");
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.output.find("--stats: cannot write /nonexistent/folder/stats.json: the folder /nonexistent/folder does not exist"),
            std::string::npos)
      << missing.output;
  EXPECT_EQ(missing.output.find(" frames ("), std::string::npos) << "no frame was run:\n" << missing.output;

  const fs::path dir = temp_dir();
  const DemoRun folder = run_demo("--headless --frames 30 --eye 64x64 --stats " + dir.string());
  EXPECT_EQ(folder.exit_code, 1);
  EXPECT_NE(folder.output.find("--stats: cannot write " + dir.string() + ": it is a folder"), std::string::npos) << folder.output;
  EXPECT_EQ(folder.output.find(" frames ("), std::string::npos) << "no frame was run:\n" << folder.output;
  EXPECT_TRUE(fs::is_empty(dir)) << "the check leaves nothing behind";
}

// A replay that runs on past the recording's end says so once, and holds the last frame.
TEST(DemoCli, AReplaySaysOnceWhereTheRecordingEnded) {
  const fs::path rec = temp_dir() / "short.jsonl";
  const DemoRun recorded = run_demo("--headless --frames 20 --eye 64x64 --record " + rec.string());
  ASSERT_EQ(recorded.exit_code, 0) << recorded.output;
  const DemoRun replayed = run_demo("--headless --frames 40 --eye 64x64 --source replay:" + rec.string());
  ASSERT_EQ(replayed.exit_code, 0) << replayed.output;
  const std::string said = "replay: the recording " + rec.string() + " ended at frame ";
  const std::size_t at = replayed.output.find(said);
  ASSERT_NE(at, std::string::npos) << replayed.output;
  EXPECT_EQ(replayed.output.find(said, at + 1), std::string::npos) << "said once:\n" << replayed.output;
  EXPECT_NE(replayed.output.find("its 20 frames (0.211 s) have played, and its last frame is held from here on", at), std::string::npos)
      << replayed.output;
  EXPECT_NE(replayed.output.find("40 frames ("), std::string::npos) << "the run goes on:\n" << replayed.output;
}

// A rig of more cameras than rhot tracks with (256) is refused as it is loaded, before any frame.
TEST(DemoCli, ARigOfTooManyCamerasIsRefusedBeforeAnyFrame) {
  const fs::path rig = temp_dir() / "too_many.yaml";
  {
    std::ofstream out(rig);
    out << "%YAML:1.0\n---\nrig_name: \"too-many\"\ncameras:\n";
    for (int i = 0; i < 257; ++i) {
      out << "   -\n      name: \"cam" << i << "\"\n      image_width: 640\n      image_height: 480\n"
          << "      camera_matrix: !!opencv-matrix\n         rows: 3\n         cols: 3\n         dt: d\n"
          << "         data: [ 500.0, 0.0, 319.5, 0.0, 500.0, 239.5, 0.0, 0.0, 1.0 ]\n"
          << "      distortion_coefficients: !!opencv-matrix\n         rows: 1\n         cols: 5\n         dt: d\n"
          << "         data: [ 0.0, 0.0, 0.0, 0.0, 0.0 ]\n"
          << "      rotation: !!opencv-matrix\n         rows: 3\n         cols: 3\n         dt: d\n"
          << "         data: [ 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0 ]\n"
          << "      translation: !!opencv-matrix\n         rows: 3\n         cols: 1\n         dt: d\n"
          << "         data: [ " << 0.01 * i << ", 0.0, 2.0 ]\n";
    }
  }
  const DemoRun r = run_demo("--headless --frames 5 --eye 64x64 --rig " + rig.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find(rig.string() + ": cameras: a rig may have at most 256 cameras, got 257"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find(" frames ("), std::string::npos) << "no frame was run:\n" << r.output;
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
