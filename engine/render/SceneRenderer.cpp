#include "engine/render/SceneRenderer.h"

#include <cmath>
#include <numbers>

#include <glm/gtc/matrix_transform.hpp>
#include <spdlog/spdlog.h>

#include "engine/core/Transform.h"
#include "engine/core/World.h"
#include "tracking/hand/HandJoints.h"

namespace rhot {

namespace {

// Side of a cylinder of radius 1 from y = -0.5 to 0.5 (its ends are hidden inside joint spheres).
MeshData make_unit_cylinder_side(int segments = 12) {
  MeshData m;
  for (int i = 0; i <= segments; ++i) {
    const float a = 2.0f * std::numbers::pi_v<float> * static_cast<float>(i) / static_cast<float>(segments);
    const glm::vec3 n(std::cos(a), 0.0f, -std::sin(a));
    m.vertices.push_back({{n.x, -0.5f, n.z}, n});
    m.vertices.push_back({{n.x, 0.5f, n.z}, n});
  }
  for (std::uint32_t i = 0; i < static_cast<std::uint32_t>(segments); ++i) {
    const std::uint32_t b = 2 * i;
    // Counter-clockwise seen from outside.
    m.indices.insert(m.indices.end(), {b, b + 2, b + 1, b + 1, b + 2, b + 3});
  }
  return m;
}

// Places the unit cylinder between a and b with the given radius.
glm::mat4 bone_transform(const glm::vec3& a, const glm::vec3& b, float radius) {
  const glm::vec3 d = b - a;
  const float length = glm::length(d);
  const glm::vec3 y = d / length;
  const glm::vec3 helper = std::abs(y.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 0, 1);
  const glm::vec3 x = glm::normalize(glm::cross(helper, y));
  const glm::vec3 z = glm::cross(x, y);
  glm::mat4 m(1.0f);
  m[0] = glm::vec4(x * radius, 0.0f);
  m[1] = glm::vec4(y * length, 0.0f);
  m[2] = glm::vec4(z * radius, 0.0f);
  m[3] = glm::vec4((a + b) * 0.5f, 1.0f);
  return m;
}

}  // namespace

SceneRenderer::SceneRenderer(Renderer& renderer, SceneRenderSettings settings)
    : renderer_(renderer),
      settings_(settings),
      unit_box_(renderer.upload_mesh(make_box(glm::vec3(1.0f)))),
      unit_sphere_(renderer.upload_mesh(make_sphere(1.0f, 24, 12))),
      small_sphere_(renderer.upload_mesh(make_sphere(1.0f, 12, 6))),
      unit_plane_(renderer.upload_mesh(make_plane(glm::vec2(1.0f)))),
      unit_cylinder_(renderer.upload_mesh(make_unit_cylinder_side())) {}

std::pair<MeshHandle, glm::mat4> SceneRenderer::mesh_for(const MeshShape& shape) {
  if (const auto* box = std::get_if<BoxShape>(&shape)) return {unit_box_, glm::scale(glm::mat4(1.0f), box->size_m)};
  if (const auto* sphere = std::get_if<SphereShape>(&shape)) {
    return {unit_sphere_, glm::scale(glm::mat4(1.0f), glm::vec3(sphere->radius_m))};
  }
  if (const auto* plane = std::get_if<PlaneShape>(&shape)) {
    return {unit_plane_, glm::scale(glm::mat4(1.0f), glm::vec3(plane->size_m.x, 1.0f, plane->size_m.y))};
  }
  if (const auto* capsule = std::get_if<CapsuleShape>(&shape)) {
    const auto key = std::make_pair(capsule->radius_m, capsule->height_m);
    auto it = capsules_.find(key);
    if (it == capsules_.end()) it = capsules_.emplace(key, renderer_.upload_mesh(make_capsule(key.first, key.second))).first;
    return {it->second, glm::mat4(1.0f)};
  }
  const auto& gltf = std::get<GltfMeshShape>(shape);
  const std::string key = gltf.file.string();
  auto it = gltf_.find(key);
  if (it == gltf_.end()) {
    auto mesh = load_gltf_mesh(gltf.file);
    if (!mesh) spdlog::error("cannot load mesh, drawing a grey box instead: {}", mesh.error());
    it = gltf_.emplace(key, mesh ? renderer_.upload_mesh(*mesh) : MeshHandle{~0u}).first;
  }
  if (it->second.index == ~0u) return {unit_box_, glm::scale(glm::mat4(1.0f), glm::vec3(0.1f))};
  return {it->second, glm::mat4(1.0f)};
}

void SceneRenderer::add(FrameInput& frame, MeshHandle mesh, const glm::mat4& world_from_local, const glm::vec4& color) {
  auto [it, fresh] = batch_of_mesh_.try_emplace(mesh.index, frame.batches.size());
  if (fresh) frame.batches.push_back(MeshBatch{mesh, {}});
  frame.batches[it->second].instances.push_back({world_from_local, color});
}

FrameInput SceneRenderer::build(World& world, const StereoViews& views, std::span<const HandDrawInput> hands, const DebugDraw* debug) {
  FrameInput frame;
  frame.views = views;
  batch_of_mesh_.clear();
  world.view<Mesh, WorldTransform>().each([&](Entity e, Mesh& mesh, WorldTransform& t) {
    if (world.has<Disabled>(e)) return;
    const Material* material = world.find<Material>(e);
    const auto [handle, local_from_mesh] = mesh_for(mesh.shape);
    add(frame, handle, t.world_from_local * local_from_mesh, material != nullptr ? material->color : Material{}.color);
  });
  for (const HandDrawInput& hand : hands) {
    for (int j = 0; j < kHandJointCount; ++j) {
      const float r = hand.radius_m[static_cast<std::size_t>(j)];
      const glm::vec3 p = hand.joint_world[static_cast<std::size_t>(j)];
      add(frame, small_sphere_, glm::scale(glm::translate(glm::mat4(1.0f), p), glm::vec3(r)), hand.color);
      if (const auto parent = joint_parent(static_cast<HandJoint>(j))) {
        const auto pj = static_cast<std::size_t>(*parent);
        const glm::vec3 q = hand.joint_world[pj];
        if (glm::length(p - q) > 1e-6f) {
          add(frame, unit_cylinder_, bone_transform(q, p, std::min(r, hand.radius_m[pj])), hand.color);
        }
      }
    }
  }
  if (settings_.draw_grid) {
    DebugDraw grid;
    grid.grid(settings_.grid_half_extent_m, settings_.grid_spacing_m, 0.002f, settings_.grid_color);
    frame.lines = grid.lines();
  }
  if (debug != nullptr) {
    frame.lines.insert(frame.lines.end(), debug->lines().begin(), debug->lines().end());
    for (const DebugPoint& p : debug->points()) {
      add(frame, small_sphere_, glm::scale(glm::translate(glm::mat4(1.0f), p.position), glm::vec3(p.radius_m)), p.color);
    }
  }
  // Large planes (floors, walls) are mostly hidden behind other things: drawn last, the depth
  // test rejects their hidden pixels before shading, which matters on CPU rasterisers.
  const auto plane_batch = batch_of_mesh_.find(unit_plane_.index);
  if (plane_batch != batch_of_mesh_.end() && plane_batch->second + 1 < frame.batches.size()) {
    MeshBatch planes = std::move(frame.batches[plane_batch->second]);
    frame.batches.erase(frame.batches.begin() + static_cast<std::ptrdiff_t>(plane_batch->second));
    frame.batches.push_back(std::move(planes));
  }
  return frame;
}

}  // namespace rhot
