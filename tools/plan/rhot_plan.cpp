// rhot-plan: where to put cameras before buying them, and what a rig will see.
//
//   rhot-plan --volume LxWxH [--floor-only] --camera MODEL.yaml (--cameras N | --max-error-mm E) [--min-views K]
//             [--mount ceiling|walls|both] [--ceiling-m H] [--wall-margin-m M] [--sigma PX]
//             --out RIG.yaml [--pictures DIR] [--json]
//   rhot-plan evaluate --rig RIG.yaml [--volume LxWxH] [--volume-centre X Y Z] [--sigma PX]
//             [--grid-step-m S] [--slices-m H,...] [--pictures DIR] [--json]
//   rhot-plan joins --joins JOINS.json [--rig RIG.yaml] [--json]
//
// A volume LxWxH is L metres along X, W along Z and H high (Y), standing on the floor at the
// origin unless --volume-centre says otherwise. docs/planning.md explains the model and the
// figures (coverage by 1, 2 and 3 cameras; predicted error from the Cramer-Rao bound).

#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fmt/format.h>
#include <iostream>
#include <map>
#include <optional>
#include <regex>

#include <nlohmann/json.hpp>
#include <spdlog/cfg/env.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

// GCC 12 reports -Wnull-dereference inside CLI11's string splitting (a false positive through
// inlined libstdc++ code), as in the other tools.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wnull-dereference"
#include <CLI/CLI.hpp>
#pragma GCC diagnostic pop

#include "tracking/camera/RigFile.h"
#include "base/Json.h"
#include "tools/common/CliExit.h"
#include "tools/common/NumberChecks.h"
#include "tracking/plan/Coverage.h"
#include "tracking/plan/JoinGraph.h"
#include "tracking/plan/PlanPictures.h"
#include "tracking/plan/Placement.h"

