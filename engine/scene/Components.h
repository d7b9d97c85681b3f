#pragma once
// Components a scene file puts on entities (besides Transform and Parent from engine/core).
// Plain data: the physics and render systems of later layers read them.

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

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
struct Grabbable {
  // A second hand that grasps the object joins the first: the object then moves with the midpoint
  // of the hands and turns with the line between them (and their mean roll about it). False: the
  // second hand takes the object over from the first.
  bool two_handed = true;
  // Held in both hands, the object scales with the hands' distance (as MRTK's object manipulator
  // does), within [min_scale, max_scale] of the size it was created with.
  bool scale_with_hands = false;
  float min_scale = 0.5f;
  float max_scale = 2.0f;
};

// The entity follows the pose of a tracked marker star (its id in the marker-star set).
struct TrackedBy {
  int star_id = 0;
};

// Labels a socket's `accepts` may name (besides the entity's own name).
struct Tags {
  std::vector<std::string> values;
};

// A joint between this entity's dynamic body and another body (or the world), built on Bullet's
// constraints (engine/interact/Mechanisms.h). Its frame: the anchor and axis in this entity's
// local frame, where the joint is when the scene starts (its value there is 0).
enum class JointType { kHinge, kSlider, kFixed, kBall };

struct JointSpring {
  double stiffness = 0.0;  // N/m (slider) or N m/rad (hinge)
  double damping = 0.0;    // N s/m or N m s/rad
  double rest = 0.0;       // where it pulls to: m (slider) or degrees (hinge)
};

struct JointMotor {
  double velocity = 0.0;   // m/s (slider) or degrees/s (hinge)
  double max_force = 0.0;  // N or N m
};

struct Joint {
  JointType type = JointType::kHinge;
  std::string connected_to;                     // an entity with a body, or empty: the world
  glm::vec3 anchor_m{0.0f};                     // local
  glm::vec3 axis{0.0f, 1.0f, 0.0f};             // local, unit; hinge: turns about it, slider: moves along it
  std::optional<std::array<double, 2>> limits;  // hinge: degrees, slider: metres; lo <= hi
  double friction = 0.0;                        // N (slider) or N m (hinge): resists motion
  std::optional<JointSpring> spring;
  std::optional<JointMotor> motor;
};

// A physical push button: the entity's dynamic body slides along `axis` (local, the way it is
// pushed) up to `travel_m`, sprung back; a press when pushed past press_at * travel by a
// fingertip, released (and ready again) below release_at * travel.
struct Button {
  glm::vec3 axis{0.0f, -1.0f, 0.0f};
  double travel_m = 0.01;
  double press_at = 0.6;
  double release_at = 0.3;
  double stiffness = 150.0;  // N/m of the spring that pushes it back out
};

// Snaps a matching object released near its attach pose, holds it until a hand takes it out.
struct Socket {
  std::vector<std::string> accepts;  // entity names or tags; empty: any grabbable object
  double snap_distance_m = 0.05;
  glm::vec3 attach_position{0.0f};  // in the socket's frame
  glm::quat attach_rotation{1.0f, 0.0f, 0.0f, 0.0f};
};

// Fingertips touching it raise poke events (a flat panel, a touch pad). Needs a body.
struct Pokeable {};

// Neither drawn nor in the physics world (a scene's "disable" action; "enable" removes it).
struct Disabled {};

}  // namespace rhot
