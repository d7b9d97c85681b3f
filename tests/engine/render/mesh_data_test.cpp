#include "engine/render/MeshData.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include <gtest/gtest.h>

namespace rhot {
namespace {

// Volume enclosed by a closed mesh (divergence theorem); positive when faces wind outward.
double signed_volume(const MeshData& m) {
  double v = 0.0;
  for (std::size_t t = 0; t < m.indices.size(); t += 3) {
    const glm::dvec3 a(m.vertices[m.indices[t]].position);
    const glm::dvec3 b(m.vertices[m.indices[t + 1]].position);
    const glm::dvec3 c(m.vertices[m.indices[t + 2]].position);
    v += glm::dot(a, glm::cross(b, c)) / 6.0;
  }
  return v;
}

// Every index in range, every normal unit length, and every triangle's winding agreeing with its
// vertices' normals (counter-clockwise seen from the side the normals point to).
void expect_well_formed(const MeshData& m) {
  ASSERT_FALSE(m.indices.empty());
  ASSERT_EQ(m.indices.size() % 3, 0u);
  for (const std::uint32_t i : m.indices) ASSERT_LT(i, m.vertices.size());
  for (const Vertex& v : m.vertices) EXPECT_NEAR(glm::length(v.normal), 1.0f, 1e-5f);
  for (std::size_t t = 0; t < m.indices.size(); t += 3) {
    const Vertex& a = m.vertices[m.indices[t]];
    const Vertex& b = m.vertices[m.indices[t + 1]];
    const Vertex& c = m.vertices[m.indices[t + 2]];
    const glm::vec3 face = glm::cross(b.position - a.position, c.position - a.position);
    if (glm::length(face) < 1e-12f) continue;  // degenerate at a pole
    EXPECT_GT(glm::dot(face, a.normal + b.normal + c.normal), 0.0f) << "triangle " << t / 3 << " winds inward";
  }
}

glm::vec3 extent(const MeshData& m) {
  glm::vec3 lo(1e9f), hi(-1e9f);
  for (const Vertex& v : m.vertices) {
    lo = glm::min(lo, v.position);
    hi = glm::max(hi, v.position);
  }
  return hi - lo;
}

TEST(Primitives, BoxIsClosedWithExactVolumeAndSize) {
  const MeshData m = make_box({0.2f, 0.1f, 0.4f});
  expect_well_formed(m);
  EXPECT_NEAR(signed_volume(m), 0.2 * 0.1 * 0.4, 1e-9);
  const glm::vec3 e = extent(m);
  EXPECT_FLOAT_EQ(e.x, 0.2f);
  EXPECT_FLOAT_EQ(e.y, 0.1f);
  EXPECT_FLOAT_EQ(e.z, 0.4f);
}

// The tessellation is inscribed (every vertex on the surface), so its volume is a little below
// the exact one and converges to it as segments and rings grow.
TEST(Primitives, SphereVolumeConvergesFromBelow) {
  const MeshData m = make_sphere(0.05f);
  expect_well_formed(m);
  const double exact = 4.0 / 3.0 * std::numbers::pi * std::pow(0.05, 3);
  const double coarse = signed_volume(m) / exact;
  const double fine = signed_volume(make_sphere(0.05f, 256, 128)) / exact;
  EXPECT_LT(coarse, 1.0);
  EXPECT_GT(coarse, 0.96);
  EXPECT_LT(fine, 1.0);
  EXPECT_GT(fine, 0.999);
  EXPECT_NEAR(extent(m).y, 0.1f, 1e-6f);
  for (const Vertex& v : m.vertices) EXPECT_NEAR(glm::length(v.position), 0.05f, 1e-6f);
}

TEST(Primitives, CapsuleVolumeConvergesFromBelow) {
  const float r = 0.03f;
  const float h = 0.18f;
  const MeshData m = make_capsule(r, h);
  expect_well_formed(m);
  const double pi = std::numbers::pi;
  const double rd = r;
  const double hd = h;
  const double exact = pi * rd * rd * (hd - 2.0 * rd) + 4.0 / 3.0 * pi * rd * rd * rd;
  EXPECT_LT(signed_volume(m) / exact, 1.0);
  EXPECT_GT(signed_volume(m) / exact, 0.96);
  EXPECT_GT(signed_volume(make_capsule(r, h, 256, 64)) / exact, 0.999);
  EXPECT_NEAR(extent(m).y, h, 1e-6f);
  EXPECT_NEAR(extent(m).x, 2 * r, 1e-6f);
  // A capsule of height 2r is a sphere.
  EXPECT_NEAR(signed_volume(make_capsule(r, 2 * r, 256, 64)) / (4.0 / 3.0 * pi * rd * rd * rd), 1.0, 0.001);
}

TEST(Primitives, PlaneFacesUp) {
  const MeshData m = make_plane({4.0f, 2.0f});
  expect_well_formed(m);
  EXPECT_EQ(m.indices.size(), 6u);
  for (const Vertex& v : m.vertices) EXPECT_EQ(v.normal, glm::vec3(0, 1, 0));
  EXPECT_FLOAT_EQ(extent(m).x, 4.0f);
  EXPECT_FLOAT_EQ(extent(m).z, 2.0f);
}

TEST(Primitives, ShapeMeshMatchesSceneShape) {
  EXPECT_NEAR(signed_volume(make_shape_mesh(BoxShape{{1, 2, 3}})), 6.0, 1e-6);
  EXPECT_NEAR(extent(make_shape_mesh(SphereShape{0.5f})).x, 1.0f, 1e-5f);
}

// ---- glTF ------------------------------------------------------------------------------------

class GltfFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::path(::testing::TempDir()) / "rhot_gltf_test" /
           ::testing::UnitTest::GetInstance()->current_test_info()->name();
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  std::filesystem::path write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name, std::ios::binary) << text;
    return dir_ / name;
  }
  std::filesystem::path dir_;
};

