#pragma once
// Physics from glTF (docs/scene-format.md "Physics from glTF"): a scene entity's `gltf` file whose
// nodes carry KHR_physics_rigid_bodies (motion, collider, joint) with KHR_implicit_shapes becomes
// the same entities as the JSON form: one child entity of the scene entity per node with a body,
// named "<entity>/<node name>", with its Mesh (the collider's shape), Material (the node's mesh's
// base colour), PhysicsBody and Joint.
//
// What rhot reads:
//   motion      dynamic (mass, or 1000 kg/m^3 times the shape's volume when absent) or kinematic
//   collider    an implicit box, sphere, capsule (equal radii) or plane, on the body's own node;
//               a node with a collider and no motion above it is a static body
//   material    dynamicFriction and restitution
//   joint       the joint node's body and the connected node's body, classified by its limits:
//               all axes locked: fixed; linear locked, two angular locked: hinge about the third;
//               angular locked, two linear locked: slider along the third; linear locked: ball.
//               Limits on the free axis become the joint's limits; a drive on it its motor
//               (velocityTarget) or spring (positionTarget)
// What it refuses, with the file, the JSON pointer and why: cylinders, mesh colliders, colliders on
// a body's descendants (compound shapes), triggers, collision filters, joints between two bodies
// that do not move, enableCollision, joints of other shapes, malformed values. Nodes without
// physics are not read.

#include <expected>
#include <filesystem>
#include <string>
#include <vector>

#include "base/JsonError.h"
#include "engine/scene/SceneDesc.h"

namespace rhot {

// The entities of `file` (.gltf or .glb), children of the entity `parent`, named "<parent>/<node>"
// (a node without a name: "node<index>"), with transforms relative to the parent. Errors name
// `file` and the JSON pointer inside it.
[[nodiscard]] std::expected<std::vector<EntityDesc>, JsonError> read_gltf_physics(const std::filesystem::path& file,
                                                                                  const std::string& parent);

}  // namespace rhot
