#pragma once
// Marker stars over time: each star's pose every frame, kept through brief occlusions.
//
// Every frame, stars seen recently are predicted forward at constant velocity (linear and
// angular), their markers matched to the nearest free points inside a gate, and refitted; the
// points left over go to identification from scratch (StarIdentification.h) for the stars not
// found that way. A fresh identification that lands where another recently seen star is predicted
// is refused: those are that star's markers, read as a similar star (a label swap).
//
// Three markers of different objects can form a face of some star by chance; four cannot, in
// practice (six edges would have to match). So a star first found from three markers is tentative
// until it has been followed for `confirm_frames` frames in a row (or shows its fourth marker): a
// chance triangle changes shape as the objects move and is dropped. Only confirmed stars count as
// seen.

#include <span>
#include <vector>

#include <Eigen/Core>

#include "tracking/core/Rigid3.h"
#include "tracking/rigid/StarIdentification.h"

namespace rhot {

struct StarTrackerSettings {
  // How far a point may be from a predicted marker: gate_m, plus what an unforeseen acceleration of
  // max_acceleration_m_s2 moves it since the star was last seen.
  double gate_m = 0.004;
  double max_acceleration_m_s2 = 20.0;
  int max_coast_frames = 45;      // frames a star is predicted without being seen (0.5 s at 90 Hz)
  double swap_distance_m = 0.03;  // a fresh identification this near another star's prediction is refused
  // How far a star may turn from its predicted orientation: turn_gate_rad plus turn_rate_rad_s per
  // second since it was last seen (hands turn objects at up to a few radians per second).
  double turn_gate_rad = 0.35;
  double turn_rate_rad_s = 6.0;
  int confirm_frames = 3;  // frames a star found from three markers must be followed before it counts
  // A star found afresh farther from where it was last seen than gate_m plus this speed times the
  // time since is refused: another constellation that happens to match its edges, since nothing a
  // hand carries moves that fast. (Once it has not been seen for a while, anywhere is reachable.)
  double max_speed_m_s = 5.0;
};

struct TrackedStar {
  int star = 0;  // index into the library's stars()
  int id = 0;    // the star's id in its set
  Rigid3d world_from_star;
  Eigen::Vector3d velocity_m_s{0, 0, 0};
  Eigen::Vector3d angular_velocity_rad_s{0, 0, 0};  // world frame
  double rms_m = 0.0;
  int markers_seen = 0;                      // this frame (0: not seen)
  std::array<int, 4> point{-1, -1, -1, -1};  // this frame's points per marker
  int frames_since_seen = -1;                // 0: seen this frame; -1: never seen
  double last_seen_s = 0.0;
  bool confirmed = false;   // false while a three-marker acquisition is being checked
  int frames_followed = 0;  // consecutive frames this star has been fitted

  // The pose is this frame's measurement of a confirmed star.
  bool seen_now() const { return confirmed && frames_since_seen == 0; }
};

class StarTracker {
 public:
  explicit StarTracker(StarLibrary library, StarTrackerSettings settings = {});

  // One frame of triangulated points at time_s (non-decreasing). Returns every star of the set.
  const std::vector<TrackedStar>& update(double time_s, std::span<const Eigen::Vector3d> points_world);
  const std::vector<TrackedStar>& stars() const { return stars_; }
  const StarLibrary& library() const { return library_; }

 private:
  bool recent(const TrackedStar& s) const { return s.frames_since_seen >= 0 && s.frames_since_seen <= settings_.max_coast_frames; }
  bool recent_and_confirmed(const TrackedStar& s) const { return s.confirmed && recent(s); }
  Rigid3d predict(const TrackedStar& s, double time_s) const;
  bool near_prediction(const TrackedStar& s, const Rigid3d& predicted, const Rigid3d& fitted, double time_s) const;
  void accept(TrackedStar& s, const IdentifiedStar& fit, double time_s);

  StarLibrary library_;
  StarTrackerSettings settings_;
  std::vector<TrackedStar> stars_;
};

}  // namespace rhot
