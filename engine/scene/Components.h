#pragma once
// Components a scene file puts on entities (besides Transform and Parent from engine/core).
// Plain data: the physics and render systems of later layers read them.

#include <filesystem>
#include <optional>
#include <string>
#include <variant>

#include <glm/glm.hpp>

namespace rhot {

struct Name {
  std::string value;  // unique within a scene
};

// Shapes are in the entity's local frame, centred on its origin.
struct BoxShape {
  glm::vec3 size_m{1.0f};  // full edge lengths along x, y, z
};
struct SphereShape {
  float radius_m = 0.5f;
};
struct CapsuleShape {  // axis along local +Y
  float radius_m = 0.25f;
  float height_m = 1.0f;  // end to end, caps included; at least 2 * radius_m
};
struct PlaneShape {                // in local XZ, normal +Y
  glm::vec2 size_m{10.0f, 10.0f};  // drawn extent along x and z; as a physics body it is unbounded
};
struct GltfMeshShape {
  std::filesystem::path file;  // absolute; checked to exist when the scene loaded
};
using MeshShape = std::variant<BoxShape, SphereShape, CapsuleShape, PlaneShape, GltfMeshShape>;

struct Mesh {
  MeshShape shape;
};

// Half a shape's extent along its local x, y and z (before the entity's scale); nothing for a
// glTF mesh, whose extent is in its file.
inline std::optional<glm::vec3> shape_half_extents(const MeshShape& shape) {
  if (const auto* b = std::get_if<BoxShape>(&shape)) return 0.5f * b->size_m;
  if (const auto* s = std::get_if<SphereShape>(&shape)) return glm::vec3(s->radius_m);
  if (const auto* c = std::get_if<CapsuleShape>(&shape)) return glm::vec3(c->radius_m, 0.5f * c->height_m, c->radius_m);
  if (const auto* p = std::get_if<PlaneShape>(&shape)) return glm::vec3(0.5f * p->size_m.x, 0.0f, 0.5f * p->size_m.y);
  return std::nullopt;
}

struct Material {
  glm::vec4 color{0.8f, 0.8f, 0.8f, 1.0f};  // linear RGBA in [0, 1], as glTF's baseColorFactor
};

enum class BodyType { kStatic, kDynamic, kKinematic };

struct PhysicsBody {
  BodyType type = BodyType::kStatic;
  float mass_kg = 0.0f;  // > 0 for dynamic bodies, 0 otherwise
  float friction = 0.5f;
  float restitution = 0.0f;
};

// May be picked up by a hand. Only on dynamic bodies.
struct Grabbable {};

// The entity follows the pose of a tracked marker star (its id in the marker-star set).
struct TrackedBy {
  int star_id = 0;
};

}  // namespace rhot
