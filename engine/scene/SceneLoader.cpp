#include "engine/scene/SceneLoader.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <unordered_map>
#include <variant>

#include <glm/gtc/quaternion.hpp>
#include <nlohmann/json.hpp>

#include "engine/core/World.h"
#include "base/Check.h"
#include "base/Json.h"
#include "engine/scene/GltfPhysics.h"

namespace rhot {

namespace {

using nlohmann::json;

using Node = JsonNode;

std::string describe(const json& j) { return describe_json(j); }

glm::vec3 vec3(const Node& n) {
  const auto v = n.numbers(3);
  return {static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2])};
}

// Resolves a file reference relative to the scene's folder and checks that it exists.
std::filesystem::path existing_file(const Node& node, const std::filesystem::path& base_dir) {
  const std::filesystem::path given = node.non_empty_string();
  const std::filesystem::path full = given.is_absolute() ? given : base_dir / given;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(full, ec)) {
    node.fail("file not found: " + full.lexically_normal().string());
  }
  return full.lexically_normal();
}

Transform read_transform(const Node& n) {
  n.expect_object({"position", "rotation", "rotation_deg", "scale"});
  Transform t;
  if (auto p = n.optional("position")) t.position = vec3(*p);
  if (n.has("rotation") && n.has("rotation_deg")) {
    n["rotation_deg"].fail("give either \"rotation\" (a quaternion) or \"rotation_deg\" (Euler angles), not both");
  }
  if (auto r = n.optional("rotation")) {
    const auto q = r->numbers(4);  // x, y, z, w as in glTF
    const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (std::abs(norm - 1.0) > 1e-3) {
      r->fail("expected a unit quaternion [x, y, z, w], got one of length " + std::to_string(norm));
    }
    t.rotation =
        glm::normalize(glm::quat(static_cast<float>(q[3]), static_cast<float>(q[0]), static_cast<float>(q[1]), static_cast<float>(q[2])));
  }
  if (auto r = n.optional("rotation_deg")) {
    // Extrinsic X, then Y, then Z: R = Rz * Ry * Rx.
    const glm::vec3 deg = vec3(*r);
    const glm::quat qx = glm::angleAxis(glm::radians(deg.x), glm::vec3(1, 0, 0));
    const glm::quat qy = glm::angleAxis(glm::radians(deg.y), glm::vec3(0, 1, 0));
    const glm::quat qz = glm::angleAxis(glm::radians(deg.z), glm::vec3(0, 0, 1));
    t.rotation = glm::normalize(qz * qy * qx);
  }
  if (auto s = n.optional("scale")) {
    if (s->raw().is_number()) {
      t.scale = glm::vec3(static_cast<float>(s->positive()));
    } else {
      const auto v = s->numbers(3);
      const auto elements = s->elements();
      for (std::size_t i = 0; i < 3; ++i) elements[i].positive();
      t.scale = {static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2])};
    }
  }
  return t;
}

Mesh read_mesh(const Node& n, const std::filesystem::path& base_dir) {
  if (!n.raw().is_object()) n.fail("expected an object, got " + describe(n.raw()));
  const Node shape_node = n["shape"];
  const std::string shape = shape_node.string();
  if (shape == "box") {
    n.expect_object({"shape", "size_m"});
    const Node size = n["size_m"];
    size.numbers(3);
    const auto e = size.elements();
    return Mesh{BoxShape{{static_cast<float>(e[0].positive()), static_cast<float>(e[1].positive()), static_cast<float>(e[2].positive())}}};
  }
  if (shape == "sphere") {
    n.expect_object({"shape", "radius_m"});
    return Mesh{SphereShape{static_cast<float>(n["radius_m"].positive())}};
  }
  if (shape == "capsule") {
    n.expect_object({"shape", "radius_m", "height_m"});
    const double r = n["radius_m"].positive();
    const Node h = n["height_m"];
    const double height = h.positive();
    if (height < 2.0 * r) {
      h.fail("expected a height (end to end) of at least twice the radius (" + std::to_string(2.0 * r) + "), got " + describe(h.raw()));
    }
    return Mesh{CapsuleShape{static_cast<float>(r), static_cast<float>(height)}};
  }
  if (shape == "plane") {
    n.expect_object({"shape", "size_m"});
    const Node size = n["size_m"];
    size.numbers(2);
    const auto e = size.elements();
    return Mesh{PlaneShape{{static_cast<float>(e[0].positive()), static_cast<float>(e[1].positive())}}};
  }
  if (shape == "gltf") {
    n.expect_object({"shape", "file"});
    const Node file = n["file"];
    const std::filesystem::path path = existing_file(file, base_dir);
    const std::string ext = path.extension().string();
    if (ext != ".gltf" && ext != ".glb") file.fail("expected a .gltf or .glb file, got " + describe(file.raw()));
    return Mesh{GltfMeshShape{path}};
  }
  shape_node.fail("expected one of \"box\", \"sphere\", \"capsule\", \"plane\", \"gltf\", got " + describe(shape_node.raw()));
}

