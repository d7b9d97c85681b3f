#include "tracking/plan/Placement.h"
#include "tracking/core/Solvers.h"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>

#include <limits>

namespace rhot {

namespace {

struct Candidate {
  Camera camera;
  bool ceiling = false;
  int place = 0;  // candidates at one place differ only in where they look; a place holds one camera
  // The grid points it sees, and its Fisher information J^T J (pixels^2 / m^2) at each: xx, xy,
  // xz, yy, yz, zz.
  std::vector<int> points;
  std::vector<std::array<double, 6>> info;
};

// What the cameras chosen so far give one grid point.
struct PointState {
  int views = 0;
  std::array<double, 6> info{0, 0, 0, 0, 0, 0};
  double bound_mm = 0.0;  // with the chosen cameras (Search::bound_mm), kept by Search::apply
  double score = 0.0;     // Search::score, kept by Search::apply (no views: 0)
};

class Search {
 public:
  Search(std::vector<Candidate> candidates, std::size_t points, int min_views, double sigma_px, double ref_mm)
      : candidates_(std::move(candidates)), state_(points), k_(min_views), sigma_px_(sigma_px), ref_mm_(ref_mm) {}

  std::size_t size() const { return candidates_.size(); }
  std::size_t places() const {
    std::vector<int> all;
    for (const Candidate& c : candidates_) all.push_back(c.place);
    std::sort(all.begin(), all.end());
    return static_cast<std::size_t>(std::unique(all.begin(), all.end()) - all.begin());
  }
  const Candidate& candidate(std::size_t c) const { return candidates_[c]; }
  const std::vector<std::size_t>& chosen() const { return chosen_; }

  // The score's change were candidate c added (sign +1) or removed (-1).
  double delta(std::size_t c, int sign) const {
    const Candidate& cand = candidates_[c];
    double d = 0.0;
    for (std::size_t n = 0; n < cand.points.size(); ++n) {
      const PointState& now = state_[static_cast<std::size_t>(cand.points[n])];
      PointState then = now;
      then.views += sign;
      for (std::size_t e = 0; e < 6; ++e) then.info[e] += sign * cand.info[n][e];
      d += score(then) - now.score;
    }
    return d;
  }
  void add(std::size_t c) {
    apply(c, +1);
    chosen_.push_back(c);
  }
  void remove_at(std::size_t slot) {
    apply(chosen_[slot], -1);
    chosen_.erase(chosen_.begin() + static_cast<std::ptrdiff_t>(slot));
  }
  // A candidate whose place a chosen camera holds already.
  bool is_taken(std::size_t c) const {
    return std::any_of(chosen_.begin(), chosen_.end(), [&](std::size_t k) { return candidates_[k].place == candidates_[c].place; });
  }