namespace {

using rhot::TrackingVolume;

// A side of the volume: a number from the pattern's digits; nothing where it does not fit a double.
std::optional<double> side_of(const std::string& digits) {
  double v = 0.0;
  const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), v);
  if (ec != std::errc() || end != digits.data() + digits.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

// "4.6x4.6x2" -> size X = 4.6, Z = 4.6, Y = 2.
// With floor_only, "LxW" (or LxWxH, H ignored) -> the floor's layer, kFloorLayer_m high.
constexpr double kFloorLayer_m = 0.05;
std::expected<Eigen::Vector3d, std::string> parse_volume(const std::string& text, bool floor_only = false) {
  static const std::regex pattern(R"(^\s*([0-9]*\.?[0-9]+)\s*[xX]\s*([0-9]*\.?[0-9]+)\s*[xX]\s*([0-9]*\.?[0-9]+)\s*$)");
  static const std::regex floor_pattern(R"(^\s*([0-9]*\.?[0-9]+)\s*[xX]\s*([0-9]*\.?[0-9]+)\s*([xX]\s*[0-9]*\.?[0-9]+\s*)?$)");
  std::smatch m;
  if (floor_only) {
    if (!std::regex_match(text, m, floor_pattern)) {
      return std::unexpected("--volume: expected LxW in metres with --floor-only (length along X, width along Z), got \"" + text + "\"");
    }
    const auto l = side_of(m[1]), w = side_of(m[2]);
    if (!l || !w || !(*l > 0.0) || !(*w > 0.0)) return std::unexpected("--volume: every side must be positive, got \"" + text + "\"");
    return Eigen::Vector3d(*l, kFloorLayer_m, *w);
  }
  if (!std::regex_match(text, m, pattern)) {
    return std::unexpected("--volume: expected LxWxH in metres (length along X, width along Z, height), got \"" + text + "\"");
  }
  const auto l = side_of(m[1]), w = side_of(m[2]), h = side_of(m[3]);
  if (!l || !w || !h) return std::unexpected("--volume: every side must be positive, got \"" + text + "\"");
  const Eigen::Vector3d size(*l, *h, *w);
  if (!(size.minCoeff() > 0.0) || !size.allFinite()) return std::unexpected("--volume: every side must be positive, got \"" + text + "\"");
  return size;
}

TrackingVolume volume_of(const Eigen::Vector3d& size, const std::vector<double>& centre) {
  TrackingVolume v;
  v.size_m = size;
  v.centre_m = centre.size() == 3 ? Eigen::Vector3d(centre[0], centre[1], centre[2]) : Eigen::Vector3d(0.0, 0.5 * size.y(), 0.0);
  return v;
}

nlohmann::json report_json(const rhot::CoverageReport& r) {
  nlohmann::json j;
  j["volume_centre_m"] = {r.volume.centre_m.x(), r.volume.centre_m.y(), r.volume.centre_m.z()};
  j["volume_size_m"] = {r.volume.size_m.x(), r.volume.size_m.y(), r.volume.size_m.z()};
  j["sigma_px"] = r.sigma_px;
  j["grid_points"] = r.grid.size();
  j["coverage_1"] = r.coverage_1;
  j["coverage_2"] = r.coverage_2;
  j["coverage_3"] = r.coverage_3;
  // null where nothing is seen by two cameras (or, for the maximum, two see a point along one line)
  const auto number_or_null = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  j["predicted_median_mm"] = number_or_null(r.predicted_median_mm);
  j["predicted_p95_mm"] = number_or_null(r.predicted_p95_mm);
  j["predicted_max_mm"] = number_or_null(r.predicted_max_mm);
  j["worst_point_m"] = r.worst_point_m.allFinite() ? nlohmann::json({r.worst_point_m.x(), r.worst_point_m.y(), r.worst_point_m.z()})
                                                   : nlohmann::json(nullptr);
  return j;
}

void log_report(const rhot::CoverageReport& r) {
  spdlog::info(
      "seen by 1+ {:.1f} %, 2+ {:.1f} %, 3+ {:.1f} % of the volume; predicted error median {:.3f} mm, p95 {:.3f} mm, worst {:.3f} mm",
      100.0 * r.coverage_1, 100.0 * r.coverage_2, 100.0 * r.coverage_3, r.predicted_median_mm, r.predicted_p95_mm, r.predicted_max_mm);
}

// Slices at the given heights (default: a tenth of the way up, the middle, a tenth from the top),
// and the rig from above.
std::expected<void, std::string> write_pictures(const std::filesystem::path& dir, const rhot::CameraRig& rig, const rhot::CoverageReport& r,
                                                std::vector<double> heights) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  const double bottom = r.volume.centre_m.y() - 0.5 * r.volume.size_m.y();
  if (heights.empty())
    heights = {bottom + 0.1 * r.volume.size_m.y(), bottom + 0.5 * r.volume.size_m.y(), bottom + 0.9 * r.volume.size_m.y()};
  const double scale = std::isfinite(r.predicted_p95_mm) && r.predicted_p95_mm > 0.0 ? 1.5 * r.predicted_p95_mm : 1.0;
  for (const double h : heights) {
    const std::string tag = fmt::format("{:.2f}m", h);
    if (auto ok = rhot::write_coverage_slice(dir / ("coverage-" + tag + ".png"), r, h); !ok) return ok;
    if (auto ok = rhot::write_error_slice(dir / ("error-" + tag + ".png"), r, h, scale); !ok) return ok;
  }
  if (auto ok = rhot::write_plan_top_view(dir / "top-view.png", rig, r.volume); !ok) return ok;
  spdlog::info("pictures in {}: coverage-H.png and error-H.png at {} heights, top-view.png", dir.string(), heights.size());
  return {};
}

// "rhot-plan: MESSAGE" on stderr; the exit status 1.
int fail(const std::string& message) {
  std::fprintf(stderr, "rhot-plan: %s\n", message.c_str());
  return 1;
}