glm::vec4 read_color(const Node& c) {
  if (!c.raw().is_array() || (c.raw().size() != 3 && c.raw().size() != 4)) {
    c.fail("expected [r, g, b] or [r, g, b, a] with each in [0, 1], got " + describe(c.raw()));
  }
  glm::vec4 color(1.0f);
  const auto e = c.elements();
  for (std::size_t i = 0; i < e.size(); ++i) {
    color[static_cast<glm::length_t>(i)] = static_cast<float>(e[i].number_in(0.0, 1.0, "a number from 0 to 1"));
  }
  return color;
}

Material read_material(const Node& n) {
  n.expect_object({"color"});
  return Material{read_color(n["color"])};
}

PhysicsBody read_body(const Node& n) {
  n.expect_object({"type", "mass_kg", "friction", "restitution"});
  PhysicsBody b;
  const Node type = n["type"];
  const std::string t = type.string();
  if (t == "static") {
    b.type = BodyType::kStatic;
  } else if (t == "dynamic") {
    b.type = BodyType::kDynamic;
  } else if (t == "kinematic") {
    b.type = BodyType::kKinematic;
  } else {
    type.fail("expected \"static\", \"dynamic\" or \"kinematic\", got " + describe(type.raw()));
  }
  if (b.type == BodyType::kDynamic) {
    const Node mass = n["mass_kg"];
    const double m = mass.number();
    if (!(m > 0.0)) mass.fail("expected a mass greater than 0 kg for a dynamic body, got " + describe(mass.raw()));
    b.mass_kg = static_cast<float>(m);
  } else if (auto mass = n.optional("mass_kg")) {
    mass->fail("only dynamic bodies have a mass; a " + t + " body does not move under forces");
  }
  if (auto f = n.optional("friction")) b.friction = static_cast<float>(f->number_in(0.0, 10.0, "a friction coefficient from 0 to 10"));
  if (auto r = n.optional("restitution")) b.restitution = static_cast<float>(r->number_in(0.0, 1.0, "a restitution from 0 to 1"));
  return b;
}

EyeFovDeg read_eye_fov(const Node& n) {
  n.expect_object({"left", "right", "up", "down"});
  EyeFovDeg f;
  const char* range = "an angle from 1 to 89 degrees";
  f.left = n["left"].number_in(1.0, 89.0, range);
  f.right = n["right"].number_in(1.0, 89.0, range);
  f.up = n["up"].number_in(1.0, 89.0, range);
  f.down = n["down"].number_in(1.0, 89.0, range);
  return f;
}

HeadsetSettings read_headset(const Node& n) {
  n.expect_object({"ipd_m", "eye_resolution_px", "refresh_hz", "near_m", "far_m", "fov_deg"});
  HeadsetSettings h;
  if (auto v = n.optional("ipd_m")) h.ipd_m = v->number_in(0.04, 0.09, "an interpupillary distance from 0.04 to 0.09 m");
  if (auto v = n.optional("eye_resolution_px")) {
    const auto e = v->elements();
    if (e.size() != 2) v->fail("expected [width, height] in pixels");
    h.eye_width_px = e[0].integer_in(16, 8192);
    h.eye_height_px = e[1].integer_in(16, 8192);
  }
  if (auto v = n.optional("refresh_hz")) h.refresh_hz = v->number_in(1.0, 1000.0, "a refresh rate from 1 to 1000 Hz");
  if (auto v = n.optional("near_m")) h.near_m = v->positive();
  if (auto v = n.optional("far_m")) {
    h.far_m = v->positive();
    if (h.far_m <= h.near_m) v->fail("expected far_m greater than near_m (" + std::to_string(h.near_m) + ")");
  }
  if (auto v = n.optional("fov_deg")) {
    v->expect_object({"left_eye", "right_eye"});
    if (auto l = v->optional("left_eye")) h.left_eye = read_eye_fov(*l);
    if (auto r = v->optional("right_eye")) h.right_eye = read_eye_fov(*r);
  }
  return h;
}

GraspSettings read_grasp(const Node& n) {
  n.expect_object({"contact_distance_m", "opposing_cos", "pad_radius_m", "min_curl_rad", "release_distance_m", "open_for_s", "confident",
                   "regrasp_delay_s", "throw_window_s", "throw_window_end_s", "max_hold_error_m", "max_object_speed_mps",
                   "hover_distance_m", "hidden_finger_curl_rad", "fingers_join"});
  GraspSettings g;
  const auto set = [&](const char* key, double& value, double lo, double hi, const char* what) {
    if (auto v = n.optional(key)) value = v->number_in(lo, hi, what);
  };
  set("contact_distance_m", g.contact_distance_m, 0.0, 0.05, "a distance from 0 to 0.05 m");
  set("opposing_cos", g.opposing_cos, -1.0, 1.0, "a cosine from -1 to 1");
  set("pad_radius_m", g.pad_radius_m, 0.0, 0.05, "a distance from 0 to 0.05 m");
  set("min_curl_rad", g.min_curl_rad, 0.0, 3.2, "an angle from 0 to 3.2 rad");
  set("release_distance_m", g.release_distance_m, 0.001, 0.2, "a distance from 0.001 to 0.2 m");
  set("open_for_s", g.open_for_s, 0.0, 1.0, "a time from 0 to 1 s");
  set("confident", g.confident, 0.0, 1.0, "a confidence from 0 to 1");
  set("regrasp_delay_s", g.regrasp_delay_s, 0.0, 10.0, "a time from 0 to 10 s");
  set("throw_window_s", g.throw_window_s, 0.0, 1.0, "a time from 0 to 1 s");
  set("throw_window_end_s", g.throw_window_end_s, 0.0, 0.2, "a time from 0 to 0.2 s");
  set("max_hold_error_m", g.max_hold_error_m, 0.01, 10.0, "a distance from 0.01 to 10 m");
  set("max_object_speed_mps", g.max_object_speed_mps, 0.1, 100.0, "a speed from 0.1 to 100 m/s");
  set("hover_distance_m", g.hover_distance_m, 0.0, 1.0, "a distance from 0 to 1 m");
  set("hidden_finger_curl_rad", g.hidden_finger_curl_rad, 0.0, 2.0, "an angle from 0 to 2 rad");
  if (auto v = n.optional("fingers_join")) g.fingers_join = v->boolean();
  return g;
}

