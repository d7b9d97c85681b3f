// Runs the real rhot-plan: planning a rig, evaluating it and the seed's arrangement, bad input.

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/support/RunCommand.h"
#include "tracking/camera/RigFile.h"

namespace {

namespace fs = std::filesystem;
using rhot::test::run_program;

fs::path temp_dir() {
  const fs::path d = fs::path(::testing::TempDir()) / "rhot_plan_cli" / ::testing::UnitTest::GetInstance()->current_test_info()->name();
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

const std::string kAssets = RHOT_ASSET_DIR;

TEST(PlanCli, HelpNamesEveryOption) {
  auto r = run_program("rhot-plan", "--help", "2>&1");
  EXPECT_EQ(r.exit_code, 0);
  for (const char* option : {"--volume", "--camera", "--cameras", "--max-error-mm", "--min-views", "--mount", "--ceiling-m",
                             "--wall-margin-m", "--sigma", "--out", "--pictures", "--json", "--floor-only", "evaluate", "joins"}) {
    EXPECT_NE(r.output.find(option), std::string::npos) << option;
  }
  r = run_program("rhot-plan", "evaluate --help", "2>&1");
  EXPECT_EQ(r.exit_code, 0);
  for (const char* option : {"--rig", "--volume", "--volume-centre", "--sigma", "--grid-step-m", "--slices-m", "--pictures", "--json"}) {
    EXPECT_NE(r.output.find(option), std::string::npos) << option;
  }
}

// A room planned with six webcams: the rig file loads, carries the volume, and evaluating it
// again gives the figures the planner printed; the pictures are written.
TEST(PlanCli, PlansARoomAndEvaluatesTheRigItWrote) {
  const fs::path dir = temp_dir();
  const fs::path out = dir / "room.yaml";
  const auto plan = run_program(
      "rhot-plan", "--volume 3x3x2 --camera " + kAssets + "/rigs/room-8.yaml --cameras 6 --ceiling-m 2.6 --out " + out.string() + " --json",
      "2>/dev/null");
  ASSERT_EQ(plan.exit_code, 0) << plan.output;
  const nlohmann::json p = nlohmann::json::parse(plan.output);
  EXPECT_EQ(p["cameras"], 6);
  EXPECT_GT(p["coverage_3"].get<double>(), 0.95);
  const auto rig = rhot::load_rig(out);
  ASSERT_TRUE(rig.has_value()) << rig.error();
  EXPECT_EQ(rig->cameras.size(), 6u);
  ASSERT_TRUE(rig->volume.has_value());
  EXPECT_EQ(rig->volume->size_m, Eigen::Vector3d(3, 2, 3));
  for (const char* picture : {"coverage-1.00m.png", "error-1.00m.png", "top-view.png"}) EXPECT_TRUE(fs::exists(dir / picture)) << picture;

  const auto eval = run_program("rhot-plan", "evaluate --rig " + out.string() + " --json", "2>/dev/null");
  ASSERT_EQ(eval.exit_code, 0) << eval.output;
  const nlohmann::json e = nlohmann::json::parse(eval.output);
  // The same figures from the rig file as from the plan (the file keeps poses to about 1e-15).
  for (const char* key : {"coverage_1", "coverage_2", "coverage_3"}) EXPECT_EQ(e[key], p[key]) << key;
  for (const char* key : {"predicted_median_mm", "predicted_p95_mm", "predicted_max_mm"}) {
    EXPECT_NEAR(e[key].get<double>(), p[key].get<double>(), 1e-9 * p[key].get<double>()) << key;
  }
}

// The prediction proven in simulation: two rigs planned by rhot-plan, markers spread uniformly
// through their volumes by rhot-eval, triangulated from 0.3 px detections; the measured median
// and 95th percentile of the 3D error agree with the predicted ones (the issue asks 15 %; they
// agreed within 1.5 % when this was written).
TEST(PlanCli, PredictedErrorsAreWhatASimulatedRunOnThePlannedRigMeasures) {
  const fs::path dir = temp_dir();
  const std::vector<std::string> plans = {
      "--volume 3x3x2 --camera " + kAssets + "/rigs/room-8.yaml --cameras 6 --ceiling-m 2.6",
      "--volume 4.6x4.6x2 --camera " + kAssets + "/rigs/seed-wiimote-10.yaml --cameras 10 --mount ceiling --ceiling-m 7",
  };
  for (std::size_t i = 0; i < plans.size(); ++i) {
    const fs::path rig = dir / ("planned-" + std::to_string(i) + ".yaml");
    const auto planned = run_program("rhot-plan", plans[i] + " --out " + rig.string() + " --json", "2>/dev/null");
    ASSERT_EQ(planned.exit_code, 0) << planned.output;
    const nlohmann::json p = nlohmann::json::parse(planned.output);
    const auto run = run_program("rhot-eval", "triangulation --rig " + rig.string() + " --markers 500 --frames 40 --spread uniform --json",
                                 "2>/dev/null");
    ASSERT_EQ(run.exit_code, 0) << run.output;
    const nlohmann::json m = nlohmann::json::parse(run.output);
    EXPECT_EQ(m["spread"], "uniform");
    EXPECT_GT(m["found_fraction"].get<double>(), 0.98) << plans[i];
    EXPECT_NEAR(p["predicted_median_mm"].get<double>() / m["error_median_mm"].get<double>(), 1.0, 0.05) << plans[i];
    EXPECT_NEAR(p["predicted_p95_mm"].get<double>() / m["error_p95_mm"].get<double>(), 1.0, 0.05) << plans[i];
  }
}

// Only the floor: a 5 cm layer on it, every camera above it; the rig's folder is made.
TEST(PlanCli, PlansForTheFloorOnly) {
  const fs::path dir = temp_dir();
  const auto r = run_program("rhot-plan",
                             "--volume 4x3 --floor-only --camera " + kAssets + "/rigs/room-8.yaml --cameras 4 --ceiling-m 2.5 --out " +
                                 (dir / "new" / "floor.yaml").string() + " --json",
                             "2>/dev/null");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["volume_size_m"], nlohmann::json({4.0, 0.05, 3.0}));
  EXPECT_EQ(j["volume_centre_m"], nlohmann::json({0.0, 0.025, 0.0}));
  EXPECT_GT(j["coverage_3"].get<double>(), 0.95);
  const auto rig = rhot::load_rig(dir / "new" / "floor.yaml");  // its folder made
  ASSERT_TRUE(rig.has_value()) << rig.error();
  for (const rhot::Camera& c : rig->cameras) EXPECT_GT(c.centre_world().y(), 0.05) << c.name;
}

TEST(PlanCli, EvaluatesTheSeedsArrangementWithPictures) {
  const fs::path dir = temp_dir();
  const auto r = run_program(
      "rhot-plan", "evaluate --rig " + kAssets + "/rigs/seed-wiimote-10.yaml --slices-m 0.5,1.5 --pictures " + dir.string() + " --json",
      "2>/dev/null");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["cameras"], 10);
  EXPECT_EQ(j["volume_size_m"], nlohmann::json({4.6, 2.0, 4.6}));
  EXPECT_GT(j["coverage_2"].get<double>(), 0.3);
  EXPECT_LT(j["coverage_2"].get<double>(), 1.0);
  for (const char* picture : {"coverage-0.50m.png", "error-1.50m.png", "top-view.png"}) EXPECT_TRUE(fs::exists(dir / picture)) << picture;
}

