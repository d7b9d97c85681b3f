// Physics from glTF: a file whose nodes carry KHR_physics_rigid_bodies and KHR_implicit_shapes
// loads into the same entities, and then the same Bullet world, as its hand-written JSON twin;
// malformed or unsupported extension data is refused naming the glTF file, the JSON pointer and why.

#include "engine/scene/GltfPhysics.h"

#include <filesystem>
#include <functional>
#include <sstream>
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "engine/core/World.h"
#include "engine/interact/HandPhysics.h"
#include "engine/scene/SceneLoader.h"

namespace rhot {
namespace {

const std::filesystem::path kData = RHOT_SOURCE_DIR "/tests/engine/scene/data";

SceneDesc load(const std::filesystem::path& file) {
  auto scene = load_scene_file(file);
  EXPECT_TRUE(scene.has_value()) << (scene ? "" : scene.error().to_string());
  return scene.value_or(SceneDesc{});
}

void expect_same(const EntityDesc& a, const EntityDesc& b) {
  SCOPED_TRACE(a.name);
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.parent, b.parent);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(a.transform.position[i], b.transform.position[i], 1e-6f);
    EXPECT_NEAR(a.transform.scale[i], b.transform.scale[i], 1e-6f);
  }
  EXPECT_NEAR(std::abs(glm::dot(a.transform.rotation, b.transform.rotation)), 1.0f, 1e-6f);
  ASSERT_EQ(a.mesh.has_value(), b.mesh.has_value());
  if (a.mesh) {
    ASSERT_EQ(a.mesh->shape.index(), b.mesh->shape.index());
    const auto ha = shape_half_extents(a.mesh->shape), hb = shape_half_extents(b.mesh->shape);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR((*ha)[i], (*hb)[i], 1e-6f);
  }
  const glm::vec4 ca = a.material.value_or(Material{}).color, cb = b.material.value_or(Material{}).color;
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(ca[i], cb[i], 1e-6f);
  ASSERT_EQ(a.body.has_value(), b.body.has_value());
  if (a.body) {
    EXPECT_EQ(a.body->type, b.body->type);
    EXPECT_NEAR(a.body->mass_kg, b.body->mass_kg, 1e-6f);
    EXPECT_NEAR(a.body->friction, b.body->friction, 1e-6f);
    EXPECT_NEAR(a.body->restitution, b.body->restitution, 1e-6f);
  }
  ASSERT_EQ(a.joint.has_value(), b.joint.has_value());
  if (a.joint) {
    EXPECT_EQ(a.joint->type, b.joint->type);
    EXPECT_EQ(a.joint->connected_to, b.joint->connected_to);
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(a.joint->anchor_m[i], b.joint->anchor_m[i], 1e-6f);
      if (a.joint->type == JointType::kHinge || a.joint->type == JointType::kSlider) {
        EXPECT_NEAR(a.joint->axis[i], b.joint->axis[i], 1e-6f);
      }
    }
    ASSERT_EQ(a.joint->limits.has_value(), b.joint->limits.has_value());
    if (a.joint->limits) {
      EXPECT_NEAR((*a.joint->limits)[0], (*b.joint->limits)[0], 1e-9);
      EXPECT_NEAR((*a.joint->limits)[1], (*b.joint->limits)[1], 1e-9);
    }
    ASSERT_EQ(a.joint->motor.has_value(), b.joint->motor.has_value());
    if (a.joint->motor) {
      EXPECT_DOUBLE_EQ(a.joint->motor->velocity, b.joint->motor->velocity);
      EXPECT_DOUBLE_EQ(a.joint->motor->max_force, b.joint->motor->max_force);
    }
  }
  EXPECT_EQ(a.grabbable.has_value(), b.grabbable.has_value());
}

TEST(GltfPhysics, AFileWithPhysicsExtensionsLoadsIntoTheSameWorldAsItsJsonTwin) {
  const SceneDesc from_gltf = load(kData / "cabinet-physics.json");
  const SceneDesc twin = load(kData / "cabinet-physics-twin.json");
  ASSERT_EQ(from_gltf.entities.size(), 7u);
  ASSERT_EQ(twin.entities.size(), 7u);
  for (std::size_t i = 0; i < twin.entities.size(); ++i) expect_same(from_gltf.entities[i], twin.entities[i]);

  // The same bodies and joints step the same: the door swings shut against its limit, the
  // drawer's motor pulls it out to its limit, the ball hangs from its pivot.
  World wa, wb;
  instantiate(from_gltf, wa);
  instantiate(twin, wb);
  auto pa = HandPhysics::create(wa, from_gltf);
  auto pb = HandPhysics::create(wb, twin);
  ASSERT_TRUE(pa.has_value()) << (pa ? "" : pa.error());
  ASSERT_TRUE(pb.has_value()) << (pb ? "" : pb.error());
  const std::array<HandInput, 2> no_hands{};
  for (int i = 0; i < 450; ++i) {
    (*pa)->step(wa, no_hands);
    (*pb)->step(wb, no_hands);
  }
  for (const char* name : {"cabinet/door", "cabinet/drawer", "cabinet/ball"}) {
    SCOPED_TRACE(name);
    const btTransform a = (*pa)->physics().body(find_named(wa, name))->getWorldTransform();
    const btTransform b = (*pb)->physics().body(find_named(wb, name))->getWorldTransform();
    EXPECT_LT(static_cast<double>((a.getOrigin() - b.getOrigin()).length()), 1e-5);
    EXPECT_LT(static_cast<double>(a.getRotation().angleShortestPath(b.getRotation())), 1e-4);
  }
  const Mechanisms& m = (*pa)->mechanisms();
  EXPECT_NEAR(*m.value(find_named(wa, "cabinet/drawer")), 0.2, 0.005) << "the drive pulled the drawer to its limit";
  const btVector3 ball = (*pa)->physics().body(find_named(wa, "cabinet/ball"))->getWorldTransform().getOrigin();
  EXPECT_NEAR(static_cast<double>(ball.x()), 1.4, 0.01);
  EXPECT_NEAR(static_cast<double>(ball.y()), 0.5, 0.01) << "hanging 0.2 m below its pivot";
}

