#include "engine/scene/SceneLoader.h"

#include <filesystem>
#include <fstream>
#include <string>
#include <variant>
#include <vector>

#include <gtest/gtest.h>

#include "engine/core/World.h"

namespace rhot {
namespace {

namespace fs = std::filesystem;

// Each test writes its files into a fresh folder of its own.
class SceneFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::path(::testing::TempDir()) / "rhot_scene_test" / info->name();
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  fs::path write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    fs::create_directories(p.parent_path());
    std::ofstream(p) << text;
    return p;
  }
  // Loads scene text from a file and returns the error message ("" when it loaded).
  std::string error_of(const std::string& text) {
    const fs::path p = write("scene.json", text);
    const auto r = load_scene_file(p);
    if (r) return "";
    EXPECT_EQ(r.error().file, p.string());
    return r.error().json_path + ": " + r.error().message;
  }
  fs::path dir_;
};

// A valid entity to build bad ones around.
const char* kCube = R"({"name": "cube", "mesh": {"shape": "box", "size_m": [0.1, 0.1, 0.1]},
                        "body": {"type": "dynamic", "mass_kg": 0.2}})";

std::string scene_with(const std::string& entities) { return R"({"entities": [)" + entities + "]}"; }

TEST_F(SceneFiles, DefaultSceneLoadsAndInstantiates) {
  const auto scene = load_scene_file(fs::path(RHOT_ASSET_DIR) / "scenes" / "default.json");
  ASSERT_TRUE(scene.has_value()) << scene.error().to_string();
  World w;
  const auto entities = instantiate(*scene, w);
  EXPECT_EQ(entities.size(), scene->entities.size());
  EXPECT_EQ(w.count<Grabbable>(), 10u);
  EXPECT_EQ(w.count<TrackedBy>(), 3u);
  EXPECT_TRUE(scene->settings.left_hand && scene->settings.right_hand);
  EXPECT_EQ(scene->settings.headset.eye_width_px, 1080);
  EXPECT_EQ(scene->settings.headset.eye_height_px, 1200);
  EXPECT_DOUBLE_EQ(scene->settings.headset.ipd_m, 0.063);
  // Every grabbable object rests on the table top (y = 0.74 m) and within its 1.2 x 0.8 m extent.
  w.view<Grabbable, WorldTransform, Mesh>().each([&](Entity e, Grabbable&, WorldTransform& t, Mesh&) {
    const glm::vec3 p(t.world_from_local[3]);
    EXPECT_GT(p.y, 0.74f) << w.get<Name>(e).value;
    EXPECT_LT(p.y, 0.9f) << w.get<Name>(e).value;
    EXPECT_LT(std::abs(p.x), 0.6f) << w.get<Name>(e).value;
    EXPECT_LT(std::abs(p.z + 0.5f), 0.4f) << w.get<Name>(e).value;
  });
}

