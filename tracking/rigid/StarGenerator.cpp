#include "tracking/rigid/StarGenerator.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>
#include <sstream>

#include <Eigen/Geometry>

namespace rhot {

namespace {

using Triple = std::array<double, 3>;  // a face's edge lengths, sorted

struct Candidate {
  std::array<Eigen::Vector3d, 4> markers;
  std::array<Triple, 4> faces;
  double shortest = 0.0;  // edge
  double total = 0.0;     // sum of edges
};

double chebyshev(const Triple& a, const Triple& b) {
  return std::max({std::abs(a[0] - b[0]), std::abs(a[1] - b[1]), std::abs(a[2] - b[2])});
}

// Sorted-to-sorted is the correspondence of vertices that brings two faces' edges closest (in the
// largest difference), so comparing sorted triples covers all six.
bool faces_apart(const Triple& a, const Triple& b, double v) { return chebyshev(a, b) >= v; }

// A random tetrahedron inside the box that keeps every rule that concerns one star alone, or
// nothing. Faces must also be well shaped (every altitude at least one marker diameter), so three
// markers fix a pose.
std::optional<Candidate> draw(const StarSetRules& r, std::mt19937_64& rng) {
  const double radius = 0.5 * r.marker_diameter_mm;
  std::uniform_real_distribution<double> ux(-0.5 * r.box_mm.x() + radius, 0.5 * r.box_mm.x() - radius);
  std::uniform_real_distribution<double> uy(-0.5 * r.box_mm.y() + radius, 0.5 * r.box_mm.y() - radius);
  std::uniform_real_distribution<double> uz(radius, r.box_mm.z() - radius);
  Candidate c;
  for (Eigen::Vector3d& m : c.markers) m = {ux(rng), uy(rng), uz(rng)};
  std::array<double, 6> edges{};
  for (std::size_t e = 0; e < 6; ++e) {
    edges[e] = (c.markers[static_cast<std::size_t>(kStarEdges[e][0])] - c.markers[static_cast<std::size_t>(kStarEdges[e][1])]).norm();
  }
  std::array<double, 6> sorted = edges;
  std::sort(sorted.begin(), sorted.end());
  if (sorted[0] < r.marker_diameter_mm) return std::nullopt;
  for (std::size_t e = 0; e + 1 < 6; ++e) {
    if (sorted[e + 1] - sorted[e] < r.variation_mm) return std::nullopt;
  }
  for (std::size_t f = 0; f < 4; ++f) {
    const auto& face = kStarFaces[f];
    const Eigen::Vector3d& a = c.markers[static_cast<std::size_t>(face[0])];
    const Eigen::Vector3d& b = c.markers[static_cast<std::size_t>(face[1])];
    const Eigen::Vector3d& d = c.markers[static_cast<std::size_t>(face[2])];
    Triple t{(b - d).norm(), (a - d).norm(), (a - b).norm()};
    std::sort(t.begin(), t.end());
    const double twice_area = (b - a).cross(d - a).norm();
    if (twice_area / t[2] < r.marker_diameter_mm) return std::nullopt;  // the smallest altitude
    c.faces[f] = t;
  }
  for (std::size_t f = 0; f < 4; ++f) {
    for (std::size_t g = f + 1; g < 4; ++g) {
      if (!faces_apart(c.faces[f], c.faces[g], r.variation_mm)) return std::nullopt;
    }
  }
  c.shortest = sorted[0];
  for (const double e : edges) c.total += e;
  return c;
}

// Greedy packing in the given order: a candidate joins when each of its faces is `v` from every
// face already taken.
std::vector<const Candidate*> pack(const std::vector<const Candidate*>& order, double v, int max_stars) {
  std::vector<const Candidate*> taken;
  std::vector<Triple> faces;
  for (const Candidate* c : order) {
    bool fits = true;
    for (std::size_t f = 0; f < 4 && fits; ++f) {
      for (const Triple& t : faces) {
        if (!faces_apart(c->faces[f], t, v)) {
          fits = false;
          break;
        }
      }
    }
    if (!fits) continue;
    taken.push_back(c);
    faces.insert(faces.end(), c->faces.begin(), c->faces.end());
    if (max_stars > 0 && static_cast<int>(taken.size()) >= max_stars) break;
  }
  return taken;
}

std::string mm(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

}  // namespace

std::expected<StarSet, std::string> generate_star_set(const StarGeneratorSettings& settings, const GeneratorProgress& progress) {
  const StarSetRules& r = settings.rules;
  if (!(r.marker_diameter_mm > 0.0) || !std::isfinite(r.marker_diameter_mm)) {
    return std::unexpected("marker diameter: must be a positive number of millimetres, got " + mm(r.marker_diameter_mm));
  }
  if (!(r.variation_mm > 0.0) || !std::isfinite(r.variation_mm)) {
    return std::unexpected("variation: must be a positive number of millimetres, got " + mm(r.variation_mm));
  }
  if (!r.box_mm.allFinite() || !(r.box_mm.minCoeff() > 0.0)) {
    return std::unexpected("box: every side must be a positive number of millimetres, got " + mm(r.box_mm.x()) + " x " + mm(r.box_mm.y()) +
                           " x " + mm(r.box_mm.z()));
  }
  if (settings.candidates < 1) return std::unexpected("candidates: must be at least 1");
  const std::string too_small = "box " + mm(r.box_mm.x()) + " x " + mm(r.box_mm.y()) + " x " + mm(r.box_mm.z()) +
                                " mm is too small for one star of " + mm(r.marker_diameter_mm) + " mm markers with edges " +
                                mm(r.variation_mm) + " mm apart";
  if (r.box_mm.minCoeff() <= r.marker_diameter_mm) return std::unexpected(too_small);
  // Six edges at least a diameter long and `variation` apart: the longest is at least
  // diameter + 5 variation, and no two marker centres are further apart than the inner diagonal.
  const Eigen::Vector3d inner = r.box_mm.array() - r.marker_diameter_mm;
  if (inner.norm() < r.marker_diameter_mm + 5.0 * r.variation_mm) return std::unexpected(too_small);

  // Draw candidates; give up on boxes where almost nothing fits.
  std::mt19937_64 rng(settings.seed);
  std::vector<Candidate> pool;
  pool.reserve(static_cast<std::size_t>(settings.candidates));
  // Where a star is possible at all, a million draws find one; past that, give up when candidates
  // come so rarely that the search would take minutes.
  const long max_draws = 200L * settings.candidates + 1000000L;
  long draws = 0;
  const long report_every = std::max(1, settings.candidates / 20);
  while (static_cast<int>(pool.size()) < settings.candidates && draws < max_draws) {
    if (++draws == 1000000L && pool.empty()) break;
    if (auto c = draw(r, rng)) {
      pool.push_back(*c);
      if (progress && static_cast<long>(pool.size()) % report_every == 0) progress(static_cast<long>(pool.size()), settings.candidates);
    }
  }
  if (pool.empty()) return std::unexpected(too_small);

  // Several orders; the largest set wins (ties: the earlier order).
  std::vector<const Candidate*> drawn;
  for (const Candidate& c : pool) drawn.push_back(&c);
  std::vector<std::vector<const Candidate*>> orders(4, drawn);
  std::stable_sort(orders[1].begin(), orders[1].end(), [](const Candidate* a, const Candidate* b) { return a->shortest > b->shortest; });
  std::stable_sort(orders[2].begin(), orders[2].end(), [](const Candidate* a, const Candidate* b) { return a->total < b->total; });
  std::stable_sort(orders[3].begin(), orders[3].end(),
                   [](const Candidate* a, const Candidate* b) { return a->faces[0][2] < b->faces[0][2]; });
  std::vector<const Candidate*> best;
  for (const auto& order : orders) {
    auto taken = pack(order, r.variation_mm, settings.max_stars);
    if (taken.size() > best.size()) best = std::move(taken);
  }

  StarSet set;
  set.rules = r;
  for (const Candidate* c : best) {
    MarkerStar s;
    s.id = static_cast<int>(set.stars.size());
    // Place by the bounding box of the spheres: centred in x and y, standing on z = 0.
    Eigen::Vector3d lo = c->markers[0], hi = c->markers[0];
    for (const Eigen::Vector3d& m : c->markers) {
      lo = lo.cwiseMin(m);
      hi = hi.cwiseMax(m);
    }
    const Eigen::Vector3d shift(-0.5 * (lo.x() + hi.x()), -0.5 * (lo.y() + hi.y()), 0.5 * r.marker_diameter_mm - lo.z());
    for (std::size_t m = 0; m < 4; ++m) s.markers_mm[m] = c->markers[m] + shift;
    set.stars.push_back(s);
  }
  return set;
}

}  // namespace rhot
