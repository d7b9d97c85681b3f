#include "tracking/rigid/StarSet.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "base/Json.h"

namespace rhot {

namespace {

std::string format_mm(double v) {
  std::ostringstream s;
  s.precision(4);
  s << v;
  return s.str();
}

std::string star_label(std::size_t index, int id) { return "stars[" + std::to_string(index) + "] (id " + std::to_string(id) + ")"; }

// The edge of a face opposite each of its vertices, in vertex order: edge k joins the other two.
std::array<double, 3> face_edges(const MarkerStar& s, const std::array<int, 3>& face) {
  std::array<double, 3> e{};
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d& a = s.markers_mm[static_cast<std::size_t>(face[static_cast<std::size_t>((k + 1) % 3)])];
    const Eigen::Vector3d& b = s.markers_mm[static_cast<std::size_t>(face[static_cast<std::size_t>((k + 2) % 3)])];
    e[static_cast<std::size_t>(k)] = (a - b).norm();
  }
  return e;
}

// How far two faces are apart: under the vertex correspondence that brings them nearest, the
// largest difference of an edge.
double face_difference_mm(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  double least = std::numeric_limits<double>::infinity();
  std::array<std::size_t, 3> perm{0, 1, 2};
  do {
    double most = 0.0;
    for (std::size_t k = 0; k < 3; ++k) most = std::max(most, std::abs(a[k] - b[perm[k]]));
    least = std::min(least, most);
  } while (std::next_permutation(perm.begin(), perm.end()));
  return least;
}

}  // namespace

std::vector<std::string> clashing_faces(const MarkerStar& a, std::string_view a_name, const MarkerStar& b, std::string_view b_name,
                                        double variation_mm) {
  std::vector<std::string> problems;
  for (std::size_t fa = 0; fa < 4; ++fa) {
    for (std::size_t fb = 0; fb < 4; ++fb) {
      const double most = face_difference_mm(face_edges(a, kStarFaces[fa]), face_edges(b, kStarFaces[fb]));
      if (!(most >= variation_mm)) {
        problems.push_back(std::string(a_name) + " face " + std::to_string(fa) + " and " + std::string(b_name) + " face " +
                           std::to_string(fb) + " differ by at most " + format_mm(most) + " mm in every edge");
      }
    }
  }
  return problems;
}

std::vector<std::string> check_star_set(const StarSet& set) {
  std::vector<std::string> problems;
  const StarSetRules& r = set.rules;
  const double v = r.variation_mm;
  const double radius = 0.5 * r.marker_diameter_mm;
  std::set<int> ids;
  for (std::size_t i = 0; i < set.stars.size(); ++i) {
    const MarkerStar& s = set.stars[i];
    const std::string where = star_label(i, s.id);
    if (!ids.insert(s.id).second) problems.push_back(where + ": duplicate id");
    // Edges: distinct by the variation, markers apart by a diameter.
    std::array<double, 6> edges{};
    for (std::size_t e = 0; e < 6; ++e) {
      edges[e] =
          (s.markers_mm[static_cast<std::size_t>(kStarEdges[e][0])] - s.markers_mm[static_cast<std::size_t>(kStarEdges[e][1])]).norm();
      if (!(edges[e] >= r.marker_diameter_mm)) {
        problems.push_back(where + ": markers " + std::to_string(kStarEdges[e][0]) + " and " + std::to_string(kStarEdges[e][1]) +
                           " overlap (" + format_mm(edges[e]) + " mm apart)");
      }
    }
    for (std::size_t a = 0; a < 6; ++a) {
      for (std::size_t b = a + 1; b < 6; ++b) {
        if (!(std::abs(edges[a] - edges[b]) >= v)) {
          problems.push_back(where + ": edges " + format_mm(edges[a]) + " and " + format_mm(edges[b]) + " mm differ by less than " +
                             format_mm(v) + " mm");
        }
      }
    }
    // The box.
    for (std::size_t m = 0; m < 4; ++m) {
      const Eigen::Vector3d& p = s.markers_mm[m];
      const bool inside = std::abs(p.x()) + radius <= 0.5 * r.box_mm.x() + 1e-9 && std::abs(p.y()) + radius <= 0.5 * r.box_mm.y() + 1e-9 &&
                          p.z() - radius >= -1e-9 && p.z() + radius <= r.box_mm.z() + 1e-9;
      if (!inside) problems.push_back(where + ": marker " + std::to_string(m) + " is not inside the box");
    }
  }
  // Faces against every other face, under all six vertex correspondences.
  struct Face {
    std::size_t star;
    int face;
    std::array<double, 3> edges;
  };
  std::vector<Face> faces;
  for (std::size_t i = 0; i < set.stars.size(); ++i) {
    for (std::size_t f = 0; f < 4; ++f) faces.push_back({i, static_cast<int>(f), face_edges(set.stars[i], kStarFaces[f])});
  }
  for (std::size_t a = 0; a < faces.size(); ++a) {
    for (std::size_t b = a + 1; b < faces.size(); ++b) {
      const double most = face_difference_mm(faces[a].edges, faces[b].edges);
      if (!(most >= v)) {
        problems.push_back(star_label(faces[a].star, set.stars[faces[a].star].id) + " face " + std::to_string(faces[a].face) + " and " +
                           star_label(faces[b].star, set.stars[faces[b].star].id) + " face " + std::to_string(faces[b].face) +
                           " differ by at most " + format_mm(most) + " mm in every edge");
      }
    }
  }
  return problems;
}

