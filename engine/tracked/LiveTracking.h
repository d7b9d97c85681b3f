#pragma once
// Live tracking: camera frames from a frame source (tracking/source/FrameSource.h, any kind)
// through the tracker, as four timed stages:
//
//   source    the next multi-camera frame (the source's warnings are logged)
//   matching  detections matched across cameras and triangulated
//   stars     the tracked objects' marker stars and both hands' stars identified and followed
//             by one StarTracker (a point is one star's marker at most; with coloured markers,
//             points of a colour only fingertips wear are not offered); each object's pose
//   hands     the points left shared out to both hands' fingertips, nearest first; each hand's
//             star and fingertip markers -> a 26-joint hand (HandTracker.h, track_hands)
//
// Once the source has ended, frames have no detections (nothing is seen, hands ease to rest) and
// ended() is true. A frame from outside never stops the runtime: one whose cameras are not the
// rig's, in rig order, is dropped (the frame has no detections), and non-finite detections are
// dropped; both are logged at the 1st, 10th, 100th ... bad frame.

#include <array>
#include <cstdint>
#include <expected>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "base/Jobs.h"
#include "engine/tracked/ResultSource.h"
#include "engine/tracked/TrackedObjects.h"
#include "tracking/geometry/Matching.h"
#include "tracking/hand/HandLayout.h"
#include "tracking/hand/HandTracker.h"
#include "tracking/rigid/StarTracker.h"
#include "tracking/source/FrameSource.h"

namespace rhot {

struct LiveTrackingSettings {
  // 1-euro filtering of each hand's frame and fingertips before the IK (HandTrackerSettings):
  // steadier hands at rest, some lag in fast moves. Off by default (docs/tracking.md).
  bool filter_hands = false;
  // 1-euro filtering of each hand's frame alone (HandTrackerSettings::filter_frame): on by default.
  bool filter_hand_frames = true;
  // The rig the tracker believes (empty: the source's own). A simulation with a calibration error
  // gives the tracker a rig a little off the one that made the detections.
  std::optional<CameraRig> tracker_rig;
  // Threads the matching and hands stages run on (base/Jobs.h), 0: every core there is. The results do not
  // depend on it (docs/tracking.md "Threads").
  int threads = 0;
  std::shared_ptr<JobPool> jobs;  // or this pool, shared with the frame source (threads is then unused)
};

// A tracked hand as the engine takes it.
HandInput hand_input(const TrackedHand& tracked);

class LiveTracking final : public ResultSource {
 public:
  // layouts: the left hand's, then the right's.
  LiveTracking(std::unique_ptr<FrameSource> source, const TrackedObjects& objects, const std::array<HandLayout, 2>& layouts,
               LiveTrackingSettings settings = {});

  std::vector<TrackingStage> stages() override;
  TrackingResults& results() override { return results_; }
  const CameraRig* rig() const override { return &tracker_rig(); }
  const CameraRig& tracker_rig() const { return settings_.tracker_rig ? *settings_.tracker_rig : source_->rig(); }
  // The detection noise the tracker estimates from the residuals (pixels).
  double pixel_sigma() const { return pixel_sigma_.sigma_px(); }
  bool ended() const override { return ended_; }
  std::vector<std::string> summary() const override { return source_->summary(); }

  // The stages, one by one (stages() runs these).
  void read_source(double t_s);
  void match();
  void track_stars(double t_s);
  void track_hands(double t_s);

  // This frame's camera detections.
  const RigFrame& frame() const { return frame_; }
  FrameSource& source() { return *source_; }
  const TrackedHand& tracked_hand(HandSide side) const { return hand_trackers_[side == HandSide::kLeft ? 0 : 1]->last(); }
  const std::array<HandLayout, 2>& layouts() const { return layouts_; }
  // The objects' stars, then the left and right hands' (ids -1 and -2).
  const StarLibrary& star_library() const { return star_tracker_->library(); }

 private:
  std::unique_ptr<FrameSource> source_;
  LiveTrackingSettings settings_;
  std::shared_ptr<JobPool> jobs_;        // none with one thread
  std::unique_ptr<RigMatcher> matcher_;  // the tracker's rig, prepared for matching once
  PixelSigmaEstimate pixel_sigma_;
  std::vector<double> point_sigma_m_;                      // this frame's points' standard deviations
  std::vector<std::pair<int, Rigid3d>> object_from_star_;  // per tracked object: star id, where the star sits on it
  std::array<HandLayout, 2> layouts_;
  std::unique_ptr<StarTracker> star_tracker_;  // the objects' stars, then the left and right hand stars
  std::array<int, 2> hand_star_{};             // each hand's star in star_tracker_
  // Colours only fingertips wear (coloured layouts): points of these colours are never a star's
  // marker, so the star tracker does not see them. star_point_ maps its points to this frame's,
  // and stars_ holds its stars with this frame's point indices.
  std::vector<int> fingertip_only_colours_;
  std::vector<int> star_point_;
  std::vector<Eigen::Vector3d> star_points_;
  std::vector<double> star_point_sigma_m_;
  std::vector<TrackedStar> stars_;
  std::array<std::unique_ptr<HandTracker>, 2> hand_trackers_;
  std::vector<bool> taken_;  // this frame's points used by a star or a fingertip
  RigFrame frame_;
  TrackingResults results_;
  bool ended_ = false;
  std::uint64_t bad_frames_ = 0;
  std::uint64_t next_bad_frame_told_ = 1;
};

}  // namespace rhot
