#include "engine/render/MeshData.h"

#include <cmath>
#include <cstring>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <tiny_gltf.h>

namespace rhot {

namespace {

struct Failure {
  std::string message;
};

glm::mat4 node_matrix(const tinygltf::Node& node) {
  if (node.matrix.size() == 16) {
    glm::dmat4 m;
    for (int i = 0; i < 16; ++i) glm::value_ptr(m)[i] = node.matrix[static_cast<std::size_t>(i)];
    return glm::mat4(m);
  }
  glm::dmat4 m(1.0);
  if (node.translation.size() == 3) m = glm::translate(m, glm::dvec3(node.translation[0], node.translation[1], node.translation[2]));
  if (node.rotation.size() == 4) {
    m = m * glm::mat4_cast(glm::dquat(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]));
  }
  if (node.scale.size() == 3) m = glm::scale(m, glm::dvec3(node.scale[0], node.scale[1], node.scale[2]));
  return glm::mat4(m);
}

// The bytes of element i of an accessor, checked against its buffer view and buffer.
const unsigned char* element(const tinygltf::Model& model, const tinygltf::Accessor& accessor, std::size_t i,
                             std::size_t element_bytes) {
  if (accessor.bufferView < 0 || static_cast<std::size_t>(accessor.bufferView) >= model.bufferViews.size()) {
    throw Failure{"an accessor has no valid bufferView (sparse accessors are not supported)"};
  }
  const tinygltf::BufferView& view = model.bufferViews[static_cast<std::size_t>(accessor.bufferView)];
  if (view.buffer < 0 || static_cast<std::size_t>(view.buffer) >= model.buffers.size()) throw Failure{"a bufferView has no valid buffer"};
  const tinygltf::Buffer& buffer = model.buffers[static_cast<std::size_t>(view.buffer)];
  const std::size_t stride = view.byteStride != 0 ? view.byteStride : element_bytes;
  const std::size_t offset = view.byteOffset + accessor.byteOffset + i * stride;
  if (offset + element_bytes > view.byteOffset + view.byteLength || offset + element_bytes > buffer.data.size()) {
    throw Failure{"accessor data runs past the end of its buffer"};
  }
  return buffer.data.data() + offset;
}

glm::vec3 read_vec3(const tinygltf::Model& model, const tinygltf::Accessor& a, std::size_t i) {
  if (a.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT || a.type != TINYGLTF_TYPE_VEC3) {
    throw Failure{"positions and normals must be float VEC3"};
  }
  glm::vec3 v;
  std::memcpy(&v, element(model, a, i, sizeof(glm::vec3)), sizeof(glm::vec3));
  if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z)) throw Failure{"a vertex value is not finite"};
  return v;
}

std::uint32_t read_index(const tinygltf::Model& model, const tinygltf::Accessor& a, std::size_t i) {
  switch (a.componentType) {
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return *element(model, a, i, 1);
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
      std::uint16_t v;
      std::memcpy(&v, element(model, a, i, 2), 2);
      return v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
      std::uint32_t v;
      std::memcpy(&v, element(model, a, i, 4), 4);
      return v;
    }
    default: throw Failure{"indices must be unsigned byte, short or int"};
  }
}

const tinygltf::Accessor& accessor(const tinygltf::Model& model, int index) {
  if (index < 0 || static_cast<std::size_t>(index) >= model.accessors.size()) throw Failure{"an accessor index is out of range"};
  return model.accessors[static_cast<std::size_t>(index)];
}

