#include "engine/scene/SceneLoader.h"

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

namespace rhot {

std::string SceneError::to_string() const {
  std::string s = file;
  if (!json_path.empty()) s += (json_path.front() == '/' ? ": " : ":") + json_path;
  return s + ": " + message;
}

namespace {

using nlohmann::json;

// Thrown inside the loader only; load_scene_file/parse_scene turn it into the returned error.
struct LoadFailure {
  std::string json_path;
  std::string message;
};

std::string describe(const json& j) {
  switch (j.type()) {
    case json::value_t::number_float: {
      const double v = j.get<double>();
      if (std::isnan(v)) return "NaN";
      if (std::isinf(v)) return v > 0 ? "infinity" : "-infinity";
      return j.dump();
    }
    case json::value_t::number_integer:
    case json::value_t::number_unsigned:
    case json::value_t::boolean:
    case json::value_t::null:
      return j.dump();
    case json::value_t::string: {
      std::string s = j.dump();
      return s.size() > 40 ? s.substr(0, 37) + "...\"" : s;
    }
    default:
      return std::string("an ") + j.type_name();
  }
}

// A JSON value and where it is, with typed accessors that fail naming the path.
class Node {
 public:
  Node(const json& value, std::string path) : j_(value), path_(std::move(path)) {}

  const std::string& path() const { return path_; }
  const json& raw() const { return j_; }

  [[noreturn]] void fail(const std::string& message) const { throw LoadFailure{path_, message}; }

  // Checks that this is an object whose keys are all among `allowed`.
  void expect_object(std::initializer_list<std::string_view> allowed) const {
    if (!j_.is_object()) fail("expected an object, got " + describe(j_));
    for (const auto& [key, value] : j_.items()) {
      bool known = false;
      for (const std::string_view a : allowed) known = known || a == key;
      if (!known) {
        std::string list;
        for (const std::string_view a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
        Node(value, path_ + "/" + key).fail("unknown key \"" + key + "\"; expected one of: " + list);
      }
    }
  }

  bool has(const char* key) const { return j_.contains(key); }
  Node operator[](const char* key) const {
    if (!j_.contains(key)) fail(std::string("missing required key \"") + key + "\"");
    return Node(j_.at(key), path_ + "/" + key);
  }
  std::optional<Node> optional(const char* key) const {
    if (!j_.contains(key)) return std::nullopt;
    return Node(j_.at(key), path_ + "/" + key);
  }
  std::vector<Node> elements() const {
    if (!j_.is_array()) fail("expected an array, got " + describe(j_));
    std::vector<Node> out;
    for (std::size_t i = 0; i < j_.size(); ++i) out.emplace_back(j_[i], path_ + "/" + std::to_string(i));
    return out;
  }

  double number() const {
    if (!j_.is_number()) fail("expected a number, got " + describe(j_));
    const double v = j_.get<double>();
    if (!std::isfinite(v)) fail("expected a finite number, got " + describe(j_));
    if (std::abs(v) > static_cast<double>(std::numeric_limits<float>::max())) {
      fail("expected a number within float range (magnitude up to 3.4e38), got " + describe(j_));
    }
    return v;
  }
  double number_in(double lo, double hi, const char* what) const {
    const double v = number();
    if (v < lo || v > hi) fail(std::string("expected ") + what + ", got " + describe(j_));
    return v;
  }
  double positive() const {
    const double v = number();
    // Stored as float downstream: refuse what a float turns into 0 or infinity.
    if (!(v > 0.0) || !(static_cast<float>(v) > 0.0f) || v > static_cast<double>(std::numeric_limits<float>::max())) {
      fail("expected a number greater than 0 (and within float range), got " + describe(j_));
    }
    return v;
  }
  int integer_in(int lo, int hi) const {
    if (!j_.is_number_integer() && !j_.is_number_unsigned()) fail("expected an integer, got " + describe(j_));
    const auto v = j_.get<long long>();
    if (v < lo || v > hi) {
      fail("expected an integer from " + std::to_string(lo) + " to " + std::to_string(hi) + ", got " + describe(j_));
    }
    return static_cast<int>(v);
  }
  bool boolean() const {
    if (!j_.is_boolean()) fail("expected true or false, got " + describe(j_));
    return j_.get<bool>();
  }
  std::string string() const {
    if (!j_.is_string()) fail("expected a string, got " + describe(j_));
    return j_.get<std::string>();
  }
  std::string non_empty_string() const {
    std::string s = string();
    if (s.empty()) fail("expected a non-empty string");
    return s;
  }
  // An array of exactly n finite numbers.
  std::vector<double> numbers(std::size_t n) const {
    if (!j_.is_array() || j_.size() != n) {
      fail("expected an array of " + std::to_string(n) + " numbers, got " + describe(j_) +
           (j_.is_array() ? " of " + std::to_string(j_.size()) : ""));
    }
    std::vector<double> out;
    for (const Node& e : elements()) out.push_back(e.number());
    return out;
  }
  glm::vec3 vec3() const {
    const auto v = numbers(3);
    return {static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2])};
  }

