#pragma once
// A hand from triangulated points, with a layout (HandLayout.h): the hand star gives the hand
// frame (StarTracker), the points left near each fingertip's predicted marker are its marker
// (nearest first, each point once), and HandSolver fits the fingers.
//
// Alone, a HandTracker follows its hand star with a StarTracker of its own. With other hands and
// objects in view (track_hands below), the hand stars are followed by one StarTracker with every
// other star, so that a point is one star's marker at most, and the points left are shared out to
// every hand's fingertips at once, nearest first: two hands passing each other cannot claim the
// same markers.

#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "tracking/filter/OneEuroFilter.h"
#include "tracking/hand/HandLayout.h"
#include "tracking/hand/HandSolver.h"
#include "tracking/hand/HiddenMarkers.h"
#include "tracking/rigid/StarTracker.h"

namespace rhot {

struct TrackedHand {
  bool hand_seen = false;   // the hand star was seen this frame
  Rigid3d world_from_hand;  // last known
  HandState state;          // hand frame
  std::array<Eigen::Vector3d, kHandJointCount> joints_world{};
  std::array<int, kFingerCount> fingertip_point{-1, -1, -1, -1, -1};  // index into the points, -1 for none
  int segment_stars_seen = 0;
};

struct HandTrackerSettings {
  // 1-euro filtering of the hand frame and of each fingertip target (hand frame) before the IK.
  bool filter = false;
  OneEuroSettings position;  // for the hand's origin and the fingertips, metres
  OneEuroSettings rotation{1.0, 2.0, 1.0};
  // Hidden fingertips predicted from the seen ones (HiddenMarkers.h) by a model of how this hand's
  // fingertips lie together, fitted as the tracker runs from the frames in which all five are seen
  // (used once it has HandTracker::kFingertipModelFrames of them). Off, or before that, a hidden
  // finger follows HandSolver's rule alone. Layouts that mark all five fingertips only. Off by
  // default until the demo's soak passes with it (docs/tracking.md, "Inside the tracker").
  bool fingertip_model = false;
};

class HandTracker {
 public:
  HandTracker(const HandLayout& layout, const HandPose& skeleton, HandTrackerSettings settings = {});

  // points_world with each one's standard deviation per axis (metres; empty: the star library's
  // default) and marker colour (MatchedPoint::colour; empty: none known). The hand star is
  // followed by the tracker's own StarTracker.
  const TrackedHand& update(double time_s, std::span<const Eigen::Vector3d> points_world, std::span<const double> sigma_m = {},
                            std::span<const int> colour = {});

  // A fingertip marker a point could be: how far it is from where the finger's marker is predicted.
  struct FingertipCandidate {
    double distance_m = 0.0;
    int finger = 0;
    int point = 0;
  };
  // The update in three steps, for a hand star followed outside (track_hands):
  //   begin      the hand frame from this frame's star
  //   fingertip_candidates  the free points near each marked fingertip's predicted marker
  //   finish     the fingers solved with the points given to each fingertip (-1: none)
  void begin(double time_s, const TrackedStar& hand_star);
  // A fingertip the layout gives a colour takes only points of that colour (when `colour` is given),
  // within kColourGate_m of its predicted marker and without the reappearance rule: the colour
  // names the marker, so a finger lost for a while is found again at once.
  std::vector<FingertipCandidate> fingertip_candidates(std::span<const Eigen::Vector3d> points_world, const std::vector<bool>& taken,
                                                       std::span<const int> colour = {});
  const TrackedHand& finish(double time_s, std::span<const Eigen::Vector3d> points_world, std::span<const double> sigma_m,
                            const std::array<int, kFingerCount>& fingertip_point);
  const HandSolver& solver() const { return solver_; }
  const TrackedHand& last() const { return out_; }  // the last update's result
  // Time spent in HandSolver::update (the IK) on the last frame.
  double last_ik_us() const { return last_ik_us_; }

  // A fingertip's marker is looked for within a gate of its predicted place: kFingertipGate_m
  // while the finger is followed frame to frame, widening by kGateGrowth_mps for each second it
  // has gone without its marker, up to kFingertipGateMax_m. A tight gate keeps a finger from
  // jumping to a neighbour's marker, or to a ghost, when its own is hidden for a frame; a finger
  // that has lost its marker widens its search to find it again, but takes a point outside the
  // tight gate only when a point was there (within kFingertipGate_m, hand frame) the frame before
  // too: a marker found again persists, a ghost of the matching flickers.
  static constexpr double kFingertipGate_m = 0.025;
  static constexpr double kGateGrowth_mps = 0.25;
  static constexpr double kFingertipGateMax_m = 0.04;
  static constexpr double kColourGate_m = 0.08;
  // The fingertip model: frames with all five tips seen before it is used, how often it is refitted
  // (frames), how long a hidden tip's last offset from the prediction is kept (HiddenMarkerModel::
  // memory_s, the value fitted to the real glove take) and the ridge on its seen tips.
  static constexpr int kFingertipModelFrames = 90;
  static constexpr int kFingertipModelRefit = 30;
  static constexpr double kFingertipMemory_s = 0.5;
  static constexpr double kFingertipRidge_m2 = 1e-6;
  // How many frames the fingertip model has been fitted to (0: not in use yet).
  int fingertip_model_frames() const { return tip_estimator_ ? tip_estimator_->model().training_frames : 0; }

 private:
  HandLayout layout_;
  HandTrackerSettings settings_;
  std::unique_ptr<StarTracker> star_;    // for update(): the hand star alone
  std::optional<StarTracker> segments_;  // the layout's segment stars, if any
  PoseFilter hand_filter_;
  std::array<OneEuroFilter<3>, kFingerCount> tip_filters_;
  // This frame's, from begin(): each marked fingertip's last bone direction and predicted marker (hand frame).
  std::array<Eigen::Vector3d, kFingerCount> along_{};
  std::array<Eigen::Vector3d, kFingerCount> predicted_marker_{};
  std::array<double, kFingerCount> gate_m_{};
  std::array<std::optional<double>, kFingerCount> tip_found_s_{};  // when each fingertip last had its marker
  // Per fingertip, the free points outside its tight gate but inside its widened one, last frame
  // and this frame (hand frame): where a lost marker may be reappearing.
  std::array<std::vector<Eigen::Vector3d>, kFingerCount> reappearing_{}, reappearing_now_{};
  // The hidden tips' places from the model (hand frame), fitting it first with this frame's tips
  // when all five are seen.
  std::array<std::optional<Eigen::Vector3d>, kFingerCount> predict_hidden_tips(
      double time_s, const std::array<std::optional<Eigen::Vector3d>, kFingerCount>& tips);
  bool every_tip_marked_ = false;
  MarkerStatistics tip_statistics_{kFingerCount};
  std::optional<HiddenMarkerEstimator> tip_estimator_;
  HandSolver solver_;
  TrackedHand out_;
  double last_ik_us_ = 0.0;
};

// Every hand of a frame, their stars followed with every other star by one StarTracker (`stars`:
// that tracker's output; hand_star[h]: the index of hand h's star in it). The points of every star
// seen this frame are taken; the fingertips get the points left, nearest first over all hands.
// `taken` comes back marking the points the stars and the fingertips use.
void track_hands(std::span<HandTracker* const> hands, std::span<const int> hand_star, const std::vector<TrackedStar>& stars, double time_s,
                 std::span<const Eigen::Vector3d> points_world, std::span<const double> sigma_m, std::vector<bool>& taken,
                 std::span<const int> colour = {});

}  // namespace rhot
