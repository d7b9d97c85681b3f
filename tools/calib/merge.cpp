// rhot-calib merge: two rigs calibrated apart joined through the cameras they share.

#include <memory>
#include <string>

#include <spdlog/spdlog.h>

#include "tools/calib/Calib.h"
#include "tracking/calib/CalibPictures.h"
#include "tracking/calib/Detections.h"
#include "tracking/calib/RigMerge.h"
#include "tracking/camera/RigFile.h"

namespace rhot::calib_tool {

namespace {

struct MergeOptions {
  std::string a, b, out, pictures;
  std::string detections_a, detections_b;
  bool json = false;
};

int run(const MergeOptions& o) {
  const auto a = load_rig(o.a);
  if (!a) {
    spdlog::error("{}", a.error());
    return 1;
  }
  const auto b = load_rig(o.b);
  if (!b) {
    spdlog::error("{}", b.error());
    return 1;
  }
  if (o.detections_a.empty() != o.detections_b.empty()) {
    spdlog::error("give both --detections-a and --detections-b, or neither");
    return 1;
  }
  std::optional<Detections> da, db;
  if (!o.detections_a.empty()) {
    auto x = read_detections(o.detections_a);
    if (!x) {
      spdlog::error("{}", x.error());
      return 1;
    }
    auto y = read_detections(o.detections_b);
    if (!y) {
      spdlog::error("{}", y.error());
      return 1;
    }
    if (x->camera_count > static_cast<int>(a->cameras.size()) || y->camera_count > static_cast<int>(b->cameras.size())) {
      spdlog::error("the detections name more cameras than their rigs have");
      return 1;
    }
    da = std::move(*x);
    db = std::move(*y);
  }
  const auto merged = merge_rigs(*a, *b, MergeSettings{}, da ? &*da : nullptr, db ? &*db : nullptr);
  if (!merged) {
    spdlog::error("{}", merged.error());
    return 1;
  }
  make_parent_folder(o.out);
  if (const auto saved = save_rig(merged->rig, o.out); !saved) {
    spdlog::error("{}", saved.error());
    return 1;
  }
  const MergeReport& r = merged->report;
  if (r.shared_cameras.empty()) {
    spdlog::info("joined through {} shared points ({:.2f} mm RMS after the alignment)", r.shared_points, r.point_rms_mm);
  }
  spdlog::info("{}: {} cameras ({} shared); shared centres agree within {:.2f} mm RMS, orientations {:.3f} degrees{}", o.out,
               merged->rig.cameras.size(), r.shared_cameras.size(), r.centre_rms_mm, r.rotation_rms_deg,
               r.adjusted ? fmt::format("; adjusted together: {:.3f} px RMS over {} points", r.rms_px, r.points) : std::string());
  const std::filesystem::path dir = pictures_dir(o.pictures, o.out);
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  const std::filesystem::path top = dir / (std::filesystem::path(o.out).stem().string() + "_top.png");
  if (const auto ok = write_rig_top_view(top, merged->rig, {}, "merged rig"); !ok) spdlog::warn("{}", ok.error());
  if (o.json) {
    nlohmann::json j;
    j["rig"] = o.out;
    j["cameras"] = merged->rig.cameras.size();
    j["shared_cameras"] = r.shared_cameras;
    if (r.shared_cameras.empty()) {
      j["shared_points"] = r.shared_points;
      j["point_rms_mm"] = r.point_rms_mm;
    }
    j["scale_b_to_a"] = r.a_from_b.scale;
    j["centre_rms_mm"] = r.centre_rms_mm;
    j["rotation_rms_deg"] = r.rotation_rms_deg;
    j["adjusted"] = r.adjusted;
    if (r.adjusted) {
      j["rms_px"] = r.rms_px;
      j["points"] = r.points;
    }
    j["picture"] = top.string();
    print_json(j);
  }
  return 0;
}

}  // namespace

void add_merge(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<MergeOptions>();
  CLI::App* cmd = app.add_subcommand(
      "merge", "join two rigs calibrated apart through the cameras they share (same names), or the points of one wave both saw");
  cmd->add_option("rig_a", o->a, "the first rig: its world is kept (OpenCV YAML)")->required();
  cmd->add_option("rig_b", o->b, "the second rig, moved into the first's world")->required();
  cmd->add_option("--out", o->out, "the merged rig")->required();
  cmd->add_option("--detections-a", o->detections_a,
                  "the first rig's wand session: with --detections-b, one bundle adjustment over both (and, for rigs sharing no camera, "
                  "the points both saw)");
  cmd->add_option("--detections-b", o->detections_b, "the second rig's wand session");
  cmd->add_option("--pictures", o->pictures, "folder for the picture of the merged rig from above (default: --out's folder)");
  cmd->add_flag("--json", o->json, "print the report as JSON on stdout");
  cmd->callback([o, &exit_code] { exit_code = run(*o); });
}

}  // namespace rhot::calib_tool