 private:
  const json& j_;
  std::string path_;
};

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
  if (auto p = n.optional("position")) t.position = p->vec3();
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
    const glm::vec3 deg = r->vec3();
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

Material read_material(const Node& n) {
  n.expect_object({"color"});
  const Node c = n["color"];
  if (!c.raw().is_array() || (c.raw().size() != 3 && c.raw().size() != 4)) {
    c.fail("expected [r, g, b] or [r, g, b, a] with each in [0, 1], got " + describe(c.raw()));
  }
  Material m;
  const auto e = c.elements();
  for (std::size_t i = 0; i < e.size(); ++i) {
    m.color[static_cast<glm::length_t>(i)] = static_cast<float>(e[i].number_in(0.0, 1.0, "a number from 0 to 1"));
  }
  return m;
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
  n.expect_object({"contact_distance_m", "opposing_cos", "min_curl_rad", "release_distance_m", "confident", "regrasp_delay_s",
                   "throw_window_s", "throw_window_end_s", "max_hold_error_m", "max_object_speed_mps", "hover_distance_m"});
  GraspSettings g;
  const auto set = [&](const char* key, double& value, double lo, double hi, const char* what) {
    if (auto v = n.optional(key)) value = v->number_in(lo, hi, what);
  };
  set("contact_distance_m", g.contact_distance_m, 0.0, 0.05, "a distance from 0 to 0.05 m");
  set("opposing_cos", g.opposing_cos, -1.0, 1.0, "a cosine from -1 to 1");
  set("min_curl_rad", g.min_curl_rad, 0.0, 3.2, "an angle from 0 to 3.2 rad");
  set("release_distance_m", g.release_distance_m, 0.001, 0.2, "a distance from 0.001 to 0.2 m");
  set("confident", g.confident, 0.0, 1.0, "a confidence from 0 to 1");
  set("regrasp_delay_s", g.regrasp_delay_s, 0.0, 10.0, "a time from 0 to 10 s");
  set("throw_window_s", g.throw_window_s, 0.0, 1.0, "a time from 0 to 1 s");
  set("throw_window_end_s", g.throw_window_end_s, 0.0, 0.2, "a time from 0 to 0.2 s");
  set("max_hold_error_m", g.max_hold_error_m, 0.01, 10.0, "a distance from 0.01 to 10 m");
  set("max_object_speed_mps", g.max_object_speed_mps, 0.1, 100.0, "a speed from 0.1 to 100 m/s");
  set("hover_distance_m", g.hover_distance_m, 0.0, 1.0, "a distance from 0 to 1 m");
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
  if (auto g = n.optional("gravity_mps2")) s.gravity_mps2 = g->vec3();
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
        throw LoadFailure{path + "/name",
                          "duplicate interaction name \"" + d.name + "\" (also at /interactions/" + std::to_string(k) + "/name)"};
      }
    }
    const EntityDesc* object = find(d.object);
    if (!object) throw LoadFailure{path + "/object", "no entity is named \"" + d.object + "\""};
    if (!object->grabbable) throw LoadFailure{path + "/object", "\"" + d.object + "\" is not grabbable"};
    if (d.type == InteractionType::kPlace) {
      const EntityDesc* zone = find(d.zone);
      if (!zone) throw LoadFailure{path + "/zone", "no entity is named \"" + d.zone + "\""};
      if (!zone->mesh || !std::holds_alternative<BoxShape>(zone->mesh->shape)) {
        throw LoadFailure{path + "/zone", "zone \"" + d.zone + "\" needs a box mesh (the zone is its box)"};
      }
      if (zone->body) throw LoadFailure{path + "/zone", "zone \"" + d.zone + "\" has a physics body; a zone must let objects in"};
    }
  }
}