std::string base64(const std::string& bytes) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    std::uint32_t n = static_cast<std::uint8_t>(bytes[i]) << 16;
    if (i + 1 < bytes.size()) n |= static_cast<std::uint8_t>(bytes[i + 1]) << 8;
    if (i + 2 < bytes.size()) n |= static_cast<std::uint8_t>(bytes[i + 2]);
    out += k[(n >> 18) & 63];
    out += k[(n >> 12) & 63];
    out += i + 1 < bytes.size() ? k[(n >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? k[n & 63] : '=';
  }
  return out;
}

// One triangle (three float positions, then three uint16 indices), a node moving it by +1 in x,
// and the primitive mode given.
std::string triangle_gltf(std::uint16_t last_index = 2, int mode = 4) {
  const float positions[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const std::uint16_t indices[3] = {0, 1, last_index};
  std::string buffer(reinterpret_cast<const char*>(positions), sizeof(positions));
  buffer.append(reinterpret_cast<const char*>(indices), sizeof(indices));
  return R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
    "nodes": [{"mesh": 0, "translation": [1, 0, 0]}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": )" +
         std::to_string(mode) + R"(}]}],
    "buffers": [{"byteLength": 42, "uri": "data:application/octet-stream;base64,)" + base64(buffer) + R"("}],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
                  {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]})";
}

TEST_F(GltfFiles, LoadsATriangleWithItsNodeTransformAndFlatNormals) {
  const auto m = load_gltf_mesh(write("tri.gltf", triangle_gltf()));
  ASSERT_TRUE(m.has_value()) << m.error();
  ASSERT_EQ(m->indices.size(), 3u);
  EXPECT_EQ(m->vertices[m->indices[0]].position, glm::vec3(1, 0, 0));
  EXPECT_EQ(m->vertices[m->indices[1]].position, glm::vec3(2, 0, 0));
  EXPECT_EQ(m->vertices[m->indices[2]].position, glm::vec3(1, 1, 0));
  for (const Vertex& v : m->vertices) EXPECT_EQ(v.normal, glm::vec3(0, 0, 1));
}

TEST_F(GltfFiles, LoadsGlb) {
  std::string json = triangle_gltf();
  while (json.size() % 4 != 0) json += ' ';
  auto u32 = [](std::uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); };
  const std::string glb = "glTF" + u32(2) + u32(static_cast<std::uint32_t>(12 + 8 + json.size())) +
                          u32(static_cast<std::uint32_t>(json.size())) + "JSON" + json;
  const auto m = load_gltf_mesh(write("tri.glb", glb));
  ASSERT_TRUE(m.has_value()) << m.error();
  EXPECT_EQ(m->indices.size(), 3u);
}

TEST_F(GltfFiles, BadFilesGiveMessagesNamingThem) {
  const auto missing = load_gltf_mesh(dir_ / "none.gltf");
  ASSERT_FALSE(missing.has_value());
  EXPECT_EQ(missing.error(), (dir_ / "none.gltf").string() + ": file not found");

  const auto junk = load_gltf_mesh(write("junk.gltf", "this is not json"));
  ASSERT_FALSE(junk.has_value());
  EXPECT_EQ(junk.error().rfind((dir_ / "junk.gltf").string() + ": not a readable glTF 2.0 file: ", 0), 0u) << junk.error();

  const auto out_of_range = load_gltf_mesh(write("bad_index.gltf", triangle_gltf(7)));
  ASSERT_FALSE(out_of_range.has_value());
  EXPECT_EQ(out_of_range.error(), (dir_ / "bad_index.gltf").string() + ": index 7 is out of range (3 vertices)");

  const auto points = load_gltf_mesh(write("points.gltf", triangle_gltf(2, 0)));
  ASSERT_FALSE(points.has_value());
  EXPECT_EQ(points.error(), (dir_ / "points.gltf").string() + ": no triangle primitives");
}

}  // namespace
}  // namespace rhot
