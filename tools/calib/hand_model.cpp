// rhot-calib hand-model: a hidden-marker model (tracking/hand/HiddenMarkers.h) fitted to a
// labelled take of a user's own hand, for estimating hidden fingers the way that hand moves.

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include <spdlog/spdlog.h>

#include "tools/calib/Calib.h"
#include "tracking/hand/HiddenMarkers.h"
#include "tracking/take/MarkerTake.h"

namespace rhot::calib_tool {

namespace {

struct HandModelOptions {
  std::string take, out;
  std::vector<std::string> frame_markers{kGloveFrameMarkers.begin(), kGloveFrameMarkers.end()};
  std::vector<std::string> markers;
  double fit_seconds = 0.0;
  bool json = false;
};

int run_hand_model(const HandModelOptions& o) {
  const auto take = read_marker_take(o.take);
  if (!take) return fail(take.error());
  std::vector<std::string> markers = o.markers;
  if (markers.empty()) {
    markers = glove_finger_markers(*take);
    if (markers.empty()) return fail(o.take + ": no <finger>_tip or <finger>_middle markers (name them with --markers)");
  }
  HiddenMarkerFitSettings settings;
  if (o.fit_seconds > 0.0) {
    settings.end_frame = static_cast<int>(std::min(static_cast<double>(take->frame_count()), o.fit_seconds * take->frame_rate_hz));
  }
  spdlog::info("fitting {} markers to {} of {} frames", markers.size(), settings.end_frame < 0 ? take->frame_count() : settings.end_frame,
               take->frame_count());
  auto model = fit_hidden_marker_model(*take, {o.frame_markers[0], o.frame_markers[1], o.frame_markers[2]}, markers, settings);
  if (!model) return fail(o.take + ": " + model.error());
  model->source = o.take + (o.fit_seconds > 0.0 ? ", its first " + std::to_string(o.fit_seconds) + " s" : "");
  make_parent_folder(o.out);
  if (auto saved = save_hidden_marker_model(*model, o.out); !saved) return fail(saved.error());
  spdlog::info("wrote {}: {} training frames, ridge {:.3g} mm^2, memory {:.2f} s", o.out, model->training_frames, model->ridge_m2 * 1e6,
               model->memory_s);
  if (o.json) {
    print_json({{"out", o.out},
                {"training_frames", model->training_frames},
                {"markers", model->markers},
                {"ridge_mm2", model->ridge_m2 * 1e6},
                {"memory_s", model->memory_s}});
  }
  return 0;
}

}  // namespace

void add_hand_model(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<HandModelOptions>();
  auto* cmd = app.add_subcommand("hand-model", "fit a hidden-finger model to a labelled take of a hand (C3D or Qualisys TSV)");
  cmd->add_option("--take", options->take, "the take")->required()->check(CLI::ExistingFile);
  cmd->add_option("--out", options->out, "the model (JSON)")->required();
  cmd->add_option("--frame-markers", options->frame_markers, "the three markers on the back of the hand")
      ->expected(3)
      ->capture_default_str();
  cmd->add_option("--markers", options->markers, "the markers to model (default: every <finger>_tip and <finger>_middle in the take)");
  cmd->add_option("--fit-seconds", options->fit_seconds, "fit the first S seconds only (keep the rest to test on)")
      ->check(finite_number())
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--json", options->json, "print a JSON report on stdout");
  cmd->callback([options, &exit_code] { exit_code = run_hand_model(*options); });
}

}  // namespace rhot::calib_tool
