#include "engine/mesh/MeshData.h"

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <tuple>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

namespace rhot {
namespace {

constexpr double kPi = std::numbers::pi;

// Volume enclosed by a closed mesh (divergence theorem); positive when faces wind outward.
double signed_volume(const MeshData& m) {
  double v = 0.0;
  for (std::size_t t = 0; t + 2 < m.indices.size(); t += 3) {
    const glm::dvec3 a(m.vertices[m.indices[t]].position);
    const glm::dvec3 b(m.vertices[m.indices[t + 1]].position);
    const glm::dvec3 c(m.vertices[m.indices[t + 2]].position);
    v += glm::dot(a, glm::cross(b, c)) / 6.0;
  }
  return v;
}

glm::vec3 face_normal(const MeshData& m, std::size_t t) {
  const glm::vec3 a = m.vertices[m.indices[t]].position;
  return glm::cross(m.vertices[m.indices[t + 1]].position - a, m.vertices[m.indices[t + 2]].position - a);
}

// Every index in range, every normal unit length, no zero-area triangle, and every triangle
// winding counter-clockwise seen from the side its vertices' normals point to.
void expect_well_formed(const MeshData& m) {
  ASSERT_FALSE(m.indices.empty());
  ASSERT_EQ(m.indices.size() % 3, 0u);
  for (const std::uint32_t i : m.indices) ASSERT_LT(i, m.vertices.size());
  for (const Vertex& v : m.vertices) EXPECT_NEAR(glm::length(v.normal), 1.0f, 1e-5f);
  for (std::size_t t = 0; t < m.indices.size(); t += 3) {
    const glm::vec3 face = face_normal(m, t);
    ASSERT_GT(glm::length(face), 0.0f) << "triangle " << t / 3 << " is degenerate";
    const glm::vec3 normals = m.vertices[m.indices[t]].normal + m.vertices[m.indices[t + 1]].normal + m.vertices[m.indices[t + 2]].normal;
    EXPECT_GT(glm::dot(face, normals), 0.0f) << "triangle " << t / 3 << " winds against its normals";
  }
}

// For a convex mesh around the origin: every face points away from the centre.
void expect_faces_outward(const MeshData& m) {
  for (std::size_t t = 0; t < m.indices.size(); t += 3) {
    const glm::vec3 centroid =
        (m.vertices[m.indices[t]].position + m.vertices[m.indices[t + 1]].position + m.vertices[m.indices[t + 2]].position) / 3.0f;
    EXPECT_GT(glm::dot(face_normal(m, t), centroid), 0.0f) << "triangle " << t / 3 << " faces inward";
  }
}

// Closed and consistently wound: welding vertices by position, every directed edge a->b is
// matched by exactly one b->a.
void expect_closed(const MeshData& m) {
  using Key = std::tuple<float, float, float>;
  auto key = [&](std::uint32_t i) {
    const glm::vec3 p = m.vertices[i].position + 0.0f;  // -0 and +0 weld
    return Key{p.x, p.y, p.z};
  };
  std::map<std::pair<Key, Key>, int> edges;
  for (std::size_t t = 0; t < m.indices.size(); t += 3) {
    for (std::size_t k = 0; k < 3; ++k) ++edges[{key(m.indices[t + k]), key(m.indices[t + (k + 1) % 3])}];
  }
  for (const auto& [edge, count] : edges) {
    EXPECT_EQ(count, 1);
    const auto reverse = edges.find({edge.second, edge.first});
    ASSERT_NE(reverse, edges.end()) << "an edge has no opposite: the mesh has a hole";
    EXPECT_EQ(reverse->second, 1);
  }
}

glm::vec3 extent(const MeshData& m) {
  glm::vec3 lo(std::numeric_limits<float>::max()), hi(std::numeric_limits<float>::lowest());
  for (const Vertex& v : m.vertices) {
    lo = glm::min(lo, v.position);
    hi = glm::max(hi, v.position);
  }
  return hi - lo;
}

TEST(Primitives, BoxIsClosedWithExactVolumeSizeAndFlatNormals) {
  const MeshData m = make_box({0.2f, 0.1f, 0.4f});
  expect_well_formed(m);
  expect_faces_outward(m);
  expect_closed(m);
  EXPECT_EQ(m.vertices.size(), 24u);
  EXPECT_EQ(m.indices.size(), 36u);
  EXPECT_NEAR(signed_volume(m), 0.2 * 0.1 * 0.4, 1e-9);
  const glm::vec3 e = extent(m);
  EXPECT_FLOAT_EQ(e.x, 0.2f);
  EXPECT_FLOAT_EQ(e.y, 0.1f);
  EXPECT_FLOAT_EQ(e.z, 0.4f);
  for (std::size_t t = 0; t < m.indices.size(); t += 3) {  // flat: each corner carries the face normal
    for (std::size_t k = 0; k < 3; ++k) EXPECT_EQ(m.vertices[m.indices[t + k]].normal, glm::normalize(face_normal(m, t)));
  }
}

// The tessellation is inscribed (every vertex on the surface), so its volume is a little below
// the exact one and converges to it as segments and rings grow.
TEST(Primitives, SphereHasItsRadiusSmoothNormalsAndConvergingVolume) {
  const float r = 0.05f;
  const MeshData m = make_sphere(r);
  expect_well_formed(m);
  expect_faces_outward(m);
  expect_closed(m);
  const double exact = 4.0 / 3.0 * kPi * std::pow(static_cast<double>(r), 3);
  const double coarse = signed_volume(m) / exact;
  const double fine = signed_volume(make_sphere(r, 256, 128)) / exact;
  EXPECT_LT(coarse, 1.0);
  EXPECT_GT(coarse, 0.98);
  EXPECT_LT(fine, 1.0);
  EXPECT_GT(fine, 0.999);
  const glm::vec3 e = extent(m);
  EXPECT_NEAR(e.x, 2 * r, 1e-6f);
  EXPECT_NEAR(e.y, 2 * r, 1e-6f);
  EXPECT_NEAR(e.z, 2 * r, 1e-6f);
  for (const Vertex& v : m.vertices) {
    EXPECT_NEAR(glm::length(v.position), r, 1e-6f);
    EXPECT_LT(glm::distance(v.normal, v.position / r), 1e-5f);  // smooth: the exact surface normal
  }
}

TEST(Primitives, OddTessellationsAreStillWellFormed) {
  for (const auto& [segments, rings] : {std::pair{3, 2}, {5, 3}, {7, 9}}) {
    SCOPED_TRACE(::testing::Message() << segments << " x " << rings);
    const MeshData sphere = make_sphere(1.0f, segments, rings);
    expect_well_formed(sphere);
    expect_faces_outward(sphere);
    expect_closed(sphere);
    const MeshData capsule = make_capsule(0.5f, 2.0f, segments, rings / 2 + 1);
    expect_well_formed(capsule);
    expect_faces_outward(capsule);
    expect_closed(capsule);
  }
}

// Capsule ground truth: every vertex is r from the axis segment, its normal points straight away
// from the nearest point of that segment, and the volume is a cylinder plus a sphere.
void expect_capsule(float r, float h, double max_volume_error) {
  SCOPED_TRACE(::testing::Message() << "radius " << r << ", height " << h);
  const MeshData m = make_capsule(r, h);
  expect_well_formed(m);
  expect_faces_outward(m);
  expect_closed(m);
  const float half = 0.5f * h - r;
  for (const Vertex& v : m.vertices) {
    const glm::vec3 on_axis(0.0f, glm::clamp(v.position.y, -half, half), 0.0f);
    EXPECT_NEAR(glm::distance(v.position, on_axis), r, 1e-6f);
    EXPECT_LT(glm::distance(v.normal, (v.position - on_axis) / r), 1e-4f);
  }
  const glm::vec3 e = extent(m);
  EXPECT_NEAR(e.x, 2 * r, 1e-6f);
  EXPECT_NEAR(e.y, h, 1e-6f);
  EXPECT_NEAR(e.z, 2 * r, 1e-6f);
  const auto rd = static_cast<double>(r);
  const double exact = kPi * rd * rd * (static_cast<double>(h) - 2.0 * rd) + 4.0 / 3.0 * kPi * rd * rd * rd;
  const double ratio = signed_volume(m) / exact;
  EXPECT_LT(ratio, 1.0);
  EXPECT_GT(ratio, 1.0 - max_volume_error);
  EXPECT_GT(signed_volume(make_capsule(r, h, 256, 64)) / exact, 0.999);
}

TEST(Primitives, CapsuleIsACylinderBetweenTwoHemispheres) {
  expect_capsule(0.03f, 0.18f, 0.03);
  expect_capsule(0.25f, 1.0f, 0.03);
  expect_capsule(0.03f, 2 * 0.03f, 0.03);  // no cylinder: a sphere, with no degenerate band at the equator
}

TEST(Primitives, PlaneFacesUp) {
  const MeshData m = make_plane({4.0f, 2.0f});
  expect_well_formed(m);
  EXPECT_EQ(m.vertices.size(), 4u);
  EXPECT_EQ(m.indices.size(), 6u);
  for (const Vertex& v : m.vertices) {
    EXPECT_EQ(v.normal, glm::vec3(0, 1, 0));
    EXPECT_EQ(v.position.y, 0.0f);
  }
  for (std::size_t t = 0; t < m.indices.size(); t += 3) EXPECT_GT(face_normal(m, t).y, 0.0f);
  EXPECT_FLOAT_EQ(extent(m).x, 4.0f);
  EXPECT_FLOAT_EQ(extent(m).z, 2.0f);
}

TEST(Primitives, ShapeMeshMatchesSceneShape) {
  EXPECT_NEAR(signed_volume(make_shape_mesh(BoxShape{{1, 2, 3}})), 6.0, 1e-6);
  EXPECT_NEAR(extent(make_shape_mesh(SphereShape{0.5f})).x, 1.0f, 1e-5f);
  EXPECT_NEAR(extent(make_shape_mesh(CapsuleShape{0.1f, 0.5f})).y, 0.5f, 1e-6f);
  EXPECT_FLOAT_EQ(extent(make_shape_mesh(PlaneShape{{3.0f, 5.0f}})).z, 5.0f);
}

TEST(PrimitivesDeathTest, ContractViolationsAbortWithAMessage) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_DEATH(make_shape_mesh(GltfMeshShape{"/tmp/x.gltf"}), "precondition.*load_gltf_mesh");
  EXPECT_DEATH(make_capsule(0.5f, 0.9f), "precondition.*make_capsule");
  EXPECT_DEATH(make_sphere(0.0f), "precondition.*make_sphere");
}

// ---- glTF ------------------------------------------------------------------------------------

template <typename T>
std::string bytes_of(const std::vector<T>& values) {
  std::string out(values.size() * sizeof(T), '\0');
  std::memcpy(out.data(), values.data(), out.size());
  return out;
}

std::string base64(const std::string& bytes) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    std::uint32_t n = std::uint32_t{static_cast<std::uint8_t>(bytes[i])} << 16;
    if (i + 1 < bytes.size()) n |= std::uint32_t{static_cast<std::uint8_t>(bytes[i + 1])} << 8;
    if (i + 2 < bytes.size()) n |= std::uint32_t{static_cast<std::uint8_t>(bytes[i + 2])};
    out += k[(n >> 18) & 63];
    out += k[(n >> 12) & 63];
    out += i + 1 < bytes.size() ? k[(n >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? k[n & 63] : '=';
  }
  return out;
}

// Builds a glTF file around one binary buffer: add data, views and accessors, then give the
// scenes, nodes and meshes as JSON members.
struct GltfBuilder {
  std::string bin;
  std::vector<std::string> views;
  std::vector<std::string> accessors;

