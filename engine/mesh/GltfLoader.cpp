// load_gltf_mesh: tinygltf parses the file (Debian ships it as a shared library, libtinygltf, so
// no TINYGLTF_IMPLEMENTATION here and no stb symbols of its own); everything after parsing treats
// the model as untrusted: every index, offset and count is checked before it is used.

#include "engine/mesh/MeshData.h"

#include <cmath>
#include <cstring>
#include <exception>
#include <fstream>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <tiny_gltf.h>

namespace rhot {

namespace {

// Thrown while reading the parsed model, caught in load_gltf_mesh, which adds the file name.
struct Failure {
  std::string message;
};

template <typename T>
const T& at(const std::vector<T>& items, int index, const char* what) {
  if (index < 0 || static_cast<std::size_t>(index) >= items.size()) {
    throw Failure{std::string(what) + " index " + std::to_string(index) + " is out of range (" + std::to_string(items.size()) + " " + what +
                  "s)"};
  }
  return items[static_cast<std::size_t>(index)];
}

template <typename V>
bool finite(const V& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// parent_from_node: the node's matrix, or translation * rotation * scale.
glm::dmat4 node_matrix(const tinygltf::Node& node) {
  if (node.matrix.size() == 16) {
    glm::dmat4 m;
    for (std::size_t i = 0; i < 16; ++i) glm::value_ptr(m)[i] = node.matrix[i];  // column-major, as glTF
    return m;
  }
  glm::dmat4 m(1.0);
  const auto& t = node.translation;
  const auto& r = node.rotation;
  const auto& s = node.scale;
  if (t.size() == 3) m = glm::translate(m, glm::dvec3(t[0], t[1], t[2]));
  if (r.size() == 4) m *= glm::mat4_cast(glm::normalize(glm::dquat(r[3], r[0], r[1], r[2])));  // glTF: x, y, z, w
  if (s.size() == 3) m = glm::scale(m, glm::dvec3(s[0], s[1], s[2]));
  return m;
}

// The elements of one accessor, all proven to lie inside their buffer view and buffer.
struct Elements {
  const unsigned char* first = nullptr;
  std::size_t stride = 0;
  std::size_t count = 0;

  template <typename T>
  T get(std::size_t i) const {
    T value;
    std::memcpy(&value, first + i * stride, sizeof(T));
    return value;
  }
};

// Checks that every element of the accessor (`size` bytes each) lies inside its buffer view
// and buffer. Types are the caller's to check.
Elements elements(const tinygltf::Model& model, int accessor_index, std::size_t size, const std::string& name) {
  const tinygltf::Accessor& accessor = at(model.accessors, accessor_index, "accessor");
  if (accessor.sparse.isSparse) throw Failure{name + " is sparse (not supported)"};
  Elements out;
  out.count = accessor.count;
  if (out.count == 0) return out;
  const tinygltf::BufferView& view = at(model.bufferViews, accessor.bufferView, "bufferView");
  const tinygltf::Buffer& buffer = at(model.buffers, view.buffer, "buffer");
  out.stride = view.byteStride != 0 ? view.byteStride : size;
  if (out.stride < size) throw Failure{name + ": byteStride " + std::to_string(out.stride) + " is less than an element"};
  // Offsets and counts come from the file: compare without sums that could wrap.
  const std::size_t bytes = buffer.data.size();
  const std::size_t length = view.byteLength;
  if (length > bytes || view.byteOffset > bytes - length) {
    throw Failure{"bufferView " + std::to_string(accessor.bufferView) + " runs past the end of its buffer"};
  }
  if (accessor.byteOffset > length || size > length - accessor.byteOffset ||
      out.count - 1 > (length - accessor.byteOffset - size) / out.stride) {
    throw Failure{name + " runs past the end of its bufferView"};
  }
  out.first = buffer.data.data() + view.byteOffset + accessor.byteOffset;
  return out;
}

// A float VEC3 attribute (POSITION or NORMAL).
Elements vec3_elements(const tinygltf::Model& model, int accessor_index, const char* attribute) {
  const std::string name = std::string(attribute) + " accessor " + std::to_string(accessor_index);
  const tinygltf::Accessor& accessor = at(model.accessors, accessor_index, "accessor");
  if (accessor.type != TINYGLTF_TYPE_VEC3 || accessor.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT) {
    throw Failure{name + " is not float VEC3"};
  }
  return elements(model, accessor_index, sizeof(glm::vec3), name);
}

std::string primitive_name(int mesh, std::size_t primitive) {
  return "mesh " + std::to_string(mesh) + " primitive " + std::to_string(primitive);
}

// A primitive's triangle corners, each an index into its `vertex_count` vertices: its indices
// accessor's, or 0, 1, 2, ... without one.
std::vector<std::uint32_t> primitive_corners(const tinygltf::Model& model, const tinygltf::Primitive& prim, std::size_t vertex_count) {
  std::vector<std::uint32_t> corners;
  if (prim.indices < 0) {
    if (vertex_count > std::numeric_limits<std::uint32_t>::max()) throw Failure{"too many vertices"};
    corners.resize(vertex_count);
    for (std::size_t i = 0; i < corners.size(); ++i) corners[i] = static_cast<std::uint32_t>(i);
    return corners;
  }
  const tinygltf::Accessor& accessor = at(model.accessors, prim.indices, "accessor");
  const std::string name = "indices accessor " + std::to_string(prim.indices);
  std::size_t size = 0;
  switch (accessor.componentType) {
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
      size = 1;
      break;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
      size = 2;
      break;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
      size = 4;
      break;
    default:
      throw Failure{name + " is not unsigned byte, short or int"};
  }
  if (accessor.type != TINYGLTF_TYPE_SCALAR) throw Failure{name + " is not SCALAR"};
  const Elements idx = elements(model, prim.indices, size, name);
  corners.reserve(idx.count);
  for (std::size_t i = 0; i < idx.count; ++i) {
    std::uint32_t v = 0;
    switch (size) {
      case 1:
        v = idx.get<std::uint8_t>(i);
        break;
      case 2:
        v = idx.get<std::uint16_t>(i);
        break;
      default:
        v = idx.get<std::uint32_t>(i);
        break;
    }
    if (v >= vertex_count) throw Failure{"index " + std::to_string(v) + " is out of range (" + std::to_string(vertex_count) + " vertices)"};
    corners.push_back(v);
  }
  return corners;
}

// A primitive's vertices placed by world_from_mesh, their normals (if `normals` has any) turned
// by normal_from_mesh. Returns whether every vertex has a usable normal (smooth shading); false
// falls back to face normals.
bool place_vertices(const Elements& positions, const Elements& normals, const glm::dmat4& world_from_mesh,
                    const glm::dmat3& normal_from_mesh, std::vector<Vertex>& vertices) {
  vertices.resize(positions.count);
  bool smooth = normals.count != 0;
  for (std::size_t i = 0; i < positions.count; ++i) {
    const glm::dvec3 local(positions.get<glm::vec3>(i));
    if (!finite(local)) throw Failure{"POSITION " + std::to_string(i) + " is not finite"};
    vertices[i].position = glm::vec3(world_from_mesh * glm::dvec4(local, 1.0));
    if (!finite(vertices[i].position)) {  // also when it only overflows float
      throw Failure{"POSITION " + std::to_string(i) + " is not finite after the node transforms"};
    }
    if (!smooth) continue;
    const glm::dvec3 n(normals.get<glm::vec3>(i));
    if (!finite(n)) throw Failure{"NORMAL " + std::to_string(i) + " is not finite"};
    const glm::dvec3 turned = normal_from_mesh * n;
    const double length = glm::length(turned);
    if (length > 0.0 && std::isfinite(length)) {
      vertices[i].normal = glm::vec3(turned / length);
    } else {
      smooth = false;  // a zero normal, or one the transform flattened: fall back to faces
    }
  }
  return smooth;
}

// The triangles into `out`: sharing the vertices when smooth, else each with its own three.
void append_triangles(const std::vector<Vertex>& vertices, const std::vector<std::uint32_t>& corners, bool smooth, MeshData& out) {
  if (out.vertices.size() + (smooth ? vertices.size() : corners.size()) > std::numeric_limits<std::uint32_t>::max()) {
    throw Failure{"too many vertices"};
  }
  const auto base = static_cast<std::uint32_t>(out.vertices.size());
  if (smooth) {
    out.vertices.insert(out.vertices.end(), vertices.begin(), vertices.end());
    for (const std::uint32_t c : corners) out.indices.push_back(base + c);
    return;
  }
  // Flat normals: every triangle gets its own three vertices. A zero-area triangle cannot be
  // seen; it keeps the default normal.
  for (std::size_t t = 0; t < corners.size(); t += 3) {
    const glm::vec3 a = vertices[corners[t]].position;
    const glm::vec3 b = vertices[corners[t + 1]].position;
    const glm::vec3 c = vertices[corners[t + 2]].position;
    const glm::dvec3 face = glm::cross(glm::dvec3(b) - glm::dvec3(a), glm::dvec3(c) - glm::dvec3(a));  // no float overflow
    const double length = glm::length(face);
    const glm::vec3 n = length > 0.0 ? glm::vec3(face / length) : Vertex{}.normal;
    for (const glm::vec3& corner : {a, b, c}) {
      out.indices.push_back(static_cast<std::uint32_t>(out.vertices.size()));
      out.vertices.push_back({corner, n});
    }
  }
}

// One triangle primitive into `out` (append_mesh says how it is placed and mirrored).
void append_primitive(const tinygltf::Model& model, const tinygltf::Primitive& prim, const glm::dmat4& world_from_mesh,
                      const glm::dmat3& normal_from_mesh, bool mirrored, MeshData& out) {
  const auto pos_it = prim.attributes.find("POSITION");
  if (pos_it == prim.attributes.end()) throw Failure{"no POSITION attribute"};
  const Elements positions = vec3_elements(model, pos_it->second, "POSITION");
  const auto nrm_it = prim.attributes.find("NORMAL");
  Elements normals;
  if (nrm_it != prim.attributes.end()) {
    normals = vec3_elements(model, nrm_it->second, "NORMAL");
    if (normals.count != positions.count) throw Failure{"NORMAL and POSITION counts differ"};
  }
  std::vector<std::uint32_t> corners = primitive_corners(model, prim, positions.count);
  if (corners.size() % 3 != 0) throw Failure{std::to_string(corners.size()) + " corners are not whole triangles"};
  if (mirrored) {
    for (std::size_t t = 0; t < corners.size(); t += 3) std::swap(corners[t + 1], corners[t + 2]);
  }
  std::vector<Vertex> vertices;
  const bool smooth = place_vertices(positions, normals, world_from_mesh, normal_from_mesh, vertices);
  append_triangles(vertices, corners, smooth, out);
}

// Appends the triangle primitives of one mesh, placed by world_from_mesh. A transform with a
// negative determinant mirrors the mesh; glTF then winds its front faces clockwise, so each
// triangle's last two corners are swapped to keep them counter-clockwise.
void append_mesh(const tinygltf::Model& model, int mesh_index, const glm::dmat4& world_from_mesh, MeshData& out) {
  const tinygltf::Mesh& mesh = at(model.meshes, mesh_index, "mesh");
  const glm::dmat3 linear(world_from_mesh);
  const double det = glm::determinant(linear);
  if (!std::isfinite(det)) throw Failure{"a node transform is not finite"};
  // Normals transform by the cofactor matrix, det * inverse-transpose: the same directions, but
  // defined when the transform flattens the mesh (det == 0). Its sign is fixed to match the swap
  // of corners below, so normals keep pointing outward.
  const glm::dmat3 normal_from_mesh =
      glm::dmat3(glm::cross(linear[1], linear[2]), glm::cross(linear[2], linear[0]), glm::cross(linear[0], linear[1])) *
      (det < 0.0 ? -1.0 : 1.0);
  const bool mirrored = det < 0.0;

  for (std::size_t p = 0; p < mesh.primitives.size(); ++p) {
    const tinygltf::Primitive& prim = mesh.primitives[p];
    if (prim.mode != TINYGLTF_MODE_TRIANGLES && prim.mode != -1) continue;  // -1: unset, i.e. triangles
    const std::string where = primitive_name(mesh_index, p) + ": ";
    try {
      append_primitive(model, prim, world_from_mesh, normal_from_mesh, mirrored, out);
    } catch (const Failure& f) {
      throw Failure{where + f.message};
    }
  }
}

// Walks the node trees under `roots` (without recursion: the depth comes from the file) and
// appends every mesh. glTF nodes form a forest, so a node reached twice means a cycle or a shared
// child, which would otherwise loop forever or blow up exponentially.
void append_nodes(const tinygltf::Model& model, const std::vector<int>& roots, MeshData& out) {
  std::vector<bool> reached(model.nodes.size(), false);
  std::vector<std::pair<int, glm::dmat4>> pending;  // node, world_from_parent
  for (auto it = roots.rbegin(); it != roots.rend(); ++it) pending.emplace_back(*it, glm::dmat4(1.0));
  while (!pending.empty()) {
    const auto [index, world_from_parent] = pending.back();
    pending.pop_back();
    const tinygltf::Node& node = at(model.nodes, index, "node");
    if (reached[static_cast<std::size_t>(index)]) {
      throw Failure{"node " + std::to_string(index) + " is reached twice (a cycle, or a node with two parents)"};
    }
    reached[static_cast<std::size_t>(index)] = true;
    const glm::dmat4 world_from_node = world_from_parent * node_matrix(node);
    if (node.mesh >= 0) append_mesh(model, node.mesh, world_from_node, out);
    for (auto it = node.children.rbegin(); it != node.children.rend(); ++it) pending.emplace_back(*it, world_from_node);
  }
}

// The nodes to draw: those of the default scene (or scene 0); without scenes, every node that is
// no other node's child.
std::vector<int> root_nodes(const tinygltf::Model& model) {
  if (!model.scenes.empty()) {
    const bool valid = model.defaultScene >= 0 && static_cast<std::size_t>(model.defaultScene) < model.scenes.size();
    return model.scenes[valid ? static_cast<std::size_t>(model.defaultScene) : 0].nodes;
  }
  std::vector<bool> child(model.nodes.size(), false);
  for (const tinygltf::Node& node : model.nodes) {
    for (const int c : node.children) {
      at(model.nodes, c, "node");  // range check
      child[static_cast<std::size_t>(c)] = true;
    }
  }
  std::vector<int> roots;
  for (std::size_t i = 0; i < child.size(); ++i) {
    if (!child[i]) roots.push_back(static_cast<int>(i));
  }
  return roots;
}

// Meshes need no textures: skip decoding images (and failing on a missing or broken one).
bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) { return true; }

std::string trimmed(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  return s;
}

}  // namespace

std::expected<MeshData, std::string> load_gltf_mesh(const std::filesystem::path& file) {
  const std::string name = file.string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) return std::unexpected(name + ": file not found");
  // Binary or JSON by content (GLB starts with the magic "glTF"), not by extension.
  char magic[4] = {};
  std::ifstream(file, std::ios::binary).read(magic, sizeof(magic));
  const bool binary = std::memcmp(magic, "glTF", 4) == 0;

  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(skip_image, nullptr);
  tinygltf::Model model;
  std::string err;
  std::string warn;
  MeshData out;
  try {
    const bool ok = binary ? loader.LoadBinaryFromFile(&model, &err, &warn, name) : loader.LoadASCIIFromFile(&model, &err, &warn, name);
    if (!ok) {
      err = trimmed(err.empty() ? warn : err);
      return std::unexpected(name + ": not a readable glTF 2.0 file: " + (err.empty() ? "unknown error" : err));
    }
    if (!model.scenes.empty() || !model.nodes.empty()) {
      append_nodes(model, root_nodes(model), out);
    } else {
      for (std::size_t m = 0; m < model.meshes.size(); ++m) append_mesh(model, static_cast<int>(m), glm::dmat4(1.0), out);
    }
  } catch (const Failure& f) {
    return std::unexpected(name + ": " + f.message);
  } catch (const std::exception& e) {  // tinygltf or the allocator
    return std::unexpected(name + ": not a readable glTF 2.0 file: " + e.what());
  }
  if (out.indices.empty()) return std::unexpected(name + ": no triangle primitives");
  return out;
}

}  // namespace rhot