SceneSettings read_settings(const Node& n, const std::filesystem::path& base_dir) {
  n.expect_object({"rig", "headset", "hands", "gravity_mps2", "physics_substeps", "grasp"});
  SceneSettings s;
  if (auto rig = n.optional("rig")) s.rig_file = existing_file(*rig, base_dir);
  if (auto h = n.optional("headset")) s.headset = read_headset(*h);
  if (auto hands = n.optional("hands")) {
    s.left_hand = s.right_hand = false;
    for (const Node& h : hands->elements()) {
      const std::string side = h.string();
      bool& slot = side == "left" ? s.left_hand : s.right_hand;
      if (side != "left" && side != "right") h.fail("expected \"left\" or \"right\", got " + describe(h.raw()));
      if (slot) h.fail("hand \"" + side + "\" is listed twice");
      slot = true;
    }
  }
  if (auto g = n.optional("gravity_mps2")) s.gravity_mps2 = vec3(*g);
  if (auto p = n.optional("physics_substeps")) s.physics_substeps = p->integer_in(1, 16);
  if (auto g = n.optional("grasp")) s.grasp = read_grasp(*g);
  return s;
}

InteractionDesc read_interaction(const Node& n) {
  n.expect_object({"name", "type", "object", "zone", "dwell_s"});
  InteractionDesc d;
  d.name = n["name"].non_empty_string();
  const Node type = n["type"];
  const std::string t = type.string();
  if (t == "place") {
    d.type = InteractionType::kPlace;
  } else if (t == "hand_over") {
    d.type = InteractionType::kHandOver;
  } else {
    type.fail("expected \"place\" or \"hand_over\", got " + describe(type.raw()));
  }
  d.object = n["object"].non_empty_string();
  if (d.type == InteractionType::kPlace) {
    d.zone = n["zone"].non_empty_string();
    if (auto w = n.optional("dwell_s")) d.dwell_s = w->number_in(0.0, 60.0, "a time from 0 to 60 s");
  } else {
    if (auto z = n.optional("zone")) z->fail("a hand_over has no zone");
    if (auto w = n.optional("dwell_s")) w->fail("a hand_over has no dwell time");
  }
  return d;
}

void check_interactions(const std::vector<InteractionDesc>& interactions, const std::vector<EntityDesc>& entities) {
  const auto find = [&](const std::string& name) -> const EntityDesc* {
    for (const EntityDesc& e : entities) {
      if (e.name == name) return &e;
    }
    return nullptr;
  };
  for (std::size_t i = 0; i < interactions.size(); ++i) {
    const InteractionDesc& d = interactions[i];
    const std::string path = "/interactions/" + std::to_string(i);
    for (std::size_t k = 0; k < i; ++k) {
      if (interactions[k].name == d.name) {
        throw JsonFailure{path + "/name",
                          "duplicate interaction name \"" + d.name + "\" (also at /interactions/" + std::to_string(k) + "/name)"};
      }
    }
    const EntityDesc* object = find(d.object);
    if (!object) throw JsonFailure{path + "/object", "no entity is named \"" + d.object + "\""};
    if (!object->grabbable) throw JsonFailure{path + "/object", "\"" + d.object + "\" is not grabbable"};
    if (d.type == InteractionType::kPlace) {
      const EntityDesc* zone = find(d.zone);
      if (!zone) throw JsonFailure{path + "/zone", "no entity is named \"" + d.zone + "\""};
      if (!zone->mesh || !std::holds_alternative<BoxShape>(zone->mesh->shape)) {
        throw JsonFailure{path + "/zone", "zone \"" + d.zone + "\" needs a box mesh (the zone is its box)"};
      }
      if (zone->body) throw JsonFailure{path + "/zone", "zone \"" + d.zone + "\" has a physics body; a zone must let objects in"};
    }
  }
}

// A unit vector from three numbers, not all zero.
glm::vec3 unit_axis(const Node& n) {
  const glm::vec3 v = vec3(n);
  const float len = glm::length(v);
  if (!(len > 1e-6f)) n.fail("expected a direction [x, y, z] that is not zero, got " + describe(n.raw()));
  return v / len;
}

