// rhot-demo --xr against a real OpenXR runtime (tests/support/XrRuntime.h), and without one.

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/support/RunCommand.h"
#include "tests/support/XrRuntime.h"

namespace {

namespace fs = std::filesystem;

TEST(DemoXr, RunsASessionThroughItsStatesShowingThreeHundredFramesWithBothValidationLayersSilent) {
  RHOT_REQUIRE_XR_RUNTIME(runtime);
  const fs::path dir = fs::path(::testing::TempDir()) / "rhot_xr_cli";
  fs::create_directories(dir);
  const fs::path stats = dir / "stats.json";
  const auto r = rhot::test::run_program("rhot-demo", "--xr --frames 300 --validation --stats " + stats.string(), "2>&1",
                                         "env " + rhot::test::xr_test_environment(runtime));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // Every state of a session asked to end, in order.
  std::size_t at = 0;
  for (const char* state :
       {"idle", "ready", "synchronized", "visible", "focused", "visible", "synchronized", "stopping", "idle", "exiting"}) {
    at = r.output.find(std::string("OpenXR session: ") + state + "\n", at);
    ASSERT_NE(at, std::string::npos) << "no state " << state << " in order in:\n" << r.output;
    ++at;
  }
  std::ifstream in(stats);
  ASSERT_TRUE(in.good()) << r.output;
  const nlohmann::json xr = nlohmann::json::parse(in).at("xr");
  EXPECT_EQ(xr.at("frames_shown").get<int>(), 300);
  EXPECT_EQ(xr.at("session_end").get<std::string>(), "the session ended as asked");
  EXPECT_TRUE(xr.at("validation_enabled").get<bool>());
  EXPECT_TRUE(xr.at("vulkan_validation_enabled").get<bool>());
  EXPECT_EQ(xr.at("validation_messages").get<int>(), 0) << r.output;
  EXPECT_EQ(xr.at("vulkan_validation_messages").get<int>(), 0) << r.output;
  EXPECT_NEAR(xr.at("refresh_hz").get<double>(), 20.0, 1.0);
}

TEST(DemoXr, WithoutARuntimeSaysInOneLineHowToSelectOne) {
  const auto r = rhot::test::run_program("rhot-demo", "--xr --frames 3", "2>&1", "env XR_RUNTIME_JSON=/nonexistent/openxr_runtime.json");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  EXPECT_NE(r.output.find("[error] --xr: no OpenXR runtime (XR_ERROR_RUNTIME_UNAVAILABLE): XR_RUNTIME_JSON names "
                          "/nonexistent/openxr_runtime.json, which is not a file\n"),
            std::string::npos)
      << r.output;
}

TEST(DemoXr, MirrorNeedsAHeadset) {
  const auto r = rhot::test::run_program("rhot-demo", "--mirror --frames 3", "2>&1");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("[error] --mirror: needs --xr (without a headset the window shows the eyes anyway)\n"), std::string::npos)
      << r.output;
}

TEST(CalibHeadset, RegistersTheSimulatedRigToTheRuntimesStageFromThirtySecondsOfItsMovingHead) {
  RHOT_REQUIRE_XR_RUNTIME(runtime);
  const fs::path dir = fs::path(::testing::TempDir()) / "rhot_xr_calib";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path out = dir / "headset.yaml";
  const auto r = rhot::test::run_program("rhot-calib", "headset --simulate --sigma 0.5 --seconds 30 --json --out " + out.string(),
                                         "2>" + (dir / "log.txt").string(), "env " + rhot::test::xr_test_environment(runtime));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  // 30 s at the runtime's 20 Hz, the star seen in nearly every frame.
  EXPECT_GE(j.at("samples").get<int>(), 500);
  const nlohmann::json& err = j.at("truth_error").at("world_from_stage");
  EXPECT_LT(err.at("rotation_deg").get<double>(), 0.2) << r.output;
  EXPECT_LT(err.at("translation_mm").get<double>(), 2.0) << r.output;
  EXPECT_TRUE(fs::exists(dir / "headset_residuals.png"));
  // The demo takes the registration; a file that is not one is refused naming it.
  const auto demo = rhot::test::run_program("rhot-demo", "--xr --frames 10 --registration " + out.string(), "2>&1",
                                            "env " + rhot::test::xr_test_environment(runtime));
  EXPECT_EQ(demo.exit_code, 0) << demo.output;
  EXPECT_NE(demo.output.find("the rig registered to the headset by " + out.string()), std::string::npos) << demo.output;
  const fs::path bad = dir / "bad.yaml";
  std::ofstream(bad) << "%YAML:1.0\n---\nrms_mm: 1.0\n";
  const auto refused = rhot::test::run_program("rhot-demo", "--xr --frames 10 --registration " + bad.string(), "2>&1",
                                               "env " + rhot::test::xr_test_environment(runtime));
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_NE(refused.output.find("[error] --registration: " + bad.string() + ": world_from_stage: missing\n"), std::string::npos)
      << refused.output;
}

}  // namespace