TEST(PlanCli, BadInputGetsOneClearLine) {
  const fs::path dir = temp_dir();
  const std::string model = " --camera " + kAssets + "/rigs/room-8.yaml";
  const std::string out = " --out " + (dir / "x.yaml").string();
  const std::string huge = "1" + std::string(400, '0');  // digits beyond a double's range
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"--volume 3x3 --cameras 4" + model + out,
       "rhot-plan: --volume: expected LxWxH in metres (length along X, width along Z, height), got \"3x3\"\n"},
      {"--volume 3x0x2 --cameras 4" + model + out, "rhot-plan: --volume: every side must be positive, got \"3x0x2\"\n"},
      {"--volume 3x3x2" + model + out, "rhot-plan: give one of --cameras and --max-error-mm\n"},
      {"--volume 3x3x2 --cameras 4 --max-error-mm 2" + model + out, "rhot-plan: give one of --cameras and --max-error-mm\n"},
      {"--volume 3x3x2 --cameras 4 --ceiling-m 1" + model + out, "rhot-plan: ceiling: 1.00 m is not above the volume's top (2.00 m)\n"},
      {"--volume 3x3x2 --cameras 4 --camera /nonexistent.yaml" + out, "rhot-plan: /nonexistent.yaml: rig file not found\n"},
      {"--volume 3x" + huge + "x2 --cameras 4" + model + out,
       "rhot-plan: --volume: every side must be positive, got \"3x" + huge + "x2\"\n"},
      {"--volume 3x" + huge + " --floor-only --cameras 4" + model + out,
       "rhot-plan: --volume: every side must be positive, got \"3x" + huge + "\"\n"},
      {"--volume 3 --floor-only --cameras 4" + model + out,
       "rhot-plan: --volume: expected LxW in metres with --floor-only (length along X, width along Z), got \"3\"\n"},
      {"evaluate --rig " + kAssets + "/rigs/room-8.yaml --volume 1x1",
       "rhot-plan: --volume: expected LxWxH in metres (length along X, width along Z, height), got \"1x1\"\n"},
  };
  for (const auto& [args, message] : cases) {
    const auto r = run_program("rhot-plan", args, "2>&1");
    EXPECT_EQ(r.exit_code, 1) << args;
    EXPECT_EQ(r.output, message) << args;
  }
  // A folder for the rig that cannot be made: said before planning.
  {
    std::ofstream(dir / "a-file") << "not a folder";
    const auto r =
        run_program("rhot-plan", "--volume 3x3x2 --cameras 4" + model + " --out " + (dir / "a-file" / "x.yaml").string(), "2>&1");
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_EQ(r.output, "rhot-plan: --out: cannot make the folder " + (dir / "a-file").string() + ": Not a directory\n");
  }
  // Numbers the flags' own checks refuse, each said in words (CLI11 adds its hint to --help).
  const std::vector<std::pair<std::string, std::string>> numbers = {
      {"--sigma " + huge, "--sigma: expected a finite number, got " + huge},
      {"--sigma abc", "--sigma: expected a number, got abc"},
      {"--sigma 0", "--sigma: expected a number above 0, got 0"},
      {"--wall-margin-m -1", "--wall-margin-m: expected 0 or more, got -1"},
      {"--volume-centre 0 nan 0", "--volume-centre: expected a finite number, got nan"},
  };
  for (const auto& [flag, message] : numbers) {
    const auto r = run_program("rhot-plan", "--volume 3x3x2 --cameras 4 " + flag + model + out, "2>&1");
    EXPECT_NE(r.exit_code, 0) << flag;
    EXPECT_EQ(r.output, message + "\nRun with --help for more information.\n") << flag;
  }
  EXPECT_FALSE(fs::exists(dir / "x.yaml")) << "a failed plan wrote a rig";
}

}  // namespace

