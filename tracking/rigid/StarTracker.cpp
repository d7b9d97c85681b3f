#include "tracking/rigid/StarTracker.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <Eigen/Geometry>

namespace rhot {

StarTracker::StarTracker(StarLibrary library, StarTrackerSettings settings) : library_(std::move(library)), settings_(settings) {
  for (std::size_t s = 0; s < library_.stars().size(); ++s) {
    TrackedStar t;
    t.star = static_cast<int>(s);
    t.id = library_.stars()[s].id;
    stars_.push_back(t);
  }
}

Rigid3d StarTracker::predict(const TrackedStar& s, double time_s) const {
  const double dt = time_s - s.last_seen_s;
  Rigid3d p = s.world_from_star;
  p.translation += s.velocity_m_s * dt;
  const Eigen::Vector3d turn = s.angular_velocity_rad_s * dt;
  if (turn.norm() > 1e-12) p.rotation = (Eigen::Quaterniond(Eigen::AngleAxisd(turn.norm(), turn.normalized())) * p.rotation).normalized();
  return p;
}

bool StarTracker::near_prediction(const TrackedStar& s, const Rigid3d& predicted, const Rigid3d& fitted, double time_s) const {
  const double turned = Eigen::AngleAxisd(fitted.rotation * predicted.rotation.conjugate()).angle();
  return (fitted.translation - predicted.translation).norm() < settings_.swap_distance_m &&
         turned <= settings_.turn_gate_rad + settings_.turn_rate_rad_s * (time_s - s.last_seen_s);
}

void StarTracker::accept(TrackedStar& s, const IdentifiedStar& fit, double time_s) {
  const double dt = time_s - s.last_seen_s;
  // Velocities from the last two poses: smoothed from frame to frame, the average across a gap.
  if (recent(s) && dt > 1e-6) {
    const Eigen::Vector3d v = (fit.world_from_star.translation - s.world_from_star.translation) / dt;
    const Eigen::AngleAxisd turn(fit.world_from_star.rotation * s.world_from_star.rotation.conjugate());
    const Eigen::Vector3d w = turn.axis() * (turn.angle() > std::numbers::pi ? turn.angle() - 2 * std::numbers::pi : turn.angle()) / dt;
    const bool consecutive = s.frames_since_seen == 0;
    s.velocity_m_s = consecutive ? Eigen::Vector3d(0.5 * (s.velocity_m_s + v)) : v;
    s.angular_velocity_rad_s = consecutive ? Eigen::Vector3d(0.5 * (s.angular_velocity_rad_s + w)) : w;
  } else {
    s.velocity_m_s.setZero();
    s.angular_velocity_rad_s.setZero();
  }
  s.world_from_star = fit.world_from_star;
  s.rms_m = fit.rms_m;
  s.markers_seen = fit.markers_seen;
  s.point = fit.point;
  s.frames_followed = s.frames_since_seen == 0 ? s.frames_followed + 1 : 1;
  s.confirmed = s.confirmed || fit.markers_seen == 4 || s.frames_followed >= settings_.confirm_frames;
  s.frames_since_seen = 0;
  s.last_seen_s = time_s;
}

const std::vector<TrackedStar>& StarTracker::update(double time_s, std::span<const Eigen::Vector3d> points) {
  const std::size_t n = points.size();
  std::vector<bool> taken(n, false);
  std::vector<bool> updated(stars_.size(), false);
  std::vector<Rigid3d> predicted(stars_.size());

  // 1. Recently seen stars: nearest points to their predicted markers, closest pairs first.
  struct Pairing {
    double d;
    int star, marker, point;
  };
  std::vector<Pairing> pairings;
  for (std::size_t s = 0; s < stars_.size(); ++s) {
    if (!recent(stars_[s])) continue;
    predicted[s] = predict(stars_[s], time_s);
    const double since = time_s - stars_[s].last_seen_s;
    const double gate = settings_.gate_m + 0.5 * settings_.max_acceleration_m_s2 * since * since;
    for (int m = 0; m < 4; ++m) {
      const Eigen::Vector3d at = predicted[s] * library_.stars()[s].markers_m[static_cast<std::size_t>(m)];
      for (std::size_t q = 0; q < n; ++q) {
        const double d = (points[q] - at).norm();
        if (d <= gate) pairings.push_back({d, static_cast<int>(s), m, static_cast<int>(q)});
      }
    }
  }
  std::sort(pairings.begin(), pairings.end(), [](const Pairing& a, const Pairing& b) { return a.d < b.d; });
  std::vector<std::array<int, 4>> assigned(stars_.size(), {-1, -1, -1, -1});
  std::vector<bool> point_claimed(n, false);
  for (const Pairing& p : pairings) {
    auto& slot = assigned[static_cast<std::size_t>(p.star)][static_cast<std::size_t>(p.marker)];
    if (slot >= 0 || point_claimed[static_cast<std::size_t>(p.point)]) continue;
    slot = p.point;
    point_claimed[static_cast<std::size_t>(p.point)] = true;
  }
  for (std::size_t s = 0; s < stars_.size(); ++s) {
    if (!recent(stars_[s])) continue;
    // The prediction says which points are the star's; the edges say which marker each one is (a
    // star turning fast can put a marker nearest another's prediction).
    std::vector<int> mine;
    for (const int p : assigned[s]) {
      if (p >= 0) mine.push_back(p);
    }
    std::optional<IdentifiedStar> fit;
    if (mine.size() >= 3)
      fit = fit_star(library_, static_cast<int>(s), best_correspondence(library_, static_cast<int>(s), mine, points), points);
    // One of four points may be wrong (two markers merged into one point): the best three.
    for (std::size_t drop = 0; !fit && mine.size() == 4 && drop < 4; ++drop) {
      std::vector<int> three = mine;
      three.erase(three.begin() + static_cast<std::ptrdiff_t>(drop));
      auto f = fit_star(library_, static_cast<int>(s), best_correspondence(library_, static_cast<int>(s), three, points), points);
      if (f && (!fit || f->rms_m < fit->rms_m)) fit = f;
    }
    if (!fit) continue;
    // A fit turned far from the prediction took the wrong markers for the right ones.
    if (!near_prediction(stars_[s], predicted[s], fit->world_from_star, time_s)) continue;
    accept(stars_[s], *fit, time_s);
    updated[s] = true;
    for (const int p : fit->point) {
      if (p >= 0) taken[static_cast<std::size_t>(p)] = true;
    }
  }

  // 2. Identification from scratch on the points left, for the stars not yet found.
  std::vector<Eigen::Vector3d> rest;
  std::vector<int> rest_index;
  for (std::size_t q = 0; q < n; ++q) {
    if (taken[q]) continue;
    rest.push_back(points[q]);
    rest_index.push_back(static_cast<int>(q));
  }
  for (IdentifiedStar found : identify_stars(library_, rest)) {
    const auto s = static_cast<std::size_t>(found.star);
    if (updated[s]) continue;
    // A label swap: these markers sit where another star, seen moments ago, is predicted.
    bool swap = false;
    for (std::size_t o = 0; o < stars_.size() && !swap; ++o) {
      swap = o != s && recent_and_confirmed(stars_[o]) && !updated[o] &&
             (predicted[o].translation - found.world_from_star.translation).norm() < settings_.swap_distance_m;
    }
    if (swap) continue;
    const TrackedStar& before = stars_[s];
    if (before.confirmed && before.frames_since_seen >= 0 &&
        (found.world_from_star.translation - before.world_from_star.translation).norm() >
            settings_.gate_m + settings_.max_speed_m_s * (time_s - before.last_seen_s)) {
      continue;
    }
    // Found afresh from three markers, not where and how it was heading: tentative again.
    if (found.markers_seen < 4 && !(recent(stars_[s]) && near_prediction(stars_[s], predicted[s], found.world_from_star, time_s))) {
      stars_[s].confirmed = false;
      stars_[s].frames_since_seen = -1;
    }
    for (int& p : found.point) {
      if (p >= 0) p = rest_index[static_cast<std::size_t>(p)];
    }
    accept(stars_[s], found, time_s);
    updated[s] = true;
  }

  for (std::size_t s = 0; s < stars_.size(); ++s) {
    if (updated[s]) continue;
    TrackedStar& t = stars_[s];
    t.markers_seen = 0;
    t.point = {-1, -1, -1, -1};
    t.frames_followed = 0;
    if (!t.confirmed) {
      t.frames_since_seen = -1;  // a tentative star lost is forgotten
    } else if (t.frames_since_seen >= 0) {
      ++t.frames_since_seen;
    }
  }
  return stars_;
}

}  // namespace rhot
