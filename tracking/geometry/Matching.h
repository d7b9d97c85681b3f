#pragma once
// Multi-camera correspondence: which detections in different cameras are the same marker.
//
// 1. Every detection is undistorted to normalised image coordinates.
// 2. Frame after frame (RigMatcher::match_frame, MatchSettings::follow_points), each of the last
//    frame's points is grown first, as a seed is in step 4 but with no detection given (into every
//    camera that may see it, any two of its views free to be dropped), from where it is expected
//    now: its position moved on by its velocity (from the last two frames' points of its marker). Those three or more cameras confirm
//    explain their detections before step 3: a marker that moved as it did is found without a seed.
// 3. Seeds: for every pair of cameras, detection pairs that satisfy the epipolar constraint
//    within `epipolar_tolerance_px` (measured in the second camera's pixels), triangulated as the
//    midpoint of the two rays. The second camera's detections are found by epipolar line
//    (EpipolarIndex), not by testing each, and tried nearest the line first.
// 4. Each seed is grown: every other camera contributes its detection nearest the point's
//    reprojection, if within `reprojection_tolerance_px`. A seed that three or more cameras
//    confirm (refined, every residual within `max_residual_px`, after dropping up to two
//    observations that disagree with the rest) explains its detections: they seed nothing more,
//    which keeps seeding near linear in the markers. A two-view seed that more
//    than two other cameras should see, and do not, is dropped at once (step 5 would refuse it).
//    Seeds whose two detections already belong to one cluster are skipped, and so are seeds far
//    outside the rig's tracking volume (MatchSettings::seed_margin).
// 5. Clusters are refined (Gauss-Newton), grown again from the refined point, and pruned of
//    observations whose residual exceeds `max_residual_px` (worst first); then accepted greedily,
//    best supported first, each detection used once, so a ghost built from detections that
//    better-supported points explain is never accepted. A cluster is also refused when more
//    cameras that should see its point (in front, inside the image) have no detection there than
//    cameras that do, or when its reprojection RMS exceeds `max_rms_px`.
//
// Colour (Detection::colour): only detections of one colour are matched with each other, at every
// step, so coloured markers make ghosts between markers of different colours impossible; infrared
// detections (colour -1) match only each other.
//
// Markers seen by only two of many cameras are still found when the others cannot see them (out
// of view). A marker hidden by occlusion from most cameras that could see it is refused like a
// ghost: the rule cannot tell the two apart.

#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "tracking/camera/Camera.h"
#include "tracking/geometry/CameraVisibility.h"
#include "tracking/geometry/Triangulation.h"
#include "tracking/core/Frames.h"

namespace rhot {

class JobPool;

struct MatchSettings {
  double epipolar_tolerance_px = 2.0;
  double reprojection_tolerance_px = 2.5;
  double max_rms_px = 1.5;
  double max_residual_px = 1.5;  // an observation further than this from its point's reprojection is dropped
  // Where the rig has a tracking volume (CameraRig::volume), two-view seeds are grown only inside
  // it widened by seed_margin of its size and seed_margin_m on every side (the default: a box
  // twice the volume's size plus 25 cm each way). Most ghosts, two rays that happen to pass
  // close, meet far outside: on a large rig they were most of the matching's work. Negative
  // seed_margin: seeds anywhere.
  double seed_margin = 0.5;
  double seed_margin_m = 0.25;
  // RigMatcher::match_frame only: the last frame's points (within 0.1 s) are looked for first,
  // each where it is expected now (moved on by its velocity), before any pair of cameras is
  // seeded; markers that move as they did are then found without seeding (step 2 at the top of this file).
  bool follow_points = true;
};

// Tolerances for detections with sigma_px of noise: the defaults (right up to about 0.4 px), or
// wider in proportion (a residual's norm exceeds 3.7 sigma once in a thousand), so noisier
// cameras do not lose their markers' observations to the gates.
MatchSettings match_settings_for(double sigma_px);

struct MatchedPoint {
  TriangulatedPoint point;
  std::vector<Observation> observations;
  std::vector<int> detection;  // per observation: its index in that camera's detections
  int colour = -1;             // its detections' marker colour (tracking/core/MarkerColour.h), -1 for none
};

// The ground-truth marker a matched point belongs to (simulated frames only): -1 when its
// detections come from different markers (a ghost or a mix-up) or carry no truth.
int truth_marker(const RigFrame& frame, const MatchedPoint& point);

// The detection noise (pixels per axis) that explains the points' reprojection residuals: a
// point refined from n cameras keeps 2n - 3 of its 2n residuals' degrees of freedom, so
// sum(n rms^2) / sum(2n - 3) over the points estimates sigma^2. It includes whatever else moves
// detections off the rig's model (calibration error, unsynchronised exposures). Nothing when no
// point has a degree of freedom left.
std::optional<double> estimate_pixel_sigma(std::span<const MatchedPoint> points);

// The detection noise over time: each frame's estimate_pixel_sigma averaged with a time constant
// of `frames` frames, never below floor_px (detections are never better than that in practice).
class PixelSigmaEstimate {
 public:
  explicit PixelSigmaEstimate(double frames = 30.0, double floor_px = 0.1, double initial_px = 0.5)
      : frames_(frames), floor_px_(floor_px), variance_(initial_px * initial_px) {}
  // This frame's points in, the estimate (pixels) out.
  double update(std::span<const MatchedPoint> points);
  double sigma_px() const;