  int view(const std::string& bytes, int stride = 0) {
    while (bin.size() % 4 != 0) bin += '\0';
    views.push_back(R"({"buffer": 0, "byteOffset": )" + std::to_string(bin.size()) + R"(, "byteLength": )" + std::to_string(bytes.size()) +
                    (stride != 0 ? R"(, "byteStride": )" + std::to_string(stride) : "") + "}");
    bin += bytes;
    return static_cast<int>(views.size()) - 1;
  }
  int accessor(int view_index, int component_type, std::size_t count, const char* type, std::size_t offset = 0) {
    accessors.push_back(R"({"bufferView": )" + std::to_string(view_index) + R"(, "byteOffset": )" + std::to_string(offset) +
                        R"(, "componentType": )" + std::to_string(component_type) + R"(, "count": )" + std::to_string(count) +
                        R"(, "type": ")" + type + R"("})");
    return static_cast<int>(accessors.size()) - 1;
  }
  // embed: the buffer as a base64 data URI; otherwise no URI (a GLB's BIN chunk).
  std::string json(const std::string& members, bool embed = true) const {
    auto list = [](const std::vector<std::string>& items) {
      std::string out;
      for (const std::string& s : items) out += (out.empty() ? "" : ", ") + s;
      return "[" + out + "]";
    };
    const std::string uri = embed ? R"(, "uri": "data:application/octet-stream;base64,)" + base64(bin) + "\"" : "";
    return R"({"asset": {"version": "2.0"}, )" + members + R"(, "buffers": [{"byteLength": )" + std::to_string(bin.size()) + uri +
           "}], \"bufferViews\": " + list(views) + ", \"accessors\": " + list(accessors) + "}";
  }
};

