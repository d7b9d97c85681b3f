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
  glm::vec3 position{0.0f};            // metres, mesh frame
  glm::vec3 normal{0.0f, 1.0f, 0.0f};  // unit length
};

// An indexed triangle list. Front faces wind counter-clockwise seen from outside (glTF's rule),
// normals point outward.
struct MeshData {
  std::vector<Vertex> vertices;
  std::vector<std::uint32_t> indices;  // three per triangle, each < vertices.size()
};

// Primitives centred on the origin, matching the scene shapes (engine/scene/Components.h). Box
// and plane have flat normals (no vertex shared between faces); sphere and capsule are smooth,
// their vertices on the exact surface (so their volume is slightly under the exact one).
// Preconditions: sizes and radii finite and > 0; segments >= 3, rings >= 2, cap_rings >= 1.
MeshData make_box(glm::vec3 size_m);
MeshData make_sphere(float radius_m, int segments = 32, int rings = 16);
// Axis along +Y; height_m end to end, caps included (height_m >= 2 * radius_m).
MeshData make_capsule(float radius_m, float height_m, int segments = 24, int cap_rings = 8);
// In the XZ plane, normal +Y.
MeshData make_plane(glm::vec2 size_m);
// The mesh for a scene shape. Precondition: not a GltfMeshShape (use load_gltf_mesh).
MeshData make_shape_mesh(const MeshShape& shape);

// Reads every triangle primitive of a glTF 2.0 file (.gltf or .glb) into one mesh, in the frame
// of the file's default scene (node transforms applied; the default scene, or scene 0, or every
// root node when there is no scene, or every mesh as it is when there are no nodes). Other
// primitive modes are skipped. Positions (float VEC3) are required; missing normals are computed
// from the faces (flat). Mirroring nodes keep faces counter-clockwise. Images are not decoded.
// Fails with a message that starts with the file's path and says what was wrong (unreadable, not
// glTF, no triangles, a non-finite value, an index or accessor out of range, a node cycle).
[[nodiscard]] std::expected<MeshData, std::string> load_gltf_mesh(const std::filesystem::path& file);

}  // namespace rhot