TEST_F(SceneFiles, ReadsEveryField) {
  write("meshes/mug.glb", "glTF");
  write("rigs/desk.yaml", "%YAML:1.0\n");
  const std::string text = R"({
    "format": "rhot-scene", "version": 1,
    "settings": {"rig": "rigs/desk.yaml", "hands": ["right"], "gravity_mps2": [0, -1.62, 0],
                 "headset": {"ipd_m": 0.07, "eye_resolution_px": [640, 720], "refresh_hz": 120,
                             "near_m": 0.1, "far_m": 50,
                             "fov_deg": {"left_eye": {"left": 45, "right": 40, "up": 44, "down": 46}}}},
    "entities": [
      {"name": "table", "transform": {"position": [0, 0.7, -0.5], "rotation_deg": [0, 90, 0]},
       "mesh": {"shape": "box", "size_m": [1, 0.05, 0.6]}, "body": {"type": "static"}},
      {"name": "mug", "parent": "table", "transform": {"position": [0.1, 0.1, 0], "rotation": [0, 0, 0, 1], "scale": 2},
       "mesh": {"shape": "gltf", "file": "meshes/mug.glb"}, "material": {"color": [1, 0, 0, 0.5]},
       "body": {"type": "kinematic", "friction": 0.9, "restitution": 0.2}, "tracked_by": 7},
      {"name": "ball", "mesh": {"shape": "sphere", "radius_m": 0.03},
       "body": {"type": "dynamic", "mass_kg": 0.05}, "grabbable": true},
      {"name": "bottle", "mesh": {"shape": "capsule", "radius_m": 0.03, "height_m": 0.2}},
      {"name": "floor", "mesh": {"shape": "plane", "size_m": [4, 4]}},
      {"name": "anchor"}
    ]})";
  const fs::path p = write("scene.json", text);
  const auto r = load_scene_file(p);
  ASSERT_TRUE(r.has_value()) << r.error().to_string();
  const SceneDesc& s = *r;
  EXPECT_EQ(s.settings.rig_file, (dir_ / "rigs/desk.yaml").lexically_normal());
  EXPECT_FALSE(s.settings.left_hand);
  EXPECT_TRUE(s.settings.right_hand);
  EXPECT_FLOAT_EQ(s.settings.gravity_mps2.y, -1.62f);
  EXPECT_EQ(s.settings.headset.eye_width_px, 640);
  EXPECT_DOUBLE_EQ(s.settings.headset.left_eye.right, 40.0);
  EXPECT_DOUBLE_EQ(s.settings.headset.right_eye.right, 52.0) << "the right eye keeps its default";
  ASSERT_EQ(s.entities.size(), 6u);
  EXPECT_EQ(s.entities[1].parent, "table");
  EXPECT_EQ(std::get<GltfMeshShape>(s.entities[1].mesh->shape).file, (dir_ / "meshes/mug.glb").lexically_normal());
  EXPECT_EQ(*s.entities[1].tracked_by, 7);
  EXPECT_FLOAT_EQ(s.entities[1].material->color.a, 0.5f);
  EXPECT_EQ(s.entities[2].body->type, BodyType::kDynamic);
  EXPECT_TRUE(s.entities[2].grabbable);

  World w;
  const auto es = instantiate(s, w);
  // The mug sits 0.1 m along the table's +X, which the table's 90 deg yaw turns to -Z.
  const glm::vec3 mug(w.get<WorldTransform>(es[1]).world_from_local[3]);
  EXPECT_NEAR(mug.x, 0.0f, 1e-5f);
  EXPECT_NEAR(mug.y, 0.8f, 1e-5f);
  EXPECT_NEAR(mug.z, -0.6f, 1e-5f);
  EXPECT_EQ(w.get<Parent>(es[1]).entity, es[0]);
  EXPECT_FALSE(w.has<Mesh>(es[5]));
}

// ---- bad input: one test per kind, each checking the exact message --------------------------

TEST_F(SceneFiles, SyntaxErrorGivesLineAndColumn) {
  const fs::path p = write("scene.json", "{\n  \"entities\": [\n    {\"name\": \"a\",}\n  ]\n}\n");
  const auto r = load_scene_file(p);
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error().json_path, "3:18");
  EXPECT_EQ(r.error().message.rfind("invalid JSON: syntax error while parsing object key", 0), 0u) << r.error().message;
  EXPECT_EQ(r.error().to_string().rfind(p.string() + ":3:18: invalid JSON", 0), 0u) << r.error().to_string();
}

TEST_F(SceneFiles, MissingSceneFile) {
  const auto r = load_scene_file(dir_ / "nope.json");
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error().to_string(), (dir_ / "nope.json").string() + ": scene file not found");
}

TEST_F(SceneFiles, UnknownKey) {
  EXPECT_EQ(error_of(scene_with(R"({"name": "a", "bodyy": {}})")),
            "/entities/0/bodyy: unknown key \"bodyy\"; expected one of: name, parent, transform, mesh, material, "
            "body, grabbable, tracked_by, tags, joint, button, socket, pokeable, gltf");
  EXPECT_EQ(error_of(R"({"entities": [], "setings": {}})"),
            "/setings: unknown key \"setings\"; expected one of: format, version, settings, entities, interactions, rules");
}