void append_mesh(const tinygltf::Model& model, const tinygltf::Mesh& mesh, const glm::mat4& world, MeshData& out) {
  const glm::mat3 normal_matrix = glm::transpose(glm::inverse(glm::mat3(world)));
  for (const tinygltf::Primitive& prim : mesh.primitives) {
    if (prim.mode != TINYGLTF_MODE_TRIANGLES && prim.mode != -1) continue;  // -1: the default, triangles
    const auto pos_it = prim.attributes.find("POSITION");
    if (pos_it == prim.attributes.end()) throw Failure{"a triangle primitive has no POSITION"};
    const tinygltf::Accessor& positions = accessor(model, pos_it->second);
    const auto nrm_it = prim.attributes.find("NORMAL");
    const tinygltf::Accessor* normals = nrm_it != prim.attributes.end() ? &accessor(model, nrm_it->second) : nullptr;
    if (normals != nullptr && normals->count != positions.count) throw Failure{"NORMAL and POSITION counts differ"};

    std::vector<std::uint32_t> indices;
    if (prim.indices >= 0) {
      const tinygltf::Accessor& ia = accessor(model, prim.indices);
      for (std::size_t i = 0; i < ia.count; ++i) {
        const std::uint32_t v = read_index(model, ia, i);
        if (v >= positions.count) throw Failure{"index " + std::to_string(v) + " is out of range (" + std::to_string(positions.count) + " vertices)"};
        indices.push_back(v);
      }
    } else {
      for (std::size_t i = 0; i < positions.count; ++i) indices.push_back(static_cast<std::uint32_t>(i));
    }
    if (indices.size() % 3 != 0) throw Failure{"a triangle primitive's index count is not a multiple of 3"};

    const auto base = static_cast<std::uint32_t>(out.vertices.size());
    for (std::size_t i = 0; i < positions.count; ++i) {
      const glm::vec3 p = glm::vec3(world * glm::vec4(read_vec3(model, positions, i), 1.0f));
      glm::vec3 n(0.0f, 1.0f, 0.0f);
      if (normals != nullptr) {
        const glm::vec3 raw = normal_matrix * read_vec3(model, *normals, i);
        if (glm::length(raw) > 0.0f) n = glm::normalize(raw);
      }
      out.vertices.push_back({p, n});
    }
    if (normals == nullptr) {
      // Flat normals: give every triangle its own three vertices.
      std::vector<Vertex> flat;
      for (std::size_t t = 0; t < indices.size(); t += 3) {
        const glm::vec3 a = out.vertices[base + indices[t]].position;
        const glm::vec3 b = out.vertices[base + indices[t + 1]].position;
        const glm::vec3 c = out.vertices[base + indices[t + 2]].position;
        const glm::vec3 cross = glm::cross(b - a, c - a);
        const glm::vec3 n = glm::length(cross) > 0.0f ? glm::normalize(cross) : glm::vec3(0, 1, 0);
        flat.push_back({a, n});
        flat.push_back({b, n});
        flat.push_back({c, n});
      }
      out.vertices.resize(base);
      for (std::size_t k = 0; k < flat.size(); ++k) {
        out.vertices.push_back(flat[k]);
        out.indices.push_back(base + static_cast<std::uint32_t>(k));
      }
    } else {
      for (const std::uint32_t i : indices) out.indices.push_back(base + i);
    }
  }
}

void visit(const tinygltf::Model& model, int node_index, const glm::mat4& parent, MeshData& out, int depth) {
  if (node_index < 0 || static_cast<std::size_t>(node_index) >= model.nodes.size()) throw Failure{"a node index is out of range"};
  if (depth > 64) throw Failure{"the node hierarchy is deeper than 64 (a cycle?)"};
  const tinygltf::Node& node = model.nodes[static_cast<std::size_t>(node_index)];
  const glm::mat4 world = parent * node_matrix(node);
  if (node.mesh >= 0) {
    if (static_cast<std::size_t>(node.mesh) >= model.meshes.size()) throw Failure{"a mesh index is out of range"};
    append_mesh(model, model.meshes[static_cast<std::size_t>(node.mesh)], world, out);
  }
  for (const int child : node.children) visit(model, child, world, out, depth + 1);
}

// Meshes need no textures: skip decoding images (and failing on a missing one).
bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) {
  return true;
}

}  // namespace

std::expected<MeshData, std::string> load_gltf_mesh(const std::filesystem::path& file) {
  const std::string name = file.string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) return std::unexpected(name + ": file not found");
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(skip_image, nullptr);
  tinygltf::Model model;
  std::string err;
  std::string warn;
  const bool binary = file.extension() == ".glb";
  const bool ok = binary ? loader.LoadBinaryFromFile(&model, &err, &warn, name) : loader.LoadASCIIFromFile(&model, &err, &warn, name);
  if (!ok) {
    while (!err.empty() && (err.back() == '\n' || err.back() == ' ')) err.pop_back();
    return std::unexpected(name + ": not a readable glTF 2.0 file: " + (err.empty() ? "unknown error" : err));
  }
  MeshData out;
  try {
    if (!model.scenes.empty()) {
      const std::size_t s = model.defaultScene >= 0 && static_cast<std::size_t>(model.defaultScene) < model.scenes.size()
                                ? static_cast<std::size_t>(model.defaultScene)
                                : 0;
      for (const int root : model.scenes[s].nodes) visit(model, root, glm::mat4(1.0f), out, 0);
    } else {
      for (const tinygltf::Mesh& mesh : model.meshes) append_mesh(model, mesh, glm::mat4(1.0f), out);
    }
  } catch (const Failure& f) {
    return std::unexpected(name + ": " + f.message);
  }
  if (out.indices.empty()) return std::unexpected(name + ": no triangle primitives");
  return out;
}

}  // namespace rhot