 private:
  double frames_;
  double floor_px_;
  double variance_;
  int seen_ = 0;
};

// Per point its standard deviation per axis (metres) under sigma_px of detection noise.
std::vector<double> point_sigmas_m(std::span<const MatchedPoint> points, double sigma_px);
// The same into `out` (replacing what it held; its storage is kept).
void point_sigmas_m(std::span<const MatchedPoint> points, double sigma_px, std::vector<double>& out);

struct MatchScratch;

// Matching for one rig, frame after frame: the rig prepared once (its cameras' projections, and
// which cameras may see each part of the box where seeds may lie with the default settings, the
// tracking volume twice over plus 25 cm each way: CameraVisibility; no grid for a rig without a
// volume), so that a point is projected only into the cameras that may see it. Keep one where
// frames keep coming; it holds a copy of the rig.
class RigMatcher {
 public:
  explicit RigMatcher(const CameraRig& rig);
  ~RigMatcher();
  RigMatcher(RigMatcher&&) noexcept;
  RigMatcher& operator=(RigMatcher&&) noexcept;

  // Precondition: frame.cameras[i].camera == i for every camera of the rig. With a job pool, the
  // cameras' detections, the seeds and the clusters' refinement are spread over its threads; the
  // points are the same, bit for bit, whatever the thread count (docs/tracking.md "Threads").
  std::vector<MatchedPoint> match(const RigFrame& frame, const MatchSettings& settings = {}, JobPool* jobs = nullptr) const;

  // The points of a frame of a sequence (RigFrame::time_s rising), matched with this matcher's own
  // working storage, kept from frame to frame: once frames have shown it their largest counts (of
  // detections, seeds, points), matching allocates nothing. With MatchSettings::follow_points,
  // the last frame's points are followed into this one first (step 2 above): the points depend on
  // the frames before, and are the same as match()'s for the first frame, or after a gap of more
  // than 0.1 s; without, they are always match()'s. Whatever the thread count, they are the same.
  // The points stay valid until the next call; one frame at a time.
  std::span<const MatchedPoint> match_frame(const RigFrame& frame, const MatchSettings& settings = {}, JobPool* jobs = nullptr);

  // Of the last match_frame's points, how many were followed from the frame before (the rest
  // were seeded).
  std::size_t followed_points() const;

  const CameraRig& rig() const { return rig_; }
  const CameraVisibility& visibility() const { return visibility_; }

 private:
  CameraRig rig_;
  std::vector<CameraProjection> projections_;
  CameraVisibility visibility_;
  std::unique_ptr<MatchScratch> scratch_;  // match_frame's
};

// One frame, without a grid (building one costs more than a frame's matching saves): the same
// points as RigMatcher(rig).match(...). For a frame or a few; hold a RigMatcher where frames keep
// coming.
std::vector<MatchedPoint> match_and_triangulate(const CameraRig& rig, const RigFrame& frame, const MatchSettings& settings = {},
                                                JobPool* jobs = nullptr);

}  // namespace rhot
