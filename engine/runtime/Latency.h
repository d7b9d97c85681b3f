#pragma once
// Latency, measured and predicted away (docs/latency.md).
//
// Every frame is stamped on the steady clock (base/SteadyClock.h) at four moments:
//   capture   its images were exposed (the source's own time where it knows: camera nodes, video
//             devices; else the start of the frame, as for the simulated rig)
//   pose      tracking has produced the hands and objects (the start of the `tracked` stage)
//   submit    the renderer has submitted both eyes
//   display   the first refresh of the headset at or after the GPU finished the frame (the
//             renderer's completion time, vk/FenceWatch.h, on a vsync grid of the headset's
//             refresh rate anchored at the first frame)
// tracking latency = pose - capture, render latency = submit - pose, motion-to-photon = display -
// capture.
//
// Prediction: before a frame is drawn its display time is predicted (the next refresh at or after
// now plus the GPU's recent time per frame), and the hands are drawn where their tracked motion
// puts them then: each joint moves on at its velocity, fitted over its last few tracked positions.

#include <array>
#include <cstddef>
#include <deque>
#include <optional>
#include <span>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <nlohmann/json_fwd.hpp>

#include "engine/app/FrameStats.h"
#include "tracking/core/Rigid3.h"

namespace rhot {

// A headset's refresh: vsyncs every period_s from anchor_s (steady clock, seconds).
class VsyncClock {
 public:
  // Precondition: period_s > 0, both finite.
  VsyncClock(double period_s, double anchor_s);
  // The first vsync at or after t_s (the anchor itself for times before it).
  double next_at_or_after(double t_s) const;
  double period_s() const { return period_s_; }

 private:
  double period_s_;
  double anchor_s_;
};

// One frame's four moments (steady clock, seconds).
struct FrameMoments {
  double capture_s = 0.0;
  double pose_s = 0.0;
  double submit_s = 0.0;
  double display_s = 0.0;
};

// Tracking, render and motion-to-photon latency over a run: p50/p99 over the last `window`
// frames, mean and max over all.
class LatencyStats {
 public:
  explicit LatencyStats(std::size_t window = 65536);
  // Precondition: capture <= pose <= submit <= display, all finite.
  void record(const FrameMoments& m);
  std::uint64_t frames() const { return frames_; }
  TimingSummary tracking() const { return summary(tracking_); }
  TimingSummary render() const { return summary(render_); }
  TimingSummary motion_to_photon() const { return summary(motion_to_photon_); }
  // {"frames", "tracking_ms": {"p50", "p99", "mean", "max"}, "render_ms": {...},
  //  "motion_to_photon_ms": {...}}
  nlohmann::json to_json() const;

 private:
  struct Series {
    std::deque<double> window;
    double sum = 0.0;
    double max = 0.0;
  };
  void push(Series& s, double ms);
  TimingSummary summary(const Series& s) const;

  std::size_t window_;
  std::uint64_t frames_ = 0;
  Series tracking_;
  Series render_;
  Series motion_to_photon_;
};

// Constant-velocity motion of a fixed set of points tracked over time: each point's velocity is
// the slope of a least-squares line through its last `frames` positions against their times, so
// one noisy position moves it less than a two-frame difference would. The history (of all the
// points: they share their times) restarts when they are lost, when time does not move forward,
// or when any point jumps faster than max_speed.
class MotionPredictor {
 public:
  // Preconditions: points > 0, frames >= 2, max_speed_m_s > 0.
  explicit MotionPredictor(std::size_t points, int frames = 5, double max_speed_m_s = 10.0);
  // This frame's positions at t_s (the runtime's clock); seen false: the points are lost.
  // Precondition: positions.size() == points.
  void update(double t_s, std::span<const Eigen::Vector3d> positions, bool seen);
  // A point's velocity (m/s); zero until it has two positions.
  Eigen::Vector3d velocity(std::size_t point) const;
  // positions (the points at the last update's time) moved on by horizon_s at their velocities,
  // the horizon capped at kMaxPredictionHorizon_s. A horizon that is not positive (or NaN)
  // predicts nothing: the positions are returned as they are.
  std::vector<Eigen::Vector3d> predict(std::span<const Eigen::Vector3d> positions, double horizon_s) const;
  void reset();

 private:
  std::size_t points_;
  int frames_;
  double max_speed_m_s_;
  std::deque<double> times_;
  std::deque<std::vector<Eigen::Vector3d>> history_;
  std::vector<Eigen::Vector3d> velocity_;
};

// Constant-velocity motion of a rigid pose (a star-tracked object): its origin as MotionPredictor
// fits it, its rotation at the angular velocity between its last two orientations. Restarts as
// MotionPredictor does, and when it turns faster than max_turn_rad_s. An object moving slower than
// kStillSpeed_m_s or turning slower than kStillTurn_rad_s is not moved that way: a still object's
// star jitters by about a millimetre a frame, and moving it on by that jitter's velocity would only
// add to its error (measured: 0.90 -> 0.99 mm in the demo's first two seconds without this).
class PoseMotion {
 public:
  static constexpr double kStillSpeed_m_s = 0.1;
  static constexpr double kStillTurn_rad_s = 1.0;

  explicit PoseMotion(int frames = 5, double max_speed_m_s = 10.0, double max_turn_rad_s = 30.0);
  // This frame's pose at t_s; seen false: lost.
  void update(double t_s, const Rigid3d& world_from_object, bool seen);
  // The pose moved on by horizon_s (capped at kMaxPredictionHorizon_s; nothing for negative or
  // non-finite horizons).
  Rigid3d predict(const Rigid3d& world_from_object, double horizon_s) const;
  Eigen::Vector3d angular_velocity() const { return angular_velocity_; }

 private:
  MotionPredictor origin_;
  double max_turn_rad_s_;
  double last_t_s_ = 0.0;
  std::optional<Eigen::Quaterniond> last_rotation_;
  Eigen::Vector3d angular_velocity_ = Eigen::Vector3d::Zero();  // world frame, rad/s
};

// How far ahead a frame's poses may be predicted: beyond this the constant-velocity guess is
// worse than none (a hand turns round in about 0.1 s), so longer horizons are capped here.
inline constexpr double kMaxPredictionHorizon_s = 0.05;

}  // namespace rhot