TEST_F(SceneFiles, WrongTypes) {
  EXPECT_EQ(error_of(scene_with(R"({"name": "a", "transform": {"position": "up"}})")),
            "/entities/0/transform/position: expected an array of 3 numbers, got \"up\"");
  EXPECT_EQ(error_of(scene_with(R"({"name": "a", "transform": {"position": [1, 2]}})")),
            "/entities/0/transform/position: expected an array of 3 numbers, got an array of 2");
  EXPECT_EQ(error_of(scene_with(R"({"name": 5})")), "/entities/0/name: expected a string, got 5");
  EXPECT_EQ(error_of(R"({"entities": {"name": "a"}})"), "/entities: expected an array, got an object");
  EXPECT_EQ(error_of(scene_with(std::string(kCube) + R"(, {"name": "b", "grabbable": "yes"})")),
            "/entities/1/grabbable: expected true, false or an object, got \"yes\"");
  EXPECT_EQ(error_of(scene_with(R"({"name": "a", "mesh": {"shape": "cone"}})")),
            "/entities/0/mesh/shape: expected one of \"box\", \"sphere\", \"capsule\", \"plane\", \"gltf\", got \"cone\"");
  EXPECT_EQ(error_of("[1, 2]"), "/: expected an object, got an array");
}

TEST_F(SceneFiles, MissingRequiredKey) {
  EXPECT_EQ(error_of(scene_with(R"({"transform": {}})")), "/entities/0: missing required key \"name\"");
  EXPECT_EQ(error_of(scene_with(R"({"name": "a", "mesh": {"shape": "sphere"}})")), "/entities/0/mesh: missing required key \"radius_m\"");
}

TEST_F(SceneFiles, MissingReferencedFiles) {
  EXPECT_EQ(error_of(scene_with(R"({"name": "mug", "mesh": {"shape": "gltf", "file": "meshes/mug.glb"}})")),
            "/entities/0/mesh/file: file not found: " + (dir_ / "meshes/mug.glb").string());
  EXPECT_EQ(error_of(R"({"settings": {"rig": "../rigs/none.yaml"}})"),
            "/settings/rig: file not found: " + (dir_.parent_path() / "rigs/none.yaml").string());
}

TEST_F(SceneFiles, InfiniteAndNaNNumbers) {
  // JSON has no NaN or infinity literals, and a number too large for a double (such as 1e999, which
  // would become infinity) is refused with its position before anything reaches physics or rendering.
  EXPECT_EQ(error_of(scene_with(R"({"name": "a", "transform": {"position": [0, 1e999, 0]}})")),
            "1:59: invalid JSON: the number 1e999 is out of range");
  EXPECT_EQ(error_of("{\n\"settings\": {\"gravity_mps2\": [0, -1e400, 0]}}"), "2:34: invalid JSON: the number -1e400 is out of range");
  EXPECT_EQ(error_of(scene_with(R"({"name": "a", "transform": {"position": [NaN, 0, 0]}})")),
            "1:56: invalid JSON: syntax error while parsing value - invalid literal; last read: '\"position\": [N'");
  EXPECT_EQ(error_of(scene_with(R"({"name": "a", "transform": {"position": [Infinity, 0, 0]}})")).substr(0, 5), "1:56:");
}

TEST_F(SceneFiles, NonPositiveMassOnDynamicBody) {
  EXPECT_EQ(error_of(scene_with(R"({"name": "a", "mesh": {"shape": "sphere", "radius_m": 0.1},
                                    "body": {"type": "dynamic", "mass_kg": -1}})")),
            "/entities/0/body/mass_kg: expected a mass greater than 0 kg for a dynamic body, got -1");
  EXPECT_EQ(error_of(scene_with(R"({"name": "a", "mesh": {"shape": "sphere", "radius_m": 0.1},
                                    "body": {"type": "dynamic", "mass_kg": 0}})")),
            "/entities/0/body/mass_kg: expected a mass greater than 0 kg for a dynamic body, got 0");
  EXPECT_EQ(error_of(scene_with(R"({"name": "a", "mesh": {"shape": "sphere", "radius_m": 0.1},
                                    "body": {"type": "dynamic"}})")),
            "/entities/0/body: missing required key \"mass_kg\"");
  EXPECT_EQ(error_of(scene_with(R"({"name": "a", "mesh": {"shape": "sphere", "radius_m": 0.1},
                                    "body": {"type": "static", "mass_kg": 3}})")),
            "/entities/0/body/mass_kg: only dynamic bodies have a mass; a static body does not move under forces");
}

