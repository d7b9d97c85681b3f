// Runs the real rhot-demo executable and checks its exit status, output and statistics file.

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace {

namespace fs = std::filesystem;

struct DemoRun {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

// env_prefix: e.g. "env -u DISPLAY" to run the demo in a changed environment.
DemoRun run_demo(const std::string& args, const std::string& env_prefix = "") {
  const std::string command = env_prefix + " " + std::string(RHOT_BINARY_DIR) + "/rhot-demo " + args + " 2>&1";
  DemoRun r;
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return r;
  std::array<char, 4096> buffer{};
  while (fgets(buffer.data(), static_cast<int>(buffer.size()), pipe) != nullptr) r.output += buffer.data();
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

fs::path temp_dir() {
  const fs::path d = fs::path(::testing::TempDir()) / "rhot_demo_cli" /
                     ::testing::UnitTest::GetInstance()->current_test_info()->name();
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
  const DemoRun r = run_demo("--headless --frames 90 --stats " + stats.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
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

  const DemoRun unknown = run_demo("--fly");
  EXPECT_NE(unknown.exit_code, 0);
  EXPECT_NE(unknown.output.find("--fly"), std::string::npos) << unknown.output;
}

}  // namespace
