#include "tracking/rigid/StarIdentification.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <span>
#include <tuple>

#include "base/Capacity.h"
#include "tracking/rigid/RigidFit.h"

namespace rhot {

StarLibrary::StarLibrary(const StarSet& set, const StarIdentificationSettings& settings)
    : settings_(settings),
      tolerance_m_(settings.edge_tolerance_fraction * set.rules.variation_mm * 1e-3),
      check_m_(settings.edge_check_fraction * set.rules.variation_mm * 1e-3) {
  for (std::size_t s = 0; s < set.stars.size(); ++s) {
    Star star;
    star.id = set.stars[s].id;
    for (std::size_t m = 0; m < 4; ++m) star.markers_m[m] = set.stars[s].markers_mm[m] * 1e-3;
    std::array<double, 16> distances{};
    for (std::size_t a = 0; a < 4; ++a) {
      for (std::size_t b = 0; b < 4; ++b) distances[4 * a + b] = (star.markers_m[a] - star.markers_m[b]).norm();
    }
    edge_.push_back(distances);
    for (const auto& e : kStarEdges) {
      const double length = (star.markers_m[static_cast<std::size_t>(e[0])] - star.markers_m[static_cast<std::size_t>(e[1])]).norm();
      edge_lengths_.push_back(length);
      longest_m_ = std::max(longest_m_, length);
    }
    for (const auto& f : kStarFaces) {
      // Edge opposite each vertex, then sorted with its vertex.
      std::array<std::pair<double, int>, 3> opposite{};
      for (std::size_t k = 0; k < 3; ++k) {
        const auto& a = star.markers_m[static_cast<std::size_t>(f[(k + 1) % 3])];
        const auto& b = star.markers_m[static_cast<std::size_t>(f[(k + 2) % 3])];
        opposite[k] = {(a - b).norm(), f[k]};
      }
      std::sort(opposite.begin(), opposite.end());
      Face face;
      face.star = static_cast<int>(s);
      for (std::size_t k = 0; k < 3; ++k) {
        face.edges[k] = opposite[k].first;
        face.marker[k] = opposite[k].second;
      }
      faces_.push_back(face);
    }
    stars_.push_back(star);
  }
  std::sort(faces_.begin(), faces_.end(), [](const Face& a, const Face& b) { return a.edges[0] < b.edges[0]; });
  std::sort(edge_lengths_.begin(), edge_lengths_.end());
}

void StarLibrary::find_faces(const std::array<double, 3>& e, double tolerance_m, std::vector<const Face*>& out) const {
  out.clear();
  auto it = std::lower_bound(faces_.begin(), faces_.end(), e[0] - tolerance_m, [](const Face& f, double v) { return f.edges[0] < v; });
  for (; it != faces_.end() && it->edges[0] <= e[0] + tolerance_m; ++it) {
    if (std::abs(it->edges[1] - e[1]) <= tolerance_m && std::abs(it->edges[2] - e[2]) <= tolerance_m) out.push_back(&*it);
  }
}

bool StarLibrary::is_edge_length(double length_m, double tolerance_m) const {
  const auto it = std::lower_bound(edge_lengths_.begin(), edge_lengths_.end(), length_m - tolerance_m);
  return it != edge_lengths_.end() && *it <= length_m + tolerance_m;
}

double chi2_limit(int dof) {
  if (dof <= 0) return 0.0;
  // Wilson-Hilferty: (chi2 / k)^(1/3) is nearly normal with mean 1 - 2 / 9k, variance 2 / 9k.
  const double k = dof;
  const double z = 3.719;  // the normal's upper 1e-4 quantile
  const double c = 1.0 - 2.0 / (9.0 * k) + z * std::sqrt(2.0 / (9.0 * k));
  return k * c * c * c;
}

StarPoints star_points(const StarLibrary& library, std::span<const Eigen::Vector3d> points_world, std::span<const double> sigma_m) {
  return StarPoints{points_world, sigma_m, library.settings().point_sigma_m};
}

double edge_chi2(const StarLibrary& library, int star, const std::array<int, 4>& point, const StarPoints& points, int* edges) {
  double chi2 = 0.0;
  int count = 0;
  for (const auto& e : kStarEdges) {
    const int a = point[static_cast<std::size_t>(e[0])], b = point[static_cast<std::size_t>(e[1])];
    if (a < 0 || b < 0) continue;
    const auto ua = static_cast<std::size_t>(a), ub = static_cast<std::size_t>(b);
    const double measured = (points[ua] - points[ub]).norm();
    const double difference = measured - library.edge_m(star, e[0], e[1]);
    chi2 += difference * difference / (points.sigma(ua) * points.sigma(ua) + points.sigma(ub) * points.sigma(ub));
    ++count;
  }
  if (edges) *edges = count;
  return chi2;
}

namespace {

// Whether every edge between the seen markers is within the larger of the library's edge check and
// gate_sigmas standard deviations of the model's.
bool edges_agree(const StarLibrary& library, int star, const std::array<int, 4>& point, const StarPoints& points) {
  const double gate = library.settings().gate_sigmas;
  for (const auto& e : kStarEdges) {
    const int a = point[static_cast<std::size_t>(e[0])], b = point[static_cast<std::size_t>(e[1])];
    if (a < 0 || b < 0) continue;
    const auto ua = static_cast<std::size_t>(a), ub = static_cast<std::size_t>(b);
    const double difference = std::abs((points[ua] - points[ub]).norm() - library.edge_m(star, e[0], e[1]));
    const double sd = std::sqrt(points.sigma(ua) * points.sigma(ua) + points.sigma(ub) * points.sigma(ub));
    if (difference > std::max(library.edge_check_m(), gate * sd)) return false;
  }
  return true;
}

}  // namespace

std::array<int, 4> best_correspondence(const StarLibrary& library, int star, std::span<const int> point_indices, const StarPoints& points) {
  std::array<int, 4> best{-1, -1, -1, -1};
  if (point_indices.size() < 3 || point_indices.size() > 4) return best;
  std::array<int, 4> marker_of{0, 1, 2, 3};  // point k is marker marker_of[k]
  double best_chi2 = std::numeric_limits<double>::infinity();
  do {
    std::array<int, 4> point{-1, -1, -1, -1};
    for (std::size_t k = 0; k < point_indices.size(); ++k) point[static_cast<std::size_t>(marker_of[k])] = point_indices[k];
    const double chi2 = edge_chi2(library, star, point, points);
    if (chi2 < best_chi2) {
      best_chi2 = chi2;
      best = point;
    }
  } while (std::next_permutation(marker_of.begin(), marker_of.end()));
  return best;
}

std::optional<IdentifiedStar> fit_star(const StarLibrary& library, int star, const std::array<int, 4>& point, const StarPoints& points) {
  if (!edges_agree(library, star, point, points)) return std::nullopt;
  std::array<Eigen::Vector3d, 4> model;
  std::array<Eigen::Vector3d, 4> measured;
  std::array<double, 4> sigma{};
  std::size_t n = 0;
  const StarLibrary::Star& s = library.stars()[static_cast<std::size_t>(star)];
  for (std::size_t m = 0; m < 4; ++m) {
    if (point[m] < 0) continue;
    model[n] = s.markers_m[m];
    measured[n] = points[static_cast<std::size_t>(point[m])];
    sigma[n] = points.sigma(static_cast<std::size_t>(point[m]));
    ++n;
  }
  std::array<double, 4> weight{};
  for (std::size_t k = 0; k < n; ++k) weight[k] = 1.0 / (sigma[k] * sigma[k]);
  const auto fit = fit_rigid(std::span(model.data(), n), std::span(measured.data(), n), std::span(weight.data(), n));
  if (!fit) return std::nullopt;
  // The residual's chi-square: 3n coordinates less the six of the pose.
  double residual_chi2 = 0.0;
  for (std::size_t k = 0; k < n; ++k) residual_chi2 += (fit->to_from_from * model[k] - measured[k]).squaredNorm() / (sigma[k] * sigma[k]);
  if (residual_chi2 > chi2_limit(3 * static_cast<int>(n) - 6)) return std::nullopt;
  IdentifiedStar out;
  out.star = star;
  out.world_from_star = fit->to_from_from;
  out.rms_m = fit->rms_m;
  out.chi2 = edge_chi2(library, star, point, points);
  out.point = point;
  out.markers_seen = static_cast<int>(n);
  return out;
}

namespace {

// Point p's neighbours: the points at a star edge's length from it, with the distance (found by a
// sweep along x, in the order found; edge_candidates).
std::span<const std::pair<int, double>> neighbours_of(const StarIdentificationScratch& scratch, std::size_t p) {
  const auto begin = static_cast<std::size_t>(scratch.neighbour_start[p]);
  const auto end = static_cast<std::size_t>(scratch.neighbour_start[p + 1]);
  return std::span<const std::pair<int, double>>(scratch.neighbour).subspan(begin, end - begin);
}

// The tolerance of an edge between two points: gate_sigmas standard deviations of its length, at
// least the library's least tolerance.
double edge_tolerance(const StarLibrary& library, const StarPoints& points, std::size_t a, std::size_t b) {
  const double sd = std::sqrt(points.sigma(a) * points.sigma(a) + points.sigma(b) * points.sigma(b));
  return std::max(library.edge_tolerance_m(), library.settings().gate_sigmas * sd);
}

void edge_candidates(const StarLibrary& library, const StarPoints& points, StarIdentificationScratch& scratch) {
  const std::size_t n = points.size();
  double largest_sigma = 0.0;
  for (std::size_t i = 0; i < n; ++i) largest_sigma = std::max(largest_sigma, points.sigma(i));
  const double reach =
      library.longest_edge_m() + std::max(library.edge_tolerance_m(), library.settings().gate_sigmas * std::sqrt(2.0) * largest_sigma);
  std::vector<std::size_t>& by_x = scratch.by_x;
  reserve_room(by_x, n);
  by_x.resize(n);
  for (std::size_t i = 0; i < n; ++i) by_x[i] = i;
  std::sort(by_x.begin(), by_x.end(), [&](std::size_t a, std::size_t b) { return points[a].x() < points[b].x(); });
  std::vector<StarIdentificationScratch::Edge>& edges = scratch.edges;
  edges.clear();
  for (std::size_t a = 0; a < n; ++a) {
    const Eigen::Vector3d& p = points[by_x[a]];
    if (!p.allFinite()) continue;
    for (std::size_t b = a + 1; b < n && points[by_x[b]].x() - p.x() <= reach; ++b) {
      const double d = (points[by_x[b]] - p).norm();
      if (!library.is_edge_length(d, edge_tolerance(library, points, by_x[a], by_x[b]))) continue;
      edges.push_back({static_cast<int>(by_x[a]), static_cast<int>(by_x[b]), d});
    }
  }
  // Per point, its edges' other ends in the order found.
  std::vector<int>& start = scratch.neighbour_start;
  reserve_room(start, n + 1);
  reserve_room(scratch.fill, n);
  reserve_room(scratch.neighbour, 2 * edges.size());
  start.assign(n + 1, 0);
  for (const auto& e : edges) {
    ++start[static_cast<std::size_t>(e.a) + 1];
    ++start[static_cast<std::size_t>(e.b) + 1];
  }
  for (std::size_t k = 1; k < start.size(); ++k) start[k] += start[k - 1];
  scratch.fill.assign(start.begin(), start.end() - 1);
  scratch.neighbour.resize(static_cast<std::size_t>(start.back()));
  for (const auto& e : edges) {
    scratch.neighbour[static_cast<std::size_t>(scratch.fill[static_cast<std::size_t>(e.a)]++)] = {e.b, e.d};
    scratch.neighbour[static_cast<std::size_t>(scratch.fill[static_cast<std::size_t>(e.b)]++)] = {e.a, e.d};
  }
}

// Hypotheses: stars, and per star the faces that found it (support).
struct Hypotheses {
  std::vector<IdentifiedStar>& stars;
  std::vector<int>& support;
};

// A three-marker fit with its fourth marker added where the three put it, if a point is there and
// the four still fit; else the three.
IdentifiedStar with_fourth_marker(const StarLibrary& library, const IdentifiedStar& three, const StarPoints& points) {
  const std::array<int, 4>& point = three.point;
  const auto missing = static_cast<std::size_t>(std::find(point.begin(), point.end(), -1) - point.begin());
  const Eigen::Vector3d predicted = three.world_from_star * library.stars()[static_cast<std::size_t>(three.star)].markers_m[missing];
  int best = -1;
  double best_d = std::numeric_limits<double>::infinity();
  for (std::size_t q = 0; q < points.size(); ++q) {
    const double d = (points[q] - predicted).norm();
    // The prediction carries the three's error too: about twice a point's.
    const double gate = std::max(library.settings().fourth_marker_gate_m, 2.0 * library.settings().gate_sigmas * points.sigma(q));
    if (d <= gate && d < best_d && static_cast<int>(q) != point[0] && static_cast<int>(q) != point[1] && static_cast<int>(q) != point[2] &&
        static_cast<int>(q) != point[3]) {
      best_d = d;
      best = static_cast<int>(q);
    }
  }
  if (best >= 0) {
    std::array<int, 4> four = point;
    four[missing] = best;
    if (auto full = fit_star(library, three.star, four, points)) return *full;
  }
  return three;
}

// Hypotheses from every candidate triangle (i < j < k) that is a face of the set: per triangle, of
// the stars with a matching face, the reading whose edges match best.
void face_hypotheses(const StarLibrary& library, const StarPoints& points, StarIdentificationScratch& scratch) {
  auto distance_between = [&](int i, int j) -> double {
    for (const auto& [k, d] : neighbours_of(scratch, static_cast<std::size_t>(i))) {
      if (k == j) return d;
    }
    return -1.0;
  };
  Hypotheses out{scratch.stars, scratch.support};
  out.stars.clear();
  out.support.clear();
  std::vector<const StarLibrary::Face*>& faces = scratch.faces;
  reserve_room(faces, 4 * library.stars().size());  // every face of every star: the most find_faces gives
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto ni = neighbours_of(scratch, i);
    for (std::size_t x = 0; x < ni.size(); ++x) {
      const int j = ni[x].first;
      if (j <= static_cast<int>(i)) continue;
      for (std::size_t y = 0; y < ni.size(); ++y) {
        const int k = ni[y].first;
        if (k <= j) continue;
        const double djk = distance_between(j, k);
        if (djk < 0.0) continue;
        std::array<double, 3> sorted{djk, ni[y].second, ni[x].second};
        std::sort(sorted.begin(), sorted.end());
        const double tolerance = std::max({edge_tolerance(library, points, i, static_cast<std::size_t>(j)),
                                           edge_tolerance(library, points, i, static_cast<std::size_t>(k)),
                                           edge_tolerance(library, points, static_cast<std::size_t>(j), static_cast<std::size_t>(k))});
        library.find_faces(sorted, tolerance, faces);
        if (faces.empty()) continue;
        // Under noise the order of nearly equal edges is not the face's: every correspondence of
        // the three points to each matching star's markers is weighed.
        const std::array<int, 3> triangle{static_cast<int>(i), j, k};
        int best_star = -1;
        std::array<int, 4> point{-1, -1, -1, -1};
        double best_chi2 = std::numeric_limits<double>::infinity();
        for (const StarLibrary::Face* face : faces) {
          if (face->star == best_star) continue;
          const std::array<int, 4> p = best_correspondence(library, face->star, triangle, points);
          const double chi2 = edge_chi2(library, face->star, p, points);
          if (chi2 < best_chi2) {
            best_chi2 = chi2;
            best_star = face->star;
            point = p;
          }
        }
        // Another face of a star already found with these markers: more support, no new fit.
        bool known = false;
        for (std::size_t h = 0; h < out.stars.size() && !known; ++h) {
          if (out.stars[h].star != best_star || out.stars[h].markers_seen != 4) continue;
          known = true;
          for (std::size_t m = 0; m < 4; ++m) known = known && (point[m] < 0 || point[m] == out.stars[h].point[m]);
          if (known) ++out.support[h];
        }
        if (known) continue;
        auto three = fit_star(library, best_star, point, points);
        if (!three) continue;
        out.stars.push_back(with_fourth_marker(library, *three, points));
        out.support.push_back(1);
      }
    }
  }
}

// A star in view is found from each of its faces whose edges are within the tolerance: the number
// of faces that found a hypothesis is its support. A chance match rarely has more than one.
// Hypotheses of one star on the same points become one, their support added.
void merge_duplicates(StarIdentificationScratch& scratch) {
  const Hypotheses found{scratch.stars, scratch.support};
  std::vector<std::size_t>& order = scratch.order;
  reserve_room(order, found.stars.size());
  order.resize(found.stars.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return std::tie(found.stars[a].star, found.stars[a].point) < std::tie(found.stars[b].star, found.stars[b].point);
  });
  Hypotheses unique{scratch.unique, scratch.unique_support};
  unique.stars.clear();
  unique.support.clear();
  for (const std::size_t k : order) {
    const IdentifiedStar& x = found.stars[k];
    if (!unique.stars.empty() && unique.stars.back().star == x.star && unique.stars.back().point == x.point) {
      unique.support.back() += found.support[k];
      continue;
    }
    unique.stars.push_back(x);
    unique.support.push_back(found.support[k]);
  }
}