TEST_F(SceneFiles, DuplicateNames) {
  EXPECT_EQ(error_of(scene_with(std::string(kCube) + ", " + R"({"name": "ball"}, )" + kCube)),
            "/entities/2/name: duplicate name \"cube\" (also at /entities/0/name)");
}

TEST_F(SceneFiles, DuplicateKeys) {
  EXPECT_EQ(error_of(scene_with(R"({"name": "a"}, {"name": "b", "body": {"type": "static"}, "name": "c"})")),
            "/entities/1/name: duplicate key \"name\"");
}

TEST_F(SceneFiles, BadParents) {
  EXPECT_EQ(error_of(scene_with(R"({"name": "a", "parent": "table"})")), "/entities/0/parent: no entity is named \"table\"");
  EXPECT_EQ(error_of(scene_with(R"({"name": "a", "parent": "b"}, {"name": "b", "parent": "a"})")),
            "/entities/0/parent: parent \"b\" makes a cycle");
  EXPECT_EQ(error_of(scene_with(R"({"name": "a", "parent": "a"})")), "/entities/0/parent: parent \"a\" makes a cycle");
}

TEST_F(SceneFiles, InconsistentEntities) {
  EXPECT_EQ(error_of(scene_with(R"({"name": "a", "body": {"type": "static"}})")),
            "/entities/0/body: a body needs a \"mesh\" on the same entity to give it a shape");
  EXPECT_EQ(error_of(scene_with(R"({"name": "a", "mesh": {"shape": "box", "size_m": [1, 1, 1]}, "grabbable": true})")),
            "/entities/0/grabbable: only an entity with a dynamic body can be grabbable");
  EXPECT_EQ(error_of(scene_with(std::string(kCube).insert(1, R"("tracked_by": 1, )"))),
            "/entities/0/tracked_by: a tracked entity follows its marker star, so its body must be kinematic");
  EXPECT_EQ(error_of(scene_with(R"({"name": "a", "tracked_by": 1}, {"name": "b", "tracked_by": 1})")),
            "/entities/1/tracked_by: marker star 1 already tracks /entities/0");
  EXPECT_EQ(error_of(scene_with(R"({"name": "f", "mesh": {"shape": "plane", "size_m": [1, 1]},
                                    "body": {"type": "dynamic", "mass_kg": 1}})")),
            "/entities/0/body: a plane is unbounded and can only be a static body");
  EXPECT_EQ(error_of(scene_with(R"({"name": "c", "mesh": {"shape": "capsule", "radius_m": 0.1, "height_m": 0.1}})")),
            "/entities/0/mesh/height_m: expected a height (end to end) of at least twice the radius (0.200000), got 0.1");
}

TEST_F(SceneFiles, OutOfRangeValues) {
  EXPECT_EQ(error_of(scene_with(R"({"name": "a", "transform": {"scale": [1, 0, 1]}})")),
            "/entities/0/transform/scale/1: expected a number greater than 0 (and within float range), got 0");
  EXPECT_EQ(error_of(scene_with(R"({"name": "a", "transform": {"rotation": [0, 0, 0, 2]}})")),
            "/entities/0/transform/rotation: expected a unit quaternion [x, y, z, w], got one of length 2.000000");
  EXPECT_EQ(error_of(scene_with(R"({"name": "a", "transform": {"rotation": [0, 0, 0, 1], "rotation_deg": [0, 0, 0]}})")),
            "/entities/0/transform/rotation_deg: give either \"rotation\" (a quaternion) or \"rotation_deg\" (Euler "
            "angles), not both");
  EXPECT_EQ(error_of(scene_with(R"({"name": "a", "mesh": {"shape": "sphere", "radius_m": 0.1}, "material": {"color": [1.5, 0, 0]}})")),
            "/entities/0/material/color/0: expected a number from 0 to 1, got 1.5");
  EXPECT_EQ(error_of(R"({"settings": {"headset": {"ipd_m": 63}}})"),
            "/settings/headset/ipd_m: expected an interpupillary distance from 0.04 to 0.09 m, got 63");
  EXPECT_EQ(error_of(R"({"settings": {"headset": {"eye_resolution_px": [1080.5, 1200]}}})"),
            "/settings/headset/eye_resolution_px/0: expected an integer, got 1080.5");
  EXPECT_EQ(error_of(R"({"settings": {"hands": ["left", "left"]}})"), "/settings/hands/1: hand \"left\" is listed twice");
  EXPECT_EQ(error_of(R"({"version": 2})"), "/version: expected an integer from 1 to 1, got 2");
  // Sizes are floats at run time: 1e-50 would become 0 and 1e50 infinity.
  EXPECT_EQ(error_of(scene_with(R"({"name": "a", "mesh": {"shape": "sphere", "radius_m": 1e-50}})")),
            "/entities/0/mesh/radius_m: expected a number greater than 0 (and within float range), got 1e-50");
  EXPECT_EQ(error_of(scene_with(R"({"name": "a", "transform": {"position": [1e50, 0, 0]}})")),
            "/entities/0/transform/position/0: expected a number within float range (magnitude up to 3.4e38), got 1e+50");
}

