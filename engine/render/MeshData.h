#pragma once
// Triangle meshes on the CPU: generated primitives and meshes read from glTF files. The renderer
// uploads these once and draws them instanced.

#include <cstdint>
#include <expected>
#include <filesystem>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "engine/scene/Components.h"

namespace rhot {

struct Vertex {
  glm::vec3 position{0.0f};  // metres, mesh frame
  glm::vec3 normal{0.0f, 1.0f, 0.0f};  // unit length
};

// An indexed triangle list. Front faces wind counter-clockwise seen from outside (glTF's rule),
// normals point outward.
struct MeshData {
  std::vector<Vertex> vertices;
  std::vector<std::uint32_t> indices;  // three per triangle, each < vertices.size()
};

// Primitives centred on the origin, matching the scene shapes (engine/scene/Components.h).
MeshData make_box(glm::vec3 size_m);
MeshData make_sphere(float radius_m, int segments = 32, int rings = 16);
// Axis along +Y; height_m end to end, caps included (height_m >= 2 * radius_m).
MeshData make_capsule(float radius_m, float height_m, int segments = 24, int cap_rings = 8);
// In the XZ plane, normal +Y.
MeshData make_plane(glm::vec2 size_m);
// The mesh for a scene shape. Precondition: not a GltfMeshShape (use load_gltf_mesh).
MeshData make_shape_mesh(const MeshShape& shape);

// Reads every triangle primitive of a glTF 2.0 file (.gltf or .glb) into one mesh, in the frame
// of the file's default scene (node transforms applied; the default scene, or scene 0, or all
// root meshes when there is no scene). Positions are required; missing normals are computed
// from the faces. Fails with a message naming the file and what was wrong (unreadable, not glTF,
// no triangles, a non-finite value, an index out of range).
[[nodiscard]] std::expected<MeshData, std::string> load_gltf_mesh(const std::filesystem::path& file);

}  // namespace rhot