EntityDesc read_entity(const Node& n, const std::filesystem::path& base_dir) {
  n.expect_object({"name", "parent", "transform", "mesh", "material", "body", "grabbable", "tracked_by"});
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
    e.grabbable = g->boolean();
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
  return e;
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
      throw LoadFailure{entity_path(i) + "/name",
                        "duplicate name \"" + entities[i].name + "\" (also at " + entity_path(it->second) + "/name)"};
    }
    if (entities[i].tracked_by) {
      const auto [s, new_star] = by_star.emplace(*entities[i].tracked_by, i);
      if (!new_star) {
        throw LoadFailure{entity_path(i) + "/tracked_by",
                          "marker star " + std::to_string(s->first) + " already tracks " + entity_path(s->second)};
      }
    }
  }
  for (std::size_t i = 0; i < entities.size(); ++i) {
    if (entities[i].parent.empty()) continue;
    if (!by_name.contains(entities[i].parent)) {
      throw LoadFailure{entity_path(i) + "/parent", "no entity is named \"" + entities[i].parent + "\""};
    }
    // Walk up; more steps than there are entities means a cycle.
    std::size_t a = i;
    for (std::size_t steps = 0; !entities[a].parent.empty(); ++steps) {
      a = by_name.at(entities[a].parent);
      if (a == i || steps > entities.size()) {
        throw LoadFailure{entity_path(i) + "/parent", "parent \"" + entities[i].parent + "\" makes a cycle"};
      }
    }
  }
}

// Rejects duplicate keys, which nlohmann::json would otherwise resolve silently (last one wins),
// reporting the JSON pointer of the repeated key.
class DuplicateKeyCheck {
 public:
  bool operator()(int /*depth*/, json::parse_event_t event, json& parsed) {
    switch (event) {
      case json::parse_event_t::object_start:
        frames_.push_back(Frame{false, 0, {}, {}});
        break;
      case json::parse_event_t::array_start:
        frames_.push_back(Frame{true, 0, {}, {}});
        break;
      case json::parse_event_t::key: {
        Frame& f = frames_.back();
        f.key = parsed.get<std::string>();
        if (!f.keys.insert(f.key).second && !duplicate_) duplicate_ = LoadFailure{path(), "duplicate key \"" + f.key + "\""};
        break;
      }
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        frames_.pop_back();
        element_done();
        break;
      case json::parse_event_t::value:
        element_done();
        break;
    }
    return true;
  }
  const std::optional<LoadFailure>& duplicate() const { return duplicate_; }

 private:
  struct Frame {
    bool is_array;
    std::size_t index;
    std::string key;
    std::set<std::string> keys;
  };
  void element_done() {
    if (!frames_.empty() && frames_.back().is_array) ++frames_.back().index;
  }
  std::string path() const {
    std::string p;
    for (const Frame& f : frames_) p += "/" + (f.is_array ? std::to_string(f.index) : f.key);
    return p;
  }
  std::vector<Frame> frames_;
  std::optional<LoadFailure> duplicate_;
};

