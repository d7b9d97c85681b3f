// rhot-eval hands --take: a recorded take's fingertips hidden by rule and estimated from the rest
// (tracking/hand/HiddenMarkers.h), against the recorded positions.

#include <algorithm>
#include <iostream>
#include <numeric>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tools/eval/Eval.h"
#include "tracking/hand/HiddenMarkers.h"
#include "tracking/take/MarkerTake.h"

namespace rhot::eval {
namespace {

// The glove's names (assets/hands: three on the back of the hand, a tip and a middle per finger).

double take_mean(const std::vector<double>& v) {
  return v.empty() ? 0.0 : std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
}

nlohmann::json take_report(const HiddenMarkerErrors& e) {
  nlohmann::json j;
  j["hidden_tip_mean_mm"] = take_mean(e.hidden_mm);
  j["hidden_tip_p95_mm"] = percentile(e.hidden_mm, 0.95);
  // Labelled points: a visible tip is its recorded position.
  j["visible_tip_mean_mm"] = 0.0;
  j["held_tip_mean_mm"] = take_mean(e.held_mm);
  j["held_tip_p95_mm"] = percentile(e.held_mm, 0.95);
  j["hidden_frames"] = e.hidden_frames;
  j["estimated_frames"] = e.hidden_mm.size();
  for (const auto& [name, errors] : e.hidden_by_marker_mm) {
    j["fingers"][name] = {{"mean_mm", take_mean(errors)}, {"p95_mm", percentile(errors, 0.95)}, {"frames", errors.size()}};
  }
  return j;
}

}  // namespace

int hands_take(const HandsArgs& args) {
  const auto fail = [](const std::string& what) {
    std::cerr << "rhot-eval: " << what << "\n";
    return 1;
  };
  if (!args.labelled) return fail("hands --take: only --labelled is built so far (the take's 3D points, no cameras)");
  const auto take = read_marker_take(args.take_file);
  if (!take) return fail(take.error());
  HiddenMarkerModel model;
  int unfitted_first = 0;
  if (!args.model_file.empty()) {
    auto loaded = load_hidden_marker_model(args.model_file);
    if (!loaded) return fail(loaded.error());
    model = std::move(*loaded);
    unfitted_first = static_cast<int>(std::min(static_cast<double>(take->frame_count() - 1), args.evaluate_from_s * take->frame_rate_hz));
  } else {
    const std::vector<std::string> markers = glove_finger_markers(*take);
    unfitted_first = static_cast<int>(args.fit_fraction * take->frame_count());
    std::cerr << "rhot-eval: fitting a hidden-marker model to frames 1-" << unfitted_first << " of " << take->frame_count() << "\n";
    auto fitted = fit_hidden_marker_model(*take, kGloveFrameMarkers, markers, {.end_frame = unfitted_first});
    if (!fitted) return fail(args.take_file + ": " + fitted.error());
    model = std::move(*fitted);
  }
  const HideSettings hide{.gap_s = args.hide_gap_s, .together = args.hide_together, .seed = args.seed, .first_frame = unfitted_first};
  const auto errors = evaluate_hidden_markers(*take, model, hide);
  if (!errors) return fail(args.take_file + ": " + errors.error());
  nlohmann::json j = take_report(*errors);
  j["take"] = args.take_file;
  j["frames"] = take->frame_count();
  j["frame_rate_hz"] = take->frame_rate_hz;
  j["hide_gap_s"] = args.hide_gap_s;
  j["hide_together"] = args.hide_together;
  j["seed"] = args.seed;
  j["model"] = {{"ridge_mm2", model.ridge_m2 * 1e6},
                {"memory_s", model.memory_s},
                {"training_frames", model.training_frames},
                {"file", args.model_file}};
  j["evaluated_frames"] = {unfitted_first + 1, take->frame_count()};
  if (unfitted_first > 0 && args.model_file.empty()) {
    HideSettings fitted_part = hide;
    fitted_part.first_frame = 0;
    fitted_part.end_frame = unfitted_first;
    const auto on_fitted = evaluate_hidden_markers(*take, model, fitted_part);
    if (on_fitted) j["fitted_part"] = take_report(*on_fitted);
  }
  std::cout << j.dump(2) << "\n";
  return 0;
}

}  // namespace rhot::eval