namespace {

Eigen::Vector3d vector3(const JsonNode& n) {
  const auto v = n.numbers(3);
  return {v[0], v[1], v[2]};
}

StarSet read_star_set(const JsonNode& j) {
  j.expect_object({"format", "version", "marker_diameter_mm", "box_mm", "variation_mm", "stars"});
  const JsonNode format = j["format"];
  if (format.string() != "rhot-marker-stars") format.fail("expected \"rhot-marker-stars\", got " + describe_json(format.raw()));
  j["version"].integer_in(1, 1);
  StarSet set;
  set.rules.marker_diameter_mm = j["marker_diameter_mm"].positive();
  const JsonNode box = j["box_mm"];
  set.rules.box_mm = vector3(box);
  for (const JsonNode& side : box.elements()) side.positive();
  set.rules.variation_mm = j["variation_mm"].positive();
  for (const JsonNode& s : j["stars"].elements()) {
    s.expect_object({"id", "markers_mm"});
    MarkerStar star;
    star.id = s["id"].integer_in(0, 1000000);
    const JsonNode markers = s["markers_mm"];
    if (!markers.raw().is_array() || markers.raw().size() != 4) {
      markers.fail("expected four [x, y, z] marker centres, got " + describe_json(markers.raw()));
    }
    const auto corners = markers.elements();
    for (std::size_t m = 0; m < 4; ++m) star.markers_mm[m] = vector3(corners[m]);
    set.stars.push_back(star);
  }
  return set;
}

}  // namespace

std::expected<StarSet, std::string> load_star_set(const std::filesystem::path& file) {
  auto set = read_json_file<StarSet>(file, "star set", read_star_set);
  if (!set) return std::unexpected(set.error().to_string());
  // The rules of a set (docs/marker-stars.md): the first problem, and how many more.
  if (const auto problems = check_star_set(*set); !problems.empty()) {
    return std::unexpected(file.string() + ": " + problems.front() +
                           (problems.size() > 1 ? " (and " + std::to_string(problems.size() - 1) + " more)" : ""));
  }
  return *set;
}

std::expected<void, std::string> save_star_set(const StarSet& set, const std::filesystem::path& file) {
  nlohmann::json j;
  j["format"] = "rhot-marker-stars";
  j["version"] = 1;
  j["marker_diameter_mm"] = set.rules.marker_diameter_mm;
  j["box_mm"] = {set.rules.box_mm.x(), set.rules.box_mm.y(), set.rules.box_mm.z()};
  j["variation_mm"] = set.rules.variation_mm;
  j["stars"] = nlohmann::json::array();
  for (const MarkerStar& s : set.stars) {
    nlohmann::json markers = nlohmann::json::array();
    for (const Eigen::Vector3d& m : s.markers_mm) markers.push_back({m.x(), m.y(), m.z()});
    j["stars"].push_back({{"id", s.id}, {"markers_mm", markers}});
  }
  const std::filesystem::path tmp = file.string() + ".tmp";
  {
    std::ofstream out(tmp);
    if (!out) return std::unexpected(file.string() + ": cannot write");
    out << j.dump(2) << "\n";
    if (!out) return std::unexpected(file.string() + ": write failed");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, file, ec);
  if (ec) return std::unexpected(file.string() + ": cannot write: " + ec.message());
  return {};
}

}  // namespace rhot