std::string line_and_column(std::string_view text, std::size_t byte) {
  std::size_t line = 1, column = 1;
  for (std::size_t i = 0; i + 1 < byte && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return std::to_string(line) + ":" + std::to_string(column);
}

SceneDesc read_scene(const json& root, const std::filesystem::path& base_dir) {
  const Node n(root, "");
  n.expect_object({"format", "version", "settings", "entities", "interactions"});
  if (auto f = n.optional("format"); f && f->string() != "rhot-scene") {
    f->fail("expected \"rhot-scene\", got " + describe(f->raw()));
  }
  if (auto v = n.optional("version")) v->integer_in(1, 1);
  SceneDesc scene;
  if (auto s = n.optional("settings")) scene.settings = read_settings(*s, base_dir);
  if (auto list = n.optional("entities")) {
    for (const Node& e : list->elements()) scene.entities.push_back(read_entity(e, base_dir));
  }
  check_references(scene.entities);
  if (auto list = n.optional("interactions")) {
    for (const Node& i : list->elements()) scene.interactions.push_back(read_interaction(i));
  }
  check_interactions(scene.interactions, scene.entities);
  return scene;
}

}  // namespace

std::expected<SceneDesc, SceneError> parse_scene(std::string_view json_text, const std::filesystem::path& base_dir, std::string_view name) {
  const std::string file(name);
  DuplicateKeyCheck duplicates;
  json root;
  try {
    root = json::parse(json_text.begin(), json_text.end(), std::ref(duplicates));
  } catch (const json::parse_error& e) {
    // nlohmann's message starts "[json.exception.parse_error.101] parse error at line 1, column 2: ";
    // keep only the part after the position, which we give in the file:line:col form ourselves.
    std::string what = e.what();
    if (const auto colon = what.find(": "); colon != std::string::npos) what = what.substr(colon + 2);
    return std::unexpected(SceneError{file, line_and_column(json_text, e.byte), "invalid JSON: " + what});
  } catch (const json::out_of_range& e) {
    // A number too large for a double, such as 1e999: nlohmann gives the token but no position,
    // so find the token in the text. Such a number would be infinity, which must never reach
    // physics or rendering.
    const std::string what = e.what();
    const auto open = what.find('\'');
    const auto close = what.rfind('\'');
    std::string where;
    if (open != std::string::npos && close > open) {
      const std::string token = what.substr(open + 1, close - open - 1);
      if (const auto at = json_text.find(token); at != std::string_view::npos) where = line_and_column(json_text, at + 1);
      return std::unexpected(SceneError{file, where, "invalid JSON: the number " + token + " is out of range"});
    }
    return std::unexpected(SceneError{file, where, "invalid JSON: " + what});
  }
  if (duplicates.duplicate()) {
    return std::unexpected(SceneError{file, duplicates.duplicate()->json_path, duplicates.duplicate()->message});
  }
  try {
    SceneDesc scene = read_scene(root, base_dir);
    return scene;
  } catch (const LoadFailure& f) {
    return std::unexpected(SceneError{file, f.json_path.empty() ? "/" : f.json_path, f.message});
  }
}

std::expected<SceneDesc, SceneError> load_scene_file(const std::filesystem::path& file) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) {
    return std::unexpected(SceneError{file.string(), "", "scene file not found"});
  }
  std::ifstream in(file, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  if (!in && !in.eof()) return std::unexpected(SceneError{file.string(), "", "cannot read the file"});
  auto scene = parse_scene(text.str(), file.parent_path(), file.string());
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
    if (d.grabbable) world.add<Grabbable>(e);
    if (d.tracked_by) world.add<TrackedBy>(e, TrackedBy{*d.tracked_by});
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
