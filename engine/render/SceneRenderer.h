#pragma once
// Turns the world into a frame for the renderer: every entity with a Mesh and a WorldTransform
// (coloured by its Material) becomes an instance, batched so that all boxes, all spheres and all
// planes each share one unit mesh scaled per instance (capsules share a mesh per radius and
// height; glTF meshes one per file). Adds the ground grid, hands and the debug-draw layer.
//
// A glTF file that fails to load is logged once and drawn as a grey box of 10 cm instead, so a
// bad asset never stops the frame.

#include <array>
#include <map>
#include <span>
#include <string>
#include <utility>

#include "engine/render/DebugDraw.h"
#include "engine/render/Renderer.h"

namespace rhot {

class World;

// One hand to draw: 26 joints in OpenXR order (tracking/hand/HandJoints.h), world coordinates.
// Drawn as a sphere per joint and a capsule per bone (a cylinder between two joint spheres).
struct HandDrawInput {
  std::array<glm::vec3, 26> joint_world{};
  std::array<float, 26> radius_m{};
  glm::vec4 color{0.9f, 0.72f, 0.6f, 1.0f};
};

struct SceneRenderSettings {
  bool draw_grid = true;
  float grid_half_extent_m = 3.0f;
  float grid_spacing_m = 0.25f;
  glm::vec4 grid_color{0.18f, 0.18f, 0.2f, 1.0f};
};

class SceneRenderer {
 public:
  explicit SceneRenderer(Renderer& renderer, SceneRenderSettings settings = {});

  // Everything to draw this frame. Precondition: the world is not iterating.
  FrameInput build(World& world, const StereoViews& views, std::span<const HandDrawInput> hands = {}, const DebugDraw* debug = nullptr);

 private:
  // The mesh for a shape and the scale that turns the mesh into the shape.
  std::pair<MeshHandle, glm::mat4> mesh_for(const MeshShape& shape);
  void add(FrameInput& frame, MeshHandle mesh, const glm::mat4& world_from_local, const glm::vec4& color);

  Renderer& renderer_;
  SceneRenderSettings settings_;
  MeshHandle unit_box_;
  MeshHandle unit_sphere_;
  MeshHandle small_sphere_;  // fewer triangles, for joints and markers a few centimetres across
  MeshHandle unit_plane_;
  MeshHandle unit_cylinder_;
  std::map<std::pair<float, float>, MeshHandle> capsules_;
  std::map<std::string, MeshHandle> gltf_;
  std::map<std::uint32_t, std::size_t> batch_of_mesh_;  // per frame: mesh index -> batch
};

}  // namespace rhot