// The cabinet file with one change, written next to the original, loaded through a scene.
std::string error_with(const std::function<void(nlohmann::json&)>& change, const std::string& scene_entity_extra = "") {
  std::ifstream in(kData / "cabinet-physics.gltf");
  nlohmann::json gltf = nlohmann::json::parse(in);
  change(gltf);
  const std::filesystem::path dir = std::filesystem::path(testing::TempDir()) / "rhot-gltf-physics";
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "broken.gltf") << gltf.dump();
  const std::string scene = R"({"entities": [{"name": "cabinet", "gltf": )" +
                            (scene_entity_extra.empty() ? std::string(R"("broken.gltf")") : scene_entity_extra) + "}]}";
  auto loaded = parse_scene(scene, dir, "s.json");
  if (loaded) return "loaded";
  std::string text = loaded.error().to_string();
  const std::string prefix = (dir / "broken.gltf").string();
  if (text.starts_with(prefix)) text = "broken.gltf" + text.substr(prefix.size());
  return text;
}

TEST(GltfPhysics, MalformedOrUnsupportedExtensionDataIsRefusedWithTheFilePathAndReason) {
  EXPECT_EQ(error_with([](nlohmann::json&) {}), "loaded");
  EXPECT_EQ(error_with([](nlohmann::json& g) {
              g["extensions"]["KHR_implicit_shapes"]["shapes"][3] = {{"type", "cylinder"}};
            }),
            "broken.gltf: /extensions/KHR_implicit_shapes/shapes/3/type: cylinders are not supported by rhot; use a capsule or a box");
  EXPECT_EQ(error_with([](nlohmann::json& g) { g["nodes"][1]["extensions"]["KHR_physics_rigid_bodies"]["motion"]["mass"] = -1; }),
            "broken.gltf: /nodes/1/extensions/KHR_physics_rigid_bodies/motion/mass: expected a number greater than 0 (and within float "
            "range), got -1");
  EXPECT_EQ(error_with([](nlohmann::json& g) { g["nodes"][1]["extensions"]["KHR_physics_rigid_bodies"]["motion"]["massive"] = true; }),
            "broken.gltf: /nodes/1/extensions/KHR_physics_rigid_bodies/motion/massive: unknown key \"massive\"; expected one of: "
            "isKinematic, mass, centerOfMass, inertiaDiagonal, inertiaOrientation, linearVelocity, angularVelocity, gravityFactor, "
            "extensions, extras");
  EXPECT_EQ(
      error_with([](nlohmann::json& g) { g["nodes"][1]["extensions"]["KHR_physics_rigid_bodies"]["collider"]["geometry"]["shape"] = 17; }),
      "broken.gltf: /nodes/1/extensions/KHR_physics_rigid_bodies/collider/geometry/shape: expected an integer from 0 to 5, got 17");
  EXPECT_EQ(error_with([](nlohmann::json& g) {
              g["extensions"]["KHR_physics_rigid_bodies"]["physicsJoints"][0]["limits"][1]["angularAxes"] = {0};
            }),
            "broken.gltf: /extensions/KHR_physics_rigid_bodies/physicsJoints/0: a joint that locks linear axes x, y, z and angular axes x "
            "is not a hinge, slider, fixed or ball joint, the ones rhot supports");
  EXPECT_EQ(error_with([](nlohmann::json& g) {
              g["nodes"][6]["extensions"]["KHR_physics_rigid_bodies"]["trigger"] = {{"nodes", {10}}};
            }),
            "broken.gltf: /nodes/6/extensions/KHR_physics_rigid_bodies/trigger: triggers are not supported by rhot");
  EXPECT_EQ(error_with([](nlohmann::json& g) {
              g["nodes"][10]["extensions"]["KHR_physics_rigid_bodies"]["collider"] = {{"geometry", {{"shape", 3}}}};
            }),
            "broken.gltf: /nodes/10/extensions/KHR_physics_rigid_bodies/collider/geometry: a collider on a child of the body at /nodes/6 "
            "(a compound shape) is not supported by rhot; put one collider on the body's node");
  EXPECT_EQ(error_with([](nlohmann::json& g) { g["nodes"][2]["extensions"]["KHR_physics_rigid_bodies"]["joint"]["connectedNode"] = 1; }),
            "broken.gltf: /nodes/2/extensions/KHR_physics_rigid_bodies/joint/connectedNode: the joint's two nodes are on the same body");
  EXPECT_EQ(error_with([](nlohmann::json& g) {
              g["nodes"][1]["translation"] = {1e20, 0, 0};
            }),
            "broken.gltf: /nodes/1: the node's transform is not finite or beyond 1e6");
  EXPECT_EQ(error_with([](nlohmann::json& g) {
              g["extensions"]["KHR_physics_rigid_bodies"]["physicsJoints"][1]["drives"][0]["velocityTarget"] = 1e30;
            }),
            "broken.gltf: /extensions/KHR_physics_rigid_bodies/physicsJoints/1/drives/0/velocityTarget: expected a velocity from -100 to "
            "100 (m/s or rad/s), got 1e+30");
  EXPECT_EQ(error_with([](nlohmann::json& g) {
              g["nodes"][1]["children"] = {2, 3};
            }),
            "broken.gltf: /nodes/1/children/1: node 3 has two parents");
  // The scene's own part of the reference.
  EXPECT_EQ(error_with([](nlohmann::json&) {}, R"({"file": "broken.gltf", "grabbable": ["frame"]})"),
            "s.json: /entities/0/gltf/grabbable/0: \"cabinet/frame\" is not a dynamic body and cannot be grabbable");
  EXPECT_EQ(error_with([](nlohmann::json&) {}, R"({"file": "broken.gltf", "grabbable": ["lid"]})"),
            "s.json: /entities/0/gltf/grabbable/0: no body named \"cabinet/lid\" in broken.gltf");
  EXPECT_EQ(
      error_with([](nlohmann::json&) {}, R"("broken.gltf", "body": {"type": "static"})"),
      "s.json: /entities/0/body: an entity made from a glTF file takes its shapes, bodies and joints from the file; no \"body\" here");
  EXPECT_EQ(error_with([](nlohmann::json&) {}, R"({"file": "broken.gltf", "grabbable": ["ball"]})"), "loaded");
  EXPECT_EQ(error_with([](nlohmann::json& g) { g["nodes"][4]["name"] = "door"; }),
            "broken.gltf: /nodes/4/name: two bodies would both be named \"cabinet/door\"");
  EXPECT_EQ(error_with([](nlohmann::json&) {}, R"("broken.gltf", "transform": {"scale": 2})"),
            "s.json: /entities/0/transform/scale: an entity made from a glTF file is not scaled (its joints' anchors would not follow); "
            "scale the file's nodes");
}

