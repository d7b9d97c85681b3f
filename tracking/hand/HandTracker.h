#pragma once
// A hand from triangulated points, with a layout (HandLayout.h): the hand star gives the hand
// frame (StarTracker), the points left near each finger marker's predicted place are its marker
// (nearest first, each point once), and HandSolver fits the fingers to their fingertip markers.
// A layout's other finger markers (a glove's middle markers) are matched alike and, with the
// fingertip model on, tell where a hidden fingertip is. Labelled markers (a take's) need no
// matching: update_labelled takes them by the layout's order, the hand frame from the back of the
// hand's three or four.
//
// Alone, a HandTracker follows its hand star with a StarTracker of its own, or, with three markers
// on the back of the hand (a glove's), follows them as a triangle (TriangleTracker.h). With other hands and
// objects in view (track_hands below), the hand stars are followed by one StarTracker with every
// other star, so that a point is one star's marker at most, and the points left are shared out to
// every hand's fingertips at once, nearest first: two hands passing each other cannot claim the
// same markers.

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "tracking/filter/OneEuroFilter.h"
#include "tracking/hand/HandLayout.h"
#include "tracking/hand/HandSolver.h"
#include "tracking/hand/HiddenMarkers.h"
#include "tracking/rigid/StarTracker.h"
#include "tracking/rigid/TriangleTracker.h"

namespace rhot {

class JobPool;

// How this frame's hand frame was found.
enum class HandFrameSource {
  kNone,     // not this frame: world_from_hand is the last known
  kStar,     // the hand star (or, labelled, the back of the hand's markers)
  kMarkers,  // the star hidden: the hand's markers found near where the last frame put them
             // (HandTracker::frame_from_markers), a fit no better than the fingers' last pose
};

struct TrackedHand {
  bool hand_seen = false;  // the hand frame was found this frame (frame_source: how)
  HandFrameSource frame_source = HandFrameSource::kNone;
  Rigid3d world_from_hand;  // last known
  HandState state;          // hand frame
  std::array<Eigen::Vector3d, kHandJointCount> joints_world{};
  std::array<int, kFingerCount> fingertip_point{-1, -1, -1, -1, -1};  // index into the points, -1 for none
  std::vector<int> marker_point;  // per layout marker (HandLayout::markers): index into the points, -1 for none
  int segment_stars_seen = 0;
};

// How a hand's own stars (its back's, its fingers' segments') move for their pose filter
// (StarTracker::set_motion): hands turn and stop far quicker than the objects they carry, and
// their solver weighs each frame's fit itself, so the filter is there to refuse the impossible,
// not to smooth.
inline PoseKalmanSettings hand_star_motion() {
  PoseKalmanSettings s;
  s.acceleration_density = 30.0;
  s.angular_acceleration_density = 150.0;
  return s;
}

struct HandTrackerSettings {
  // 1-euro filtering of the hand frame and of each finger marker (hand frame) before the fit.
  bool filter = false;
  // 1-euro filtering of the hand frame alone (where it comes from points the cameras saw, not from
  // labelled markers): the frame's jitter, turned about the back of the hand, moves every finger
  // marker's predicted place and every fitted fingertip (docs/tracking.md, "The hand frame
  // steadied"). Started afresh when the hand is seen again after HandTracker::kFrameFilterGap_s.
  // On by default: on the real glove take through the seated rig it brings the hidden fingertips
  // from 1.5-2.0 to 1.3-1.4 times their labelled error; off where a test measures the solve itself
  // on exact points (a moving hand's frame lags by a few millimetres).
  bool filter_frame = true;
  // The hand frame's origin (metres): the cutoff rises quickly with speed (80 per metre per second,
  // 41 Hz at 0.5 m/s), so a moving hand is not dragged behind; what the frame's jitter does to the
  // fingers is its rotation's.
  OneEuroSettings frame_position{1.0, 80.0, 1.0};
  OneEuroSettings position;  // for the fingertips (filter), metres
  OneEuroSettings rotation{1.0, 2.0, 1.0};
  // Hidden fingertips predicted from the seen markers (HiddenMarkers.h) by a model of how this
  // hand's finger markers lie together, fitted as the tracker runs from the frames in which all are
  // seen (used once it has HandTracker::kFingertipModelFrames of them). Off, or before that, a
  // hidden finger follows HandSolver's rule alone. Layouts that mark all five fingertips (and have
  // at most 63 finger markers) only. Off
  // by default until the demo's soak passes with it (docs/tracking.md, "Inside the tracker").
  bool fingertip_model = false;
  // The hand frame from the hand's markers while its star is hidden (frame_from_markers below):
  // a hand turned palm up to the cameras, whose fingertip markers are still seen, stays tracked.
  // By default only for layouts whose every fingertip marker is known by its colour: with
  // anonymous markers (the infrared layouts), keeping the hand made the showcases' two-handed bar
  // 1.0 -> 0.87 over seeds 221-250, a hand whose grip was hidden no longer let go when it was lost
  // (docs/tracking.md, "A hand whose star is hidden").
  enum class MarkerFrame : std::uint8_t { kOff, kWhereColoured, kOn };
  MarkerFrame frame_from_markers = MarkerFrame::kWhereColoured;
  // How much longer or shorter than the skeleton's a user's fingers may be, as a fraction of each
  // finger's length: a finger marker found again by its reach (take_by_reach) may lie where the
  // finger, with its marker, would reach at its own size or scaled about its root by (1 + this) or
  // 1 / (1 + this) (clamped to [0, HandTracker::kFingerLengthToleranceMax]). The reference hand
  // stands for adults whose hands span about +-10 % around it (the simulated users' hands,
  // independent_hand, do too). At 0, a user's longer finger opened while its marker was hidden was
  // not found again (docs/tracking.md, "A finger longer than the skeleton's"). 0 for a skeleton
  // calibrated to the user (HandCalibration.h).
  double finger_length_tolerance = 0.1;
};

class HandTracker {
 public:
  HandTracker(const HandLayout& layout, const HandPose& skeleton, HandTrackerSettings settings = {});

