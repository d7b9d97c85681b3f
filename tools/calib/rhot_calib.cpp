// rhot-calib: from a box of cameras to a metric rig.
//
//   rhot-calib intrinsics --board chess:COLSxROWS:SQUARE_MM IMAGES... --out CAM.yaml [--json]
//   rhot-calib record --rig RIG.yaml --source video:DEV[,DEV...] --out DETECTIONS.csv
//   rhot-calib wand --intrinsics RIG.yaml --detections PATH [--wand-mm L] --out RIG.yaml [--json]
//   rhot-calib world --rig RIG.yaml --detections PATH (--lframe | --floor) --out RIG.yaml [--json]
//   rhot-calib merge RIG_A.yaml RIG_B.yaml --out RIG.yaml [--json]
//   rhot-calib colours IMAGES... | --source video:DEV --out colours.json [--expect red,...] [--mask FILE...] [--json]
//   rhot-calib hand-model --take TAKE.c3d|TAKE.tsv --out MODEL.json [--fit-seconds S] [--json]
//   rhot-calib headset --simulate | --rig RIG.yaml --source SRC --star ID --out headset.yaml [--seconds 30] [--json]
//   rhot-calib simulate wand|lframe|floor|board ...
//
// docs/calibration.md walks through them in order.

#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <iostream>

#include <spdlog/cfg/env.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include "tools/calib/Calib.h"
#include "tools/common/CliExit.h"
#include "tools/common/NumberChecks.h"
#include "tracking/camera/RigFile.h"

namespace rhot::calib_tool {

namespace {
std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop.store(true); }
}  // namespace

void stop_on_signals() {
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
}

bool stop_asked() { return g_stop.load(); }

const CLI::Validator& finite_number() {
  static const CLI::Validator validator = number_check(NumberBound::kAny);
  return validator;
}

std::filesystem::path pictures_dir(const std::string& pictures, const std::string& out) {
  if (!pictures.empty()) return pictures;
  const std::filesystem::path parent = std::filesystem::path(out).parent_path();
  return parent.empty() ? std::filesystem::path(".") : parent;
}

void make_parent_folder(const std::string& file) {
  const std::filesystem::path parent = std::filesystem::path(file).parent_path();
  std::error_code ec;
  if (!parent.empty()) std::filesystem::create_directories(parent, ec);
}

std::expected<rhot::CameraRig, std::string> load_cameras(const std::vector<std::string>& files) {
  rhot::CameraRig rig;
  for (const std::string& file : files) {
    auto loaded = rhot::load_rig_intrinsics(file);
    if (!loaded) return std::unexpected(loaded.error());
    if (rig.name.empty()) rig.name = loaded->name;
    for (rhot::Camera& c : loaded->cameras) {
      for (const rhot::Camera& other : rig.cameras) {
        if (other.name == c.name) {
          return std::unexpected(file + ": camera \"" + c.name +
                                 "\" is already in an earlier file; name each camera apart (intrinsics --name)");
        }
      }
      rig.cameras.push_back(std::move(c));
    }
  }
  return rig;
}

void print_json(const nlohmann::json& report) { std::cout << report.dump(2) << "\n"; }

}  // namespace rhot::calib_tool

int main(int argc, char** argv) {
  // Progress and warnings on stderr, so stdout holds only the JSON report.
  spdlog::set_default_logger(spdlog::stderr_color_mt("rhot-calib"));
  spdlog::set_pattern("rhot-calib: %^%l%$: %v");
  spdlog::cfg::load_env_levels();

  CLI::App app{"rhot-calib: calibrate cameras into a metric rig (intrinsics, wand, world frame, merge), or simulate sessions to try it"};
  app.require_subcommand(1);
  int exit_code = 0;
  rhot::calib_tool::add_intrinsics(app, exit_code);
  rhot::calib_tool::add_record(app, exit_code);
  rhot::calib_tool::add_wand(app, exit_code);
  rhot::calib_tool::add_world(app, exit_code);
  rhot::calib_tool::add_merge(app, exit_code);
  rhot::calib_tool::add_colours(app, exit_code);
  rhot::calib_tool::add_hand_model(app, exit_code);
  rhot::calib_tool::add_headset(app, exit_code);
  rhot::calib_tool::add_simulate(app, exit_code);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return rhot::cli_exit_status(app, e);
  }
  return exit_code;
}
