#pragma once
// Hidden hand markers estimated from everything known at that moment (docs/tracking.md, "Hidden
// fingers"): the hand's other markers, the way real fingers move together, and the marker's own
// past.
//
// The model is a Gaussian over the finger markers' positions in the hand's frame (the frame of the
// three markers on the back of the hand), fitted to a labelled take of real motion
// (`rhot-calib hand-model`). With some markers hidden, their expected position given the visible
// ones is the Gaussian's conditional mean, a linear predictor fitted to the visible set at hand:
//
//   x_H = mean_H + C_HV (C_VV + ridge I)^-1 (x_V - mean_V)
//
// What the others cannot tell, the marker's own past can: the predictor's error on the last frame
// the marker was seen is carried on while it is hidden, fading with the time constant memory_s
// (fitted with the model), so that a short gap starts exactly where the marker was last seen and a
// long one ends on the other markers' word alone.

#include <array>
#include <cstdint>
#include <expected>
#include <filesystem>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "tracking/core/Rigid3.h"
#include "tracking/take/MarkerTake.h"

namespace rhot {

struct HiddenMarkerModel {
  std::array<std::string, 3> frame_markers;  // the back of the hand: the hand's frame
  std::vector<std::string> markers;          // the modelled markers (a finger's tip, its middle, ...)
  Eigen::VectorXd mean_m;                    // hand frame, 3 per marker
  Eigen::MatrixXd covariance_m2;             // of mean_m's entries
  double ridge_m2 = 1e-6;                    // added to the visible block's diagonal
  double memory_s = 0.5;                     // how long a hidden marker's last error is remembered
  int training_frames = 0;
  std::string source;  // the take it was fitted to, and which part
};

// The hand's frame from its three back markers (world): origin at their centroid, x from the
// second to the third, z out of their plane. Nothing when one is hidden or they are collinear.
std::optional<Rigid3d> hand_frame_from_markers(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c);

struct HiddenMarkerFitSettings {
  int first_frame = 0;
  int end_frame = -1;  // one past the last frame fitted; -1: the take's end
  // Each candidate memory is scored by hiding each marker in turn in 0.5 s gaps over the fitted frames.
  std::vector<double> memory_candidates_s{0.05, 0.1, 0.2, 0.35, 0.5, 1.0, 2.0};
  std::vector<double> ridge_candidates_m2{1e-7, 1e-6, 1e-5};
};

// The three markers on the back of the glove (tests/data, docs/tracking.md) that carry its hand frame.
inline const std::array<std::string, 3> kGloveFrameMarkers{"hand_top", "hand_left", "hand_right"};
// The glove's finger markers present in `take`: each <finger>_tip and <finger>_middle, thumb first.
[[nodiscard]] std::vector<std::string> glove_finger_markers(const MarkerTake& take);

// Fits a model to the frames of `take` in which the frame markers and every modelled marker are seen.
[[nodiscard]] std::expected<HiddenMarkerModel, std::string> fit_hidden_marker_model(const MarkerTake& take,
                                                                                    const std::array<std::string, 3>& frame_markers,
                                                                                    const std::vector<std::string>& markers,
                                                                                    const HiddenMarkerFitSettings& settings = {});

[[nodiscard]] std::expected<void, std::string> save_hidden_marker_model(const HiddenMarkerModel& model, const std::filesystem::path& file);
[[nodiscard]] std::expected<HiddenMarkerModel, std::string> load_hidden_marker_model(const std::filesystem::path& file);

// The running mean and covariance of a vector of positions (3 per marker, hand frame), from frames
// in which every marker is seen: a model fitted as a tracker runs (Welford's update).
class MarkerStatistics {
 public:
  explicit MarkerStatistics(int markers);
  void add(const Eigen::VectorXd& positions_m);
  int frames() const { return frames_; }
  const Eigen::VectorXd& mean_m() const { return mean_; }
  Eigen::MatrixXd covariance_m2() const;

 private:
  int frames_ = 0;
  Eigen::VectorXd mean_;
  Eigen::MatrixXd scatter_;  // sum of outer products of the differences from the running mean
};

// How a marker's position was obtained.
enum class MarkerEstimate : std::uint8_t {
  kSeen,       // measured this frame
  kPredicted,  // hidden: from the visible markers and its own last error
  kHeld,       // hidden, and the hand's frame unknown or no other marker seen: where it was last seen, in the hand's frame
  kUnknown,    // never seen and nothing to predict it from
};

// Runs the model over a stream of frames.
class HiddenMarkerEstimator {
 public:
  // keep_predictors: each set of visible markers' predictor is kept once computed (fast where the
  // same sets recur: evaluating and fitting a take); false, computed when needed and dropped (a
  // tracker's memory does not grow with every set of hidden tips it meets).
  explicit HiddenMarkerEstimator(HiddenMarkerModel model, bool keep_predictors = true);