constexpr int kFloat = 5126;
constexpr int kUByte = 5121;
constexpr int kUShort = 5123;
constexpr int kUInt = 5125;

// One triangle (three float positions, then three uint16 indices), a node moving it by +1 in x,
// and the primitive mode given.
std::string triangle_gltf(std::uint16_t last_index = 2, int mode = 4, float x = 0.0f, bool embed = true, std::string* bin = nullptr) {
  GltfBuilder b;
  const int pos = b.accessor(b.view(bytes_of<float>({x, 0, 0, 1, 0, 0, 0, 1, 0})), kFloat, 3, "VEC3");
  const int idx = b.accessor(b.view(bytes_of<std::uint16_t>({0, 1, last_index})), kUShort, 3, "SCALAR");
  if (bin != nullptr) *bin = b.bin;
  return b.json(R"("scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0, "translation": [1, 0, 0]}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": )" +
                    std::to_string(pos) + R"(}, "indices": )" + std::to_string(idx) + R"(, "mode": )" + std::to_string(mode) + "}]}]",
                embed);
}

// A mesh as a glTF primitive: positions and normals interleaved in one view (byteStride 24), then
// uint32 indices. Returns the primitive's JSON.
std::string add_interleaved(GltfBuilder& b, const MeshData& m) {
  std::vector<float> interleaved;
  for (const Vertex& v : m.vertices) {
    interleaved.insert(interleaved.end(), {v.position.x, v.position.y, v.position.z, v.normal.x, v.normal.y, v.normal.z});
  }
  const int view = b.view(bytes_of(interleaved), 24);
  const int pos = b.accessor(view, kFloat, m.vertices.size(), "VEC3", 0);
  const int nrm = b.accessor(view, kFloat, m.vertices.size(), "VEC3", 12);
  const int idx = b.accessor(b.view(bytes_of(m.indices)), kUInt, m.indices.size(), "SCALAR");
  return R"({"attributes": {"POSITION": )" + std::to_string(pos) + R"(, "NORMAL": )" + std::to_string(nrm) + R"(}, "indices": )" +
         std::to_string(idx) + "}";
}

class GltfFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::path(::testing::TempDir()) / "rhot_gltf_test" / ::testing::UnitTest::GetInstance()->current_test_info()->name();
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  std::filesystem::path write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name, std::ios::binary) << text;
    return dir_ / name;
  }
  // The error of loading `text` as `name`, which must fail.
  std::string error_of(const std::string& name, const std::string& text) {
    const auto m = load_gltf_mesh(write(name, text));
    EXPECT_FALSE(m.has_value()) << name << " loaded";
    return m.has_value() ? std::string() : m.error();
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::filesystem::path dir_;
};

TEST_F(GltfFiles, LoadsATriangleWithItsNodeTransformAndFlatNormals) {
  const auto m = load_gltf_mesh(write("tri.gltf", triangle_gltf()));
  ASSERT_TRUE(m.has_value()) << m.error();
  ASSERT_EQ(m->indices.size(), 3u);
  EXPECT_EQ(m->vertices[m->indices[0]].position, glm::vec3(1, 0, 0));
  EXPECT_EQ(m->vertices[m->indices[1]].position, glm::vec3(2, 0, 0));
  EXPECT_EQ(m->vertices[m->indices[2]].position, glm::vec3(1, 1, 0));
  for (const Vertex& v : m->vertices) EXPECT_EQ(v.normal, glm::vec3(0, 0, 1));
}

