#include "engine/mesh/MeshData.h"

#include <cmath>
#include <numbers>
#include <type_traits>
#include <variant>

#include "base/Check.h"

namespace rhot {

namespace {

constexpr float kPi = std::numbers::pi_v<float>;

bool positive_finite(float v) { return std::isfinite(v) && v > 0.0f; }

// Appends a quad a-b-c-d, counter-clockwise seen from the side its normal points to, with that
// normal on all four corners (flat shading: faces of a box share no vertices).
void add_quad(MeshData& m, glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d, glm::vec3 normal) {
  const auto base = static_cast<std::uint32_t>(m.vertices.size());
  for (const glm::vec3& p : {a, b, c, d}) m.vertices.push_back({p, normal});
  m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
}

// One circle of a surface of revolution about +Y, with the outward normal of the surface there
// given in the meridian plane (its components away from the axis and along +Y).
struct Ring {
  float radius;
  float y;
  float normal_radial;
  float normal_y;
};

// Joins rings listed from the top down into a smooth surface. Each ring has segments + 1
// vertices (the seam is duplicated; a pole ring of radius 0 repeats its point with the same
// normal), and a band next to a pole gets one triangle per segment instead of two, so no triangle
// is degenerate.
MeshData revolve(const std::vector<Ring>& rings, int segments) {
  MeshData m;
  m.vertices.reserve(rings.size() * static_cast<std::size_t>(segments + 1));
  for (const Ring& r : rings) {
    for (int s = 0; s <= segments; ++s) {
      // The angle turns from +X toward -Z: counter-clockwise seen from +Y.
      const float a = 2.0f * kPi * static_cast<float>(s) / static_cast<float>(segments);
      const float c = s == segments ? 1.0f : std::cos(a);  // close the seam exactly
      const float sn = s == segments ? 0.0f : std::sin(a);
      const glm::vec3 normal(r.normal_radial * c, r.normal_y, -r.normal_radial * sn);
      m.vertices.push_back({{r.radius * c, r.y, -r.radius * sn}, glm::normalize(normal)});
    }
  }
  const auto row = static_cast<std::uint32_t>(segments + 1);
  for (std::uint32_t i = 0; i + 1 < rings.size(); ++i) {
    for (std::uint32_t s = 0; s < static_cast<std::uint32_t>(segments); ++s) {
      const std::uint32_t a = i * row + s;        // upper ring
      const std::uint32_t b = (i + 1) * row + s;  // lower ring
      // Seen from outside the angle grows to the right, so upper-left, lower-left, lower-right
      // (and upper-left, lower-right, upper-right) wind counter-clockwise.
      // Next to a pole only the triangle with two corners on the other ring has any area.
      if (rings[i + 1].radius > 0.0f) m.indices.insert(m.indices.end(), {a, b, b + 1});
      if (rings[i].radius > 0.0f) m.indices.insert(m.indices.end(), {a, b + 1, a + 1});
    }
  }
  return m;
}

// A ring on a sphere of the given radius centred at (0, centre_y, 0), at polar angle `polar` from
// +Y. Exact zeros at the poles keep the pole a single point.
Ring sphere_ring(float radius_m, float centre_y, float polar, bool pole) {
  const float s = pole ? 0.0f : std::sin(polar);
  const float c = std::cos(polar);
  return {radius_m * s, centre_y + radius_m * c, s, c};
}

}  // namespace

MeshData make_box(glm::vec3 size_m) {
  RHOT_PRECONDITION(positive_finite(size_m.x) && positive_finite(size_m.y) && positive_finite(size_m.z),
                    "make_box: every edge length must be finite and > 0");
  const glm::vec3 h = size_m * 0.5f;
  MeshData m;
  m.vertices.reserve(24);
  m.indices.reserve(36);
  add_quad(m, {h.x, -h.y, h.z}, {h.x, -h.y, -h.z}, {h.x, h.y, -h.z}, {h.x, h.y, h.z}, {1, 0, 0});
  add_quad(m, {-h.x, -h.y, -h.z}, {-h.x, -h.y, h.z}, {-h.x, h.y, h.z}, {-h.x, h.y, -h.z}, {-1, 0, 0});
  add_quad(m, {-h.x, h.y, h.z}, {h.x, h.y, h.z}, {h.x, h.y, -h.z}, {-h.x, h.y, -h.z}, {0, 1, 0});
  add_quad(m, {-h.x, -h.y, -h.z}, {h.x, -h.y, -h.z}, {h.x, -h.y, h.z}, {-h.x, -h.y, h.z}, {0, -1, 0});
  add_quad(m, {-h.x, -h.y, h.z}, {h.x, -h.y, h.z}, {h.x, h.y, h.z}, {-h.x, h.y, h.z}, {0, 0, 1});
  add_quad(m, {h.x, -h.y, -h.z}, {-h.x, -h.y, -h.z}, {-h.x, h.y, -h.z}, {h.x, h.y, -h.z}, {0, 0, -1});
  return m;
}

MeshData make_sphere(float radius_m, int segments, int rings) {
  RHOT_PRECONDITION(positive_finite(radius_m) && segments >= 3 && rings >= 2,
                    "make_sphere: needs a finite radius > 0, segments >= 3 and rings >= 2");
  std::vector<Ring> r;
  r.reserve(static_cast<std::size_t>(rings) + 1);
  for (int i = 0; i <= rings; ++i) {
    const float polar = kPi * static_cast<float>(i) / static_cast<float>(rings);
    r.push_back(sphere_ring(radius_m, 0.0f, polar, i == 0 || i == rings));
  }
  return revolve(r, segments);
}

MeshData make_capsule(float radius_m, float height_m, int segments, int cap_rings) {
  RHOT_PRECONDITION(positive_finite(radius_m) && std::isfinite(height_m) && height_m >= 2.0f * radius_m && segments >= 3 && cap_rings >= 1,
                    "make_capsule: needs a finite radius > 0, height >= 2 * radius, segments >= 3 and "
                    "cap_rings >= 1");
  // Exact halving: height_m >= 2 * radius_m makes this >= 0, and exactly 0 for a sphere.
  const float half_cylinder_m = 0.5f * height_m - radius_m;
  const float step = 0.5f * kPi / static_cast<float>(cap_rings);
  std::vector<Ring> r;
  r.reserve(2 * static_cast<std::size_t>(cap_rings) + 2);
  for (int i = 0; i <= cap_rings; ++i) {  // top cap, pole to equator
    r.push_back(sphere_ring(radius_m, half_cylinder_m, step * static_cast<float>(i), i == 0));
  }
  // The bottom cap, equator to pole. With no cylinder its equator would repeat the top one and
  // the band between them would be degenerate, so it starts one ring lower.
  for (int i = half_cylinder_m > 0.0f ? 0 : 1; i <= cap_rings; ++i) {
    r.push_back(sphere_ring(radius_m, -half_cylinder_m, 0.5f * kPi + step * static_cast<float>(i), i == cap_rings));
  }
  return revolve(r, segments);
}

MeshData make_plane(glm::vec2 size_m) {
  RHOT_PRECONDITION(positive_finite(size_m.x) && positive_finite(size_m.y), "make_plane: both sizes must be finite and > 0");
  const glm::vec2 h = size_m * 0.5f;
  MeshData m;
  add_quad(m, {-h.x, 0, h.y}, {h.x, 0, h.y}, {h.x, 0, -h.y}, {-h.x, 0, -h.y}, {0, 1, 0});
  return m;
}

MeshData make_shape_mesh(const MeshShape& shape) {
  return std::visit(
      [](const auto& s) -> MeshData {
        using S = std::decay_t<decltype(s)>;
        if constexpr (std::is_same_v<S, BoxShape>) {
          return make_box(s.size_m);
        } else if constexpr (std::is_same_v<S, SphereShape>) {
          return make_sphere(s.radius_m);
        } else if constexpr (std::is_same_v<S, CapsuleShape>) {
          return make_capsule(s.radius_m, s.height_m);
        } else if constexpr (std::is_same_v<S, PlaneShape>) {
          return make_plane(s.size_m);
        } else {
          static_assert(std::is_same_v<S, GltfMeshShape>, "a MeshShape alternative is not handled");
          RHOT_PRECONDITION(false, "make_shape_mesh: a glTF mesh (" + s.file.string() + ") comes from load_gltf_mesh");
          return {};
        }
      },
      shape);
}

}  // namespace rhot