  // points_world with each one's standard deviation per axis (metres; empty: the star library's
  // default) and marker colour (MatchedPoint::colour; empty: none known). The hand star is
  // followed by the tracker's own StarTracker.
  const TrackedHand& update(double time_s, std::span<const Eigen::Vector3d> points_world, std::span<const double> sigma_m = {},
                            std::span<const int> colour = {});

  // Labelled markers: each of the layout's markers (world, in HandLayout::markers' order; NaN where
  // hidden). The hand frame comes from the back of the hand's markers (all of three, or three of
  // four); without them the hand is not seen.
  const TrackedHand& update_labelled(double time_s, std::span<const Eigen::Vector3d> markers_world);

  // A finger marker a point could be: how far it is from where the marker is predicted.
  struct FingertipCandidate {
    double distance_m = 0.0;
    int marker = 0;  // index into HandLayout::markers
    int point = 0;
    // A marker taken back after a gap: not followed the frame before, or the point outside its tight
    // gate (track_hands contests such a point between two hands).
    bool returning = false;
    // Outside the tight gate and not there the frame before: not taken (a ghost of the matching
    // flickers), but listed for the contest between hands.
    bool persists = true;
  };
  // The update in three steps, for a hand star followed outside (track_hands):
  //   begin      the hand frame from this frame's star
  //   fingertip_candidates  the free points near each finger marker's predicted place
  //   finish     the fingers solved with the points given to each marker (-1: none)
  // (track_hands also finds the frame of a hand whose star is hidden from its other markers:
  // frame_from_markers and confirm_frame_from_markers below, private to it.)
  void begin(double time_s, const TrackedStar& hand_star);
  void begin(double time_s, bool seen, const Rigid3d& world_from_hand);
  static constexpr double kMarkerFrameHold_s = 1.0;
  static constexpr double kMarkerFrameGate_m = 0.03;
  static constexpr double kMarkerFrameMiss_m = 0.006;
  static constexpr double kMarkerFrameFingerWeight = 0.5;
  static constexpr int kMarkerFrameMarkers = 4;
  static constexpr double kMarkerFrameTurn_rad = 0.5;
  // The confidence of the joints the hand frame fixes (palm, wrist, knuckles) in a frame from the
  // markers: fitted to seen markers (HandSolver.h's 0.9), not measured.
  static constexpr double kMarkerFrameConfidence = 0.9;
  // A finger whose tip marker's point take_by_reach found has the confidence of its joints past
  // the knuckle capped at this (below a grasp's `confident`, 0.95, by default) in that frame and the
  // next kReacquiredFrames - 1 frames in which its marker is found (a frame without it does not
  // count, so a stray flickering out for a frame is not trusted when it comes back): a point taken by
  // reach lies anywhere the finger reaches, far from its estimate, and can be a stray there for a few
  // frames (on the workbench a hidden thumb took one 45 mm from its estimate, followed it for a few
  // frames, and the door it held was let go as "thumb opened 41 mm"). A finger its segment stars
  // measure is left as they measure it.
  static constexpr double kReacquiredConfidence = 0.9;
  static constexpr int kReacquiredFrames = 6;
  // A fingertip the layout gives a colour takes only points of that colour (when `colour` is given),
  // within kColourGate_m of its predicted marker and without the reappearance rule: the colour
  // names the marker, so a finger lost for a while is found again at once.
  // The candidates stay valid until the next call (kept storage: nothing allocated per frame).
  const std::vector<FingertipCandidate>& fingertip_candidates(std::span<const Eigen::Vector3d> points_world, const std::vector<bool>& taken,
                                                              std::span<const int> colour = {});
  // Between fingertip_candidates and finish: neighbouring fingers' tips that took each other's
  // points put right. Nearest first keeps a swap once two fingers' predictions have crossed (where
  // fingertips crowd, the prediction follows the last solve, which followed the swapped points);
  // a finger's other markers (a glove's middle markers) are not fooled, so where both fingers have
  // one found (or carry none: a tip-only finger must reach its tip's point within its joint
  // limits), each tip's point is fitted with them (FingerFit.h), and the points change fingers
  // when that fits by kUntangleMargin_m better. A lone point between two fingers stays where it was
  // given (moved by the fits, it gave a hidden finger its neighbour's point: docs/tracking.md).
  // Coloured tips, named by their colour, are left as they are.
  void untangle_neighbours(std::span<const Eigen::Vector3d> points_world, std::span<int> marker_point) const;
  // Taking back by reach, in two steps: reach_candidates (beside fingertip_candidates) lists, for
  // each finger marker not followed the frame before (or given its point by reach then), the free
  // points its finger reaches
  // (FingerFit.h: the finger fitted to it misses by at most kReachMiss_m within its joint limits, at
  // its size or scaled by HandTrackerSettings::finger_length_tolerance),
  // however far its finger's estimate had drifted from them, each marked whether it was reachable
  // the frame before too; take_by_reach (after nearest first, before untangle_neighbours) gives each
  // marker still without a point one of those that were, and not `contested` (below). A hidden
  // finger whose estimate went astray (a thumb bent at the other fingers' rate while it was hidden)
  // is otherwise never found again: its marker lies outside every gate. A point several such
  // markers reach goes to the one in whose plane it lies nearest; `taken` is updated. Only fingers
  // with no other marker found: a glove's middle marker already holds its finger's estimate, and its
  // free neighbours' markers are within its reach. Coloured markers, named by their colour, are
  // left to it.
  // Between two hands (track_hands): a point that markers of both could take back after a gap (a
  // returning candidate, or by reach; one refused as a ghost counts too: the contest asks whose a
  // point could be, not whether it is a marker) goes to neither hand's marker unless it is
  // kContestRatio times nearer that marker's predicted place than the other hand's; a finger that
  // reaches it counts as no farther than kFingertipGateMin_m, its estimate having drifted. Two hands
  // on one object hide each other's fingers, and a hidden finger's estimate can be centimetres off:
  // a hand-over's giving hand opened with its thumb hidden, and its thumb's marker, back 17 mm from
  // that hand's estimate, was taken by the taking hand's hidden thumb 12 mm from it, which followed
  // it away and let the object go as "thumb opened". Each hand's nearest such marker is weighed
  // against the other's. A point within the tight gate of a marker followed frame to frame is that
  // marker's to take nearest first, uncontested.
  static constexpr double kContestRatio = 2.0;
  struct Reach {
    double side_m;
    double predicted_m;  // from the marker's predicted place
    int marker, point;
    bool persists;            // reached the frame before too: only such a point is taken
    Eigen::Vector3d in_hand;  // the point, hand frame
  };
  const std::vector<Reach>& reach_candidates(std::span<const Eigen::Vector3d> points_world, const std::vector<bool>& taken);
  void take_by_reach(std::span<const Eigen::Vector3d> points_world, std::vector<bool>& taken, const std::vector<bool>& contested,
                     std::span<int> marker_point);
  const TrackedHand& finish(double time_s, std::span<const Eigen::Vector3d> points_world, std::span<const double> sigma_m,
                            std::span<const int> marker_point);
  const HandLayout& layout() const { return layout_; }
  // Where the last solve puts each of the layout's markers (hand frame; their frames the solver's
  // own fingers', HandLayout.h marker_frames): a hidden marker's estimate.
  std::vector<Eigen::Vector3d> markers_in_hand() const;
  const HandSolver& solver() const { return solver_; }
  const TrackedHand& last() const { return out_; }  // the last update's result
  // Time spent in HandSolver::update (the IK) on the last frame.
  double last_ik_us() const { return last_ik_us_; }

