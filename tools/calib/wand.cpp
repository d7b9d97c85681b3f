// rhot-calib wand: extrinsics (and optionally focal length, principal point, k1) of every camera
// from a marker or a two-marker wand waved through the volume.

#include <cmath>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <spdlog/spdlog.h>

#include "tools/calib/Calib.h"
#include "tracking/calib/CalibPictures.h"
#include "tracking/calib/Detections.h"
#include "tracking/calib/WandCalibration.h"
#include "tracking/camera/RigFile.h"

namespace rhot::calib_tool {

namespace {

struct WandOptions {
  std::vector<std::string> intrinsics;
  std::string detections;
  std::string out;
  std::string pictures;
  std::string image_size;
  double wand_mm = 0.0;
  std::vector<int> wand_markers{0, 1};
  std::vector<std::string> refine;
  bool search_focal = false;
  double outlier_px = 0.0;
  int min_shared = 15;
  bool json = false;
};

nlohmann::json report_json(const WandCalibration& c, const WandOptions& o) {
  const WandReport& r = c.report;
  nlohmann::json j;
  j["rig"] = o.out;
  j["detections"] = o.detections;
  j["rms_px"] = r.rms_px;
  j["points"] = r.points;
  j["outliers"] = r.outliers;
  j["ambiguous"] = r.ambiguous;
  j["metric"] = r.metric;
  if (r.metric) {
    j["wand_mm"] = o.wand_mm;
    j["wand_frames"] = r.wand_frames;
    j["wand_mean_mm"] = r.wand_mean_mm;
    j["wand_rms_mm"] = r.wand_rms_mm;
    j["wand_max_mm"] = r.wand_max_mm;
  }
  if (r.focal_searched_px > 0) j["focal_searched_px"] = r.focal_searched_px;
  j["iterations"] = r.iterations;
  nlohmann::json cameras = nlohmann::json::array();
  for (std::size_t i = 0; i < r.cameras.size(); ++i) {
    const CameraCalibrationReport& cr = r.cameras[i];
    const Camera& cam = c.rig.cameras[i];
    const Eigen::Vector3d centre = cam.centre_world();
    cameras.push_back({{"name", cr.name},
                       {"rms_px", cr.rms_px},
                       {"median_px", cr.median_px},
                       {"p95_px", cr.p95_px},
                       {"inliers", cr.inliers},
                       {"outliers", cr.outliers},
                       {"frames_seen", cr.frames_seen},
                       {"coverage", cr.coverage},
                       {"fx", cam.intrinsics.fx},
                       {"fy", cam.intrinsics.fy},
                       {"cx", cam.intrinsics.cx},
                       {"cy", cam.intrinsics.cy},
                       {"k1", cam.intrinsics.distortion[0]},
                       {"centre_m", {centre.x(), centre.y(), centre.z()}}});
  }
  j["cameras"] = cameras;
  nlohmann::json graph = nlohmann::json::array();
  for (const GraphEdge& e : r.graph) {
    graph.push_back({{"a", c.rig.cameras[static_cast<std::size_t>(e.a)].name},
                     {"b", c.rig.cameras[static_cast<std::size_t>(e.b)].name},
                     {"shared_points", e.shared_points}});
  }
  j["graph"] = graph;
  nlohmann::json order = nlohmann::json::array();
  for (const int i : r.placement_order) order.push_back(c.rig.cameras[static_cast<std::size_t>(i)].name);
  j["placement_order"] = order;
  j["warnings"] = r.warnings;
  return j;
}

// The report's figures beside the rig, as YAML keys OpenCV's reader (and load_rig) skip over.
bool append_report(const std::string& file, const WandCalibration& c) {
  std::ofstream out(file, std::ios::app);
  char line[256];
  out << "calibration:\n   method: \"rhot-calib wand\"\n";
  std::snprintf(line, sizeof line, "   rms_px: %.4f\n   points: %d\n   outliers: %d\n", c.report.rms_px, c.report.points,
                c.report.outliers);
  out << line;
  out << "   metric: " << (c.report.metric ? 1 : 0) << "\n";
  if (c.report.metric) {
    std::snprintf(line, sizeof line, "   wand_mean_mm: %.4f\n   wand_rms_mm: %.4f\n   wand_max_mm: %.4f\n", c.report.wand_mean_mm,
                  c.report.wand_rms_mm, c.report.wand_max_mm);
    out << line;
  }
  out << "   cameras_rms_px: [";
  for (std::size_t i = 0; i < c.report.cameras.size(); ++i) {
    std::snprintf(line, sizeof line, "%s %.4f", i ? "," : "", c.report.cameras[i].rms_px);
    out << line;
  }
  out << " ]\n";
  return static_cast<bool>(out);
}

// Cameras with rough intrinsics from the image size (--image-size, else MultiCamSelfCal's
// Res.dat): the principal point at the centre, no distortion, a focal length of one image width
// (the calibration searches it).
std::expected<CameraRig, std::string> rough_intrinsics(const WandOptions& o, const Detections& detections) {
  CameraRig rig;
  int w = 0, h = 0;
  if (!o.image_size.empty()) {
    if (std::sscanf(o.image_size.c_str(), "%dx%d", &w, &h) != 2 || w < 16 || h < 16 || w > 65536 || h > 65536) {
      return std::unexpected("--image-size: expected WIDTHxHEIGHT in pixels, got \"" + o.image_size + "\"");
    }
  } else if (!detections.image_sizes_px.empty()) {
    w = detections.image_sizes_px[0].x();
    h = detections.image_sizes_px[0].y();
  } else {
    return std::unexpected(std::string("without --intrinsics, give --image-size WxH (or a MultiCamSelfCal folder with Res.dat)"));
  }
  for (int c = 0; c < detections.camera_count; ++c) {
    Camera cam;
    cam.name = "cam" + std::to_string(c);
    const Eigen::Vector2i size = c < static_cast<int>(detections.image_sizes_px.size())
                                     ? detections.image_sizes_px[static_cast<std::size_t>(c)]
                                     : Eigen::Vector2i(w, h);
    cam.intrinsics.width_px = size.x();
    cam.intrinsics.height_px = size.y();
    cam.intrinsics.fx = cam.intrinsics.fy = size.x();
    cam.intrinsics.cx = (size.x() - 1) / 2.0;
    cam.intrinsics.cy = (size.y() - 1) / 2.0;
    rig.cameras.push_back(cam);
  }
  rig.name = "wand";
  return rig;
}

// Per camera its residuals, and the rig from above with the wave; the files written.
nlohmann::json write_pictures(const WandCalibration& result, const WandOptions& o) {
  const std::filesystem::path dir = pictures_dir(o.pictures, o.out);
  const std::string stem = std::filesystem::path(o.out).stem().string();
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  nlohmann::json pictures = nlohmann::json::array();
  for (std::size_t c = 0; c < result.rig.cameras.size(); ++c) {
    const Camera& cam = result.rig.cameras[c];
    const std::filesystem::path file = dir / (stem + "_" + cam.name + "_residuals.png");
    char title[160];
    std::snprintf(title, sizeof title, "%s: %.3f px RMS, %d points, %d outliers", cam.name.c_str(), result.report.cameras[c].rms_px,
                  result.report.cameras[c].inliers, result.report.cameras[c].outliers);
    if (const auto ok = write_residual_picture(file, cam.intrinsics.width_px, cam.intrinsics.height_px, result.residuals[c], 50.0, title);
        !ok) {
      spdlog::warn("{}", ok.error());
    } else {
      pictures.push_back(file.string());
    }
  }
  const std::filesystem::path top = dir / (stem + "_top.png");
  if (const auto ok = write_rig_top_view(top, result.rig, result.points_world, result.rig.name.empty() ? "rig" : result.rig.name); !ok) {
    spdlog::warn("{}", ok.error());
  } else {
    pictures.push_back(top.string());
  }
  return pictures;
}

int run(const WandOptions& o) {
  WandSettings settings;
  if (o.wand_mm > 0) settings.wand_length_m = o.wand_mm / 1000.0;
  if (o.wand_markers.size() != 2) {
    spdlog::error("--wand-markers: expected two marker ids A,B");
    return 1;
  }
  settings.marker_a = o.wand_markers[0];
  settings.marker_b = o.wand_markers[1];
  for (const std::string& r : o.refine) {
    if (r == "focal") {
      settings.refine_focal = true;
    } else if (r == "principal") {
      settings.refine_principal_point = true;
    } else if (r == "k1") {
      settings.refine_k1 = true;
    } else {
      spdlog::error("--refine: expected focal, principal or k1, got \"{}\"", r);
      return 1;
    }
  }
  settings.search_focal = o.search_focal;
  settings.outlier_px = o.outlier_px;
  settings.min_shared_points = o.min_shared;
  if (const auto ok = settings.check(); !ok) {
    spdlog::error("{}", ok.error());
    return 1;
  }
  const auto detections = read_detections(o.detections);
  if (!detections) {
    spdlog::error("{}", detections.error());
    return 1;
  }
  CameraRig rig;
  if (!o.intrinsics.empty()) {
    auto loaded = load_cameras(o.intrinsics);
    if (!loaded) {
      spdlog::error("{}", loaded.error());
      return 1;
    }
    rig = std::move(*loaded);
  } else {
    // No intrinsics: rough ones from the image size, and the focal length searched.
    auto rough = rough_intrinsics(o, *detections);
    if (!rough) {
      spdlog::error("{}", rough.error());
      return 1;
    }
    rig = std::move(*rough);
    settings.search_focal = true;
    spdlog::info("no --intrinsics: starting from the image centre and no distortion, searching the focal length");
  }
  spdlog::info("{}: {} detections in {} frames, {} cameras", o.detections, detections->count(), detections->frames.size(),
               rig.cameras.size());
  const auto result = calibrate_wand(rig, *detections, settings, [](const std::string& line) { spdlog::info("{}", line); });
  if (!result) {
    spdlog::error("{}", result.error());
    return 1;
  }
  for (const std::string& w : result->report.warnings) spdlog::warn("{}", w);
  make_parent_folder(o.out);
  if (const auto saved = save_rig(result->rig, o.out); !saved) {
    spdlog::error("{}", saved.error());
    return 1;
  }
  if (!append_report(o.out, *result)) {
    std::error_code removed;
    std::filesystem::remove(o.out, removed);  // no rig without its report
    spdlog::error("{}: cannot append the report", o.out);
    return 1;
  }
  const nlohmann::json pictures = write_pictures(*result, o);
  spdlog::info("{}: {} cameras, {:.3f} px RMS{}", o.out, result->rig.cameras.size(), result->report.rms_px,
               result->report.metric ? fmt::format(", wand {:.3f} mm RMS", result->report.wand_rms_mm) : std::string(", not metric"));
  if (o.json) {
    nlohmann::json j = report_json(*result, o);
    j["pictures"] = pictures;
    print_json(j);
  }
  return 0;
}

}  // namespace

void add_wand(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<WandOptions>();
  CLI::App* cmd = app.add_subcommand("wand", "extrinsics of 2 to 32 cameras from a marker or a wand waved through the volume");
  cmd->add_option("--intrinsics", o->intrinsics,
                  "rig files (OpenCV YAML): one per camera from `intrinsics`, or one with every camera, in detection order; "
                  "poses are ignored. Without it: rough intrinsics from the image size and the focal length searched");
  cmd->add_option("--detections", o->detections, "rhot's CSV (frame,camera,x,y[,marker]) or a MultiCamSelfCal folder")->required();
  cmd->add_option("--out", o->out, "the calibrated rig (OpenCV YAML, the report's figures beside it)")->required();
  cmd->add_option("--wand-mm", o->wand_mm, "distance between wand markers A and B; none: the rig is not metric")
      ->check(finite_number())
      ->check(CLI::Range(1.0, 10000.0));
  cmd->add_option("--wand-markers", o->wand_markers, "the marker ids of the wand's ends A,B")
      ->delimiter(',')
      ->expected(2)
      ->capture_default_str();
  cmd->add_option("--refine", o->refine, "also refine per camera: focal, principal, k1 (comma-separated)")->delimiter(',');
  cmd->add_flag("--search-focal", o->search_focal, "the intrinsics' focal lengths are rough: search 0.5 to 2 image widths first");
  cmd->add_option("--image-size", o->image_size, "WIDTHxHEIGHT of every camera, without --intrinsics");
  cmd->add_option("--outlier-px", o->outlier_px, "drop observations further off (default 0: 5 robust sigmas, at least 1 px)")
      ->check(finite_number())
      ->check(CLI::Range(0.0, 1000.0));
  cmd->add_option("--min-shared", o->min_shared, "points two cameras must share to be connected")
      ->capture_default_str()
      ->check(CLI::Range(5, 100000));
  cmd->add_option("--pictures", o->pictures, "folder for the residual pictures and the rig from above (default: --out's folder)");
  cmd->add_flag("--json", o->json, "print the report as JSON on stdout");
  cmd->callback([o, &exit_code] { exit_code = run(*o); });
}

}  // namespace rhot::calib_tool
