// rhot-calib world: the world frame (metres, +Y up) of a calibrated rig from an L-frame on the
// floor or from points touched on the floor.

#include <memory>
#include <string>
#include <vector>

#include <spdlog/spdlog.h>

#include "tools/calib/Calib.h"
#include "tracking/calib/CalibPictures.h"
#include "tracking/calib/Detections.h"
#include "tracking/calib/WorldFrame.h"
#include "tracking/camera/RigFile.h"

namespace rhot::calib_tool {

namespace {

struct WorldOptions {
  std::string rig;
  std::string detections;
  std::string out;
  std::string pictures;
  bool lframe = false;
  bool floor = false;
  std::vector<double> lframe_mm{500, 300};
  double height_mm = 0.0;
  bool rescale = false;
  double tolerance_mm = 10.0;
  int min_frames = 10;
  bool json = false;
};

int run(const WorldOptions& o) {
  if (o.lframe == o.floor) {
    spdlog::error("give one of --lframe and --floor");
    return 1;
  }
  const auto rig = load_rig(o.rig);
  if (!rig) {
    spdlog::error("{}", rig.error());
    return 1;
  }
  const auto detections = read_detections(o.detections);
  if (!detections) {
    spdlog::error("{}", detections.error());
    return 1;
  }
  if (detections->camera_count > static_cast<int>(rig->cameras.size())) {
    spdlog::error("{}: the detections name camera {} but the rig has only {} cameras", o.detections, detections->camera_count - 1,
                  rig->cameras.size());
    return 1;
  }
  std::expected<WorldFrameResult, std::string> result;
  if (o.lframe) {
    LFrame frame;
    frame.long_m = o.lframe_mm[0] / 1000.0;
    frame.short_m = o.lframe_mm[1] / 1000.0;
    if (o.lframe_mm.size() == 3) frame.middle_m = o.lframe_mm[2] / 1000.0;
    frame.height_m = o.height_mm / 1000.0;
    spdlog::info("finding the L-frame's {} markers in {} frames", frame.markers_world().size(), detections->frames.size());
    result = world_from_lframe(*rig, *detections, frame, o.rescale, o.tolerance_mm / 1000.0);
  } else {
    spdlog::info("finding the places the marker stayed still in {} frames", detections->frames.size());
    result = world_from_floor_points(*rig, *detections, o.height_mm / 1000.0, o.min_frames);
  }
  if (!result) {
    spdlog::error("{}", result.error());
    return 1;
  }
  make_parent_folder(o.out);
  if (const auto saved = save_rig(result->rig, o.out); !saved) {
    spdlog::error("{}", saved.error());
    return 1;
  }
  const WorldFrameReport& r = result->report;
  spdlog::info("{}: world set from {} ({:.2f} mm RMS, {:.3f} degrees{})", o.out, o.lframe ? "the L-frame" : "the floor points", r.rms_mm,
               r.angle_error_deg, o.rescale ? fmt::format(", scaled by {:.5f}", r.scale) : std::string());
  const std::filesystem::path dir = pictures_dir(o.pictures, o.out);
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  const std::filesystem::path top = dir / (std::filesystem::path(o.out).stem().string() + "_top.png");
  if (const auto ok =
          write_rig_top_view(top, result->rig, r.measured_world, "world from " + std::string(o.lframe ? "L-frame" : "floor points"));
      !ok) {
    spdlog::warn("{}", ok.error());
  }
  if (o.json) {
    nlohmann::json j;
    j["rig"] = o.out;
    j["method"] = o.lframe ? "lframe" : "floor";
    j["residual_mm"] = r.marker_residual_mm;
    j["rms_mm"] = r.rms_mm;
    j["max_mm"] = r.max_mm;
    j[o.lframe ? "angle_error_deg" : "tilt_uncertainty_deg"] = r.angle_error_deg;
    j["scale"] = r.scale;
    j["frames"] = r.frames;
    nlohmann::json points = nlohmann::json::array();
    for (const auto& p : r.measured_world) points.push_back({p.x(), p.y(), p.z()});
    j["points_world_m"] = points;
    j["picture"] = top.string();
    print_json(j);
  }
  return 0;
}

}  // namespace

void add_world(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<WorldOptions>();
  CLI::App* cmd = app.add_subcommand("world", "set the world frame (Y up, metres) from an L-frame or from points touched on the floor");
  cmd->add_option("--rig", o->rig, "the calibrated rig (OpenCV YAML)")->required();
  cmd->add_option("--detections", o->detections, "detections of the L-frame lying still, or of the marker touched on the floor (CSV)")
      ->required();
  cmd->add_option("--out", o->out, "the rig in its new world (OpenCV YAML)")->required();
  cmd->add_flag("--lframe", o->lframe, "an L-frame: corner = origin, long arm along -Z, short arm along +X");
  cmd->add_flag("--floor", o->floor, "floor points: the first = origin, the second along +X, the floor's normal = +Y");
  cmd->add_option("--lframe-mm", o->lframe_mm, "the L-frame: long arm, short arm[, middle marker on the long arm], mm")
      ->check(finite_number())
      ->delimiter(',')
      ->expected(2, 3)
      ->capture_default_str();
  cmd->add_option("--height-mm", o->height_mm, "the markers' centres above the floor")->check(finite_number())->capture_default_str();
  cmd->add_flag("--rescale", o->rescale,
                "also scale the rig so the L-frame's arms have their true lengths (a rig calibrated without a wand)");
  cmd->add_option("--tolerance-mm", o->tolerance_mm, "the most a marker may lie from its place on the L-frame")
      ->check(finite_number())
      ->capture_default_str()
      ->check(CLI::Range(0.1, 1000.0));
  cmd->add_option("--min-frames", o->min_frames, "floor points: frames the marker must stay still at a place")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  cmd->add_option("--pictures", o->pictures, "folder for the picture of the rig from above (default: --out's folder)");
  cmd->add_flag("--json", o->json, "print the report as JSON on stdout");
  cmd->callback([o, &exit_code] { exit_code = run(*o); });
}

}  // namespace rhot::calib_tool