// A joins file: {"reference": NAME, "groups": [{"name", "error_mm"?, "cameras"?: [...]}],
// "joins": [{"a", "b", "error_mm"}]} -> the groups' errors, per camera where groups list them.
int run_joins(const std::string& joins_file, const std::string& rig_file, bool json) {
  struct JoinsFile {
    std::string reference;
    std::vector<rhot::CameraGroup> groups;
    std::vector<std::vector<std::string>> cameras;  // per group
    std::vector<rhot::GroupJoin> joins;
  };
  const auto file = rhot::read_json_file<JoinsFile>(joins_file, "joins", [](const rhot::JsonNode& root) {
    JoinsFile f;
    root.expect_object({"reference", "groups", "joins"});
    f.reference = root["reference"].non_empty_string();
    for (const rhot::JsonNode& g : root["groups"].elements()) {
      g.expect_object({"name", "error_mm", "cameras"});
      const auto own = g.optional("error_mm");
      f.groups.push_back({g["name"].non_empty_string(), own ? own->number_in(0.0, 1e6, "an error from 0 to 1e6 mm") : 0.0});
      f.cameras.emplace_back();
      if (const auto cams = g.optional("cameras")) {
        for (const rhot::JsonNode& c : cams->elements()) f.cameras.back().push_back(c.non_empty_string());
      }
    }
    for (const rhot::JsonNode& j : root["joins"].elements()) {
      j.expect_object({"a", "b", "error_mm"});
      f.joins.push_back(
          {j["a"].non_empty_string(), j["b"].non_empty_string(), j["error_mm"].number_in(0.0, 1e6, "an error from 0 to 1e6 mm")});
    }
    return f;
  });
  if (!file) return fail(file.error().to_string());
  const std::string& reference = file->reference;
  const std::vector<rhot::CameraGroup>& groups = file->groups;
  const std::vector<std::vector<std::string>>& cameras = file->cameras;
  const std::vector<rhot::GroupJoin>& joins = file->joins;
  const auto errors = rhot::propagate_join_errors(groups, joins, reference);
  if (!errors) return fail(joins_file + ": " + errors.error());
  // Per camera: the best of its groups' errors (a camera shared by two groups, as the seed's are,
  // is placed through whichever is known better); with a rig, every camera of it must be in one.
  std::map<std::string, std::size_t> group_of;
  for (std::size_t g = 0; g < cameras.size(); ++g) {
    for (const std::string& c : cameras[g]) {
      const auto [at, added] = group_of.emplace(c, g);
      if (!added && (*errors)[g].error_mm < (*errors)[at->second].error_mm) at->second = g;
    }
  }
  std::vector<std::string> camera_order;
  if (!rig_file.empty()) {
    const auto rig = rhot::load_rig(rig_file);
    if (!rig) return fail(rig.error());
    for (const rhot::Camera& c : rig->cameras) {
      if (!group_of.contains(c.name)) return fail(fmt::format("{}: camera \"{}\" of {} is in no group", joins_file, c.name, rig_file));
      camera_order.push_back(c.name);
    }
  } else {
    for (const auto& [c, g] : group_of) camera_order.push_back(c);
  }
  nlohmann::json out;
  out["reference"] = reference;
  double worst = 0.0;
  for (const rhot::GroupError& e : *errors) {
    const bool reached = std::isfinite(e.error_mm);
    out["groups"].push_back(
        {{"group", e.group}, {"error_mm", reached ? nlohmann::json(e.error_mm) : nlohmann::json(nullptr)}, {"chain", e.chain}});
    worst = std::max(worst, e.error_mm);
    spdlog::info("group {}: {} ({})", e.group, reached ? fmt::format("{:.2f} mm", e.error_mm) : std::string("no chain of joins reaches it"),
                 nlohmann::json(e.chain).dump());
  }
  for (const std::string& c : camera_order) {
    const rhot::GroupError& e = (*errors)[group_of.at(c)];
    out["cameras"].push_back({{"camera", c},
                              {"group", e.group},
                              {"error_mm", std::isfinite(e.error_mm) ? nlohmann::json(e.error_mm) : nlohmann::json(nullptr)}});
  }
  out["max_error_mm"] = std::isfinite(worst) ? nlohmann::json(worst) : nlohmann::json(nullptr);
  spdlog::info("worst: {:.2f} mm", worst);
  if (json) std::cout << out.dump(2) << "\n";
  return 0;
}

// The flags of planning (no subcommand).
struct PlanArgs {
  std::string volume_text, camera_file, out_file, mount = "both", pictures;
  std::vector<double> centre;
  rhot::PlanSettings plan;
  bool json = false, floor_only = false;
};

// `rhot-plan evaluate`'s flags.
struct EvaluateArgs {
  std::string rig_file, volume_text, pictures;
  std::vector<double> centre, slices;
  rhot::CoverageSettings coverage;
  bool json = false;
};

// `rhot-plan joins`' flags.
struct JoinsArgs {
  std::string joins_file, rig_file;
  bool json = false;
};

