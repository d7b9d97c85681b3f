#pragma once
// A scene as read from a file: validated plain data, not yet in any World. Loading fills this
// completely or fails; instantiate() then builds entities from it and cannot fail, so a bad file
// never leaves a half-built scene behind.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "engine/core/Transform.h"
#include "engine/scene/Components.h"

namespace rhot {

// Half-angles of one eye's view frustum, measured from the eye's forward axis, positive outward.
struct EyeFovDeg {
  double left = 50.0;
  double right = 50.0;
  double up = 50.0;
  double down = 50.0;
};

// Defaults like a consumer headset: 1080 x 1200 per eye at 90 Hz, 63 mm between the eyes, each
// eye's frustum a little narrower toward the nose.
struct HeadsetSettings {
  double ipd_m = 0.063;
  int eye_width_px = 1080;
  int eye_height_px = 1200;
  double refresh_hz = 90.0;
  double near_m = 0.05;
  double far_m = 100.0;
  EyeFovDeg left_eye{52.0, 44.0, 50.0, 50.0};
  EyeFovDeg right_eye{44.0, 52.0, 50.0, 50.0};
};

struct SceneSettings {
  std::optional<std::filesystem::path> rig_file;  // camera rig (OpenCV YAML); none: the built-in rig
  HeadsetSettings headset;
  bool left_hand = true;
  bool right_hand = true;
  glm::vec3 gravity_mps2{0.0f, -9.81f, 0.0f};
};

struct EntityDesc {
  std::string name;
  std::string parent;  // name of another entity in the scene, or empty for a root
  Transform transform;
  std::optional<Mesh> mesh;
  std::optional<Material> material;
  std::optional<PhysicsBody> body;
  bool grabbable = false;
  std::optional<int> tracked_by;  // marker-star id
};

struct SceneDesc {
  std::filesystem::path file;  // where it was read from (empty when parsed from text)
  SceneSettings settings;
  std::vector<EntityDesc> entities;
};

}  // namespace rhot