// [lo, hi] with lo <= hi, each within [min, max].
std::array<double, 2> read_limits(const Node& n, double min, double max, const char* what) {
  n.numbers(2);
  const auto e = n.elements();
  const double lo = e[0].number_in(min, max, what), hi = e[1].number_in(min, max, what);
  if (lo > hi) n.fail("expected [lower, upper] with lower <= upper, got " + describe(n.raw()));
  return {lo, hi};
}

Joint read_joint(const Node& n) {
  if (!n.raw().is_object()) n.fail("expected an object, got " + describe(n.raw()));
  const Node type = n["type"];
  const std::string t = type.string();
  Joint j;
  if (t == "hinge") {
    j.type = JointType::kHinge;
  } else if (t == "slider") {
    j.type = JointType::kSlider;
  } else if (t == "fixed") {
    j.type = JointType::kFixed;
  } else if (t == "ball") {
    j.type = JointType::kBall;
  } else {
    type.fail("expected \"hinge\", \"slider\", \"fixed\" or \"ball\", got " + describe(type.raw()));
  }
  const bool hinge = j.type == JointType::kHinge, slider = j.type == JointType::kSlider;
  if (hinge) {
    n.expect_object({"type", "connected_to", "anchor_m", "axis", "limits_deg", "friction", "spring", "motor"});
  } else if (slider) {
    n.expect_object({"type", "connected_to", "anchor_m", "axis", "limits_m", "friction", "spring", "motor"});
  } else {
    n.expect_object({"type", "connected_to", "anchor_m"});
  }
  if (auto c = n.optional("connected_to")) j.connected_to = c->non_empty_string();
  if (auto a = n.optional("anchor_m")) j.anchor_m = vec3(*a);
  if (hinge || slider) j.axis = unit_axis(n["axis"]);
  if (auto l = n.optional("limits_deg")) j.limits = read_limits(*l, -180.0, 180.0, "an angle from -180 to 180 degrees");
  if (auto l = n.optional("limits_m")) j.limits = read_limits(*l, -100.0, 100.0, "a position from -100 to 100 m");
  if (auto f = n.optional("friction")) j.friction = f->number_in(0.0, 1e4, "a friction from 0 to 10000 (N or N m)");
  if (auto sp = n.optional("spring")) {
    sp->expect_object({"stiffness", "damping", "rest"});
    JointSpring spring;
    spring.stiffness = (*sp)["stiffness"].positive();
    if (auto d = sp->optional("damping")) spring.damping = d->number_in(0.0, 1e6, "a damping from 0 to 1e6");
    if (auto r = sp->optional("rest")) spring.rest = r->number_in(-1e3, 1e3, "a rest position from -1000 to 1000 (m or degrees)");
    j.spring = spring;
  }
  if (auto m = n.optional("motor")) {
    m->expect_object({"velocity", "max_force"});
    JointMotor motor;
    motor.velocity = (*m)["velocity"].number_in(-1e4, 1e4, "a velocity from -10000 to 10000 (m/s or degrees/s)");
    motor.max_force = (*m)["max_force"].positive();
    j.motor = motor;
  }
  return j;
}

Button read_button(const Node& n) {
  n.expect_object({"axis", "travel_m", "press_at", "release_at", "stiffness"});
  Button b;
  if (auto a = n.optional("axis")) b.axis = unit_axis(*a);
  if (auto t = n.optional("travel_m")) b.travel_m = t->number_in(0.001, 0.1, "a travel from 0.001 to 0.1 m");
  if (auto p = n.optional("press_at")) b.press_at = p->number_in(0.05, 1.0, "a fraction of the travel from 0.05 to 1");
  if (auto r = n.optional("release_at")) {
    b.release_at = r->number_in(0.0, 1.0, "a fraction of the travel from 0 to 1");
    if (b.release_at >= b.press_at) r->fail("expected release_at below press_at (" + std::to_string(b.press_at) + ")");
  } else if (b.release_at >= b.press_at) {
    b.release_at = 0.5 * b.press_at;
  }
  if (auto k = n.optional("stiffness")) b.stiffness = k->number_in(1.0, 1e5, "a stiffness from 1 to 100000 N/m");
  return b;
}

// true, false, or an object of options.
std::optional<Grabbable> read_grabbable(const Node& n) {
  if (n.raw().is_boolean()) return n.boolean() ? std::optional<Grabbable>(Grabbable{}) : std::nullopt;
  if (!n.raw().is_object()) n.fail("expected true, false or an object, got " + describe(n.raw()));
  n.expect_object({"two_handed", "scale_with_hands"});
  Grabbable g;
  if (auto t = n.optional("two_handed")) g.two_handed = t->boolean();
  if (auto s = n.optional("scale_with_hands")) {
    s->expect_object({"min", "max"});
    g.scale_with_hands = true;
    if (auto lo = s->optional("min")) g.min_scale = static_cast<float>(lo->number_in(0.05, 1.0, "a factor from 0.05 to 1"));
    if (auto hi = s->optional("max")) g.max_scale = static_cast<float>(hi->number_in(1.0, 20.0, "a factor from 1 to 20"));
    if (!g.two_handed) s->fail("scaling with the hands needs a two-handed grab");
  }
  return g;
}