  // A fingertip's marker is looked for within a gate of its predicted place: its tight gate while
  // the finger is followed frame to frame, widening by kGateGrowth_mps for each second it has gone
  // without its marker, up to kFingertipGateMax_m. The tight gate is the marker's own: kGateSigmas
  // times the RMS of its predicted place's miss on the frames it was followed (found the frame
  // before and this one), over about kMissMemory_s, within [kFingertipGateMin_m, kFingertipGate_m].
  // Where the hand model fits the hand, a hidden finger's marker is not replaced by a ghost of the
  // matching 15-25 mm away (two views of two different fingertips meeting near the hand, where tips
  // crowd in a fist); where it misses (a real hand's tips 5-20 mm from the fitted skeleton's), the
  // gate stays wide enough to keep the marker. A tight gate keeps a finger from
  // jumping to a neighbour's marker, or to a ghost, when its own is hidden for a frame; a finger
  // that has lost its marker widens its search to find it again, but takes a point outside the
  // tight gate only when a point was there (within the tight gate, hand frame) the frame before
  // too: a marker found again persists, a ghost of the matching flickers.
  static constexpr double kFingertipGate_m = 0.025;
  static constexpr double kFingertipGateMin_m = 0.015;
  static constexpr double kGateSigmas = 4.0;
  static constexpr double kMissMemory_s = 1.0;
  static constexpr double kGateGrowth_mps = 0.25;
  static constexpr double kFingertipGateMax_m = 0.04;
  // A marker never yet found is looked for within kUnfoundMarkerGate_m over the first
  // kUnfoundSearch_s after the hand is first seen: a finger the skeleton starts far from (a glove on
  // a hand unlike the reference one: the shared take's thumb markers 50 mm and more from where the
  // reference hand holds them) finds its markers. The persistence rule still holds, the other
  // markers take theirs first (nearest first), and after that search, or once found, a marker is
  // followed within the gates above: a marker hidden from the start, or lost later, while the hand
  // holds an object whose markers stay put beside the fingers, does not reach that far for them.
  static constexpr double kUnfoundMarkerGate_m = 0.08;
  static constexpr double kUnfoundSearch_s = 3.0;
  static constexpr double kColourGate_m = 0.08;
  // A finger's markers other than its tip's weigh this much in its fit (FingerFit.h) against the
  // tip's: the tip's miss is what a user sees, the others pin the knuckle down. The per-user
  // calibration (HandCalibration.h) weighs them alike.
  static constexpr double kOtherMarkerWeight = 0.25;
  // untangle_neighbours: tips' points within kUntangleReach_m of each other (or a lone point of
  // the other finger's predicted tip) are checked when the two fits miss by kUntangleMiss_m
  // together (weighted RMS, FingerFit::rms_m), and swapped when the swap misses by kUntangleMargin_m
  // less.
  static constexpr double kUntangleReach_m = 0.04;
  static constexpr double kUntangleMiss_m = 0.004;
  static constexpr double kUntangleMargin_m = 0.002;
  // take_by_reach: the most a finger fitted to a free point may miss it by, and how far (hand
  // frame) the point may have moved since the frame before. Not wider: at 8 mm a pointing finger a
  // few millimetres longer than the model was found again, its straight finger's marker 5-6 mm past
  // its reach, but fingers took points by reach twice as often, some wrong (a pinching finger let a
  // cube go in rhot-eval grasp seed 4), and a hidden thumb took a stray 86 mm from its estimate.
  static constexpr double kReachMiss_m = 0.004;
  static constexpr double kFingerLengthToleranceMax = 0.3;  // HandTrackerSettings::finger_length_tolerance's largest
  static constexpr double kReachPersist_m = 0.015;
  static constexpr double kFrameFilterGap_s = 0.1;
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
  // How far to the side of marker m's finger's own plane (through its knuckle, along its rest
  // direction) a point p lies, where the finger reaches p (hand frame) within kReachMiss_m and its
  // joint limits, at its own size or scaled about its root (with its marker) by 1 + t or 1 / (1 + t),
  // t being HandTrackerSettings::finger_length_tolerance; none where it cannot.
  std::optional<double> reach_side(std::size_t m, const Eigen::Vector3d& p) const;
  // Marker m had a point on the last frame: it is followed frame to frame.
  bool followed(std::size_t m) const { return last_time_s_ && marker_found_s_[m] == last_time_s_; }
  // track_hands' step after begin() found no hand frame: the frame from the hand's markers that are found (free
  // points near where the last frame puts them), while the star has been hidden for at most
  // kMarkerFrameHold_s. Each marker of the layout is where it was on the hand in the star's last
  // frame (the finger markers where that frame's solve put them): that shape is fitted, weighing a
  // finger marker kMarkerFrameFingerWeight against a star marker, to free points within
  // kMarkerFrameGate_m of where the last frame puts each marker (a coloured marker only points of
  // its colour), nearest first. At least kMarkerFrameMarkers markers not in a line, each within
  // kMarkerFrameMiss_m of the fit (the worst dropped until they are), and the frame within
  // kMarkerFrameGate_m and kMarkerFrameTurn_rad of the last: else the hand stays unseen. Returns
  // whether it was found. Reads `taken`, takes nothing (track_hands takes the star's markers
  // used, and refuses the frame where the fingers' share-out leaves it too few of its markers).
  bool frame_from_markers(double time_s, std::span<const Eigen::Vector3d> points_world, const std::vector<bool>& taken,
                          std::span<const int> colour = {});
  // After the points are shared out (track_hands): a frame from markers that kept fewer than
  // kMarkerFrameMarkers of the markers it was fitted to (another hand's fingers took them) is
  // refused, and the hand is unseen this frame.
  void confirm_frame_from_markers(double time_s);
  HandLayout layout_;
  HandTrackerSettings settings_;
  std::unique_ptr<StarTracker> star_;             // for update(): the hand star alone (layouts with one)
  std::optional<TriangleTracker> triangle_;       // for update(): three markers on the back of the hand instead
  std::optional<StarTracker> segments_;           // the layout's segment stars, if any
  PoseFilter hand_filter_;                        // the hand frame's (filter, filter_frame), with its clock (last_sample_s)
  std::vector<OneEuroFilter<3>> marker_filters_;  // per layout marker (the fingers' used)
  // This frame's, from begin(), per layout marker (the back of the hand's unused): each finger
  // marker's predicted place and its gate (hand frame).
  std::vector<Eigen::Vector3d> predicted_marker_;
  std::vector<double> gate_m_;
  std::vector<double> tight_gate_m_;                   // this frame's tight gate per marker
  std::vector<double> miss2_m2_;                       // per marker: the mean square miss of its predicted place (kMissMemory_s)
  std::optional<double> last_time_s_;                  // the last update's
  std::vector<std::optional<double>> marker_found_s_;  // when each marker last had a point
  std::optional<double> hand_first_seen_s_;
  std::optional<double> star_seen_s_;  // when the hand frame last came from the star
  // frame_from_markers' working storage (kept: nothing allocated per frame).
  struct MarkerPick {
    double distance_m;
    int marker, point;
  };
  std::vector<MarkerPick> marker_picks_;
  std::vector<Eigen::Vector3d> shape_at_star_;  // each marker in the hand frame as the star last saw the hand
  bool shape_stale_ = false;                    // the star was seen since shape_at_star_ was taken
  std::vector<Eigen::Vector3d> frame_from_, frame_to_;
  std::vector<double> frame_weight_;
  std::vector<int> frame_marker_, frame_point_;
  // Per marker, the free points outside its tight gate but inside its widened one, last frame and
  // this frame (hand frame): where a lost marker may be reappearing.
  std::vector<std::vector<Eigen::Vector3d>> reappearing_, reappearing_now_;
  // Per marker, the free points its finger reached (take_by_reach), last frame and this one.
  std::vector<std::vector<Eigen::Vector3d>> reachable_, reachable_now_;
  // The points take_by_reach gave this frame (cleared by finish; untangle_neighbours may move
  // one to a neighbour, which then holds it), and per marker the frames it is still to be found in
  // before it is trusted.
  std::vector<int> reach_points_;
  std::vector<int> untrusted_frames_;
  // The most points kept in each of those lists (made room for once: nothing allocated per frame).
  static constexpr std::size_t kNearPointsKept = 16;
  // Per-frame working storage, kept from frame to frame (nothing allocated once frames have shown
  // it their largest counts): fingertip_candidates' result, track_hands' points per marker,
  // take_by_reach's reachable points, finish's found markers (hand frame) and the modelled
  // ones seen, predict_hidden_tips' sample and hand.
  static constexpr std::size_t kPointsRoom = 64;
  std::vector<FingertipCandidate> candidates_;
  std::vector<int> tip_points_;
  std::vector<Reach> reach_;
  std::vector<bool> held_;
  std::vector<Eigen::Vector3d> found_;
  std::vector<std::optional<Eigen::Vector3d>> seen_;
  Eigen::VectorXd tip_sample_;
  std::vector<Eigen::Vector3d> tip_hand_;
  friend void track_hands(std::span<HandTracker* const>, std::span<const int>, const std::vector<TrackedStar>&, double,
                          std::span<const Eigen::Vector3d>, std::span<const double>, std::vector<bool>&, std::span<const int>, JobPool*);
  // The model's markers (layout indices): each fingertip marker, then the other finger markers.
  std::vector<int> modelled_;
  // Each hidden fingertip marker's place from the model (hand frame), fitting it first with this
  // frame's markers when every modelled one is seen (`seen`: each modelled marker's measured place).
  std::array<std::optional<Eigen::Vector3d>, kFingerCount> predict_hidden_tips(double time_s,
                                                                               const std::vector<std::optional<Eigen::Vector3d>>& seen);
  bool every_tip_marked_ = false;
  bool frame_from_markers_ = false;  // settings_.frame_from_markers, for this layout
  // The hand frame and its filter before this frame's frame_from_markers: put back if
  // confirm_frame_from_markers refuses it.
  Rigid3d frame_before_markers_;
  PoseFilter filter_before_markers_;
  bool labelled_ = false;  // in update_labelled: the points are the layout's markers, no segment stars among them
  std::optional<MarkerStatistics> tip_statistics_;
  std::optional<HiddenMarkerEstimator> tip_estimator_;
  HandSolver solver_;
  // The layout's segment stars this frame: fingers whose bones they measure get kMeasured evidence
  // (unless `found`, each marker's place this frame, NaN where not found, has their tip marker),
  // and a seen last bone's star gives its finger's tip (returned).
  std::array<std::optional<Eigen::Vector3d>, kFingerCount> measure_segments(double time_s, std::span<const Eigen::Vector3d> points,
                                                                            std::span<const double> sigma_m,
                                                                            std::span<const Eigen::Vector3d> found,
                                                                            std::array<FingerEvidence, kFingerCount>& evidence);
  TrackedHand out_;
  double last_ik_us_ = 0.0;
};

// Every hand of a frame, their stars followed with every other star by one StarTracker (`stars`:
// that tracker's output; hand_star[h]: the index of hand h's star in it, -1 for a hand without one). The points of every star
// seen this frame are taken; the fingertips get the points left, nearest first over all hands.
// `taken` comes back marking the points the stars and the fingertips use. With a job pool, each
// hand's own steps (its frame, its candidates, its fingers' solve) run side by side; the results are
// the same whatever the thread count.
void track_hands(std::span<HandTracker* const> hands, std::span<const int> hand_star, const std::vector<TrackedStar>& stars, double time_s,
                 std::span<const Eigen::Vector3d> points_world, std::span<const double> sigma_m, std::vector<bool>& taken,
                 std::span<const int> colour = {}, JobPool* jobs = nullptr);

}  // namespace rhot