// A cube with interleaved normals under two nodes: the parent turns 90 degrees about +Y and
// stretches x by 2 (TRS), the child moves by (0, 3, 0) (matrix). The stretch is non-uniform, so
// only inverse-transpose normals stay perpendicular to the faces.
TEST_F(GltfFiles, AppliesTheNodeHierarchyToPositionsAndNormals) {
  const MeshData cube = make_box(glm::vec3(1.0f));
  GltfBuilder b;
  const std::string primitive = add_interleaved(b, cube);
  const auto m = load_gltf_mesh(write("cube.gltf", b.json(R"("scenes": [{"nodes": [0]}], "nodes": [
      {"rotation": [0, 0.70710678, 0, 0.70710678], "scale": [2, 1, 1], "children": [1]},
      {"matrix": [1, 0, 0, 0,  0, 1, 0, 0,  0, 0, 1, 0,  0, 3, 0, 1], "mesh": 0}],
    "meshes": [{"primitives": [)" + primitive + "]}]")));
  ASSERT_TRUE(m.has_value()) << m.error();
  const glm::mat4 world_from_mesh = glm::scale(glm::rotate(glm::mat4(1.0f), 0.5f * std::numbers::pi_v<float>, {0, 1, 0}), {2, 1, 1}) *
                                    glm::translate(glm::mat4(1.0f), {0, 3, 0});
  ASSERT_EQ(m->vertices.size(), cube.vertices.size());
  ASSERT_EQ(m->indices, cube.indices);
  for (std::size_t i = 0; i < cube.vertices.size(); ++i) {
    const glm::vec3 expected(world_from_mesh * glm::vec4(cube.vertices[i].position, 1.0f));
    EXPECT_LT(glm::distance(m->vertices[i].position, expected), 1e-5f) << "vertex " << i;
  }
  expect_well_formed(*m);
  expect_closed(*m);
  for (std::size_t t = 0; t < m->indices.size(); t += 3) {  // normals still perpendicular to the faces
    EXPECT_LT(glm::distance(m->vertices[m->indices[t]].normal, glm::normalize(face_normal(*m, t))), 1e-5f);
  }
  EXPECT_NEAR(signed_volume(*m), 2.0, 1e-5);
}

// A mirroring node (negative determinant) flips glTF's winding; the loader keeps front faces
// counter-clockwise and normals outward.
TEST_F(GltfFiles, MirroredNodesKeepFacesOutward) {
  GltfBuilder b;
  const std::string primitive = add_interleaved(b, make_sphere(1.0f, 8, 4));
  const auto m = load_gltf_mesh(write("mirror.gltf", b.json(R"("scenes": [{"nodes": [0]}],
    "nodes": [{"scale": [-1, 1, 1], "translation": [5, 0, 0], "mesh": 0}],
    "meshes": [{"primitives": [)" + primitive + "]}]")));
  ASSERT_TRUE(m.has_value()) << m.error();
  expect_well_formed(*m);
  expect_closed(*m);
  EXPECT_GT(signed_volume(*m), 0.0);
  for (const Vertex& v : m->vertices) EXPECT_LT(glm::distance(v.normal, v.position - glm::vec3(5, 0, 0)), 1e-5f);
}

// Byte indices, a non-indexed primitive and a POINTS primitive (skipped) in one mesh, with no
// scene: the root nodes are drawn.
TEST_F(GltfFiles, ReadsByteIndicesAndNonIndexedPrimitivesAndSkipsOthers) {
  GltfBuilder b;
  const int pos = b.accessor(b.view(bytes_of<float>({0, 0, 0, 1, 0, 0, 0, 1, 0})), kFloat, 3, "VEC3");
  const int idx = b.accessor(b.view(bytes_of<std::uint8_t>({0, 1, 2})), kUByte, 3, "SCALAR");
  const std::string p = std::to_string(pos);
  const auto m = load_gltf_mesh(write("mixed.gltf", b.json(R"("nodes": [{"mesh": 0, "translation": [0, 0, -2]}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": )" +
                                                           p + R"(}, "indices": )" + std::to_string(idx) + R"(},
                               {"attributes": {"POSITION": )" +
                                                           p + R"(}, "mode": 0},
                               {"attributes": {"POSITION": )" +
                                                           p + "}}]}]")));
  ASSERT_TRUE(m.has_value()) << m.error();
  ASSERT_EQ(m->indices.size(), 6u);
  expect_well_formed(*m);
  for (const Vertex& v : m->vertices) EXPECT_EQ(v.position.z, -2.0f);
}

TEST_F(GltfFiles, LoadsGlbWithABinChunk) {
  std::string bin;
  std::string json = triangle_gltf(2, 4, 0.0f, /*embed=*/false, &bin);
  while (json.size() % 4 != 0) json += ' ';
  while (bin.size() % 4 != 0) bin += '\0';
  auto u32 = [](std::size_t v) { return bytes_of<std::uint32_t>({static_cast<std::uint32_t>(v)}); };
  const std::string glb = "glTF" + u32(2) + u32(12 + 8 + json.size() + 8 + bin.size()) + u32(json.size()) + "JSON" + json +
                          u32(bin.size()) + std::string("BIN\0", 4) + bin;
  const auto m = load_gltf_mesh(write("tri.glb", glb));
  ASSERT_TRUE(m.has_value()) << m.error();
  ASSERT_EQ(m->indices.size(), 3u);
  EXPECT_EQ(m->vertices[m->indices[2]].position, glm::vec3(1, 1, 0));

  const std::string truncated = error_of("truncated.glb", glb.substr(0, glb.size() - 8));
  EXPECT_EQ(truncated.rfind(path("truncated.glb") + ": not a readable glTF 2.0 file: ", 0), 0u) << truncated;
}

TEST_F(GltfFiles, BadFilesGiveMessagesNamingThem) {
  const auto missing = load_gltf_mesh(dir_ / "none.gltf");
  ASSERT_FALSE(missing.has_value());
  EXPECT_EQ(missing.error(), path("none.gltf") + ": file not found");

  const std::string junk = error_of("junk.gltf", "this is not json");
  EXPECT_EQ(junk.rfind(path("junk.gltf") + ": not a readable glTF 2.0 file: ", 0), 0u) << junk;
  EXPECT_GT(junk.size(), (path("junk.gltf") + ": not a readable glTF 2.0 file: ").size());  // tinygltf's reason

  EXPECT_EQ(error_of("bad_index.gltf", triangle_gltf(7)),
            path("bad_index.gltf") + ": mesh 0 primitive 0: index 7 is out of range (3 vertices)");
  EXPECT_EQ(error_of("points.gltf", triangle_gltf(2, 0)), path("points.gltf") + ": no triangle primitives");
  EXPECT_EQ(error_of("nan.gltf", triangle_gltf(2, 4, std::numeric_limits<float>::quiet_NaN())),
            path("nan.gltf") + ": mesh 0 primitive 0: POSITION 0 is not finite");
}

TEST_F(GltfFiles, MalformedStructureIsRefusedNotTrusted) {
  GltfBuilder b;
  const int view = b.view(bytes_of<float>({0, 0, 0, 1, 0, 0, 0, 1, 0}));
  const int pos = b.accessor(view, kFloat, 3, "VEC3");
  const int too_many = b.accessor(view, kFloat, 4, "VEC3");
  const int far = b.accessor(view, kFloat, 1, "VEC3", std::size_t{1} << 62);
  const int as_ints = b.accessor(view, kUInt, 3, "VEC3");
  auto with = [&](const std::string& nodes, int accessor) {
    return b.json(R"("scenes": [{"nodes": [0]}], "nodes": )" + nodes + R"(,
      "meshes": [{"primitives": [{"attributes": {"POSITION": )" +
                  std::to_string(accessor) + "}}]}]");
  };
  const std::string one_node = R"([{"mesh": 0}])";
  EXPECT_EQ(error_of("count.gltf", with(one_node, too_many)),
            path("count.gltf") + ": mesh 0 primitive 0: POSITION accessor 1 runs past the end of its bufferView");
  EXPECT_EQ(error_of("offset.gltf", with(one_node, far)),
            path("offset.gltf") + ": mesh 0 primitive 0: POSITION accessor 2 runs past the end of its bufferView");
  EXPECT_EQ(error_of("type.gltf", with(one_node, as_ints)),
            path("type.gltf") + ": mesh 0 primitive 0: POSITION accessor 3 is not float VEC3");
  EXPECT_EQ(error_of("cycle.gltf", with(R"([{"mesh": 0, "children": [1]}, {"children": [0]}])", pos)),
            path("cycle.gltf") + ": node 0 is reached twice (a cycle, or a node with two parents)");
  EXPECT_EQ(error_of("child.gltf", with(R"([{"mesh": 0, "children": [9]}])", pos)),
            path("child.gltf") + ": node index 9 is out of range (1 nodes)");
}

}  // namespace
}  // namespace rhot