void add_plan_options(CLI::App& app, PlanArgs& a) {
  const CLI::Validator finite = rhot::number_check(rhot::NumberBound::kAny);
  const CLI::Validator positive = rhot::number_check(rhot::NumberBound::kPositive);
  const CLI::Validator non_negative = rhot::number_check(rhot::NumberBound::kNonNegative);
  app.add_option("--volume", a.volume_text, "volume to track, LxWxH metres (along X, along Z, height)");
  app.add_flag("--floor-only", a.floor_only,
               "track only on the floor (objects and feet on the ground): --volume LxW, a 5 cm layer standing on the floor");
  app.add_option("--volume-centre", a.centre, "centre of the volume, X Y Z metres (default: on the floor at the origin)")
      ->expected(3)
      ->check(finite);
  app.add_option("--camera", a.camera_file, "camera model: a rig file whose first camera gives resolution, focal length and distortion");
  app.add_option("--cameras", a.plan.cameras, "how many cameras to place")->check(CLI::Range(1, 256));
  app.add_option("--max-error-mm", a.plan.max_error_mm, "instead of --cameras: as few cameras as bring the worst predicted error to this")
      ->check(positive);
  app.add_option("--min-views", a.plan.min_views, "cameras that must see each place")->capture_default_str()->check(CLI::Range(1, 16));
  app.add_option("--mount", a.mount, "where cameras may go")->capture_default_str()->check(CLI::IsMember({"ceiling", "walls", "both"}));
  app.add_option("--ceiling-m", a.plan.ceiling_m, "height of the ceiling mount (default: the volume's top + 1 m)")->check(positive);
  app.add_option("--wall-margin-m", a.plan.wall_margin_m, "how far outside the volume the walls stand")
      ->capture_default_str()
      ->check(non_negative);
  app.add_option("--sigma", a.plan.sigma_px, "detection noise, pixels per axis")->capture_default_str()->check(positive);
  app.add_option("--out", a.out_file, "the planned rig (OpenCV YAML)");
  app.add_option("--pictures", a.pictures, "folder for the pictures (default: the rig's folder)");
  app.add_flag("--json", a.json, "print a JSON report on stdout");
}

CLI::App* add_evaluate_command(CLI::App& app, EvaluateArgs& a) {
  const CLI::Validator finite = rhot::number_check(rhot::NumberBound::kAny);
  const CLI::Validator positive = rhot::number_check(rhot::NumberBound::kPositive);
  CLI::App* evaluate = app.add_subcommand("evaluate", "coverage and predicted error of a rig over a volume, with pictures");
  evaluate->add_option("--rig", a.rig_file, "camera rig (OpenCV YAML)")->required();
  evaluate->add_option("--volume", a.volume_text, "volume, LxWxH metres (default: the rig file's volume)");
  evaluate->add_option("--volume-centre", a.centre, "centre of that volume, X Y Z metres (default: on the floor at the origin)")
      ->expected(3)
      ->check(finite);
  evaluate->add_option("--sigma", a.coverage.sigma_px, "detection noise, pixels per axis")->capture_default_str()->check(positive);
  evaluate->add_option("--grid-step-m", a.coverage.grid_step_m, "grid spacing (default: about 20,000 points)")->check(positive);
  evaluate->add_option("--slices-m", a.slices, "heights of the pictures' slices, metres")->delimiter(',')->check(finite);
  evaluate->add_option("--pictures", a.pictures, "write the pictures into this folder");
  evaluate->add_flag("--json", a.json, "print a JSON report on stdout");
  return evaluate;
}

CLI::App* add_joins_command(CLI::App& app, JoinsArgs& a) {
  CLI::App* joins = app.add_subcommand("joins", "the error each group of cameras calibrated apart carries through its chain of joins");
  joins->add_option("--joins", a.joins_file, "the groups and their measured joins (JSON, docs/planning.md)")->required();
  joins->add_option("--rig", a.rig_file, "check that every camera of this rig is in a group, and report them in its order");
  joins->add_flag("--json", a.json, "print a JSON report on stdout");
  return joins;
}

