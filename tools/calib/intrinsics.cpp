// rhot-calib intrinsics: one camera's focal length, principal point and lens distortion from
// pictures of a flat board (Zhang's method), written as a one-camera rig for `rhot-calib wand`.

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <system_error>
#include <vector>

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "tools/calib/Calib.h"
#include "tracking/calib/CalibPictures.h"
#include "tracking/calib/Intrinsics.h"
#include "tracking/camera/RigFile.h"

namespace rhot::calib_tool {

namespace {

namespace fs = std::filesystem;

struct IntrinsicsOptions {
  std::vector<std::string> images;
  std::string board;
  std::string out;
  std::string name;
  std::string pictures;
  bool json = false;
  bool fix_k3 = true;
  bool leave_one_out = true;
};

bool is_image(const fs::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  for (const char* e : {".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".pgm", ".ppm", ".webp"}) {
    if (ext == e) return true;
  }
  return false;
}

// The pictures: files as given, folders replaced by their image files in name order.
std::vector<fs::path> expand(const std::vector<std::string>& arguments) {
  std::vector<fs::path> files;
  for (const std::string& a : arguments) {
    std::error_code error;
    if (!fs::is_directory(a, error)) {
      files.emplace_back(a);
      continue;
    }
    std::vector<fs::path> inside;
    for (const fs::directory_entry& e : fs::directory_iterator(a, error)) {
      if (e.is_regular_file(error) && is_image(e.path())) inside.push_back(e.path());
    }
    std::sort(inside.begin(), inside.end());
    files.insert(files.end(), inside.begin(), inside.end());
  }
  return files;
}

nlohmann::json round_to(double value, double step) { return std::round(value / step) * step; }

int run_intrinsics(const IntrinsicsOptions& o) {
  if (o.board.empty()) return fail("intrinsics: --board is required, e.g. --board chess:9x6:25 (9 x 6 inner corners, 25 mm squares)");
  if (o.out.empty()) return fail("intrinsics: --out is required: the camera file to write, e.g. --out cam0.yaml");
  const auto board = parse_board_spec(o.board);
  if (!board) return fail(board.error());
  const std::vector<fs::path> images = expand(o.images);
  const std::string name = o.name.empty() ? fs::path(o.out).stem().string() : o.name;

  const auto views = detect_boards(images, *board, [](int index, int count, const std::string& file) {
    spdlog::info("detecting corners {}/{}: {}", index, count, file);
  });
  if (!views) return fail(views.error());
  int found = 0;
  for (const BoardView& v : *views) found += v.found() ? 1 : 0;
  spdlog::info("board found in {} of {} images; calibrating{}", found, views->size(),
               o.leave_one_out ? " (and once more per view, leaving it out)" : "");
  IntrinsicsSettings settings;
  settings.fix_k3 = o.fix_k3;
  settings.leave_one_out = o.leave_one_out;
  const auto report = calibrate_intrinsics(*views, settings);
  if (!report) return fail(report.error());
  const CameraIntrinsics& k = report->intrinsics;
  char held_out[64] = "";
  if (report->leave_one_out_rms_px) std::snprintf(held_out, sizeof held_out, " (leave-one-out %.3f px)", *report->leave_one_out_rms_px);
  spdlog::info("rms {:.3f} px{}; fx {:.2f} fy {:.2f} cx {:.2f} cy {:.2f} px; k1 {:.5f} k2 {:.5f} p1 {:.5f} p2 {:.5f} k3 {:.5f}",
               report->rms_px, held_out, k.fx, k.fy, k.cx, k.cy, k.distortion[0], k.distortion[1], k.distortion[2], k.distortion[3],
               k.distortion[4]);
  for (const std::string& w : report->warnings) spdlog::warn("{}", w);

  // The camera as a one-camera rig at the world origin: `rhot-calib wand --intrinsics` reads it.
  CameraRig rig;
  rig.name = name;
  rig.cameras.push_back(Camera{name, k, Rigid3d::identity()});
  std::error_code error;
  if (const fs::path parent = fs::path(o.out).parent_path(); !parent.empty()) fs::create_directories(parent, error);
  make_parent_folder(o.out);
  if (auto saved = save_rig(rig, o.out); !saved) return fail(saved.error());
  spdlog::info("wrote {}", o.out);

  const fs::path picture_dir = pictures_dir(o.pictures, o.out);
  fs::create_directories(picture_dir, error);
  const fs::path picture = picture_dir / (name + "_intrinsics.png");
  std::vector<ResidualSample> samples;
  for (const ViewResult& v : report->views) {
    for (std::size_t i = 0; i < v.corners_px.size(); ++i) samples.push_back({v.corners_px[i], v.residuals_px[i], true});
  }
  // Magnified so that a typical residual draws about 10 pixels long.
  const double magnify = std::clamp(std::round(10.0 / std::max(report->rms_px, 1e-3)), 5.0, 500.0);
  char title[160];
  std::snprintf(title, sizeof title, "%s intrinsics: %zu views, rms %.3f px, coverage %.0f %%", name.c_str(), report->views.size(),
                report->rms_px, 100.0 * report->coverage);
  if (auto drawn = write_residual_picture(picture, k.width_px, k.height_px, samples, magnify, title); !drawn) return fail(drawn.error());
  spdlog::info("wrote {} (corner coverage and residuals x{:.0f})", picture.string(), magnify);

  if (o.json) {
    nlohmann::json j;
    j["camera"] = name;
    j["board"] = board->to_string();
    j["out"] = o.out;
    j["images"] = views->size();
    j["views_used"] = report->views.size();
    j["skipped"] = report->skipped;
    j["image_width"] = k.width_px;
    j["image_height"] = k.height_px;
    j["rms_px"] = report->rms_px;
    j["leave_one_out_rms_px"] = report->leave_one_out_rms_px ? nlohmann::json(*report->leave_one_out_rms_px) : nlohmann::json(nullptr);
    j["fx"] = k.fx;
    j["fy"] = k.fy;
    j["cx"] = k.cx;
    j["cy"] = k.cy;
    j["dist"] = k.distortion;
    j["k3_fixed"] = report->k3_fixed;
    j["sigma"] = {{"fx", report->fx_sigma},
                  {"fy", report->fy_sigma},
                  {"cx", report->cx_sigma},
                  {"cy", report->cy_sigma},
                  {"dist", report->distortion_sigma}};
    nlohmann::json per_view = nlohmann::json::array();
    for (const ViewResult& v : report->views) {
      per_view.push_back({{"name", v.name},
                          {"points", v.corners_px.size()},
                          {"rms_px", v.rms_px},
                          {"held_out_rms_px", v.held_out_rms_px ? nlohmann::json(*v.held_out_rms_px) : nlohmann::json(nullptr)},
                          {"tilt_deg", round_to(v.tilt_deg, 0.01)}});
    }
    j["views"] = per_view;
    j["worst_views"] = report->worst_views;
    j["coverage"] = report->coverage;
    j["tilt_min_deg"] = round_to(report->tilt_min_deg, 0.01);
    j["tilt_max_deg"] = round_to(report->tilt_max_deg, 0.01);
    j["orientation_spread_deg"] = round_to(report->orientation_spread_deg, 0.01);
    j["warnings"] = report->warnings;
    j["pictures"] = {picture.string()};
    print_json(j);
  }
  return 0;
}

}  // namespace

void add_intrinsics(CLI::App& app, int& exit_code) {
  CLI::App* cmd =
      app.add_subcommand("intrinsics",
                         "one camera's focal length, principal point and lens distortion from pictures of a flat board (Zhang's method); "
                         "writes a one-camera rig for `wand --intrinsics`");
  auto o = std::make_shared<IntrinsicsOptions>();
  cmd->add_option("images", o->images, "pictures of the board from one camera (files, or folders of .png/.jpg/...), 10-20 tilted views");
  cmd->add_option("--board", o->board,
                  "the board: chess:COLSxROWS:SQUARE_MM (COLS x ROWS inner corners, as OpenCV counts: 10 x 7 squares is chess:9x6), "
                  "circles:COLSxROWS:SPACING_MM, acircles:COLSxROWS:SPACING_MM (OpenCV's asymmetric grid), or "
                  "charuco:COLSxROWS:SQUARE_MM:MARKER_MM[:DICT] (COLS x ROWS squares; DICT default 4X4_50)");
  cmd->add_option("--out", o->out, "the camera file to write (OpenCV YAML rig with one camera), e.g. cam0.yaml");
  cmd->add_option("--name", o->name, "the camera's name in the file and pictures (default: the --out file's stem)");
  cmd->add_option("--pictures", o->pictures, "folder for the picture <name>_intrinsics.png (default: the folder of --out)");
  cmd->add_flag("--json", o->json, "print a JSON report on stdout: rms_px, fx, fy, cx, cy, dist, per-view RMS, worst views, warnings");
  cmd->add_flag("--fix-k3,!--free-k3", o->fix_k3,
                "keep k3 at 0 (the default: k3 helps only wide-angle lenses); --free-k3 estimates it too");
  cmd->add_flag(
      "--leave-one-out,!--no-leave-one-out", o->leave_one_out,
      "measure each view with intrinsics calibrated without it (the default; recalibrates once per view); --no-leave-one-out skips it");
  cmd->callback([o, &exit_code] { exit_code = run_intrinsics(*o); });
}

}  // namespace rhot::calib_tool
