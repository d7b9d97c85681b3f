#pragma once
// Scene files: JSON, documented in docs/scene-format.md.
//
// Every problem with a file is reported as one SceneError naming the file, the JSON pointer of
// the offending value (such as /entities/3/body/mass_kg) and what was expected. Nothing is
// created on failure.

#include <expected>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "base/JsonError.h"
#include "engine/core/Entity.h"
#include "engine/scene/SceneDesc.h"

namespace rhot {

class World;

// "file: /json/path: message"; json_path is empty for errors about the whole file, "line:col" for
// syntax errors.
using SceneError = JsonError;

// Reads and validates a scene file. Relative file references in it (glTF meshes, the camera rig)
// are resolved against the scene file's folder and must exist.
[[nodiscard]] std::expected<SceneDesc, SceneError> load_scene_file(const std::filesystem::path& file);

// The same for scene text in memory; `base_dir` resolves relative references and `name` is used
// in messages.
[[nodiscard]] std::expected<SceneDesc, SceneError> parse_scene(std::string_view json_text, const std::filesystem::path& base_dir,
                                                               std::string_view name = "<text>");

// Creates one entity per EntityDesc with Name, Transform, WorldTransform and, where given, Parent,
// Mesh, Material, PhysicsBody, Grabbable and TrackedBy; world transforms are up to date on return.
// Returns the entities in the order of scene.entities. Cannot fail for a SceneDesc from the
// loader. Precondition: the world is not iterating; names and parents are valid.
std::vector<Entity> instantiate(const SceneDesc& scene, World& world);

// The entity with this Name, or a null entity. Linear in the number of named entities.
Entity find_named(World& world, std::string_view name);

}  // namespace rhot