Socket read_socket(const Node& n) {
  n.expect_object({"accepts", "snap_distance_m", "attach"});
  Socket s;
  if (auto a = n.optional("accepts")) {
    for (const Node& e : a->elements()) s.accepts.push_back(e.non_empty_string());
  }
  if (auto d = n.optional("snap_distance_m")) s.snap_distance_m = d->number_in(0.001, 1.0, "a distance from 0.001 to 1 m");
  if (auto a = n.optional("attach")) {
    const Transform t = read_transform(*a);
    if (t.scale != glm::vec3(1.0f)) (*a)["scale"].fail("an attach pose has no scale");
    s.attach_position = t.position;
    s.attach_rotation = t.rotation;
  }
  return s;
}

// An error in a file a scene refers to (a glTF), reported as that file's.
struct ReferencedFileFailure {
  JsonError error;
};

// A `gltf` entity's bodies and joints: children of the entity (`gltf` is a file name, or an object
// with `file` and `grabbable`, the names of its nodes that hands may pick up).
std::vector<EntityDesc> read_gltf_entities(const Node& n, const EntityDesc& owner, const std::filesystem::path& base_dir) {
  const bool short_form = n.raw().is_string();
  if (!short_form) n.expect_object({"file", "grabbable"});
  const Node file = short_form ? n : n["file"];
  const std::filesystem::path path = existing_file(file, base_dir);
  const std::string ext = path.extension().string();
  if (ext != ".gltf" && ext != ".glb") file.fail("expected a .gltf or .glb file, got " + describe(file.raw()));
  auto entities = read_gltf_physics(path.lexically_normal(), owner.name);
  if (!entities) throw ReferencedFileFailure{entities.error()};
  if (entities->empty()) file.fail("no nodes with KHR_physics_rigid_bodies colliders in " + path.filename().string());
  if (auto g = short_form ? std::nullopt : n.optional("grabbable")) {
    for (const Node& name : g->elements()) {
      const std::string full = owner.name + "/" + name.non_empty_string();
      const auto it = std::find_if(entities->begin(), entities->end(), [&](const EntityDesc& e) { return e.name == full; });
      if (it == entities->end()) name.fail("no body named \"" + full + "\" in " + path.filename().string());
      if (it->body->type != BodyType::kDynamic) name.fail("\"" + full + "\" is not a dynamic body and cannot be grabbable");
      it->grabbable = Grabbable{};
    }
  }
  return std::move(*entities);
}

// An entity a referenced file gave, with the JSON path of the reference.
struct FromFile {
  EntityDesc entity;
  std::string path;
};

EntityDesc read_entity(const Node& n, const std::filesystem::path& base_dir, std::vector<FromFile>& from_files) {
  n.expect_object({"name", "parent", "transform", "mesh", "material", "body", "grabbable", "tracked_by", "tags", "joint", "button",
                   "socket", "pokeable", "gltf"});
  if (n.has("gltf")) {
    for (const char* key : {"mesh", "material", "body", "grabbable", "tracked_by", "joint", "button", "socket", "pokeable"}) {
      if (n.has(key))
        n[key].fail("an entity made from a glTF file takes its shapes, bodies and joints from the file; no \"" + std::string(key) +
                    "\" here");
    }
  }
  EntityDesc e;
  e.name = n["name"].non_empty_string();
  if (auto p = n.optional("parent")) e.parent = p->non_empty_string();
  if (auto t = n.optional("transform")) e.transform = read_transform(*t);
  if (auto m = n.optional("mesh")) e.mesh = read_mesh(*m, base_dir);
  if (auto m = n.optional("material")) e.material = read_material(*m);
  if (auto b = n.optional("body")) {
    e.body = read_body(*b);
    if (!e.mesh) b->fail("a body needs a \"mesh\" on the same entity to give it a shape");
    if (std::holds_alternative<PlaneShape>(e.mesh->shape) && e.body->type != BodyType::kStatic) {
      b->fail("a plane is unbounded and can only be a static body");
    }
  }
  if (auto g = n.optional("grabbable")) {
    e.grabbable = read_grabbable(*g);
    if (e.grabbable && (!e.body || e.body->type != BodyType::kDynamic)) {
      g->fail("only an entity with a dynamic body can be grabbable");
    }
  }
  if (auto t = n.optional("tracked_by")) {
    e.tracked_by = t->integer_in(0, 1 << 20);
    if (e.body && e.body->type != BodyType::kKinematic) {
      t->fail("a tracked entity follows its marker star, so its body must be kinematic");
    }
  }
  if (auto t = n.optional("tags")) {
    for (const Node& tag : t->elements()) e.tags.push_back(tag.non_empty_string());
  }
  const bool dynamic = e.body && e.body->type == BodyType::kDynamic;
  if (auto j = n.optional("joint")) {
    e.joint = read_joint(*j);
    if (!dynamic) j->fail("a joint moves a dynamic body; give the entity a \"body\" of type \"dynamic\"");
    if (e.joint->connected_to == e.name) (*j)["connected_to"].fail("a joint cannot connect an entity to itself");
  }
  if (auto b = n.optional("button")) {
    e.button = read_button(*b);
    if (!dynamic) b->fail("a button is pushed physically; give the entity a \"body\" of type \"dynamic\"");
    if (e.joint) b->fail("a button slides on a joint of its own; the entity cannot have another \"joint\"");
    if (e.grabbable) b->fail("a button cannot be grabbable");
  }
  if (auto s = n.optional("socket")) e.socket = read_socket(*s);
  if (auto p = n.optional("pokeable")) {
    e.pokeable = p->boolean();
    if (e.pokeable && !e.body) p->fail("only an entity with a body can be poked");
  }
  if (auto g = n.optional("gltf")) {
    if (e.transform.scale != glm::vec3(1.0f)) {
      n["transform"]["scale"].fail(
          "an entity made from a glTF file is not scaled (its joints' anchors would not follow); scale the file's nodes");
    }
    for (EntityDesc& child : read_gltf_entities(*g, e, base_dir)) from_files.push_back({std::move(child), g->path()});
  }
  return e;
}

