#pragma once
// A rigid body of three markers followed among unlabelled points: the back of a glove's hand, as
// the shared take's glove has it. A marker star (StarIdentification.h) needs four markers, a face
// and the fourth that confirms it. Three markers whose three edges differ name themselves: each is
// the corner where two particular edges meet, so any three points whose distances match the edges
// give the body's pose (a triangle seen from behind is the same triangle turned over; it has no
// mirror image to confuse it with).
//
// Finding it anew (never seen, or lost for longer than lost_after_s): every set of points that
// matches the three edges is a candidate (near-copies of a cheaper one, as doubled points give,
// count as that one), and one that comes back (each point within follow_gate_m of the last
// frame's, a frame apart at most lost_after_s) confirm_frames frames in a row is believed, unless
// another candidate has lasted two frames or more beside it. A hand's ten finger markers make a
// chance match of three edges now and then; a chance match does not stay put, while a second body
// of the same edges (the other hand's glove: a left glove's triangle is the right's turned over)
// does, and then neither is believed. Time running backwards starts the search afresh.
// Following it: each marker is looked for near where the last pose and velocity put it, and the
// match nearest the prediction whose edges fit wins. With one marker missing (hidden, or seen by
// one camera only), the two left place the body: the prediction turned by the least rotation that
// lays its edge along theirs, moved to their midpoint.
//
// Not thread-safe: one tracker per body, updated by one thread.

#include <array>
#include <optional>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "tracking/core/Rigid3.h"

namespace rhot {

struct TriangleTrackerSettings {
  double edge_tolerance_m = 0.0015;  // an edge matches within this, plus gate_sigmas of its noise
  double gate_sigmas = 3.5;
  double point_sigma_m = 0.0003;  // a point's standard deviation per axis where none is given
  double follow_gate_m = 0.025;   // how far from its predicted place a followed marker is looked for
  int confirm_frames = 3;
  double lost_after_s = 0.25;  // unseen this long, the body is searched for anew
};

struct TrackedTriangle {
  bool seen = false;                      // placed this frame: by three markers, or two while followed
  bool followed = false;                  // confirmed, and not lost for longer than lost_after_s
  Rigid3d world_from_body;                // this frame's where seen, else the last known
  std::array<int, 3> point{-1, -1, -1};   // this frame's point per marker (-1: none)
  int markers_seen = 0;                   // 0, 2 or 3
  Eigen::Vector3d velocity_m_s{0, 0, 0};  // of the body's origin
};

class TriangleTracker {
 public:
  // markers_m: the body's markers in its own frame. Bodies whose edges differ by less than twice
  // edge_tolerance_m cannot tell their markers apart: check edge_separation_m() before use.
  explicit TriangleTracker(const std::array<Eigen::Vector3d, 3>& markers_m, TriangleTrackerSettings settings = {});

  // One frame of triangulated points at time_s (non-decreasing), with each point's standard
  // deviation per axis in metres (empty: settings' point_sigma_m). Points that are not finite are
  // never used.
  const TrackedTriangle& update(double time_s, std::span<const Eigen::Vector3d> points_world, std::span<const double> sigma_m = {});
  const TrackedTriangle& last() const { return out_; }

  // The smallest difference between two of the body's edges.
  double edge_separation_m() const;

 private:
  struct Match {
    std::array<int, 3> point{-1, -1, -1};
    double cost = 0.0;
  };
  bool edge_fits(int edge, std::span<const Eigen::Vector3d> points, std::span<const double> sigma_m, int a, int b) const;
  static constexpr std::size_t kMaxMatches = 32;
  std::vector<Match> matches(std::span<const Eigen::Vector3d> points, std::span<const double> sigma_m,
                             const std::array<Eigen::Vector3d, 3>* predicted) const;
  static std::array<Eigen::Vector3d, 3> places(std::span<const Eigen::Vector3d> points, const Match& m);
  std::optional<Rigid3d> place_by_two(const Rigid3d& predicted, std::span<const Eigen::Vector3d> points, std::span<const double> sigma_m);
  void seen_at(double time_s, const Rigid3d& pose);

  std::array<Eigen::Vector3d, 3> markers_m_;
  std::array<double, 3> edge_m_{};  // 0: markers 0-1, 1: markers 1-2, 2: markers 0-2
  TriangleTrackerSettings settings_;
  TrackedTriangle out_;
  bool confirmed_ = false;
  double last_seen_s_ = -1e300;
  // While finding it anew: the last frame's matches, each with how many frames in a row it has
  // come back.
  struct Pending {
    std::array<Eigen::Vector3d, 3> at;
    std::array<int, 3> point;
    int frames = 1;
  };
  std::vector<Pending> pending_;
  double pending_time_s_ = -1e300;  // the frame pending_ is from
};

}  // namespace rhot