  // The coverage and worst point of the chosen set: points seen by K cameras or more, by two or
  // more, and the largest predicted 95 % bound (Coverage.h's predicted_max_mm) over the points
  // seen by two or more.
  struct Worst {
    int k_seen = 0;
    int two_seen = 0;
    double max_mm = 0.0;
    // Lower, with as many points seen by two cameras (a count, not the same points), and at least
    // `k_floor` seen by K.
    bool better_than(const Worst& o, int k_floor) const {
      return k_seen >= k_floor && two_seen >= o.two_seen && max_mm < o.max_mm * (1.0 - 1e-6);
    }
  };
  Worst worst(std::size_t* at = nullptr) const {
    Worst w;
    for (std::size_t i = 0; i < state_.size(); ++i) {
      const PointState& p = state_[i];
      w.k_seen += p.views >= k_ ? 1 : 0;
      if (p.views < 2) continue;
      ++w.two_seen;
      if (p.bound_mm > w.max_mm || (at && *at >= state_.size())) {
        w.max_mm = std::max(w.max_mm, p.bound_mm);
        if (at) *at = i;
      }
    }
    return w;
  }
  // worst() were candidate c added, without adding it: `now` is worst() and `by_bound` is
  // seen_twice_by_bound() of the current state. Only c's own points change; the largest bound
  // among the others is the first point in `by_bound` that c does not see.
  Worst worst_with(std::size_t c, const Worst& now, const std::vector<int>& by_bound) const {
    const Candidate& cand = candidates_[c];
    Worst w{now.k_seen, now.two_seen, 0.0};
    for (std::size_t n = 0; n < cand.points.size(); ++n) {
      PointState then = state_[static_cast<std::size_t>(cand.points[n])];
      then.views += 1;
      w.k_seen += then.views == k_ ? 1 : 0;
      w.two_seen += then.views == 2 ? 1 : 0;
      if (then.views < 2) continue;
      for (std::size_t e = 0; e < 6; ++e) then.info[e] += cand.info[n][e];
      w.max_mm = std::max(w.max_mm, bound_mm(then));
    }
    for (const int p : by_bound) {
      if (std::binary_search(cand.points.begin(), cand.points.end(), p)) continue;
      w.max_mm = std::max(w.max_mm, state_[static_cast<std::size_t>(p)].bound_mm);
      break;
    }
    return w;
  }
  // The points seen by two chosen cameras or more, largest bound first.
  std::vector<int> seen_twice_by_bound() const {
    std::vector<int> out;
    for (std::size_t i = 0; i < state_.size(); ++i) {
      if (state_[i].views >= 2) out.push_back(static_cast<int>(i));
    }
    std::sort(out.begin(), out.end(),
              [&](int a, int b) { return state_[static_cast<std::size_t>(a)].bound_mm > state_[static_cast<std::size_t>(b)].bound_mm; });
    return out;
  }
  // Swaps the chosen camera in `slot` for the candidate that lowers the worst point most without
  // losing coverage; false when none does.
  bool lower_worst(std::size_t slot, int k_floor) {
    const Worst now = worst();
    const std::size_t was = chosen_[slot];
    remove_at(slot);
    // Without it, the worst point: only a candidate that sees it can bring the maximum below
    // `now`, and only if it lowers that point's bound below it.
    std::size_t at = state_.size();
    const Worst without = worst(&at);
    const std::vector<int> by_bound = seen_twice_by_bound();
    std::size_t best = was;
    Worst best_worst = now;
    for (std::size_t c = 0; c < candidates_.size(); ++c) {
      if (c == was || is_taken(c) || at >= state_.size()) continue;
      const Candidate& cand = candidates_[c];
      const auto hit = std::lower_bound(cand.points.begin(), cand.points.end(), static_cast<int>(at));
      if (hit == cand.points.end() || *hit != static_cast<int>(at)) continue;
      PointState there = state_[at];
      there.views += 1;
      for (std::size_t e = 0; e < 6; ++e) there.info[e] += cand.info[static_cast<std::size_t>(hit - cand.points.begin())][e];
      if (there.views >= 2 && !(bound_mm(there) < best_worst.max_mm)) continue;
      const Worst w = worst_with(c, without, by_bound);
      if (w.better_than(best_worst, k_floor)) {
        best = c;
        best_worst = w;
      }
    }
    apply(best, +1);
    chosen_.insert(chosen_.begin() + static_cast<std::ptrdiff_t>(slot), best);
    return best != was;
  }

  // The best candidate not chosen and its gain; nothing when every candidate is chosen.
  std::pair<std::size_t, double> best_addition() const {
    std::size_t best = candidates_.size();
    double gain = -std::numeric_limits<double>::infinity();
    for (std::size_t c = 0; c < candidates_.size(); ++c) {
      if (is_taken(c)) continue;
      const double d = delta(c, +1);
      if (d > gain) {
        gain = d;
        best = c;
      }
    }
    return {best, gain};
  }

 private:
  void apply(std::size_t c, int sign) {
    const Candidate& cand = candidates_[c];
    for (std::size_t n = 0; n < cand.points.size(); ++n) {
      PointState& s = state_[static_cast<std::size_t>(cand.points[n])];
      s.views += sign;
      for (std::size_t e = 0; e < 6; ++e) s.info[e] += sign * cand.info[n][e];
      s.bound_mm = s.views >= 2 ? bound_mm(s) : 0.0;
      s.score = score(s);
    }
  }
  // 2.7955 sqrt(largest eigenvalue of C), C = sigma^2 F^-1, in mm; infinite for parallel rays.
  double bound_mm(const PointState& s) const {
    const std::array<double, 3> values = symmetric_eigenvalues_packed(s.info);
    const double smallest = values[0];
    if (!(smallest > 1e-12 * values[2])) return std::numeric_limits<double>::infinity();
    return 2.7955 * 1000.0 * sigma_px_ / std::sqrt(smallest);
  }
  double score(const PointState& s) const {
    double out = static_cast<double>(std::min(s.views, k_)) / k_;
    if (s.views < 2) return out;
    out += 0.5;
    // rms error = sigma sqrt(trace(F^-1)), F the summed J^T J (symmetric 3 x 3).
    const auto& f = s.info;
    const double c00 = f[3] * f[5] - f[4] * f[4], c11 = f[0] * f[5] - f[2] * f[2], c22 = f[0] * f[3] - f[1] * f[1];
    const double det = f[0] * c00 - f[1] * (f[1] * f[5] - f[2] * f[4]) + f[2] * (f[1] * f[4] - f[2] * f[3]);
    // Rays (nearly) parallel: as bad as an error a thousand times the reference.
    const double rms_mm = det > 0.0 ? 1000.0 * sigma_px_ * std::sqrt(std::max((c00 + c11 + c22) / det, 0.0)) : 1000.0 * ref_mm_;
    return out - 0.1 * std::log1p(rms_mm / ref_mm_);
  }

