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

}  // namespace
