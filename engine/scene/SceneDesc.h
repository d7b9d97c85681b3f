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

// How hands grasp (engine/interact/GraspSystem.h, docs/grasping.md); the scene file's
// "settings": {"grasp": {...}} overrides any of these.
struct GraspSettings {
  double contact_distance_m = 0.003;  // a bone within this of an object touches it
  double opposing_cos = -0.3;         // anchor and finger normals: cosine below this (over ~107 degrees apart)
  // Above 0: anchor and finger normals also oppose as finger pads of this radius feel them (on a
  // box, its normals rounded by the radius: within it of an edge, turned toward the edge; 10 mm is
  // about half a fingertip's width). 0: the contacts' own normals only (docs/grasping.md, "finger pad").
  double pad_radius_m = 0.01;
  double min_curl_rad = 0.15;         // an opposing finger is curled at least this much (root to tip)
  double release_distance_m = 0.012;  // a grasping finger this far out of the surface is open ...
  double open_for_s = 0.05;           // ... once measured so this long (a few frames' jitter is no opening)
  double confident = 0.95;            // joint confidence below this: not measured, never "open"
  double regrasp_delay_s = 0.2;       // a hand that released cannot grasp again this soon
  double throw_window_s = 0.05;       // the release velocity is fitted over this window ...
  double throw_window_end_s = 0.02;   // ... ending this long before the release
  double max_hold_error_m = 0.1;      // a held object kept this far from the hand (stuck) is dropped
  double max_object_speed_mps = 20.0;
  double hover_distance_m = 0.05;  // the palm this close to an object's bounding box: hovering
  // A hidden finger is curled at most this much further to meet what its hand holds or touches
  // (engine/interact/FingerContact.h); 0: hidden fingers stay where the tracker puts them.
  double hidden_finger_curl_rad = 1.0;
  // Fingers that close on a held object after the grasp began join its grip (curled, touching it
  // and opposing the thumb or palm; a hidden one where the hidden-finger rule placed it, in the
  // grasp's first 0.5 s), so the grip ends only when they open too; false: the grip keeps the
  // fingers it began with.
  bool fingers_join = true;
};

struct SceneSettings {
  std::optional<std::filesystem::path> rig_file;  // camera rig (OpenCV YAML); none: the built-in rig
  HeadsetSettings headset;
  bool left_hand = true;
  bool right_hand = true;
  glm::vec3 gravity_mps2{0.0f, -9.81f, 0.0f};
  int physics_substeps = 2;  // Bullet steps per frame
  GraspSettings grasp;
};

// An interaction a scene declares: when it happens, a success event carries its name.
enum class InteractionType {
  kPlace,     // `object` comes to rest inside `zone` (an entity with a box mesh), not held
  kHandOver,  // `object` passes from one hand's grasp directly to the other's
};

struct InteractionDesc {
  std::string name;
  InteractionType type = InteractionType::kPlace;
  std::string object;     // entity names
  std::string zone;       // kPlace only
  double dwell_s = 0.25;  // kPlace: at rest inside this long
};

struct EntityDesc {
  std::string name;
  std::string parent;  // name of another entity in the scene, or empty for a root
  Transform transform;
  std::optional<Mesh> mesh;
  std::optional<Material> material;
  std::optional<PhysicsBody> body;
  std::optional<Grabbable> grabbable;
  std::optional<int> tracked_by;  // marker-star id
  std::vector<std::string> tags;
  std::optional<Joint> joint;
  std::optional<Button> button;
  std::optional<Socket> socket;
  bool pokeable = false;
};

// What a rule listens for (docs/scene-format.md "rules"): an event of this kind about `entity`
// (the object grasped or released, the button, the socket, the joint's entity; empty: any), for
// snap and unsnap optionally only of `object`; value_above and value_below fire when the
// joint's value crosses `value` (degrees or metres).
struct RuleTrigger {
  std::string event;  // one of rule_event_names()
  std::string entity;
  std::string object;
  double value = 0.0;
  std::string interaction;  // "success": the interaction's name (empty: any)
};

// What a rule does. "set_color": entity, color; "enable", "disable": entity; "motor": entity
// (with a hinge or slider joint), velocity, max_force; "spawn": entity (copied), position (world,
// optional: where the original is); "succeed": name.
struct RuleAction {
  std::string action;  // one of rule_action_names()
  std::string entity;
  glm::vec4 color{1.0f};
  double velocity = 0.0;
  double max_force = 0.0;
  std::optional<glm::vec3> position;
  std::string name;
};

struct RuleDesc {
  RuleTrigger when;
  std::vector<RuleAction> actions;
  bool once = false;  // fires at most once
};

// The vocabulary a scene's rules may use.
inline const std::vector<std::string>& rule_event_names() {
  static const std::vector<std::string> names{"grasp",       "release",     "press", "unpress", "snap", "unsnap",
                                              "value_above", "value_below", "poke",  "enter",   "exit", "success"};
  return names;
}
inline const std::vector<std::string>& rule_action_names() {
  static const std::vector<std::string> names{"set_color", "enable", "disable", "motor", "spawn", "succeed"};
  return names;
}

struct SceneDesc {
  std::filesystem::path file;  // where it was read from (empty when parsed from text)
  SceneSettings settings;
  std::vector<EntityDesc> entities;
  std::vector<InteractionDesc> interactions;
  std::vector<RuleDesc> rules;
};

}  // namespace rhot
