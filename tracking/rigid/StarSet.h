#pragma once
// Marker stars: four markers fixed rigidly to an object, whose six distances are unique to it, so
// the tracker knows which object it sees, and its pose, from one frame.
//
// A star set file (JSON, millimetres; docs/marker-stars.md):
//
//   {
//     "format": "rhot-marker-stars", "version": 1,
//     "marker_diameter_mm": 4.0, "box_mm": [20.8, 12.6, 48.3], "variation_mm": 1.5,
//     "stars": [ { "id": 0, "markers_mm": [[x, y, z], [x, y, z], [x, y, z], [x, y, z]] }, ... ]
//   }
//
// Marker centres are in the star's own frame: the origin at the centre of the bottom of its box,
// z along the box's X Y Z third side, so every marker sphere lies in
// [-X/2, X/2] x [-Y/2, Y/2] x [0, Z].

#include <array>
#include <expected>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

namespace rhot {

struct MarkerStar {
  int id = 0;
  std::array<Eigen::Vector3d, 4> markers_mm;
};

struct StarSetRules {
  double marker_diameter_mm = 4.0;
  Eigen::Vector3d box_mm{20.8, 12.6, 48.3};
  double variation_mm = 1.5;
};

struct StarSet {
  StarSetRules rules;
  std::vector<MarkerStar> stars;
};

// The four faces of a star, as marker indices, and the six edges.
inline constexpr std::array<std::array<int, 3>, 4> kStarFaces{{{0, 1, 2}, {0, 1, 3}, {0, 2, 3}, {1, 2, 3}}};
inline constexpr std::array<std::array<int, 2>, 6> kStarEdges{{{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}}};

[[nodiscard]] std::expected<StarSet, std::string> load_star_set(const std::filesystem::path& file);
[[nodiscard]] std::expected<void, std::string> save_star_set(const StarSet& set, const std::filesystem::path& file);

// Every rule a star set must keep, checked directly from the marker coordinates (not by the
// generator's own bookkeeping), one message per violation, empty when the set is valid:
//  - the six edge lengths of each star differ pairwise by at least variation_mm;
//  - markers do not overlap (centres at least marker_diameter_mm apart);
//  - every marker sphere lies inside the box, in the star's frame;
//  - every face differs from every other face in the set (other stars' and its own star's) by at
//    least variation_mm in some edge, under each of the six correspondences of its vertices.
std::vector<std::string> check_star_set(const StarSet& set);

// Where two stars could be taken for each other from three markers: every face of `a` and face of
// `b` that differ by less than variation_mm in every edge under some correspondence of their
// vertices, one message each, naming the stars as given. A face and its mirror image have the same
// edges, so a star and its mirror image clash in every face.
std::vector<std::string> clashing_faces(const MarkerStar& a, std::string_view a_name, const MarkerStar& b, std::string_view b_name,
                                        double variation_mm);

}  // namespace rhot
