#include "tracking/rigid/StarTracker.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>

#include <Eigen/Geometry>

#include "base/Capacity.h"
#include "tracking/rigid/RigidFit.h"

namespace rhot {

StarTracker::StarTracker(StarLibrary library, StarTrackerSettings settings) : library_(std::move(library)), settings_(settings) {
  filters_.assign(library_.stars().size(), PoseKalman(settings_.filter));
  refused_.assign(library_.stars().size(), 0);
  for (std::size_t s = 0; s < library_.stars().size(); ++s) {
    TrackedStar t;
    t.star = static_cast<int>(s);
    t.id = library_.stars()[s].id;
    stars_.push_back(t);
    const auto& markers = library_.stars()[s].markers_m;
    const Eigen::Vector3d centre = 0.25 * (markers[0] + markers[1] + markers[2] + markers[3]);
    double sum = 0.0;
    for (const Eigen::Vector3d& m : markers) sum += (m - centre).squaredNorm();
    spread_m_.push_back(std::max(std::sqrt(sum / 4.0), 1e-3));
  }
  // Room for the pairs of a frame's points and stars' markers (each grows, doubling, only past it),
  // and for the constellations weighed at once (kCandidatesRoom, each with every star's readings).
  scratch_.pairings.reserve(64 * library_.stars().size() + 64);
  candidates_.resize(kCandidatesRoom);
  for (Candidate& c : candidates_) c.readings.reserve(kReadingsPerStar * library_.stars().size());
}

void StarTracker::set_motion(int star, const PoseKalmanSettings& motion) {
  if (star >= 0 && static_cast<std::size_t>(star) < filters_.size()) filters_[static_cast<std::size_t>(star)] = PoseKalman(motion);
}

namespace {

// The fitted points' mean standard deviation.
double mean_sigma(const IdentifiedStar& fit, const StarPoints& points) {
  double sum = 0.0;
  int n = 0;
  for (const int p : fit.point) {
    if (p < 0) continue;
    sum += points.sigma(static_cast<std::size_t>(p));
    ++n;
  }
  return n > 0 ? sum / n : points.fallback_sigma_m;
}

}  // namespace

Rigid3d StarTracker::predict(const TrackedStar& s, double time_s) const {
  const double dt = time_s - s.last_seen_s;
  Rigid3d p = s.world_from_star;
  p.translation += s.velocity_m_s * dt;
  const Eigen::Vector3d turn = s.angular_velocity_rad_s * dt;
  if (turn.norm() > 1e-12) p.rotation = (Eigen::Quaterniond(Eigen::AngleAxisd(turn.norm(), turn.normalized())) * p.rotation).normalized();
  return p;
}

bool StarTracker::near_prediction(const TrackedStar& s, const Rigid3d& predicted, const Rigid3d& fitted, double time_s,
                                  double sigma_m) const {
  const double turned = Eigen::AngleAxisd(fitted.rotation * predicted.rotation.conjugate()).angle();
  // Noisy points turn a small star's fit: by about sigma over the markers' spread from their centre.
  const double noise_rad = settings_.gate_sigmas * sigma_m / spread_m_[static_cast<std::size_t>(s.star)];
  return (fitted.translation - predicted.translation).norm() < settings_.swap_distance_m &&
         turned <= settings_.turn_gate_rad + noise_rad + settings_.turn_rate_rad_s * (time_s - s.last_seen_s);
}

bool StarTracker::accept(TrackedStar& s, const IdentifiedStar& fit, double time_s, const StarPoints& points,
                         const std::optional<StarMotion>& start) {
  if (!filter(s, fit, time_s, points, start)) return false;
  s.measured = fit.world_from_star;
  s.rms_m = fit.rms_m;
  s.markers_seen = fit.markers_seen;
  s.point = fit.point;
  s.frames_followed = s.frames_since_seen == 0 ? s.frames_followed + 1 : 1;
  s.confirmed = s.confirmed || fit.markers_seen == 4 || s.frames_followed >= settings_.confirm_frames;
  s.frames_since_seen = 0;
  s.last_seen_s = time_s;
  return true;
}

bool StarTracker::filter(TrackedStar& s, const IdentifiedStar& fit, double time_s, const StarPoints& points,
                         const std::optional<StarMotion>& start) {
  PoseKalman& f = filters_[static_cast<std::size_t>(s.star)];
  int& refused = refused_[static_cast<std::size_t>(s.star)];
  std::array<Eigen::Vector3d, 4> model;
  std::array<double, 4> sigma{};
  std::size_t n = 0;
  for (std::size_t m = 0; m < 4; ++m) {
    if (fit.point[m] < 0) continue;
    model[n] = library_.stars()[static_cast<std::size_t>(s.star)].markers_m[m];
    sigma[n++] = points.sigma(static_cast<std::size_t>(fit.point[m]));
  }
  const Matrix6d measured = rigid_fit_covariance(fit.world_from_star, std::span(model.data(), n), std::span(sigma.data(), n));
  if (!measured.allFinite() || !fit.world_from_star.is_finite()) return false;  // a fit that measures nothing
  // A star followed until now: a fit its filter finds impossible is refused, up to refuse_frames
  // in a row (the star did what the model does not foresee: it starts again from the fit).
  // The usual case, a followed star's fit within the gate, is the filter's update itself.
  const bool followed = f.started() && recent(s) && s.confirmed;
  bool refuse = false;
  bool updated = false;
  if (followed && start) {
    refuse = f.mahalanobis2(time_s, fit.world_from_star, measured) > settings_.filter_gate_chi2;
  } else if (followed) {
    // Refused as mahalanobis2 would (a failed factorisation: infinity); a fit within the gate that
    // the filter could not fold in (non-finite) leaves it as it was.
    refuse = f.update(time_s, fit.world_from_star, measured, settings_.filter_gate_chi2).mahalanobis2 > settings_.filter_gate_chi2;
    updated = !refuse;
  }
  if (refuse && ++refused < settings_.refuse_frames) return false;
  if (!updated) {
    const StarMotion motion = start ? *start : followed ? StarMotion{f.velocity_m_s(), f.angular_velocity_rad_s()} : StarMotion{};
    f.reset(time_s, fit.world_from_star, measured, motion.velocity_m_s, motion.angular_velocity_rad_s);
  }
  refused = 0;
  s.world_from_star = f.pose();
  s.covariance = f.pose_covariance();
  s.velocity_m_s = f.velocity_m_s();
  s.angular_velocity_rad_s = f.angular_velocity_rad_s();
  s.certain = settings_.report_sigmas * largest_sigma(s.covariance.topLeftCorner<3, 3>()) <= settings_.report_position_m &&
              settings_.report_sigmas * largest_sigma(s.covariance.bottomRightCorner<3, 3>()) <= settings_.report_rotation_rad;
  return true;
}

void StarTracker::start_candidate(const IdentifiedStar& found, const StarPoints& points, double time_s, Candidate& c) const {
  // A candidate of an earlier frame's storage, started afresh (its readings' room kept).
  c.motion = TrackedStar{};
  c.readings.clear();
  c.frames = 0;
  c.confidence = 0.0;
  c.slot_point = found.point;
  c.motion.star = found.star;
  c.motion.id = library_.stars()[static_cast<std::size_t>(found.star)].id;
  c.motion.world_from_star = found.world_from_star;
  c.motion.markers_seen = found.markers_seen;
  c.motion.point = found.point;
  c.motion.frames_since_seen = 0;
  c.motion.last_seen_s = time_s;
  // Every star of the set, every correspondence of the slots to its markers.
  for (std::size_t star = 0; star < library_.stars().size(); ++star) {
    std::array<int, 4> marker{0, 1, 2, 3};
    do {
      c.readings.push_back({static_cast<int>(star), marker, 0.0});
    } while (std::next_permutation(marker.begin(), marker.end()));
  }
  weigh(c, points);
}

void StarTracker::weigh(Candidate& c, const StarPoints& points) const {
  for (Reading& r : c.readings) {
    for (const auto& e : kStarEdges) {
      const int a = c.slot_point[static_cast<std::size_t>(e[0])], b = c.slot_point[static_cast<std::size_t>(e[1])];
      if (a < 0 || b < 0) continue;
      const auto ua = static_cast<std::size_t>(a), ub = static_cast<std::size_t>(b);
      const double d = (points[ua] - points[ub]).norm() - library_.edge_m(r.star, r.slot_marker[static_cast<std::size_t>(e[0])],
                                                                          r.slot_marker[static_cast<std::size_t>(e[1])]);
      r.chi2 += d * d / (points.sigma(ua) * points.sigma(ua) + points.sigma(ub) * points.sigma(ub));
    }
  }
  std::sort(c.readings.begin(), c.readings.end(), [](const Reading& x, const Reading& y) { return x.chi2 < y.chi2; });
  const double best = c.readings.front().chi2;
  std::erase_if(c.readings, [&](const Reading& r) { return r.chi2 > best + settings_.forget_chi2; });
  double sum = 0.0;
  for (const Reading& r : c.readings) sum += std::exp(-0.5 * (r.chi2 - best));
  c.confidence = 1.0 / sum;
  ++c.frames;
  // The pose is the best reading's.
  const Reading& r = c.readings.front();
  std::array<int, 4> point{-1, -1, -1, -1};
  for (std::size_t slot = 0; slot < 4; ++slot) point[static_cast<std::size_t>(r.slot_marker[slot])] = c.slot_point[slot];
  std::array<Eigen::Vector3d, 4> model;
  std::array<Eigen::Vector3d, 4> measured;
  std::array<double, 4> weight{};
  std::size_t n = 0;
  for (std::size_t m = 0; m < 4; ++m) {
    if (point[m] < 0) continue;
    const auto q = static_cast<std::size_t>(point[m]);
    model[n] = library_.stars()[static_cast<std::size_t>(r.star)].markers_m[m];
    weight[n] = 1.0 / (points.sigma(q) * points.sigma(q));
    measured[n++] = points[q];
  }
  if (const auto fit = fit_rigid(std::span(model.data(), n), std::span(measured.data(), n), std::span(weight.data(), n))) {
    c.motion.star = r.star;
    c.motion.id = library_.stars()[static_cast<std::size_t>(r.star)].id;
    c.motion.world_from_star = fit->to_from_from;
    c.motion.rms_m = fit->rms_m;
    c.motion.point = point;
    c.motion.markers_seen = static_cast<int>(n);
  }
}

bool StarTracker::follow(Candidate& c, const StarPoints& points, std::vector<char>& taken, double time_s) {
  const Rigid3d predicted = predict(c.motion, time_s);
  const Reading& best = c.readings.front();
  const double since = time_s - c.motion.last_seen_s;
  std::vector<Pairing>& pairings = scratch_.pairings;
  pairings.clear();
  for (std::size_t slot = 0; slot < 4; ++slot) {
    const Eigen::Vector3d at =
        predicted * library_.stars()[static_cast<std::size_t>(best.star)].markers_m[static_cast<std::size_t>(best.slot_marker[slot])];
    for (std::size_t q = 0; q < points.size(); ++q) {
      if (taken[q]) continue;
      const double gate = settings_.gate_m + 0.5 * settings_.max_acceleration_m_s2 * since * since +
                          settings_.gate_sigmas * std::sqrt(3.0) * points.sigma(q);
      const double d = (points[q] - at).norm();
      if (d <= gate) pairings.push_back({d, -1, static_cast<int>(slot), static_cast<int>(q)});
    }
  }
  std::sort(pairings.begin(), pairings.end(), [](const Pairing& a, const Pairing& b) { return a.d < b.d; });
  std::array<int, 4> slot_point{-1, -1, -1, -1};
  std::array<int, 4> used{};
  std::size_t used_count = 0;
  for (const Pairing& p : pairings) {
    if (slot_point[static_cast<std::size_t>(p.marker)] >= 0 ||
        std::find(used.begin(), used.begin() + static_cast<std::ptrdiff_t>(used_count), p.point) !=
            used.begin() + static_cast<std::ptrdiff_t>(used_count))
      continue;
    slot_point[static_cast<std::size_t>(p.marker)] = p.point;
    used[used_count++] = p.point;
  }
  if (used_count < 3) return false;
  // The constellation must still be rigid as its best reading says.
  std::array<int, 4> point{-1, -1, -1, -1};
  for (std::size_t slot = 0; slot < 4; ++slot) point[static_cast<std::size_t>(best.slot_marker[slot])] = slot_point[slot];
  const auto fit = fit_star(library_, best.star, point, points);
  if (!fit) return false;
  const Rigid3d before = c.motion.world_from_star;
  c.slot_point = slot_point;
  weigh(c, points);
  if (since > 1e-6) {
    c.motion.velocity_m_s = (c.motion.world_from_star.translation - before.translation) / since;
    const Eigen::AngleAxisd turn(c.motion.world_from_star.rotation * before.rotation.conjugate());
    c.motion.angular_velocity_rad_s = turn.axis() * turn.angle() / since;
  }
  c.motion.last_seen_s = time_s;
  for (std::size_t u = 0; u < used_count; ++u) taken[static_cast<std::size_t>(used[u])] = 1;
  return true;
}

bool StarTracker::may_settle(const Candidate& c, const std::vector<char>& updated, const std::vector<Rigid3d>& predicted,
                             double time_s) const {
  const auto s = static_cast<std::size_t>(c.motion.star);
  if (updated[s] != 0) return false;  // the star is already somewhere else this frame
  if (c.confidence < settings_.min_confidence) return false;
  if (c.motion.markers_seen < 4 && c.frames < settings_.confirm_frames) return false;
  // A label swap: these markers sit where another star, seen moments ago, is predicted.
  for (std::size_t o = 0; o < stars_.size(); ++o) {
    if (o != s && recent_and_confirmed(stars_[o]) && updated[o] == 0 &&
        (predicted[o].translation - c.motion.world_from_star.translation).norm() < settings_.swap_distance_m) {
      return false;
    }
  }
  const TrackedStar& before = stars_[s];
  return !(before.confirmed && before.frames_since_seen >= 0 &&
           (c.motion.world_from_star.translation - before.world_from_star.translation).norm() >
               settings_.gate_m + settings_.max_speed_m_s * (time_s - before.last_seen_s));
}

// Recently seen stars: nearest points to their predicted markers, closest pairs first, refitted.
void StarTracker::follow_stars(double time_s, const StarPoints& points, std::vector<char>& taken, std::vector<char>& updated,
                               std::vector<Rigid3d>& predicted) {
  const std::size_t n = points.size();
  std::vector<Pairing>& pairings = scratch_.pairings;
  pairings.clear();
  for (std::size_t s = 0; s < stars_.size(); ++s) {
    if (!recent(stars_[s])) continue;
    predicted[s] = predict(stars_[s], time_s);
    const double since = time_s - stars_[s].last_seen_s;
    const double gate = settings_.gate_m + 0.5 * settings_.max_acceleration_m_s2 * since * since;
    for (int m = 0; m < 4; ++m) {
      const Eigen::Vector3d at = predicted[s] * library_.stars()[s].markers_m[static_cast<std::size_t>(m)];
      for (std::size_t q = 0; q < n; ++q) {
        const double d = (points[q] - at).norm();
        if (d <= gate + settings_.gate_sigmas * std::sqrt(3.0) * points.sigma(q))
          pairings.push_back({d, static_cast<int>(s), m, static_cast<int>(q)});
      }
    }
  }
  std::sort(pairings.begin(), pairings.end(), [](const Pairing& a, const Pairing& b) { return a.d < b.d; });
  // A point as near two stars' predicted markers as its own noise allows (two objects' markers
  // passing within millimetres) could be either's: neither takes it, and each is fitted from its
  // others.
  std::vector<int>& gated_star = scratch_.gated_star;
  std::vector<char>& contested = scratch_.contested;
  reserve_room(gated_star, n);
  reserve_room(contested, n);
  gated_star.assign(n, -1);
  contested.assign(n, 0);
  for (const Pairing& p : pairings) {
    if (p.d > settings_.gate_sigmas * std::sqrt(3.0) * points.sigma(static_cast<std::size_t>(p.point))) continue;
    int& first = gated_star[static_cast<std::size_t>(p.point)];
    if (first >= 0 && first != p.star) contested[static_cast<std::size_t>(p.point)] = 1;
    first = p.star;
  }
  // Nor does a fresh identification this frame (it would find one of the two in it).
  for (std::size_t q = 0; q < n; ++q)
    if (contested[q] != 0) taken[q] = 1;
  std::vector<std::array<int, 4>>& assigned = scratch_.assigned;
  std::vector<char>& point_claimed = scratch_.point_claimed;
  assigned.assign(stars_.size(), {-1, -1, -1, -1});
  reserve_room(point_claimed, n);
  point_claimed.assign(n, 0);
  for (const Pairing& p : pairings) {
    auto& slot = assigned[static_cast<std::size_t>(p.star)][static_cast<std::size_t>(p.marker)];
    if (slot >= 0 || point_claimed[static_cast<std::size_t>(p.point)] != 0 || contested[static_cast<std::size_t>(p.point)] != 0) continue;
    slot = p.point;
    point_claimed[static_cast<std::size_t>(p.point)] = 1;
  }
  for (std::size_t s = 0; s < stars_.size(); ++s) {
    if (!recent(stars_[s])) continue;
    // The prediction says which points are the star's; the edges say which marker each one is (a
    // star turning fast can put a marker nearest another's prediction).
    std::array<int, 4> mine_points{};
    std::size_t mine_count = 0;
    for (const int p : assigned[s]) {
      if (p >= 0) mine_points[mine_count++] = p;
    }
    const std::span<const int> mine(mine_points.data(), mine_count);
    std::optional<IdentifiedStar> fit;
    // First as predicted (under noise the edges alone may not tell two markers apart), then as the
    // edges say.
    if (mine.size() >= 3) fit = fit_star(library_, static_cast<int>(s), assigned[s], points);
    if (fit && !near_prediction(stars_[s], predicted[s], fit->world_from_star, time_s, mean_sigma(*fit, points))) fit.reset();
    if (!fit && mine.size() >= 3)
      fit = fit_star(library_, static_cast<int>(s), best_correspondence(library_, static_cast<int>(s), mine, points), points);
    // One of four points may be wrong (two markers merged into one point): the best three.
    for (std::size_t drop = 0; !fit && mine.size() == 4 && drop < 4; ++drop) {
      std::array<int, 3> three{};
      for (std::size_t k = 0, t = 0; k < 4; ++k) {
        if (k != drop) three[t++] = mine[k];
      }
      auto f = fit_star(library_, static_cast<int>(s), best_correspondence(library_, static_cast<int>(s), three, points), points);
      if (f && (!fit || f->chi2 < fit->chi2)) fit = f;
    }
    if (!fit) continue;
    // A fit turned far from the prediction took the wrong markers for the right ones; so did one
    // the star's filter finds impossible.
    if (!near_prediction(stars_[s], predicted[s], fit->world_from_star, time_s, mean_sigma(*fit, points))) continue;
    if (!accept(stars_[s], *fit, time_s, points)) continue;
    updated[s] = 1;
    for (const int p : fit->point) {
      if (p >= 0) taken[static_cast<std::size_t>(p)] = 1;
    }
  }
}

const std::vector<TrackedStar>& StarTracker::update(double time_s, std::span<const Eigen::Vector3d> positions,
                                                    std::span<const double> sigma_m) {
  const StarPoints points = star_points(library_, positions, sigma_m);
  const std::size_t n = points.size();
  std::vector<char>& taken = scratch_.taken;
  std::vector<char>& updated = scratch_.updated;
  std::vector<Rigid3d>& predicted = scratch_.predicted;
  reserve_room(taken, n);
  taken.assign(n, 0);
  updated.assign(stars_.size(), 0);
  predicted.assign(stars_.size(), Rigid3d{});

  // 1. Recently seen stars, followed to their predicted markers.
  follow_stars(time_s, points, taken, updated, predicted);

  // 2. Candidates: followed, weighed, and settled as a star once sure.
  const auto settle = [&](const Candidate& c) -> bool {
    const auto s = static_cast<std::size_t>(c.motion.star);
    IdentifiedStar fit;
    fit.star = c.motion.star;
    fit.world_from_star = c.motion.world_from_star;
    fit.rms_m = c.motion.rms_m;
    fit.point = c.motion.point;
    fit.markers_seen = c.motion.markers_seen;
    if (!accept(stars_[s], fit, time_s, points, StarMotion{c.motion.velocity_m_s, c.motion.angular_velocity_rad_s})) return false;
    stars_[s].confirmed = true;
    stars_[s].confidence = c.confidence;
    stars_[s].frames_followed = c.frames;
    updated[s] = 1;
    return true;
  };
  // The candidates kept, moved up in place (their readings' storage goes with them).
  std::size_t kept = 0;
  for (std::size_t k = 0; k < candidate_count_; ++k) {
    Candidate& c = candidates_[k];
    if (c.frames >= settings_.max_candidate_frames || !follow(c, points, taken, time_s)) continue;
    // A settled reading the star's filter refuses stays a candidate.
    if (may_settle(c, updated, predicted, time_s) && settle(c)) continue;
    if (kept != k) std::swap(candidates_[kept], c);
    ++kept;
  }
  candidate_count_ = kept;  // the others' storage is kept for new candidates

  // 3. Identification from scratch on the points left: each find a candidate.
  std::vector<Eigen::Vector3d>& rest = scratch_.rest;
  std::vector<double>& rest_sigma = scratch_.rest_sigma;
  std::vector<int>& rest_index = scratch_.rest_index;
  rest.clear();
  rest_sigma.clear();
  rest_index.clear();
  for (std::size_t q = 0; q < n; ++q) {
    if (taken[q] != 0) continue;
    rest.push_back(points[q]);
    rest_sigma.push_back(points.sigma(q));
    rest_index.push_back(static_cast<int>(q));
  }
  identify_stars(library_, star_points(library_, rest, rest_sigma), scratch_.identification, scratch_.found);
  for (IdentifiedStar found : scratch_.found) {
    for (int& p : found.point) {
      if (p >= 0) p = rest_index[static_cast<std::size_t>(p)];
    }
    const auto s = static_cast<std::size_t>(found.star);
    // A star seen moments ago found again where it was heading: itself, its identity known.
    if (updated[s] == 0 && recent_and_confirmed(stars_[s]) &&
        near_prediction(stars_[s], predicted[s], found.world_from_star, time_s, mean_sigma(found, points))) {
      if (accept(stars_[s], found, time_s, points)) updated[s] = 1;
      continue;
    }
    if (candidate_count_ == candidates_.size()) {
      // Room for more candidates at once, each with room for every reading of every star.
      const std::size_t from = candidates_.size();
      candidates_.resize(2 * from + 8);
      for (std::size_t k = from; k < candidates_.size(); ++k) candidates_[k].readings.reserve(kReadingsPerStar * library_.stars().size());
    }
    Candidate& c = candidates_[candidate_count_];
    start_candidate(found, points, time_s, c);
    if (!may_settle(c, updated, predicted, time_s) || !settle(c)) ++candidate_count_;
  }

  for (std::size_t s = 0; s < stars_.size(); ++s) {
    if (updated[s] != 0) continue;
    TrackedStar& t = stars_[s];
    t.markers_seen = 0;
    t.point = {-1, -1, -1, -1};
    t.frames_followed = 0;
    if (!t.confirmed) {
      t.frames_since_seen = -1;
    } else if (t.frames_since_seen >= 0) {
      ++t.frames_since_seen;
    }
  }
  return stars_;
}

}  // namespace rhot