  struct Marker {
    Eigen::Vector3d position_m = Eigen::Vector3d::Zero();  // world
    MarkerEstimate how = MarkerEstimate::kUnknown;
  };
  // One frame: the three frame markers and the modelled markers (world, in the model's order; NaN
  // where hidden). Returns every modelled marker, seen or estimated.
  std::vector<Marker> update(double time_s, std::span<const Eigen::Vector3d, 3> frame_markers_world,
                             std::span<const Eigen::Vector3d> markers_world);
  // One frame whose hand frame is known some other way (a tracker's hand star): the modelled markers
  // in that frame (NaN where hidden), and every one back in it, seen or estimated.
  std::vector<Marker> update_in_hand(double time_s, std::span<const Eigen::Vector3d> markers_hand);
  // A frame in which the hand's frame is not known: nothing is predicted, and a marker seen again
  // afterwards starts afresh.
  void hand_lost() { previous_visible_ = 0; }

  // New statistics for the model (a model fitted as a tracker runs); the cached predictors go.
  void set_statistics(Eigen::VectorXd mean_m, Eigen::MatrixXd covariance_m2, int training_frames);

  const HiddenMarkerModel& model() const { return model_; }

 private:
  // x_H's predictor for a set of visible coordinates: x_H = mean_H + gain (x_V - mean_V).
  const Eigen::MatrixXd& gain(std::uint64_t visible_markers);
  Eigen::MatrixXd compute_gain(std::uint64_t visible_markers) const;
  Eigen::Vector3d predict(int marker, std::uint64_t visible, const Eigen::VectorXd& hand_positions);

  HiddenMarkerModel model_;
  bool keep_predictors_ = true;
  std::map<std::uint64_t, Eigen::MatrixXd> gains_;
  Eigen::VectorXd last_seen_;           // hand frame, per marker (NaN until seen)
  std::vector<double> hidden_since_s_;  // NaN while seen
  std::vector<Eigen::Vector3d> remembered_error_;
  std::optional<Rigid3d> last_frame_;
  std::uint64_t previous_visible_ = 0;  // the markers seen in the hand's frame on the last frame
};

// The evaluation of `rhot-eval hands --take`: over [first_frame, end_frame) of a take, the modelled
// fingertips are hidden by rule, gaps of gap_s seconds each followed by as long with nothing
// hidden, each tip in turn (`together` 2: a tip and its neighbour's); the estimate is compared with
// the recorded position.
struct HideSettings {
  double gap_s = 0.5;
  int together = 1;
  unsigned seed = 1;  // where in the first cycle the gaps start
  int first_frame = 0;
  int end_frame = -1;
};

// Which tips the rule hides on each frame: gap k (frames [k 2g, k 2g + g) counted from the first
// frame plus an offset drawn from the seed, g the gap in frames) hides tip k mod the tips, and with
// `together` 2 its neighbour too (the next, or for the last the one before).
class HideSchedule {
 public:
  // Refused (nothing) for a gap that is not a positive number of seconds, or no tips.
  static std::optional<HideSchedule> make(const HideSettings& settings, double frame_rate_hz, std::size_t tips);
  std::vector<std::size_t> hidden(int frame) const;  // indices into the tips

 private:
  HideSchedule() = default;
  int first_ = 0, gap_ = 1, offset_ = 0, together_ = 1;
  std::size_t tips_ = 0;
};

struct HiddenMarkerErrors {
  std::vector<double> hidden_mm;  // every hidden frame of every hidden tip with a recorded position
  std::vector<double> held_mm;    // the same frames, the marker held where it was last seen (hand frame)
  std::map<std::string, std::vector<double>> hidden_by_marker_mm;
  int hidden_frames = 0;
};

// The names of a model's tips: markers ending in "_tip", in the model's order.
std::vector<int> fingertip_markers(const HiddenMarkerModel& model);

// Refused when the take lacks one of the model's markers (named) or the range holds no frame.
[[nodiscard]] std::expected<HiddenMarkerErrors, std::string> evaluate_hidden_markers(const MarkerTake& take, const HiddenMarkerModel& model,
                                                                                     const HideSettings& settings);

}  // namespace rhot
