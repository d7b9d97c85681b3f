#pragma once
// Marker stars over time: each star's pose every frame, kept through brief occlusions, and never
// reported under a name it is not sure of.
//
// Every frame, stars seen recently are predicted forward at constant velocity (linear and
// angular), their markers matched to the nearest free points inside a gate that grows with the
// points' uncertainty, and refitted. Points left over go to identification from scratch
// (StarIdentification.h), whose every find starts a candidate: a constellation followed from
// frame to frame like a star, while the evidence for each reading of it (every star of the set,
// every correspondence of its markers) adds up as the chi-square of its edges against that star's.
// A candidate becomes its best reading's star once that reading's posterior (all readings equally
// likely at first) reaches min_confidence; with noisy points that takes several frames, with
// precise ones one. Three markers of different objects can form a face of some star by chance,
// so a candidate of three markers is also followed for `confirm_frames` frames first: a chance
// triangle changes shape as the objects move and is dropped. Only confirmed stars count as seen.
//
// A fresh identification that lands where another recently seen star is predicted is refused:
// those are that star's markers, read as a similar star (a label swap); so is one farther from
// where the star was last seen than it could have moved.
//
// Each star's pose is filtered over time (PoseKalman.h: constant velocity, each frame's fit
// weighed by its covariance, rigid_fit_covariance), and a star counts as seen only while its
// filtered pose is certain: within report_position_m and report_rotation_rad with
// report_sigmas standard deviations of its worst direction (a few frames after it is found, and
// not at all where its markers are too noisy for the bound). A fit the filter finds impossible
// (a wrong correspondence, or a jerk the model did not foresee) is refused: the star is not
// measured that frame; after refuse_frames in a row the filter starts again from the fit. Where the star is measured but not certain, it is
// measured_now() but not seen_now(): the hands, which weigh each fit themselves, use the fit.

#include <array>
#include <optional>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "tracking/core/Rigid3.h"
#include "tracking/filter/PoseKalman.h"
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
  // How sure the tracker must be of a candidate's reading (its posterior among all readings) before
  // the star counts as seen; readings this far behind the best in chi-square are forgotten.
  double min_confidence = 0.999;
  double forget_chi2 = 40.0;
  int max_candidate_frames = 180;  // a candidate not settled by then is dropped (2 s at 90 Hz)
  // A gate in metres grows by gate_sigmas times a point's standard deviation (per axis) times sqrt(3).
  double gate_sigmas = 4.0;
  // The pose filter, and what it takes for a star to count as seen: report_sigmas standard
  // deviations of the filtered pose along its worst direction within report_position_m and
  // report_rotation_rad (4.6: a 3-D Gaussian error is beyond that one time in 10,000).
  PoseKalmanSettings filter;
  double report_position_m = 0.010;
  double report_rotation_rad = 0.0873;  // 5 degrees
  double report_sigmas = 4.6;
  // A fit farther than this from the filter's prediction (squared Mahalanobis distance, 6
  // degrees of freedom: 1 in 10^6 by chance) is not folded in.
  double filter_gate_chi2 = 36.0;
  int refuse_frames = 3;  // fits refused in a row before the filter starts again from one
};

struct TrackedStar {
  int star = 0;                                // index into the library's stars()
  int id = 0;                                  // the star's id in its set
  Rigid3d world_from_star;                     // filtered
  Matrix6d covariance = Matrix6d::Identity();  // of world_from_star (Rigid3.h)
  Rigid3d measured;                            // this frame's fit, when measured_now()
  bool certain = false;                        // world_from_star is within the tracker's report bounds
  Eigen::Vector3d velocity_m_s{0, 0, 0};
  Eigen::Vector3d angular_velocity_rad_s{0, 0, 0};  // world frame
  double rms_m = 0.0;
  int markers_seen = 0;                      // this frame (0: not seen)
  std::array<int, 4> point{-1, -1, -1, -1};  // this frame's points per marker
  int frames_since_seen = -1;                // 0: seen this frame; -1: never seen
  double last_seen_s = 0.0;
  bool confirmed = false;   // stays false until a candidate is settled as this star
  int frames_followed = 0;  // consecutive frames this star has been fitted
  double confidence = 0.0;  // the posterior of its identity when it was settled

  // A confirmed star measured this frame, its filtered pose certain: what objects follow.
  bool seen_now() const { return measured_now() && certain; }
  // A confirmed star measured this frame (`measured`), however sure its filtered pose is.
  bool measured_now() const { return confirmed && frames_since_seen == 0; }
};

class StarTracker {
 public:
  explicit StarTracker(StarLibrary library, StarTrackerSettings settings = {});