TEST_F(SceneFiles, ShippedInteractionScenesLoad) {
  for (const char* name : {"interaction-place.json", "interaction-hand-over.json"}) {
    const auto scene = load_scene_file(fs::path(RHOT_ASSET_DIR) / "scenes" / name);
    ASSERT_TRUE(scene.has_value()) << scene.error().to_string();
    ASSERT_EQ(scene->interactions.size(), 1U) << name;
  }
  const auto place = load_scene_file(fs::path(RHOT_ASSET_DIR) / "scenes" / "interaction-place.json");
  EXPECT_EQ(place->interactions[0].type, InteractionType::kPlace);
  EXPECT_EQ(place->interactions[0].zone, "bin");
  EXPECT_DOUBLE_EQ(place->settings.grasp.release_distance_m, 0.012);
}

TEST_F(SceneFiles, GraspSettingsAndSubsteps) {
  const auto scene = parse_scene(
      R"({"settings": {"physics_substeps": 4,
                       "grasp": {"regrasp_delay_s": 0.5, "opposing_cos": -0.5, "pad_radius_m": 0, "fingers_join": false,
                                 "open_for_s": 0}},
          "entities": []})",
      dir_);
  ASSERT_TRUE(scene.has_value());
  EXPECT_EQ(scene->settings.physics_substeps, 4);
  EXPECT_DOUBLE_EQ(scene->settings.grasp.regrasp_delay_s, 0.5);
  EXPECT_DOUBLE_EQ(scene->settings.grasp.opposing_cos, -0.5);
  EXPECT_DOUBLE_EQ(scene->settings.grasp.pad_radius_m, 0.0);
  EXPECT_FALSE(scene->settings.grasp.fingers_join);
  EXPECT_TRUE(GraspSettings{}.fingers_join);
  EXPECT_DOUBLE_EQ(scene->settings.grasp.open_for_s, 0.0);
  EXPECT_DOUBLE_EQ(scene->settings.grasp.release_distance_m, GraspSettings{}.release_distance_m);
  EXPECT_EQ(error_of(R"({"settings": {"grasp": {"release_distance_m": 0}}})"),
            "/settings/grasp/release_distance_m: expected a distance from 0.001 to 0.2 m, got 0");
  EXPECT_EQ(error_of(R"({"settings": {"grasp": {"open_for_s": -0.1}}})"),
            "/settings/grasp/open_for_s: expected a time from 0 to 1 s, got -0.1");
  EXPECT_EQ(error_of(R"({"settings": {"grasp": {"pad_radius_m": -0.01}}})"),
            "/settings/grasp/pad_radius_m: expected a distance from 0 to 0.05 m, got -0.01");
  EXPECT_EQ(error_of(R"({"settings": {"grasp": {"fingers_join": 1}}})"), "/settings/grasp/fingers_join: expected true or false, got 1");
  EXPECT_EQ(error_of(R"({"settings": {"grasp": {"stickiness": 1}}})").substr(0, 52),
            "/settings/grasp/stickiness: unknown key \"stickiness\"");
  EXPECT_EQ(error_of(R"({"settings": {"physics_substeps": 0}})"), "/settings/physics_substeps: expected an integer from 1 to 16, got 0");
}