// rhot-plan evaluate: a rig's coverage and predicted error over --volume or the rig file's own.
int run_evaluate(const EvaluateArgs& a) {
  const auto rig = rhot::load_rig(a.rig_file);
  if (!rig) return fail(rig.error());
  TrackingVolume volume;
  if (!a.volume_text.empty()) {
    const auto size = parse_volume(a.volume_text);
    if (!size) return fail(size.error());
    volume = volume_of(*size, a.centre);
  } else if (rig->volume) {
    volume = *rig->volume;
  } else {
    return fail(a.rig_file + ": the rig file has no volume (volume_centre, volume_size): give --volume");
  }
  const auto report = rhot::evaluate_coverage(*rig, volume, a.coverage);
  if (!report) return fail(report.error());
  log_report(*report);
  if (!a.pictures.empty()) {
    if (auto ok = write_pictures(a.pictures, *rig, *report, a.slices); !ok) return fail(ok.error());
  }
  if (a.json) {
    nlohmann::json j = report_json(*report);
    j["rig"] = a.rig_file;
    j["cameras"] = rig->cameras.size();
    std::cout << j.dump(2) << "\n";
  }
  return 0;
}

// rhot-plan without a subcommand: cameras placed around the volume, the rig written to --out,
// its coverage reported and drawn.
int run_plan(const PlanArgs& a) {
  if (a.volume_text.empty() || a.camera_file.empty() || a.out_file.empty())
    return fail("planning needs --volume, --camera and --out (or: evaluate --rig)");
  if ((a.plan.cameras > 0) == (a.plan.max_error_mm > 0.0)) return fail("give one of --cameras and --max-error-mm");
  const auto size = parse_volume(a.volume_text, a.floor_only);
  if (!size) return fail(size.error());
  const TrackingVolume volume = volume_of(*size, a.centre);
  const auto model = rhot::load_rig(a.camera_file);
  if (!model) return fail(model.error());
  // The rig's folder is made before planning, so that a path that cannot be written fails first.
  if (const auto folder = std::filesystem::path(a.out_file).parent_path(); !folder.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(folder, ec);
    if (ec) return fail("--out: cannot make the folder " + folder.string() + ": " + ec.message());
  }
  rhot::PlanSettings plan = a.plan;
  plan.mount = a.mount == "ceiling" ? rhot::Mount::kCeiling : a.mount == "walls" ? rhot::Mount::kWalls : rhot::Mount::kBoth;
  const auto planned = rhot::plan_rig(model->cameras.front(), volume, plan, [](const std::string& line) { spdlog::info("{}", line); });
  if (!planned) return fail(planned.error());
  if (auto saved = rhot::save_rig(planned->rig, a.out_file); !saved) return fail(saved.error());
  rhot::CoverageSettings evaluation;
  evaluation.sigma_px = plan.sigma_px;
  const auto report = rhot::evaluate_coverage(planned->rig, volume, evaluation);
  if (!report) return fail(report.error());
  spdlog::info("{} cameras placed ({} poses considered, {} swaps), written to {}", planned->rig.cameras.size(), planned->candidates,
               planned->swaps, a.out_file);
  log_report(*report);
  const std::filesystem::path dir =
      !a.pictures.empty() ? std::filesystem::path(a.pictures)
                          : (std::filesystem::path(a.out_file).parent_path().empty() ? std::filesystem::path(".")
                                                                                     : std::filesystem::path(a.out_file).parent_path());
  if (auto ok = write_pictures(dir, planned->rig, *report, {}); !ok) return fail(ok.error());
  if (a.json) {
    nlohmann::json j = report_json(*report);
    j["rig"] = a.out_file;
    j["cameras"] = planned->rig.cameras.size();
    j["candidates"] = planned->candidates;
    j["swaps"] = planned->swaps;
    std::cout << j.dump(2) << "\n";
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  spdlog::set_default_logger(spdlog::stderr_color_mt("rhot-plan"));
  spdlog::set_pattern("rhot-plan: %^%l%$: %v");
  spdlog::cfg::load_env_levels();

  CLI::App app{"rhot-plan: place cameras of one model around a volume to track (coverage and predicted error), or evaluate a rig"};
  app.require_subcommand(0, 1);
  PlanArgs plan_args;
  add_plan_options(app, plan_args);
  EvaluateArgs evaluate_args;
  CLI::App* evaluate = add_evaluate_command(app, evaluate_args);
  JoinsArgs joins_args;
  CLI::App* joins = add_joins_command(app, joins_args);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return rhot::cli_exit_status(app, e);
  }
  if (*joins) return run_joins(joins_args.joins_file, joins_args.rig_file, joins_args.json);
  if (*evaluate) return run_evaluate(evaluate_args);
  return run_plan(plan_args);
}