TEST(GltfPhysics, ABodyFromAFileMayNotTakeAnotherEntitysName) {
  const std::string scene = R"({"entities": [{"name": "cabinet", "gltf": "cabinet-physics.gltf"}, {"name": "cabinet/door"}]})";
  auto loaded = parse_scene(scene, kData, "s.json");
  ASSERT_FALSE(loaded.has_value());
  EXPECT_EQ(loaded.error().to_string(), "s.json: /entities/0/gltf: its body \"cabinet/door\" has the name of /entities/1");
}

TEST(GltfPhysics, ABinaryGltfReadsItsJsonChunk) {
  std::ifstream in(kData / "cabinet-physics.gltf");
  std::stringstream text;
  text << in.rdbuf();
  std::string json = text.str();
  while (json.size() % 4 != 0) json += ' ';
  const std::filesystem::path dir = std::filesystem::path(testing::TempDir()) / "rhot-gltf-physics";
  std::filesystem::create_directories(dir);
  const auto u32 = [](std::string& out, std::uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
  std::string glb = "glTF";
  u32(glb, 2);
  u32(glb, static_cast<std::uint32_t>(20 + json.size()));
  u32(glb, static_cast<std::uint32_t>(json.size()));
  u32(glb, 0x4E4F534Au);
  glb += json;
  std::ofstream(dir / "cabinet.glb", std::ios::binary) << glb;
  auto entities = read_gltf_physics(dir / "cabinet.glb", "c");
  ASSERT_TRUE(entities.has_value()) << entities.error().to_string();
  EXPECT_EQ(entities->size(), 6u);
  std::ofstream(dir / "bad.glb", std::ios::binary) << "glTF\x01";
  EXPECT_EQ(read_gltf_physics(dir / "bad.glb", "c").error().to_string(), (dir / "bad.glb").string() + ": a binary glTF cut short: 5 bytes");
}

}  // namespace
}  // namespace rhot