  std::vector<Candidate> candidates_;
  std::vector<PointState> state_;
  std::vector<std::size_t> chosen_;
  int k_;
  double sigma_px_;
  double ref_mm_;
};

// Points where candidates aim: the volume's centre and its four quarters' centres (at mid height).
std::vector<Eigen::Vector3d> aim_points(const TrackingVolume& v) {
  std::vector<Eigen::Vector3d> out{v.centre_m};
  for (const double sx : {-0.25, 0.25}) {
    for (const double sz : {-0.25, 0.25}) out.push_back(v.centre_m + Eigen::Vector3d(sx * v.size_m.x(), 0.0, sz * v.size_m.z()));
  }
  return out;
}

std::vector<Candidate> candidate_poses(const Camera& model, const TrackingVolume& v, const PlanSettings& s, double ceiling) {
  std::vector<Candidate> out;
  // Places by position: a wall's top row can meet the ceiling grid's edge, and one place holds one
  // camera whichever mount offers it.
  std::vector<Eigen::Vector3d> places;
  const auto place_of = [&](const Eigen::Vector3d& position) {
    for (std::size_t p = 0; p < places.size(); ++p) {
      if ((places[p] - position).norm() < 1e-6) return static_cast<int>(p);
    }
    places.push_back(position);
    return static_cast<int>(places.size()) - 1;
  };
  const auto add = [&](const Eigen::Vector3d& position, const Eigen::Vector3d& target, bool ceiling_mount) {
    Candidate c;
    c.place = place_of(position);
    c.camera.intrinsics = model.intrinsics;
    c.camera.cam_from_world = cam_from_world_look_at(position, target);
    c.ceiling = ceiling_mount;
    out.push_back(std::move(c));
  };
  const double half_x = 0.5 * v.size_m.x() + s.wall_margin_m, half_z = 0.5 * v.size_m.z() + s.wall_margin_m;
  const std::vector<Eigen::Vector3d> aims = aim_points(v);
  if (s.mount != Mount::kWalls) {
    constexpr int kAcross = 9;
    for (int i = 0; i < kAcross; ++i) {
      for (int j = 0; j < kAcross; ++j) {
        const Eigen::Vector3d at(v.centre_m.x() + half_x * (2.0 * i / (kAcross - 1) - 1.0), ceiling,
                                 v.centre_m.z() + half_z * (2.0 * j / (kAcross - 1) - 1.0));
        add(at, {at.x(), v.centre_m.y() - 0.5 * v.size_m.y(), at.z()}, true);  // straight down
        for (const Eigen::Vector3d& aim : aims) {
          // Tilted towards an aim point unless that is all but straight down already.
          if (Eigen::Vector2d(aim.x() - at.x(), aim.z() - at.z()).norm() > 0.15 * (at.y() - aim.y())) add(at, aim, true);
        }
      }
    }
  }
  if (s.mount != Mount::kCeiling) {
    const double top = v.centre_m.y() + 0.5 * v.size_m.y();
    const double perimeter = 4.0 * (half_x + half_z);
    const int around = static_cast<int>(std::clamp(perimeter / 0.5, 16.0, 64.0));
    for (int n = 0; n < around; ++n) {
      // Walk the walls' rectangle at equal steps, corners included.
      double t = perimeter * n / around;
      Eigen::Vector3d at;
      if (t < 2.0 * half_x) {
        at = {-half_x + t, 0.0, -half_z};
      } else if ((t -= 2.0 * half_x) < 2.0 * half_z) {
        at = {half_x, 0.0, -half_z + t};
      } else if ((t -= 2.0 * half_z) < 2.0 * half_x) {
        at = {half_x - t, 0.0, half_z};
      } else {
        t -= 2.0 * half_x;
        at = {-half_x, 0.0, half_z - t};
      }
      at += Eigen::Vector3d(v.centre_m.x(), 0.0, v.centre_m.z());
      for (const double h : {0.5, 1.0}) {
        at.y() = top + h * (ceiling - top);
        for (const Eigen::Vector3d& aim : aims) add(at, aim, false);
      }
    }
  }
  return out;
}

// The settings, camera model and volume checked: the ceiling mount's height, or what is wrong.
std::expected<double, std::string> checked_ceiling(const Camera& model, const TrackingVolume& volume, const PlanSettings& s) {
  const CameraIntrinsics& k = model.intrinsics;
  if (k.width_px <= 0 || k.height_px <= 0 || !(k.fx > 0.0) || !(k.fy > 0.0) || !std::isfinite(k.fx) || !std::isfinite(k.fy)) {
    return std::unexpected(std::string("camera model: needs a positive image size and focal length"));
  }
  if (!volume.size_m.allFinite() || !(volume.size_m.minCoeff() > 0.0)) {
    return std::unexpected(std::string("volume: every side must be positive and finite"));
  }
  if (volume.size_m.maxCoeff() > 1000.0) return std::unexpected(std::string("volume: sides of up to 1000 m"));
  if (!volume.centre_m.allFinite() || volume.centre_m.cwiseAbs().maxCoeff() > 1e4) {
    return std::unexpected(std::string("volume: its centre must be finite and within 10 km"));
  }
  const double bottom = volume.centre_m.y() - 0.5 * volume.size_m.y(), top = volume.centre_m.y() + 0.5 * volume.size_m.y();
  if (bottom < -1e-9) return std::unexpected(fmt::format("volume: reaches {:.2f} m below the floor (Y = 0)", -bottom));
  const double ceiling = s.ceiling_m > 0.0 ? s.ceiling_m : top + 1.0;
  if (!std::isfinite(ceiling) || ceiling <= top) {
    return std::unexpected(fmt::format("ceiling: {:.2f} m is not above the volume's top ({:.2f} m)", ceiling, top));
  }
  if (s.min_views < 1) return std::unexpected(std::string("min views: at least 1"));
  if (!(s.sigma_px > 0.0) || !std::isfinite(s.sigma_px)) return std::unexpected(std::string("sigma: must be positive"));
  if (!(s.wall_margin_m >= 0.0) || !std::isfinite(s.wall_margin_m)) return std::unexpected(std::string("wall margin: must be 0 or more"));
  if (s.cameras < 0 || s.cameras > 256) return std::unexpected(std::string("cameras: at most 256 (0: as few as reach the maximum error)"));
  if (s.cameras == 0 && s.max_cameras < s.min_views) return std::unexpected(std::string("max cameras: fewer than min views"));
  if (s.cameras == 0 && !(s.max_error_mm > 0.0 && std::isfinite(s.max_error_mm))) {
    return std::unexpected(std::string("give a number of cameras or a maximum error"));
  }
  return ceiling;
}

// The coarse grid the search scores on: a lattice from face to face of the volume, its corners
// and edges included (the worst errors are there), about grid_points points.
std::expected<std::vector<Eigen::Vector3d>, std::string> coarse_grid(const TrackingVolume& volume, int grid_points) {
  if (grid_points < 8 || grid_points > 1000000) return std::unexpected(std::string("grid points: from 8 to 1,000,000"));
  const double spacing = std::cbrt(volume.size_m.prod() / grid_points);
  const Eigen::Vector3d cells_d = (volume.size_m / spacing).array().round().max(1.0);
  if ((cells_d.array() + 1.0).prod() > 4e6) {
    return std::unexpected(std::string("volume: too thin for its length and width (over 4 million grid points): plan it in parts"));
  }
  const Eigen::Vector3i cells = cells_d.cast<int>();
  const Eigen::Vector3d low = volume.centre_m - 0.5 * volume.size_m;
  const Eigen::Vector3d step = volume.size_m.cwiseQuotient(cells.cast<double>());
  std::vector<Eigen::Vector3d> points;
  for (int y = 0; y <= cells.y(); ++y) {
    for (int z = 0; z <= cells.z(); ++z) {
      for (int x = 0; x <= cells.x(); ++x) points.push_back(low + step.cwiseProduct(Eigen::Vector3d(x, y, z)));
    }
  }
  return points;
}

// Each candidate's grid points in its image, and its Fisher information at each.
void add_views(std::vector<Candidate>& candidates, const std::vector<Eigen::Vector3d>& points) {
  Eigen::Matrix<double, 2, 3> j;
  for (Candidate& c : candidates) {
    const CameraProjection projection(c.camera);
    c.points.reserve(points.size());
    c.info.reserve(points.size());
    for (std::size_t p = 0; p < points.size(); ++p) {
      const auto pixel = projection.project(points[p], j);
      if (!pixel || !projection.in_image(*pixel)) continue;
      // J^T J's upper triangle, written out (Eigen's product is not inlined at -O1).
      const auto f = [&](int a, int b) { return j(0, a) * j(0, b) + j(1, a) * j(1, b); };
      c.points.push_back(static_cast<int>(p));
      c.info.push_back({f(0, 0), f(0, 1), f(0, 2), f(1, 1), f(1, 2), f(2, 2)});
    }
    c.points.shrink_to_fit();
    c.info.shrink_to_fit();
  }
}

// The chosen cameras as a rig, named "ceiling-N" / "wall-N", with the volume.
CameraRig rig_of(const Search& search, const TrackingVolume& volume) {
  CameraRig rig;
  rig.name = "planned";
  rig.volume = volume;
  int ceiling_n = 0, wall_n = 0;
  for (const std::size_t c : search.chosen()) {
    Camera cam = search.candidate(c).camera;
    cam.name = search.candidate(c).ceiling ? fmt::format("ceiling-{}", ceiling_n++) : fmt::format("wall-{}", wall_n++);
    rig.cameras.push_back(std::move(cam));
  }
  return rig;
}

// Each chosen camera in turn swapped for the candidate that adds most to the score without it,
// while that is more than it adds; passes until none is swapped. Returns the swaps.
int improve_score(Search& search, const PlanProgress& progress) {
  int swaps = 0;
  for (int pass = 0; pass < 6; ++pass) {
    int swapped = 0;
    const std::vector<std::size_t> snapshot = search.chosen();
    for (const std::size_t was : snapshot) {
      const auto slot = static_cast<std::size_t>(std::find(search.chosen().begin(), search.chosen().end(), was) - search.chosen().begin());
      const double keep = -search.delta(was, -1);  // what it adds to the others
      search.remove_at(slot);
      const auto [best, gain] = search.best_addition();
      if (best < search.size() && best != was && gain > keep + 1e-9) {
        search.add(best);
        ++swapped;
      } else {
        search.add(was);
      }
    }
    swaps += swapped;
    if (progress) progress(fmt::format("improving: pass {}, {} swaps", pass + 1, swapped));
    if (swapped == 0) break;
  }
  return swaps;
}

// Then the worst point: each camera in turn moved where the largest predicted error falls most,
// keeping as many points seen by two as before, and at least k_floor points seen by K. Returns
// the moves.
int lower_worst_error(Search& search, int k_floor, const PlanProgress& progress) {
  int moves = 0;
  for (int pass = 0; pass < 6; ++pass) {
    int moved = 0;
    for (std::size_t slot = 0; slot < search.chosen().size(); ++slot) moved += search.lower_worst(slot, k_floor) ? 1 : 0;
    moves += moved;
    if (progress) progress(fmt::format("lowering the worst error: pass {}, {} moves, {:.2f} mm", pass + 1, moved, search.worst().max_mm));
    if (moved == 0) break;
  }
  return moves;
}

// PlanSettings::cameras cameras: placed greedily, then improved.
std::expected<RigPlan, std::string> place_cameras(Search& search, const TrackingVolume& volume, const PlanSettings& s,
                                                  std::size_t grid_size, const PlanProgress& progress, RigPlan plan) {
  if (static_cast<std::size_t>(s.cameras) > search.places()) {
    return std::unexpected(
        fmt::format("cameras: {} asked for, but only {} places on the chosen mounts see the volume", s.cameras, search.places()));
  }
  for (int n = 0; n < s.cameras; ++n) {
    search.add(search.best_addition().first);
    if (progress) progress(fmt::format("placed {} of {} cameras", n + 1, s.cameras));
  }
  plan.swaps = improve_score(search, progress);
  // Coverage by K may fall by at most 1 % of the volume for a lower worst error.
  const int one_percent = static_cast<int>(0.01 * static_cast<double>(grid_size));
  plan.swaps += lower_worst_error(search, search.worst().k_seen - one_percent, progress);
  plan.rig = rig_of(search, volume);
  return plan;
}

// As few as reach the target: at each count, the cameras improved as above (keeping 99 % of
// the volume seen by K once it is), then the rig evaluated on the fine grid.
std::expected<RigPlan, std::string> place_for_error(Search& search, const TrackingVolume& volume, const PlanSettings& s,
                                                    std::size_t grid_size, const PlanProgress& progress, RigPlan plan) {
  const int one_percent = static_cast<int>(0.01 * static_cast<double>(grid_size));
  CoverageSettings fine;
  fine.sigma_px = s.sigma_px;
  fine.samples_per_point = 1;
  double best_error = std::numeric_limits<double>::infinity(), best_cover = 0.0;
  const int most = std::min<int>(s.max_cameras, static_cast<int>(search.places()));
  const int views_needed = std::max(s.min_views, 2);  // an error is predicted only where two see
  for (int n = 1; n <= most; ++n) {
    search.add(search.best_addition().first);
    if (n < s.min_views) continue;
    const int need = static_cast<int>(std::ceil(0.99 * static_cast<double>(grid_size)));
    if (search.worst().k_seen >= need)
      plan.swaps += lower_worst_error(search, std::max(need, search.worst().k_seen - one_percent), progress);
    const auto report = evaluate_coverage(rig_of(search, volume), volume, fine);
    if (!report) return std::unexpected(report.error());
    const double cover =
        static_cast<double>(std::count_if(report->views.begin(), report->views.end(), [&](int v) { return v >= s.min_views; })) /
        static_cast<double>(report->views.size());
    if (progress)
      progress(fmt::format("{} cameras: {:.1f} % seen by {} or more, worst predicted error {:.2f} mm", n, 100.0 * cover, views_needed,
                           report->predicted_max_mm));
    if (cover >= 0.99 && report->predicted_max_mm <= s.max_error_mm) {
      plan.rig = rig_of(search, volume);
      return plan;
    }
    if (cover >= 0.99) best_error = std::min(best_error, report->predicted_max_mm);
    best_cover = std::max(best_cover, cover);
  }
  if (best_cover < 0.99) {
    return std::unexpected(
        fmt::format("max error: {:.2f} mm cannot be reached: {} cameras of this model see at most {:.1f} % of the volume with {} views",
                    s.max_error_mm, most, 100.0 * best_cover, views_needed));
  }
  return std::unexpected(fmt::format("max error: {:.2f} mm cannot be reached with up to {} cameras of this model (the best: {:.2f} mm)",
                                     s.max_error_mm, most, best_error));
}

}  // namespace

std::expected<RigPlan, std::string> plan_rig(const Camera& model, const TrackingVolume& volume, const PlanSettings& s,
                                             const PlanProgress& progress) {
  const auto ceiling = checked_ceiling(model, volume, s);
  if (!ceiling) return std::unexpected(ceiling.error());
  const auto points = coarse_grid(volume, s.grid_points);
  if (!points) return std::unexpected(points.error());

  std::vector<Candidate> candidates = candidate_poses(model, volume, s, *ceiling);
  const auto considered = static_cast<int>(candidates.size());
  add_views(candidates, *points);
  std::erase_if(candidates, [](const Candidate& c) { return c.points.empty(); });
  if (candidates.empty()) {
    return std::unexpected(std::string("volume: no camera position on the chosen mounts sees any of it (camera model or ceiling?)"));
  }
  if (progress) progress(fmt::format("{} camera poses that see the volume, {} grid points", candidates.size(), points->size()));

  // The error scale: one pixel's noise at the volume's size, seen by one camera.
  const CameraIntrinsics& k = model.intrinsics;
  const double ref_mm = 1000.0 * s.sigma_px * volume.size_m.norm() / (0.5 * (k.fx + k.fy));
  Search search(std::move(candidates), points->size(), s.min_views, s.sigma_px, ref_mm);

  RigPlan plan;
  plan.candidates = considered;
  if (s.cameras > 0) {
    return place_cameras(search, volume, s, points->size(), progress, std::move(plan));
  }
  return place_for_error(search, volume, s, points->size(), progress, std::move(plan));
}

}  // namespace rhot
