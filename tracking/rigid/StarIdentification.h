#pragma once
// Finding known marker stars among unlabelled 3D points, from one frame alone.
//
// Every pair of points whose distance matches some star edge (within the edge tolerance, which
// grows with the points' uncertainty) is an edge candidate; every triangle of candidates is looked
// up among the set's faces by its sorted edge lengths. With precise points a triangle matches at
// most one face (faces of a valid set differ by at least the set's variation); with noisy ones it
// may match several, and the reading whose edges' chi-square is smallest is taken (the tracker,
// StarTracker.h, weighs the other readings over the following frames before it believes one). The
// fit of the three markers predicts the fourth; a point near it joins. Each hypothesis is fitted
// (RigidFit) and refused when its residual is more than the points' noise explains; then
// hypotheses are accepted greedily, four-marker ones first, each star and each point used once,
// so nearby stars cannot share or swap markers.

#include <array>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "tracking/core/Rigid3.h"
#include "tracking/rigid/StarSet.h"

namespace rhot {

struct StarIdentificationSettings {
  // Edges and fits are judged against the points' uncertainty: each point comes with its standard
  // deviation per axis (from triangulation), or point_sigma_m when none is given. A measured edge
  // matches a model edge within gate_sigmas of their difference's standard deviation, but never
  // less than edge_tolerance_fraction of the set's variation; a fit's residual must be what such
  // noise gives (chi-square of its degrees of freedom, 1e-4 tail).
  double point_sigma_m = 0.0003;
  double gate_sigmas = 3.5;
  double edge_tolerance_fraction = 0.45;
  // Every edge between a fit's markers must match the model within this fraction of the variation
  // (or gate_sigmas standard deviations, if more): any wrong correspondence of a star's markers
  // puts some edge a whole variation off.
  double edge_check_fraction = 0.75;
  double fourth_marker_gate_m = 0.003;  // how near the predicted fourth marker a point must be (at least)
};

// Chi-square's upper 1e-4 quantile for `dof` degrees of freedom (Wilson-Hilferty).
double chi2_limit(int dof);

// Triangulated points with their uncertainty: per point its standard deviation per axis in metres
// (empty: every point has the library's point_sigma_m).
struct StarPoints {
  std::span<const Eigen::Vector3d> position_m;
  std::span<const double> sigma_m;
  double fallback_sigma_m = 0.0003;

  std::size_t size() const { return position_m.size(); }
  const Eigen::Vector3d& operator[](std::size_t i) const { return position_m[i]; }
  double sigma(std::size_t i) const { return i < sigma_m.size() && sigma_m[i] > 1e-6 ? sigma_m[i] : fallback_sigma_m; }
};

// A star set prepared for identification: metres, and its faces indexed by sorted edge lengths.
class StarLibrary {
 public:
  StarLibrary(const StarSet& set, const StarIdentificationSettings& settings = {});

  struct Star {
    int id = 0;
    std::array<Eigen::Vector3d, 4> markers_m;  // in the star's frame
  };
  const std::vector<Star>& stars() const { return stars_; }
  const StarIdentificationSettings& settings() const { return settings_; }
  double edge_tolerance_m() const { return tolerance_m_; }  // the least tolerance of an edge
  double edge_check_m() const { return check_m_; }
  double longest_edge_m() const { return longest_m_; }

  struct Face {
    int star = 0;                   // index into stars()
    std::array<int, 3> marker{};    // markers opposite the sorted edges: marker[k] is opposite edges[k]
    std::array<double, 3> edges{};  // sorted, metres
  };
  // Every face whose sorted edges are all within `tolerance_m` of `sorted_edges`.
  void find_faces(const std::array<double, 3>& sorted_edges, double tolerance_m, std::vector<const Face*>& out) const;
  // Whether some star has an edge within `tolerance_m` of this length.
  bool is_edge_length(double length_m, double tolerance_m) const;
  // The distance between two markers of a star, metres.
  double edge_m(int star, int a, int b) const { return edge_[static_cast<std::size_t>(star)][static_cast<std::size_t>(4 * a + b)]; }

 private:
  StarIdentificationSettings settings_;
  std::vector<Star> stars_;
  std::vector<Face> faces_;                   // sorted by their shortest edge
  std::vector<double> edge_lengths_;          // every star edge, sorted
  std::vector<std::array<double, 16>> edge_;  // per star, the 4 x 4 marker distances
  double tolerance_m_ = 0.0;
  double check_m_ = 0.0;
  double longest_m_ = 0.0;
};

struct IdentifiedStar {
  int star = 0;  // index into the library's stars()
  Rigid3d world_from_star;
  double rms_m = 0.0;
  double chi2 = 0.0;                         // of the edges between the seen markers against the model's
  std::array<int, 4> point{-1, -1, -1, -1};  // per marker: index into the points, -1 when not seen
  int markers_seen = 0;
};

// The points with the library's fallback uncertainty, or with their own.
StarPoints star_points(const StarLibrary& library, std::span<const Eigen::Vector3d> points_world, std::span<const double> sigma_m = {});

std::vector<IdentifiedStar> identify_stars(const StarLibrary& library, const StarPoints& points);

// identify_stars' working storage: kept by a caller that identifies frame after frame, so that
// once frames have shown it their largest counts identification allocates nothing.
struct StarIdentificationScratch {
  std::vector<std::size_t> by_x;
  // Pairs of points at a star edge's length (point, point, distance), in the order found; then per
  // point its neighbours (point, distance), point p's at neighbour[neighbour_start[p] ..
  // neighbour_start[p + 1]).
  struct Edge {
    int a, b;
    double d;
  };
  std::vector<Edge> edges;
  std::vector<int> neighbour_start, fill;
  std::vector<std::pair<int, double>> neighbour;
  std::vector<const StarLibrary::Face*> faces;
  std::vector<IdentifiedStar> stars, unique;  // hypotheses, then with duplicates merged
  std::vector<int> support, unique_support;   // per hypothesis: faces that found it
  std::vector<std::size_t> order;
  // Conflicting pairs of hypotheses, then per hypothesis those it conflicts with (as above).
  std::vector<std::pair<std::size_t, std::size_t>> conflict_pairs;
  std::vector<std::size_t> conflict_start, conflict_fill, conflict;
  std::vector<int> degree;
  std::vector<char> alive;
};
// The same stars as identify_stars, into `out` (replacing what it held), with the scratch's storage.
void identify_stars(const StarLibrary& library, const StarPoints& points, StarIdentificationScratch& scratch,
                    std::vector<IdentifiedStar>& out);
inline std::vector<IdentifiedStar> identify_stars(const StarLibrary& library, std::span<const Eigen::Vector3d> points_world) {
  return identify_stars(library, star_points(library, points_world));
}

// Fits a star to the points given per marker (-1: not seen); nothing when fewer than three are
// seen, an edge between them is off, or the fit's residual is more than the points' noise explains.
std::optional<IdentifiedStar> fit_star(const StarLibrary& library, int star, const std::array<int, 4>& point, const StarPoints& points);

// Chi-square of the edges between the seen markers (point per marker, -1 unseen) against the star's
// model, each edge's difference over its standard deviation; `edges` gets how many were compared.
double edge_chi2(const StarLibrary& library, int star, const std::array<int, 4>& point, const StarPoints& points, int* edges = nullptr);

// Which of the star's markers three or four points are: the assignment whose edges best match the
// model's (smallest chi-square). Returns per marker the point, -1 for none.
std::array<int, 4> best_correspondence(const StarLibrary& library, int star, std::span<const int> point_indices, const StarPoints& points);

}  // namespace rhot