// Choosing among conflicting hypotheses (sharing a point, or one star at two places): a chance
// triangle takes points from two or three real stars, so it conflicts with more hypotheses than
// a real star does. Repeatedly take the hypothesis with the most markers, then the most support,
// then the fewest conflicts left, then the best matching edges; drop what it conflicts with.
void resolve_conflicts(StarIdentificationScratch& scratch, std::vector<IdentifiedStar>& out) {
  const Hypotheses hypotheses{scratch.unique, scratch.unique_support};
  const std::vector<IdentifiedStar>& stars = hypotheses.stars;
  const std::size_t h = stars.size();
  auto conflict = [&](std::size_t a, std::size_t b) {
    if (stars[a].star == stars[b].star) return true;
    for (const int p : stars[a].point) {
      if (p >= 0 && std::find(stars[b].point.begin(), stars[b].point.end(), p) != stars[b].point.end()) return true;
    }
    return false;
  };
  // Per hypothesis, those it conflicts with, in the order the pairs are found.
  std::vector<std::pair<std::size_t, std::size_t>>& pairs = scratch.conflict_pairs;
  pairs.clear();
  for (std::size_t a = 0; a < h; ++a) {
    for (std::size_t b = a + 1; b < h; ++b) {
      if (conflict(a, b)) pairs.emplace_back(a, b);
    }
  }
  std::vector<std::size_t>& start = scratch.conflict_start;
  reserve_room(start, h + 1);
  reserve_room(scratch.conflict_fill, h);
  reserve_room(scratch.conflict, 2 * pairs.size());
  reserve_room(scratch.degree, h);
  reserve_room(scratch.alive, h);
  start.assign(h + 1, 0);
  for (const auto& [a, b] : pairs) {
    ++start[a + 1];
    ++start[b + 1];
  }
  for (std::size_t k = 1; k < start.size(); ++k) start[k] += start[k - 1];
  std::vector<std::size_t>& fill = scratch.conflict_fill;
  fill.assign(start.begin(), start.end() - 1);
  scratch.conflict.resize(start.back());
  for (const auto& [a, b] : pairs) {
    scratch.conflict[fill[a]++] = b;
    scratch.conflict[fill[b]++] = a;
  }
  const auto conflicts = [&](std::size_t a) {
    return std::span<const std::size_t>(scratch.conflict).subspan(start[a], start[a + 1] - start[a]);
  };
  std::vector<int>& degree = scratch.degree;
  degree.resize(h);
  for (std::size_t a = 0; a < h; ++a) degree[a] = static_cast<int>(conflicts(a).size());
  std::vector<char>& alive = scratch.alive;
  alive.assign(h, 1);
  out.clear();
  for (;;) {
    std::size_t best = h;
    for (std::size_t a = 0; a < h; ++a) {
      if (alive[a] == 0) continue;
      if (best == h) {
        best = a;
        continue;
      }
      const IdentifiedStar& x = stars[a];
      const IdentifiedStar& y = stars[best];
      if (std::make_tuple(-x.markers_seen, -hypotheses.support[a], degree[a], x.chi2) <
          std::make_tuple(-y.markers_seen, -hypotheses.support[best], degree[best], y.chi2)) {
        best = a;
      }
    }
    if (best == h) break;
    out.push_back(stars[best]);
    alive[best] = 0;
    for (const std::size_t c : conflicts(best)) {
      if (alive[c] == 0) continue;
      alive[c] = 0;
      for (const std::size_t d : conflicts(c)) --degree[d];
    }
  }
}

}  // namespace

std::vector<IdentifiedStar> identify_stars(const StarLibrary& library, const StarPoints& points) {
  StarIdentificationScratch scratch;
  std::vector<IdentifiedStar> out;
  identify_stars(library, points, scratch, out);
  return out;
}

void identify_stars(const StarLibrary& library, const StarPoints& points, StarIdentificationScratch& scratch,
                    std::vector<IdentifiedStar>& out) {
  edge_candidates(library, points, scratch);
  face_hypotheses(library, points, scratch);
  merge_duplicates(scratch);
  resolve_conflicts(scratch, out);
}

}  // namespace rhot
