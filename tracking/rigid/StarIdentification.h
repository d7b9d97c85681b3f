#pragma once
// Finding known marker stars among unlabelled 3D points, from one frame alone.
//
// Every pair of points whose distance matches some star edge (within the edge tolerance) is an
// edge candidate; every triangle of candidates is looked up among the set's faces by its sorted
// edge lengths. Faces of a valid set differ by at least the set's variation, so with a tolerance
// under half of it a triangle matches at most one face, and the match fixes which point is which
// marker. The fit of those three markers predicts the fourth; a point near it joins. Each
// hypothesis is fitted (RigidFit) and refused when its residual or scale is off; then hypotheses
// are accepted greedily, four-marker ones first, lowest residual first, each star and each point
// used once, so nearby stars cannot share or swap markers.

#include <array>
#include <optional>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "tracking/core/Rigid3.h"
#include "tracking/rigid/StarSet.h"

namespace rhot {

struct StarIdentificationSettings {
  // Largest difference between a measured and a model edge, as a fraction of the set's variation
  // (below 0.5 keeps every face lookup unique).
  double edge_tolerance_fraction = 0.45;
  // Every edge between a fit's markers must match the model within this fraction of the variation:
  // any wrong correspondence of a star's markers puts some edge a whole variation off.
  double edge_check_fraction = 0.75;
  double max_rms_m = 0.0015;            // refuse fits whose residual is larger
  double max_scale_error = 0.03;        // refuse fits whose similarity scale is further from 1
  double fourth_marker_gate_m = 0.003;  // how near the predicted fourth marker a point must be
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
  double edge_tolerance_m() const { return tolerance_m_; }
  double edge_check_m() const { return check_m_; }
  double longest_edge_m() const { return longest_m_; }

  struct Face {
    int star = 0;                   // index into stars()
    std::array<int, 3> marker{};    // markers opposite the sorted edges: marker[k] is opposite edges[k]
    std::array<double, 3> edges{};  // sorted, metres
  };
  // The face whose sorted edges are all within the tolerance of `sorted_edges`, or nullptr.
  const Face* find_face(const std::array<double, 3>& sorted_edges) const;
  // Whether some star has an edge within the tolerance of this length.
  bool is_edge_length(double length_m) const;

 private:
  StarIdentificationSettings settings_;
  std::vector<Star> stars_;
  std::vector<Face> faces_;           // sorted by their shortest edge
  std::vector<double> edge_lengths_;  // every star edge, sorted
  double tolerance_m_ = 0.0;
  double check_m_ = 0.0;
  double longest_m_ = 0.0;
};

struct IdentifiedStar {
  int star = 0;  // index into the library's stars()
  Rigid3d world_from_star;
  double rms_m = 0.0;
  std::array<int, 4> point{-1, -1, -1, -1};  // per marker: index into the points, -1 when not seen
  int markers_seen = 0;
};

std::vector<IdentifiedStar> identify_stars(const StarLibrary& library, std::span<const Eigen::Vector3d> points_world);

// Fits a star to the points given per marker (-1: not seen); nothing when fewer than three are
// seen, an edge between them is off, or the fit's residual or scale is off.
std::optional<IdentifiedStar> fit_star(const StarLibrary& library, int star, const std::array<int, 4>& point,
                                       std::span<const Eigen::Vector3d> points_world);

// Which of the star's markers three or four points are: the assignment whose edges best match the
// model's (largest difference smallest). Returns per marker the point, -1 for none.
std::array<int, 4> best_correspondence(const StarLibrary& library, int star, std::span<const int> point_indices,
                                       std::span<const Eigen::Vector3d> points_world);

}  // namespace rhot