std::string one_of(const Node& n, const std::vector<std::string>& allowed) {
  const std::string v = n.string();
  for (const std::string& a : allowed) {
    if (a == v) return v;
  }
  std::string list;
  for (const std::string& a : allowed) list += (list.empty() ? "\"" : ", \"") + a + "\"";
  n.fail("unknown " + std::string(n.path().ends_with("/event") ? "event" : "action") + " " + describe(n.raw()) +
         "; expected one of: " + list);
}

RuleAction read_action(const Node& n) {
  if (!n.raw().is_object()) n.fail("expected an object, got " + describe(n.raw()));
  RuleAction a;
  a.action = one_of(n["action"], rule_action_names());
  if (a.action == "set_color") {
    n.expect_object({"action", "entity", "color"});
    a.entity = n["entity"].non_empty_string();
    a.color = read_color(n["color"]);
  } else if (a.action == "enable" || a.action == "disable") {
    n.expect_object({"action", "entity"});
    a.entity = n["entity"].non_empty_string();
  } else if (a.action == "motor") {
    n.expect_object({"action", "entity", "velocity", "max_force"});
    a.entity = n["entity"].non_empty_string();
    a.velocity = n["velocity"].number_in(-1e4, 1e4, "a velocity from -10000 to 10000 (m/s or degrees/s)");
    a.max_force = n["max_force"].number_in(0.0, 1e6, "a force from 0 to 1e6 (N or N m); 0 lets the joint go");
  } else if (a.action == "spawn") {
    n.expect_object({"action", "entity", "position"});
    a.entity = n["entity"].non_empty_string();
    if (auto p = n.optional("position")) a.position = vec3(*p);
  } else {
    n.expect_object({"action", "name"});
    a.name = n["name"].non_empty_string();
  }
  return a;
}

RuleDesc read_rule(const Node& n) {
  n.expect_object({"when", "do", "once"});
  RuleDesc r;
  const Node when = n["when"];
  if (!when.raw().is_object()) when.fail("expected an object, got " + describe(when.raw()));
  r.when.event = one_of(when["event"], rule_event_names());
  const std::string& ev = r.when.event;
  if (ev == "value_above" || ev == "value_below") {
    when.expect_object({"event", "entity", "value"});
    r.when.entity = when["entity"].non_empty_string();
    r.when.value = when["value"].number_in(-1e3, 1e3, "a value from -1000 to 1000 (degrees or metres)");
  } else if (ev == "snap" || ev == "unsnap" || ev == "enter" || ev == "exit") {
    when.expect_object({"event", "entity", "object"});
    if (auto e = when.optional("entity")) r.when.entity = e->non_empty_string();
    if (auto o = when.optional("object")) r.when.object = o->non_empty_string();
  } else if (ev == "success") {
    when.expect_object({"event", "interaction"});
    if (auto i = when.optional("interaction")) r.when.interaction = i->non_empty_string();
  } else {
    when.expect_object({"event", "entity"});
    if (auto e = when.optional("entity")) r.when.entity = e->non_empty_string();
  }
  const Node actions = n["do"];
  for (const Node& a : actions.elements()) r.actions.push_back(read_action(a));
  if (r.actions.empty()) actions.fail("expected at least one action");
  if (auto o = n.optional("once")) r.once = o->boolean();
  return r;
}