TEST_F(SceneFiles, BadInteractionsAreNamed) {
  const std::string zone = R"({"name": "bin", "mesh": {"shape": "box", "size_m": [0.1, 0.1, 0.1]}})";
  const std::string grabbable = R"({"name": "cube", "mesh": {"shape": "box", "size_m": [0.1, 0.1, 0.1]},
                                   "body": {"type": "dynamic", "mass_kg": 0.2}, "grabbable": true})";
  const auto with = [&](const std::string& interactions) {
    const std::string crate = R"({"name": "crate", "mesh": {"shape": "box", "size_m": [0.3, 0.3, 0.3]}, "body": {"type": "static"}})";
    return R"({"entities": [)" + grabbable + ", " + zone + ", " + crate + R"(], "interactions": [)" + interactions + "]}";
  };
  EXPECT_EQ(error_of(with(R"({"name": "a", "type": "place", "object": "cube", "zone": "bin"})")), "");
  EXPECT_EQ(error_of(with(R"({"name": "a", "type": "hand_over", "object": "cube"})")), "");
  EXPECT_EQ(error_of(with(R"({"name": "a", "type": "stack", "object": "cube"})")),
            "/interactions/0/type: expected \"place\" or \"hand_over\", got \"stack\"");
  EXPECT_EQ(error_of(with(R"({"name": "a", "type": "place", "object": "mug", "zone": "bin"})")),
            "/interactions/0/object: no entity is named \"mug\"");
  EXPECT_EQ(error_of(with(R"({"name": "a", "type": "place", "object": "cube", "zone": "shelf"})")),
            "/interactions/0/zone: no entity is named \"shelf\"");
  EXPECT_EQ(error_of(with(R"({"name": "a", "type": "hand_over", "object": "cube-2"})")),
            "/interactions/0/object: no entity is named \"cube-2\"");
  EXPECT_EQ(error_of(with(R"({"name": "a", "type": "place", "object": "bin", "zone": "bin"})")),
            "/interactions/0/object: \"bin\" is not grabbable");
  EXPECT_EQ(error_of(with(R"({"name": "a", "type": "place", "object": "cube", "zone": "crate"})")),
            "/interactions/0/zone: zone \"crate\" has a physics body; a zone must let objects in");
  EXPECT_EQ(error_of(with(R"({"name": "a", "type": "place", "object": "cube"})")), "/interactions/0: missing required key \"zone\"");
  EXPECT_EQ(error_of(with(R"({"name": "a", "type": "hand_over", "object": "cube", "zone": "bin"})")),
            "/interactions/0/zone: a hand_over has no zone");
  EXPECT_EQ(error_of(with(R"({"name": "a", "type": "hand_over", "object": "cube"}, {"name": "a", "type": "hand_over", "object": "cube"})")),
            "/interactions/1/name: duplicate interaction name \"a\" (also at /interactions/0/name)");
}

TEST_F(SceneFiles, FailedLoadLeavesTheWorldUntouched) {
  World w;
  const auto good = parse_scene(scene_with(kCube), dir_);
  ASSERT_TRUE(good.has_value());
  const std::vector<Entity> made = instantiate(*good, w);
  ASSERT_EQ(made.size(), 1u);

  // The error is in the last entity: nothing of the first two may appear anywhere.
  const auto bad = parse_scene(scene_with(R"({"name": "x", "mesh": {"shape": "sphere", "radius_m": 1}},
                                             {"name": "y"}, {"name": "z", "transform": {"position": [0, "up", 0]}})"),
                               dir_);
  ASSERT_FALSE(bad.has_value());
  EXPECT_EQ(bad.error().json_path, "/entities/2/transform/position/1");
  // The world holds the cube alone, as it was: one entity, one mesh, the cube's box.
  EXPECT_EQ(w.size(), 1u);
  EXPECT_EQ(w.count<Mesh>(), 1u);
  EXPECT_EQ(find_named(w, "cube"), made[0]);
  EXPECT_TRUE(find_named(w, "x").is_null());
  EXPECT_TRUE(find_named(w, "y").is_null());
  EXPECT_TRUE(find_named(w, "z").is_null());
  ASSERT_TRUE(std::holds_alternative<BoxShape>(w.get<Mesh>(made[0]).shape));
  EXPECT_EQ(std::get<BoxShape>(w.get<Mesh>(made[0]).shape).size_m, glm::vec3(0.1f));
}

}  // namespace
}  // namespace rhot
