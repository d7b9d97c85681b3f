#include "engine/render/MeshData.h"

#include <cmath>
#include <numbers>

#include "tracking/core/Check.h"

namespace rhot {

namespace {

constexpr float kPi = std::numbers::pi_v<float>;

// Appends a quad a-b-c-d (counter-clockwise seen from the side its normal points to).
void add_quad(MeshData& m, glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d, glm::vec3 normal) {
  const auto base = static_cast<std::uint32_t>(m.vertices.size());
  for (const glm::vec3& p : {a, b, c, d}) m.vertices.push_back({p, normal});
  m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
}

// A surface of revolution about +Y: rings from the top pole down, each ring a radius, a height
// and an outward normal. Adjacent rings are joined counter-clockwise seen from outside.
struct Ring {
  float radius;
  float y;
  float normal_xz;  // the normal is (normal_xz * cos a, normal_y, -normal_xz * sin a)
  float normal_y;
};

MeshData revolve(const std::vector<Ring>& rings, int segments) {
  MeshData m;
  for (const Ring& r : rings) {
    for (int s = 0; s <= segments; ++s) {
      const float a = 2.0f * kPi * static_cast<float>(s) / static_cast<float>(segments);
      const float c = std::cos(a);
      const float sn = std::sin(a);
      m.vertices.push_back({{r.radius * c, r.y, -r.radius * sn}, glm::normalize(glm::vec3(r.normal_xz * c, r.normal_y, -r.normal_xz * sn))});
    }
  }
  const auto row = static_cast<std::uint32_t>(segments + 1);
  for (std::uint32_t i = 0; i + 1 < rings.size(); ++i) {
    for (std::uint32_t s = 0; s < static_cast<std::uint32_t>(segments); ++s) {
      const std::uint32_t a = i * row + s;       // upper ring
      const std::uint32_t b = (i + 1) * row + s;  // lower ring
      // Seen from outside, angle increases to the right (x toward -z), so upper-left, lower-left,
      // lower-right is counter-clockwise.
      if (rings[i].radius > 0.0f) m.indices.insert(m.indices.end(), {a, b, b + 1});
      if (rings[i + 1].radius > 0.0f) m.indices.insert(m.indices.end(), {a, b + 1, a + 1});
    }
  }
  return m;
}

}  // namespace

MeshData make_box(glm::vec3 size_m) {
  const glm::vec3 h = size_m * 0.5f;
  MeshData m;
  add_quad(m, {h.x, -h.y, h.z}, {h.x, -h.y, -h.z}, {h.x, h.y, -h.z}, {h.x, h.y, h.z}, {1, 0, 0});
  add_quad(m, {-h.x, -h.y, -h.z}, {-h.x, -h.y, h.z}, {-h.x, h.y, h.z}, {-h.x, h.y, -h.z}, {-1, 0, 0});
  add_quad(m, {-h.x, h.y, h.z}, {h.x, h.y, h.z}, {h.x, h.y, -h.z}, {-h.x, h.y, -h.z}, {0, 1, 0});
  add_quad(m, {-h.x, -h.y, -h.z}, {h.x, -h.y, -h.z}, {h.x, -h.y, h.z}, {-h.x, -h.y, h.z}, {0, -1, 0});
  add_quad(m, {-h.x, -h.y, h.z}, {h.x, -h.y, h.z}, {h.x, h.y, h.z}, {-h.x, h.y, h.z}, {0, 0, 1});
  add_quad(m, {h.x, -h.y, -h.z}, {-h.x, -h.y, -h.z}, {-h.x, h.y, -h.z}, {h.x, h.y, -h.z}, {0, 0, -1});
  return m;
}

MeshData make_sphere(float radius_m, int segments, int rings) {
  RHOT_PRECONDITION(radius_m > 0.0f && segments >= 3 && rings >= 2, "make_sphere: radius > 0, segments >= 3, rings >= 2");
  std::vector<Ring> r;
  for (int i = 0; i <= rings; ++i) {
    const float polar = kPi * static_cast<float>(i) / static_cast<float>(rings);  // 0 at the top pole
    const float s = i == 0 || i == rings ? 0.0f : std::sin(polar);
    r.push_back({radius_m * s, radius_m * std::cos(polar), s, std::cos(polar)});
  }
  return revolve(r, segments);
}

MeshData make_capsule(float radius_m, float height_m, int segments, int cap_rings) {
  RHOT_PRECONDITION(radius_m > 0.0f && height_m >= 2.0f * radius_m && segments >= 3 && cap_rings >= 1,
                    "make_capsule: radius > 0, height >= 2 radius");
  const float half_cylinder = 0.5f * height_m - radius_m;
  std::vector<Ring> r;
  for (int i = 0; i <= cap_rings; ++i) {  // top hemisphere, pole to equator
    const float polar = 0.5f * kPi * static_cast<float>(i) / static_cast<float>(cap_rings);
    const float s = i == 0 ? 0.0f : std::sin(polar);
    r.push_back({radius_m * s, half_cylinder + radius_m * std::cos(polar), s, std::cos(polar)});
  }
  for (int i = 0; i <= cap_rings; ++i) {  // bottom hemisphere, equator to pole
    const float polar = 0.5f * kPi + 0.5f * kPi * static_cast<float>(i) / static_cast<float>(cap_rings);
    const float s = i == cap_rings ? 0.0f : std::sin(polar);
    r.push_back({radius_m * s, -half_cylinder + radius_m * std::cos(polar), s, std::cos(polar)});
  }
  return revolve(r, segments);
}

MeshData make_plane(glm::vec2 size_m) {
  const glm::vec2 h = size_m * 0.5f;
  MeshData m;
  add_quad(m, {-h.x, 0, h.y}, {h.x, 0, h.y}, {h.x, 0, -h.y}, {-h.x, 0, -h.y}, {0, 1, 0});
  return m;
}

MeshData make_shape_mesh(const MeshShape& shape) {
  if (const auto* b = std::get_if<BoxShape>(&shape)) return make_box(b->size_m);
  if (const auto* s = std::get_if<SphereShape>(&shape)) return make_sphere(s->radius_m);
  if (const auto* c = std::get_if<CapsuleShape>(&shape)) return make_capsule(c->radius_m, c->height_m);
  if (const auto* p = std::get_if<PlaneShape>(&shape)) return make_plane(p->size_m);
  RHOT_PRECONDITION(false, "make_shape_mesh: glTF meshes come from load_gltf_mesh");
  return {};
}

}  // namespace rhot