// Every name a rule uses refers to what it must: the entity of a value event has a hinge or
// slider joint, of a press a button, of a snap a socket; a motor's entity has a hinge or slider;
// the success event's interaction exists.
void check_rules(const SceneDesc& scene) {
  const auto find = [&](const std::string& name) -> const EntityDesc* {
    for (const EntityDesc& e : scene.entities) {
      if (e.name == name) return &e;
    }
    return nullptr;
  };
  const auto moving_joint = [](const EntityDesc* e) {
    return e && e->joint && (e->joint->type == JointType::kHinge || e->joint->type == JointType::kSlider);
  };
  for (std::size_t i = 0; i < scene.rules.size(); ++i) {
    const RuleDesc& r = scene.rules[i];
    const std::string path = "/rules/" + std::to_string(i);
    const std::string& ev = r.when.event;
    if (!r.when.entity.empty()) {
      const EntityDesc* e = find(r.when.entity);
      const std::string where = path + "/when/entity";
      if (!e) throw JsonFailure{where, "no entity is named \"" + r.when.entity + "\""};
      if ((ev == "value_above" || ev == "value_below") && !moving_joint(e)) {
        throw JsonFailure{where, "\"" + r.when.entity + "\" has no hinge or slider joint to take a value from"};
      }
      if ((ev == "press" || ev == "unpress") && !e->button) throw JsonFailure{where, "\"" + r.when.entity + "\" is not a button"};
      if ((ev == "snap" || ev == "unsnap") && !e->socket) throw JsonFailure{where, "\"" + r.when.entity + "\" is not a socket"};
      if (ev == "poke" && !e->pokeable) throw JsonFailure{where, "\"" + r.when.entity + "\" is not pokeable"};
      if ((ev == "enter" || ev == "exit") && (e->body || !e->mesh || !std::holds_alternative<BoxShape>(e->mesh->shape))) {
        throw JsonFailure{where, "\"" + r.when.entity + "\" is not a zone (a box mesh without a body)"};
      }
      if ((ev == "grasp" || ev == "release") && !e->grabbable) {
        throw JsonFailure{where, "\"" + r.when.entity + "\" is not grabbable"};
      }
    }
    if ((ev == "enter" || ev == "exit") && r.when.entity.empty()) {
      throw JsonFailure{path + "/when", "an " + ev + " rule needs the zone as its \"entity\""};
    }
    if (!r.when.object.empty() && !find(r.when.object)) {
      throw JsonFailure{path + "/when/object", "no entity is named \"" + r.when.object + "\""};
    }
    if (!r.when.interaction.empty()) {
      bool known = false;
      for (const InteractionDesc& d : scene.interactions) known = known || d.name == r.when.interaction;
      for (const RuleDesc& other : scene.rules) {
        for (const RuleAction& a : other.actions) known = known || (a.action == "succeed" && a.name == r.when.interaction);
      }
      if (!known) {
        throw JsonFailure{path + "/when/interaction", "no interaction or \"succeed\" action is named \"" + r.when.interaction + "\""};
      }
    }
    for (std::size_t k = 0; k < r.actions.size(); ++k) {
      const RuleAction& a = r.actions[k];
      const std::string where = path + "/do/" + std::to_string(k) + "/entity";
      if (a.action == "succeed") continue;
      const EntityDesc* e = find(a.entity);
      if (!e) throw JsonFailure{where, "no entity is named \"" + a.entity + "\""};
      if (a.action == "set_color" && !e->mesh) throw JsonFailure{where, "\"" + a.entity + "\" has no mesh to colour"};
      if (a.action == "motor" && !moving_joint(e)) throw JsonFailure{where, "\"" + a.entity + "\" has no hinge or slider joint to drive"};
      if (a.action == "spawn" && (e->joint || e->button || e->socket || e->tracked_by)) {
        throw JsonFailure{
            where, "\"" + a.entity +
                       "\" cannot be copied: a copy takes its mesh, material, body and tags, not a joint, button, socket or marker star"};
      }
    }
  }
}

// Checks that cut across entities: unique names, parents that exist, no parent cycles, one
// entity per marker star.
void check_references(const std::vector<EntityDesc>& entities) {
  const auto entity_path = [](std::size_t i) { return "/entities/" + std::to_string(i); };
  std::unordered_map<std::string, std::size_t> by_name;
  std::unordered_map<int, std::size_t> by_star;
  for (std::size_t i = 0; i < entities.size(); ++i) {
    const auto [it, fresh] = by_name.emplace(entities[i].name, i);
    if (!fresh) {
      throw JsonFailure{entity_path(i) + "/name",
                        "duplicate name \"" + entities[i].name + "\" (also at " + entity_path(it->second) + "/name)"};
    }
    if (entities[i].tracked_by) {
      const auto [s, new_star] = by_star.emplace(*entities[i].tracked_by, i);
      if (!new_star) {
        throw JsonFailure{entity_path(i) + "/tracked_by",
                          "marker star " + std::to_string(s->first) + " already tracks " + entity_path(s->second)};
      }
    }
  }
  for (std::size_t i = 0; i < entities.size(); ++i) {
    if (!entities[i].joint || entities[i].joint->connected_to.empty()) continue;
    const std::string& other = entities[i].joint->connected_to;
    const auto it = by_name.find(other);
    if (it == by_name.end()) throw JsonFailure{entity_path(i) + "/joint/connected_to", "no entity is named \"" + other + "\""};
    if (!entities[it->second].body) {
      throw JsonFailure{entity_path(i) + "/joint/connected_to", "\"" + other + "\" has no body to connect to"};
    }
  }
  for (std::size_t i = 0; i < entities.size(); ++i) {
    if (entities[i].parent.empty()) continue;
    if (!by_name.contains(entities[i].parent)) {
      throw JsonFailure{entity_path(i) + "/parent", "no entity is named \"" + entities[i].parent + "\""};
    }
    // Walk up; more steps than there are entities means a cycle.
    std::size_t a = i;
    for (std::size_t steps = 0; !entities[a].parent.empty(); ++steps) {
      a = by_name.at(entities[a].parent);
      if (a == i || steps > entities.size()) {
        throw JsonFailure{entity_path(i) + "/parent", "parent \"" + entities[i].parent + "\" makes a cycle"};
      }
    }
  }
}

