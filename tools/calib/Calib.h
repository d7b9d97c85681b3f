#pragma once
// rhot-calib's subcommands, one file each (intrinsics.cpp, wand.cpp, world.cpp, merge.cpp,
// simulate.cpp), and what they share. Each add_* registers its subcommand on the app; when that
// subcommand runs, its callback stores the process's exit code in `exit_code` (0 on success, 1 on
// bad input or a failed calibration, with one line on stderr saying what was wrong).
//
// Conventions shared by every subcommand: progress goes to stderr through spdlog; `--json` prints
// one JSON report on stdout; pictures are PNG files beside the output (`--pictures DIR`, default:
// the output file's folder).

#include <expected>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

// GCC 12 reports -Wnull-dereference inside CLI11's string splitting (a false positive through
// inlined libstdc++ code), as in the other tools.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wnull-dereference"
#include <CLI/CLI.hpp>
#pragma GCC diagnostic pop
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "tracking/camera/Camera.h"
#include "tracking/source/FrameSource.h"
#include "tools/common/NodeKeys.h"

namespace rhot::calib_tool {

void add_intrinsics(CLI::App& app, int& exit_code);
void add_record(CLI::App& app, int& exit_code);
void add_wand(CLI::App& app, int& exit_code);
void add_world(CLI::App& app, int& exit_code);
void add_merge(CLI::App& app, int& exit_code);
void add_colours(CLI::App& app, int& exit_code);
void add_hand_model(CLI::App& app, int& exit_code);
void add_headset(CLI::App& app, int& exit_code);
// `simulate` has subcommands of its own: wand, lframe, floor (simulate.cpp) and board.
void add_simulate(CLI::App& app, int& exit_code);
void add_simulate_board(CLI::App& simulate, int& exit_code);

// A check for every number option: CLI11's range checks let NaN through (each comparison with it
// is false), and infinity is no size or threshold either.
const CLI::Validator& finite_number();

// The folder pictures go to: `pictures` when given, else the folder of `out`.
std::filesystem::path pictures_dir(const std::string& pictures, const std::string& out);

// Creates the folder an output file goes to (nothing when it exists or the path has none).
void make_parent_folder(const std::string& file);

// The cameras of one or more rig files, in order, as one rig: one intrinsics file per camera from
// `intrinsics`, or a rig file with them all. Poses in the files are ignored (load_rig_intrinsics):
// a file gathering every camera's intrinsics at the world origin is taken as it is. Fails on a
// file that does not load, or two cameras of one name.
[[nodiscard]] std::expected<rhot::CameraRig, std::string> load_cameras(const std::vector<std::string>& files);

// The frame source --source names (record.cpp): video:DEV[,DEV...] (capture devices, video files
// or image sequences, bright blobs found with `blob_threshold`, -1 automatic) or
// nodes:NAME@ENDPOINT[,...] (camera nodes, with the security `keys` ask for: --keys or
// --insecure, tools/common/NodeKeys.h). Fails naming what is wrong.
[[nodiscard]] std::expected<std::unique_ptr<FrameSource>, std::string> open_frame_source(const CameraRig& rig, const std::string& source,
                                                                                         int blob_threshold, const NodeKeyFlags& keys);

// Ctrl-C or SIGTERM, once stop_on_signals() has run: the commands that run until stopped
// (record, headset) end their loops on it and still write what they have.
void stop_on_signals();
bool stop_asked();

// Prints a report as indented JSON on stdout.
void print_json(const nlohmann::json& report);

// Logs `message` as an error; returns the exit status for it (1).
inline int fail(const std::string& message) {
  spdlog::error("{}", message);
  return 1;
}

}  // namespace rhot::calib_tool