namespace {

// Seed 000's four vision systems over its 10 Wiimotes: every camera's error through the cheapest
// chain of joins; the farthest system carries 1 + 8.5 + 9.5 = 19 mm (the seed: about 20 mm).
TEST(PlanCli, JoinsGiveEveryCameraItsErrorThroughTheCheapestChain) {
  const auto r = run_program(
      "rhot-plan", "joins --joins " + kAssets + "/plan/seed-wiimote-10-joins.json --rig " + kAssets + "/rigs/seed-wiimote-10.yaml --json",
      "2>/dev/null");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["max_error_mm"], 19.0);
  ASSERT_EQ(j["cameras"].size(), 10u);
  EXPECT_EQ(j["cameras"][0]["camera"], "wiimote-0");
  EXPECT_EQ(j["cameras"][0]["error_mm"], 1.0);
  EXPECT_EQ(j["cameras"][2]["error_mm"], 1.0);  // shared by systems 1 and 2: known through 1
  EXPECT_EQ(j["cameras"][4]["error_mm"], 9.5);
  EXPECT_EQ(j["cameras"][9]["error_mm"], 19.0);
  EXPECT_EQ(j["groups"][3]["chain"], nlohmann::json({"1", "2", "4"}));
}

TEST(PlanCli, ABadJoinsFileNamesWhereItIsWrong) {
  const fs::path dir = temp_dir();
  const fs::path file = dir / "joins.json";
  {
    std::ofstream(file)
        << R"({"reference": "a", "groups": [{"name": "a"}, {"name": "b"}], "joins": [{"a": "a", "b": "b", "error_mm": -2}]})";
  }
  auto r = run_program("rhot-plan", "joins --joins " + file.string(), "2>&1");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.output, "rhot-plan: " + file.string() + ": /joins/0/error_mm: expected an error from 0 to 1e6 mm, got -2\n");
  { std::ofstream(file) << R"({"reference": "c", "groups": [{"name": "a"}], "joins": []})"; }
  r = run_program("rhot-plan", "joins --joins " + file.string(), "2>&1");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.output, "rhot-plan: " + file.string() + ": reference: \"c\" is not a group\n");
  { std::ofstream(file) << R"({"reference": "a", "groups": [{"name": "a", "cameras": ["wiimote-0"]}], "joins": []})"; }
  r = run_program("rhot-plan", "joins --joins " + file.string() + " --rig " + kAssets + "/rigs/seed-wiimote-10.yaml", "2>&1");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.output,
            "rhot-plan: " + file.string() + ": camera \"wiimote-1\" of " + kAssets + "/rigs/seed-wiimote-10.yaml is in no group\n");
}

}  // namespace