SceneDesc read_scene(const json& root, const std::filesystem::path& base_dir) {
  const Node n(root, "");
  n.expect_object({"format", "version", "settings", "entities", "interactions", "rules"});
  if (auto f = n.optional("format"); f && f->string() != "rhot-scene") {
    f->fail("expected \"rhot-scene\", got " + describe(f->raw()));
  }
  if (auto v = n.optional("version")) v->integer_in(1, 1);
  SceneDesc scene;
  if (auto s = n.optional("settings")) scene.settings = read_settings(*s, base_dir);
  if (auto list = n.optional("entities")) {
    std::vector<FromFile> from_files;
    for (const Node& e : list->elements()) scene.entities.push_back(read_entity(e, base_dir, from_files));
    const std::size_t own = scene.entities.size();
    for (FromFile& f : from_files) {
      for (std::size_t j = 0; j < own; ++j) {
        if (scene.entities[j].name == f.entity.name) {
          throw JsonFailure{f.path, "its body \"" + f.entity.name + "\" has the name of /entities/" + std::to_string(j)};
        }
      }
      scene.entities.push_back(std::move(f.entity));
    }
  }
  check_references(scene.entities);
  if (auto list = n.optional("interactions")) {
    for (const Node& i : list->elements()) scene.interactions.push_back(read_interaction(i));
  }
  check_interactions(scene.interactions, scene.entities);
  if (auto list = n.optional("rules")) {
    for (const Node& r : list->elements()) scene.rules.push_back(read_rule(r));
  }
  check_rules(scene);
  return scene;
}

}  // namespace

std::expected<SceneDesc, SceneError> parse_scene(std::string_view json_text, const std::filesystem::path& base_dir, std::string_view name) {
  std::optional<JsonError> referenced;
  auto scene = parse_json<SceneDesc>(json_text, name, [&](const JsonNode& root) {
    try {
      return read_scene(root.raw(), base_dir);
    } catch (const ReferencedFileFailure& f) {
      referenced = f.error;
      throw JsonFailure{"", ""};
    }
  });
  if (referenced) return std::unexpected(*referenced);
  return scene;
}

std::expected<SceneDesc, SceneError> load_scene_file(const std::filesystem::path& file) {
  auto text = read_text_file(file, "scene");
  if (!text) return std::unexpected(text.error());
  auto scene = parse_scene(*text, file.parent_path(), file.string());
  if (scene) scene->file = file;
  return scene;
}

std::vector<Entity> instantiate(const SceneDesc& scene, World& world) {
  RHOT_PRECONDITION(!world.iterating(), "instantiate: not while a view iterates");
  std::vector<Entity> created;
  created.reserve(scene.entities.size());
  std::unordered_map<std::string, Entity> by_name;
  for (const EntityDesc& d : scene.entities) {
    const Entity e = world.create();
    created.push_back(e);
    by_name.emplace(d.name, e);
    world.add<Name>(e, Name{d.name});
    world.add<Transform>(e, d.transform);
    world.add<WorldTransform>(e);
    if (d.mesh) world.add<Mesh>(e, *d.mesh);
    if (d.mesh || d.material) world.add<Material>(e, d.material.value_or(Material{}));
    if (d.body) world.add<PhysicsBody>(e, *d.body);
    if (d.grabbable) world.add<Grabbable>(e, *d.grabbable);
    if (d.tracked_by) world.add<TrackedBy>(e, TrackedBy{*d.tracked_by});
    if (!d.tags.empty()) world.add<Tags>(e, Tags{d.tags});
    if (d.joint) world.add<Joint>(e, *d.joint);
    if (d.button) world.add<Button>(e, *d.button);
    if (d.socket) world.add<Socket>(e, *d.socket);
    if (d.pokeable) world.add<Pokeable>(e);
  }
  for (std::size_t i = 0; i < scene.entities.size(); ++i) {
    const std::string& parent = scene.entities[i].parent;
    if (parent.empty()) continue;
    const auto it = by_name.find(parent);
    RHOT_PRECONDITION(it != by_name.end(), "instantiate: unknown parent \"" + parent + "\"");
    const auto linked = set_parent(world, created[i], it->second);
    RHOT_PRECONDITION(linked.has_value(), "instantiate: " + (linked ? std::string() : linked.error()));
  }
  update_world_transforms(world);
  return created;
}

Entity find_named(World& world, std::string_view name) {
  Entity found;
  world.view<Name>().each([&](Entity e, Name& n) {
    if (found.is_null() && n.value == name) found = e;
  });
  return found;
}

}  // namespace rhot
