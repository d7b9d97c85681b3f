#pragma once
// Scenes written in code for the physics tests: parsed by the real scene loader and instantiated.

#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "engine/core/World.h"
#include "engine/interact/HandPhysics.h"
#include "engine/scene/SceneLoader.h"

namespace rhot::test {

inline SceneDesc parse(const std::string& text) {
  auto scene = parse_scene(text, RHOT_SOURCE_DIR "/tests/engine/physics/data");
  EXPECT_TRUE(scene.has_value()) << (scene ? "" : scene.error().to_string());
  return scene.value_or(SceneDesc{});
}

inline Entity named(World& world, const std::string& name) { return find_named(world, name); }

inline constexpr const char* kFloor = R"({"name": "floor", "mesh": {"shape": "plane", "size_m": [4, 4]}, "body": {"type": "static"}})";

inline std::unique_ptr<HandPhysics> physics_for(World& world, const SceneDesc& scene) {
  instantiate(scene, world);
  auto p = HandPhysics::create(world, scene);
  EXPECT_TRUE(p.has_value()) << (p ? "" : p.error());
  return p ? std::move(*p) : nullptr;
}

}  // namespace rhot::test