  // One frame of triangulated points at time_s (non-decreasing), with each point's standard
  // deviation per axis in metres (empty: the library's point_sigma_m). Returns every star of the set.
  const std::vector<TrackedStar>& update(double time_s, std::span<const Eigen::Vector3d> points_world,
                                         std::span<const double> sigma_m = {});
  const std::vector<TrackedStar>& stars() const { return stars_; }
  const StarLibrary& library() const { return library_; }
  // How one star is expected to move, where it is not an object carried by a hand (settings'
  // filter): a hand's own star turns and jerks more. Starts its filter again.
  void set_motion(int star, const PoseKalmanSettings& motion);
  // Constellations being weighed (not yet any star).
  std::size_t candidates() const { return candidate_count_; }

 private:
  bool recent(const TrackedStar& s) const { return s.frames_since_seen >= 0 && s.frames_since_seen <= settings_.max_coast_frames; }
  bool recent_and_confirmed(const TrackedStar& s) const { return s.confirmed && recent(s); }
  Rigid3d predict(const TrackedStar& s, double time_s) const;
  bool near_prediction(const TrackedStar& s, const Rigid3d& predicted, const Rigid3d& fitted, double time_s, double sigma_m) const;
  struct StarMotion {
    Eigen::Vector3d velocity_m_s = Eigen::Vector3d::Zero();  // (Eigen leaves a vector uninitialised)
    Eigen::Vector3d angular_velocity_rad_s = Eigen::Vector3d::Zero();
  };
  // Takes this frame's fit as the star's; `start`: its filter starts again with these velocities
  // (a candidate settled as the star).
  // False, changing nothing, where the star's filter refuses the fit.
  bool accept(TrackedStar& s, const IdentifiedStar& fit, double time_s, const StarPoints& points,
              const std::optional<StarMotion>& start = std::nullopt);
  // Folds the fit into the star's filter (or starts it again) and says whether the star is certain;
  // false where it refuses the fit.
  bool filter(TrackedStar& s, const IdentifiedStar& fit, double time_s, const StarPoints& points, const std::optional<StarMotion>& start);
  // Step 1 of update: the recently seen stars followed; marks their points taken and them updated.
  void follow_stars(double time_s, const StarPoints& points, std::vector<char>& taken, std::vector<char>& updated,
                    std::vector<Rigid3d>& predicted);
  // One reading of a candidate: its slots (markers of the star it was found as) are this star's
  // markers slot_marker[slot]; chi2 adds up the evidence against it.
  struct Reading {
    int star = 0;
    std::array<int, 4> slot_marker{};
    double chi2 = 0.0;
  };
  struct Candidate {
    TrackedStar motion;               // the best reading's star, its pose and velocity
    std::array<int, 4> slot_point{};  // this frame's points per slot
    std::vector<Reading> readings;    // best first
    int frames = 0;
    double confidence = 0.0;
  };
  // A candidate from a fresh identification, written into c (its storage kept).
  void start_candidate(const IdentifiedStar& found, const StarPoints& points, double time_s, Candidate& c) const;
  void weigh(Candidate& c, const StarPoints& points) const;
  bool follow(Candidate& c, const StarPoints& points, std::vector<char>& taken, double time_s);
  // Whether a settled reading may become its star now (not a label swap, not too far).
  bool may_settle(const Candidate& c, const std::vector<char>& updated, const std::vector<Rigid3d>& predicted, double time_s) const;
  // A point near a star's predicted marker (follow_stars), or a candidate's slot (follow: star -1).
  struct Pairing {
    double d;
    int star, marker, point;
  };
  // update's working storage, kept from frame to frame so that following stars allocates nothing
  // once frames have shown it their largest counts.
  struct Scratch {
    std::vector<char> taken, updated;  // per point, per star
    std::vector<Rigid3d> predicted;    // per star
    std::vector<Pairing> pairings;
    std::vector<int> gated_star;
    std::vector<char> contested, point_claimed;
    std::vector<std::array<int, 4>> assigned;
    std::vector<Eigen::Vector3d> rest;
    std::vector<double> rest_sigma;
    std::vector<int> rest_index;
    StarIdentificationScratch identification;
    std::vector<IdentifiedStar> found;
  };

  StarLibrary library_;
  StarTrackerSettings settings_;
  std::vector<TrackedStar> stars_;
  static constexpr std::size_t kReadingsPerStar = 24;  // a candidate's readings: every order of four markers
  static constexpr std::size_t kCandidatesRoom = 32;
  std::vector<Candidate> candidates_;  // the first candidate_count_ are being weighed; the rest keep their room
  std::size_t candidate_count_ = 0;
  std::vector<double> spread_m_;     // per star: RMS distance of its markers from their centre
  std::vector<PoseKalman> filters_;  // per star
  std::vector<int> refused_;         // per star: fits in a row the filter did not take
  Scratch scratch_;
};

}  // namespace rhot
