#include "engine/scene/GltfPhysics.h"

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <algorithm>
#include <fstream>
#include <limits>
#include <numbers>
#include <optional>
#include <set>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <nlohmann/json.hpp>

#include "base/Json.h"

namespace rhot {

namespace {

using nlohmann::json;
using Node = JsonNode;

constexpr const char* kBodies = "KHR_physics_rigid_bodies";
constexpr const char* kShapes = "KHR_implicit_shapes";
constexpr double kDefaultDensity = 1000.0;  // kg/m^3, a body without a mass

// The JSON of a .gltf, or of a .glb's first chunk.
std::expected<json, JsonError> read_gltf_json(const std::filesystem::path& file) {
  const std::string name = file.string();
  if (file.extension() != ".glb") {
    auto text = read_text_file(file, "glTF");
    if (!text) return std::unexpected(text.error());
    return parse_json_text(*text, name);
  }
  std::ifstream in(file, std::ios::binary);
  if (!in) return std::unexpected(JsonError{name, "", "glTF file not found"});
  in.seekg(0, std::ios::end);
  std::string bytes(static_cast<std::size_t>(std::max<std::streamoff>(0, in.tellg())), '\0');
  in.seekg(0);
  in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!in) return std::unexpected(JsonError{name, "", "cannot read the file"});
  const auto u32 = [&](std::size_t at) {
    std::uint32_t v = 0;
    std::memcpy(&v, bytes.data() + at, 4);
    return v;
  };
  if (bytes.compare(0, 4, "glTF") != 0) return std::unexpected(JsonError{name, "", "not a binary glTF (no \"glTF\" header)"});
  if (bytes.size() < 20) return std::unexpected(JsonError{name, "", "a binary glTF cut short: " + std::to_string(bytes.size()) + " bytes"});
  if (u32(4) != 2) return std::unexpected(JsonError{name, "", "binary glTF version " + std::to_string(u32(4)) + "; expected 2"});
  const std::uint32_t length = u32(12);
  if (u32(16) != 0x4E4F534Au || length > bytes.size() - 20) {
    return std::unexpected(JsonError{name, "", "binary glTF without a whole JSON chunk first"});
  }
  return parse_json_text(std::string_view(bytes).substr(20, length), name);
}

glm::mat4 local_matrix(const Node& n) {
  if (auto m = n.optional("matrix")) {
    const auto v = m->numbers(16);
    glm::mat4 out(1.0f);
    for (int c = 0; c < 4; ++c) {
      for (int r = 0; r < 4; ++r) out[c][r] = static_cast<float>(v[static_cast<std::size_t>(4 * c + r)]);
    }
    return out;
  }
  glm::mat4 out(1.0f);
  if (auto t = n.optional("translation")) {
    const auto v = t->numbers(3);
    out = glm::translate(out, glm::vec3(static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2])));
  }
  if (auto r = n.optional("rotation")) {
    const auto q = r->numbers(4);
    const glm::quat rotation(static_cast<float>(q[3]), static_cast<float>(q[0]), static_cast<float>(q[1]), static_cast<float>(q[2]));
    if (std::abs(glm::length(rotation) - 1.0f) > 1e-3f) r->fail("expected a unit quaternion [x, y, z, w]");
    out = out * glm::mat4_cast(glm::normalize(rotation));
  }
  if (auto s = n.optional("scale")) {
    const auto v = s->numbers(3);
    out = glm::scale(out, glm::vec3(static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2])));
  }
  return out;
}

Transform decompose(const glm::mat4& m, const Node& where) {
  Transform t;
  t.position = glm::vec3(m[3]);
  glm::mat3 r(m);
  for (int i = 0; i < 3; ++i) {
    t.scale[i] = glm::length(r[i]);
    if (!(t.scale[i] > 1e-9f)) where.fail("a body's node has a zero scale");
    r[i] /= t.scale[i];
  }
  if (glm::determinant(r) < 0.0f) {  // a mirror: the collider uses the scale's magnitude (the spec's rule)
    r[0] = -r[0];
  }
  t.rotation = glm::normalize(glm::quat_cast(r));
  return t;
}

struct JointLimits {
  std::array<std::optional<std::array<double, 2>>, 3> linear, angular;  // per axis: [min, max] (missing side: infinite)
  std::array<bool, 3> linear_limited{}, angular_limited{};
};

class Reader {
 public:
  Reader(const json& root, std::string parent) : root_(root, ""), parent_(std::move(parent)) {}

  std::vector<EntityDesc> read() {
    if (!root_.raw().is_object()) root_.fail("expected a glTF object, got " + describe_json(root_.raw()));
    const std::vector<Node> nodes = root_.optional("nodes") ? root_["nodes"].elements() : std::vector<Node>{};
    count_ = nodes.size();
    parent_of_.assign(count_, -1);
    for (std::size_t i = 0; i < count_; ++i) {
      if (auto children = nodes[i].optional("children")) {
        for (const Node& c : children->elements()) {
          const int child = c.integer_in(0, static_cast<int>(count_) - 1);
          if (parent_of_[static_cast<std::size_t>(child)] >= 0 || child == static_cast<int>(i))
            c.fail("node " + std::to_string(child) + " has two parents");
          parent_of_[static_cast<std::size_t>(child)] = static_cast<int>(i);
        }
      }
    }
    root_from_node_.assign(count_, glm::mat4(1.0f));
    std::vector<bool> done(count_, false);
    for (std::size_t i = 0; i < count_; ++i) world_of(nodes, i, done, 0);
    read_document_level();
    entity_of_node_.assign(count_, -1);
    for (std::size_t i = 0; i < count_; ++i) read_body(nodes[i], i);
    for (std::size_t i = 0; i < count_; ++i) read_joint(nodes[i], i);
    return std::move(out_);
  }

 private:
  const glm::mat4& world_of(const std::vector<Node>& nodes, std::size_t i, std::vector<bool>& done, std::size_t depth) {
    if (done[i]) return root_from_node_[i];
    if (depth > count_) nodes[i].fail("the node hierarchy has a cycle");
    if (depth > kMaxDepth) nodes[i].fail("nodes nested more than " + std::to_string(kMaxDepth) + " deep");
    const glm::mat4 local = local_matrix(nodes[i]);
    const int p = parent_of_[i];
    root_from_node_[i] = p < 0 ? local : world_of(nodes, static_cast<std::size_t>(p), done, depth + 1) * local;
    for (int c = 0; c < 4; ++c) {
      for (int r = 0; r < 4; ++r) {
        if (!(std::abs(root_from_node_[i][c][r]) < 1e6f)) nodes[i].fail("the node's transform is not finite or beyond 1e6");
      }
    }
    done[i] = true;
    return root_from_node_[i];
  }

  std::optional<Node> extension(const Node& n, const char* name) const {
    auto ext = n.optional("extensions");
    if (!ext) return std::nullopt;
    return ext->optional(name);
  }

  void read_document_level() {
    if (auto ext = extension(root_, kShapes)) {
      ext->expect_object({"shapes"});
      shapes_ = ext->operator[]("shapes").elements();
    }
    if (auto ext = extension(root_, kBodies)) {
      ext->expect_object({"physicsMaterials", "collisionFilters", "physicsJoints"});
      if (auto m = ext->optional("physicsMaterials")) materials_ = m->elements();
      if (auto j = ext->optional("physicsJoints")) joints_ = j->elements();
      if (auto f = ext->optional("collisionFilters")) f->fail("collision filters are not supported by rhot");
    }
  }

  // The nearest node at or above `i` with a motion, if any.
  std::optional<std::size_t> body_node(const std::vector<Node>& nodes, std::size_t i) const {
    for (int k = static_cast<int>(i); k >= 0; k = parent_of_[static_cast<std::size_t>(k)]) {
      const auto ext = extension(nodes[static_cast<std::size_t>(k)], kBodies);
      if (ext && ext->has("motion")) return static_cast<std::size_t>(k);
    }
    return std::nullopt;
  }

  std::string node_name(std::size_t i) const {
    const Node n = root_["nodes"].elements()[i];
    std::string name = n.optional("name") ? n["name"].string() : std::string();
    if (name.empty()) name = "node" + std::to_string(i);
    return parent_ + "/" + name;
  }

  Mesh read_shape(const Node& geometry) {
    geometry.expect_object({"shape", "node", "convexHull"});
    if (auto n = geometry.optional("node")) n->fail("mesh colliders are not supported by rhot; use a KHR_implicit_shapes shape");
    if (auto c = geometry.optional("convexHull"); c && c->boolean()) c->fail("convex hulls of meshes are not supported by rhot");
    const Node index = geometry["shape"];
    if (shapes_.empty()) index.fail("no KHR_implicit_shapes shapes in the file");
    const Node s = shapes_[static_cast<std::size_t>(index.integer_in(0, static_cast<int>(shapes_.size()) - 1))];
    s.expect_object({"type", "name", "box", "sphere", "capsule", "cylinder", "plane", "extensions", "extras"});
    const Node type = s["type"];
    const std::string t = type.string();
    static const json kNone = json::object();
    const auto params = [&](const char* key) { return s.optional(key) ? s[key] : Node(kNone, s.path() + "/" + key); };
    if (t == "box") {
      const Node b = params("box");
      b.expect_object({"size", "extensions", "extras"});
      glm::vec3 size(1.0f);
      if (auto sz = b.optional("size")) {
        const auto e = sz->elements();
        sz->numbers(3);
        for (int i = 0; i < 3; ++i) size[i] = static_cast<float>(e[static_cast<std::size_t>(i)].positive());
      }
      return Mesh{BoxShape{size}};
    }
    if (t == "sphere") {
      const Node b = params("sphere");
      b.expect_object({"radius", "extensions", "extras"});
      return Mesh{SphereShape{b.optional("radius") ? static_cast<float>(b["radius"].positive()) : 0.5f}};
    }
    if (t == "capsule") {
      const Node b = params("capsule");
      b.expect_object({"height", "radiusTop", "radiusBottom", "extensions", "extras"});
      const double height = b.optional("height") ? b["height"].positive() : 0.5;
      const double top = b.optional("radiusTop") ? b["radiusTop"].positive() : 0.25;
      const double bottom = b.optional("radiusBottom") ? b["radiusBottom"].positive() : 0.25;
      if (std::abs(top - bottom) > 1e-9) b.fail("a capsule with different radii is not supported by rhot");
      return Mesh{CapsuleShape{static_cast<float>(top), static_cast<float>(height + 2.0 * top)}};
    }
    if (t == "plane") {
      const Node b = params("plane");
      b.expect_object({"sizeX", "sizeZ", "doubleSided", "extensions", "extras"});
      const float x = b.optional("sizeX") ? static_cast<float>(b["sizeX"].positive()) : 10.0f;
      const float z = b.optional("sizeZ") ? static_cast<float>(b["sizeZ"].positive()) : 10.0f;
      return Mesh{PlaneShape{{x, z}}};
    }
    if (t == "cylinder") type.fail("cylinders are not supported by rhot; use a capsule or a box");
    type.fail("expected \"box\", \"sphere\", \"capsule\" or \"plane\", got " + describe_json(type.raw()));
  }

  static double volume(const Mesh& mesh, const glm::vec3& scale) {
    const double s = static_cast<double>(scale.x) * static_cast<double>(scale.y) * static_cast<double>(scale.z);
    if (const auto* b = std::get_if<BoxShape>(&mesh.shape)) {
      return s * static_cast<double>(b->size_m.x) * static_cast<double>(b->size_m.y) * static_cast<double>(b->size_m.z);
    }
    if (const auto* sp = std::get_if<SphereShape>(&mesh.shape))
      return s * 4.0 / 3.0 * std::numbers::pi * std::pow(static_cast<double>(sp->radius_m), 3);
    if (const auto* c = std::get_if<CapsuleShape>(&mesh.shape)) {
      const double r = static_cast<double>(c->radius_m);
      return s * std::numbers::pi * r * r * (static_cast<double>(c->height_m) - 2.0 * r + 4.0 / 3.0 * r);
    }
    return 0.0;
  }

  // The colour of a node's mesh's first primitive's material, if any.
  std::optional<Material> colour_of(const Node& n) const {
    auto mesh = n.optional("mesh");
    auto meshes = root_.optional("meshes");
    auto materials = root_.optional("materials");
    if (!mesh || !meshes || !materials) return std::nullopt;
    const auto mesh_list = meshes->elements();
    const Node m = mesh_list[static_cast<std::size_t>(mesh->integer_in(0, static_cast<int>(mesh_list.size()) - 1))];
    const auto primitives = m["primitives"].elements();
    if (primitives.empty() || !primitives[0].has("material")) return std::nullopt;
    const auto material_list = materials->elements();
    const Node mat =
        material_list[static_cast<std::size_t>(primitives[0]["material"].integer_in(0, static_cast<int>(material_list.size()) - 1))];
    auto pbr = mat.optional("pbrMetallicRoughness");
    if (!pbr || !pbr->has("baseColorFactor")) return std::nullopt;
    const auto c = (*pbr)["baseColorFactor"].numbers(4);
    return Material{glm::vec4(static_cast<float>(c[0]), static_cast<float>(c[1]), static_cast<float>(c[2]), static_cast<float>(c[3]))};
  }

  void read_body(const Node& n, std::size_t i) {
    const auto ext = extension(n, kBodies);
    if (!ext) return;
    ext->expect_object({"motion", "collider", "trigger", "joint"});
    if (auto t = ext->optional("trigger")) t->fail("triggers are not supported by rhot");
    const std::vector<Node> nodes = root_["nodes"].elements();
    const auto motion = ext->optional("motion");
    const auto collider = ext->optional("collider");
    if (!collider) {
      if (motion) motion->fail("a body needs a collider on its own node (rhot does not build compound shapes)");
      return;
    }
    collider->expect_object({"geometry", "physicsMaterial", "collisionFilter"});
    if (auto f = collider->optional("collisionFilter")) f->fail("collision filters are not supported by rhot");
    if (!motion) {
      if (const auto body = body_node(nodes, i)) {
        (*collider)["geometry"].fail("a collider on a child of the body at /nodes/" + std::to_string(*body) +
                                     " (a compound shape) is not supported by rhot; put one collider on the body's node");
      }
    }
    EntityDesc e;
    e.name = node_name(i);
    for (const EntityDesc& other : out_) {
      if (other.name == e.name) (n.has("name") ? n["name"] : n).fail("two bodies would both be named \"" + e.name + "\"");
    }
    e.parent = parent_;
    e.transform = decompose(root_from_node_[i], n);
    e.mesh = read_shape((*collider)["geometry"]);
    e.material = colour_of(n);
    PhysicsBody body;
    body.type = BodyType::kStatic;
    if (motion) {
      motion->expect_object({"isKinematic", "mass", "centerOfMass", "inertiaDiagonal", "inertiaOrientation", "linearVelocity",
                             "angularVelocity", "gravityFactor", "extensions", "extras"});
      const bool kinematic = motion->optional("isKinematic") && (*motion)["isKinematic"].boolean();
      body.type = kinematic ? BodyType::kKinematic : BodyType::kDynamic;
      if (auto g = motion->optional("gravityFactor"); g && g->number() != 1.0)
        g->fail("gravity factors other than 1 are not supported by rhot");
      if (!kinematic) {
        const double mass = motion->optional("mass") ? (*motion)["mass"].positive() : kDefaultDensity * volume(*e.mesh, e.transform.scale);
        if (!(mass > 0.0)) (*motion).fail("a body of this shape needs a \"mass\"");
        body.mass_kg = static_cast<float>(mass);
      }
    }
    if (std::holds_alternative<PlaneShape>(e.mesh->shape) && body.type != BodyType::kStatic) {
      (*collider)["geometry"].fail("a plane is unbounded and can only be a static body");
    }
    if (auto m = collider->optional("physicsMaterial")) {
      if (materials_.empty()) m->fail("no physicsMaterials in the file");
      const Node mat = materials_[static_cast<std::size_t>(m->integer_in(0, static_cast<int>(materials_.size()) - 1))];
      mat.expect_object(
          {"staticFriction", "dynamicFriction", "restitution", "frictionCombine", "restitutionCombine", "extensions", "extras"});
      body.friction = mat.optional("dynamicFriction")
                          ? static_cast<float>(mat["dynamicFriction"].number_in(0.0, 10.0, "a friction from 0 to 10"))
                          : 0.6f;
      if (auto r = mat.optional("restitution")) body.restitution = static_cast<float>(r->number_in(0.0, 1.0, "a restitution from 0 to 1"));
    }
    e.body = body;
    entity_of_node_[i] = static_cast<int>(out_.size());
    out_.push_back(std::move(e));
  }

  static std::string axes_text(const std::array<bool, 3>& on) {
    std::string s;
    for (int i = 0; i < 3; ++i) {
      if (on[static_cast<std::size_t>(i)]) s += std::string(s.empty() ? "" : ", ") + "xyz"[i];
    }
    return s.empty() ? "none" : s;
  }

  // A joint definition's limits: the axes locked (min = max = 0) and the ranges of the others.
  struct Limits {
    std::array<bool, 3> lin_locked{}, ang_locked{};
    std::array<std::optional<std::array<double, 2>>, 3> lin_range, ang_range;  // a missing side: infinite
  };
  static Limits read_limits(const Node& def) {
    Limits out;
    auto limits = def.optional("limits");
    if (!limits) return out;
    for (const Node& l : limits->elements()) {
      l.expect_object({"linearAxes", "angularAxes", "min", "max", "stiffness", "damping", "extensions", "extras"});
      const bool linear = l.has("linearAxes");
      if (linear == l.has("angularAxes")) l.fail("a limit needs exactly one of \"linearAxes\" and \"angularAxes\"");
      const Node axes = l[linear ? "linearAxes" : "angularAxes"];
      const double inf = std::numeric_limits<double>::infinity();
      const double lo = l.optional("min") ? l["min"].number_in(-1e6, 1e6, "a number from -1e6 to 1e6") : -inf;
      const double hi = l.optional("max") ? l["max"].number_in(-1e6, 1e6, "a number from -1e6 to 1e6") : inf;
      if (lo > hi) l.fail("min is greater than max");
      const auto list = axes.elements();
      if (list.empty()) axes.fail("expected 1 to 3 axes");
      const bool locked = lo == 0.0 && hi == 0.0;
      if (!locked && list.size() > 1) axes.fail("a limit over several axes (a cone or a distance) is not supported by rhot");
      for (const Node& a : list) {
        const std::size_t k = static_cast<std::size_t>(a.integer_in(0, 2));
        if (locked) {
          (linear ? out.lin_locked : out.ang_locked)[k] = true;
        } else {
          (linear ? out.lin_range : out.ang_range)[k] = std::array<double, 2>{lo, hi};
        }
      }
    }
    return out;
  }

  // The joint the limits make (and its free axis, -1 for fixed and ball), with the free axis's
  // limits.
  static std::pair<Joint, int> classify(const Node& def, const Limits& l) {
    const auto count = [](const std::array<bool, 3>& a) {
      return static_cast<int>(a[0]) + static_cast<int>(a[1]) + static_cast<int>(a[2]);
    };
    const auto free_axis = [](const std::array<bool, 3>& a) { return a[0] ? (a[1] ? 2 : 1) : 0; };
    Joint joint;
    int axis = -1;
    const int nl = count(l.lin_locked), na = count(l.ang_locked);
    if (nl == 3 && na == 3) {
      joint.type = JointType::kFixed;
    } else if (nl == 3 && na == 2) {
      joint.type = JointType::kHinge;
      axis = free_axis(l.ang_locked);
    } else if (na == 3 && nl == 2) {
      joint.type = JointType::kSlider;
      axis = free_axis(l.lin_locked);
    } else if (nl == 3 && na == 0) {
      joint.type = JointType::kBall;
    } else {
      def.fail("a joint that locks linear axes " + axes_text(l.lin_locked) + " and angular axes " + axes_text(l.ang_locked) +
               " is not a hinge, slider, fixed or ball joint, the ones rhot supports");
    }
    const bool hinge = joint.type == JointType::kHinge;
    for (std::size_t k = 0; k < 3; ++k) {
      const bool free_one = static_cast<int>(k) == axis;
      const auto& range = hinge ? l.ang_range[k] : l.lin_range[k];
      if ((l.lin_range[k] && !(joint.type == JointType::kSlider && free_one)) || (l.ang_range[k] && !(hinge && free_one))) {
        def["limits"].fail("a limit on an axis the joint locks or leaves free (ball) is not supported by rhot");
      }
      if (free_one && range && std::isfinite((*range)[0]) && std::isfinite((*range)[1])) {
        joint.limits =
            hinge ? std::array<double, 2>{(*range)[0] * 180.0 / std::numbers::pi, (*range)[1] * 180.0 / std::numbers::pi} : *range;
      }
    }
    return {joint, axis};
  }

  // A force drive on the free axis: its velocity target a motor, its position target a spring.
  static void read_drives(const Node& def, Joint& joint, int axis) {
    auto drives = def.optional("drives");
    if (!drives) return;
    const bool hinge = joint.type == JointType::kHinge;
    for (const Node& d : drives->elements()) {
      d.expect_object(
          {"type", "mode", "axis", "maxForce", "positionTarget", "velocityTarget", "stiffness", "damping", "extensions", "extras"});
      const std::string type = d["type"].string();
      const std::string mode = d["mode"].string();
      if (type != "linear" && type != "angular")
        d["type"].fail("expected \"linear\" or \"angular\", got " + describe_json(d["type"].raw()));
      if (mode != "force") d["mode"].fail("only \"force\" drives are supported by rhot");
      const int k = d["axis"].integer_in(0, 2);
      if (k != axis || (type == "angular") != hinge) d.fail("a drive on an axis the joint does not move along is not supported by rhot");
      const double scale = hinge ? 180.0 / std::numbers::pi : 1.0;
      if (d.has("velocityTarget")) {
        JointMotor m;
        m.velocity = d["velocityTarget"].number_in(-100.0, 100.0, "a velocity from -100 to 100 (m/s or rad/s)") * scale;
        m.max_force = d.optional("maxForce") ? d["maxForce"].number_in(0.0, 1e6, "a force from 0 to 1e6 (N or N m)") : 1e4;
        joint.motor = m;
      }
      if (d.has("positionTarget")) {
        JointSpring s;
        s.stiffness = d["stiffness"].number_in(0.0, 1e6, "a stiffness from 0 to 1e6");
        s.damping = d.optional("damping") ? d["damping"].number_in(0.0, 1e6, "a damping from 0 to 1e6") : 0.0;
        s.rest = d["positionTarget"].number_in(-100.0, 100.0, "a position from -100 to 100 (m or rad)") * scale;
        joint.spring = s;
      }
    }
  }

  void read_joint(const Node& n, std::size_t i) {
    const auto ext = extension(n, kBodies);
    if (!ext || !ext->has("joint")) return;
    const Node j = (*ext)["joint"];
    j.expect_object({"connectedNode", "joint", "enableCollision", "extensions", "extras"});
    if (auto c = j.optional("enableCollision"); c && c->boolean()) c->fail("rhot's joints never let the bodies they join collide");
    const Node connected = j["connectedNode"];
    const std::size_t other = static_cast<std::size_t>(connected.integer_in(0, static_cast<int>(count_) - 1));
    if (joints_.empty()) j["joint"].fail("no physicsJoints in the file");
    const Node def = joints_[static_cast<std::size_t>(j["joint"].integer_in(0, static_cast<int>(joints_.size()) - 1))];
    def.expect_object({"limits", "drives", "extensions", "extras"});
    auto [joint, axis] = classify(def, read_limits(def));
    read_drives(def, joint, axis);
    attach(j, i, other, joint, axis);
  }

  // Puts the joint on whichever of its two bodies is dynamic (the connected node's first), in that
  // body's frame, connected to the other body (or the static body above its node, or the world).
  void attach(const Node& j, std::size_t i, std::size_t other, Joint joint, int axis) {
    const std::vector<Node> nodes = root_["nodes"].elements();
    const auto a = body_node(nodes, i), b = body_node(nodes, other);
    if (a && b && *a == *b) j["connectedNode"].fail("the joint's two nodes are on the same body");
    const auto dynamic = [&](std::optional<std::size_t> node) {
      return node && entity_of_node_[*node] >= 0 && out_[static_cast<std::size_t>(entity_of_node_[*node])].body->type == BodyType::kDynamic;
    };
    std::size_t carrier = 0, frame = 0, partner_frame = 0;
    std::optional<std::size_t> partner;
    float sign = 1.0f;
    if (dynamic(b)) {
      carrier = *b;
      frame = other;
      partner = a;
      partner_frame = i;
    } else if (dynamic(a)) {
      carrier = *a;
      frame = i;
      partner = b;
      partner_frame = other;
      sign = -1.0f;  // the joint measures the connected node against the joint node
    } else {
      j.fail("neither of the bodies this joint connects is dynamic");
    }
    std::string partner_name;
    if (partner) {
      partner_name = out_[static_cast<std::size_t>(entity_of_node_[*partner])].name;
    } else {
      for (int k = static_cast<int>(partner_frame); k >= 0 && partner_name.empty(); k = parent_of_[static_cast<std::size_t>(k)]) {
        if (entity_of_node_[static_cast<std::size_t>(k)] >= 0)
          partner_name = out_[static_cast<std::size_t>(entity_of_node_[static_cast<std::size_t>(k)])].name;
      }
    }
    joint.connected_to = partner_name;
    EntityDesc& e = out_[static_cast<std::size_t>(entity_of_node_[carrier])];
    if (e.joint) j.fail("\"" + e.name + "\" already has a joint; rhot gives a body one");
    // The joint's frame in the carrier's (unscaled) frame.
    glm::mat4 body_frame = root_from_node_[carrier];
    for (int c = 0; c < 3; ++c) body_frame[c] = glm::normalize(body_frame[c]);
    if (glm::determinant(glm::mat3(body_frame)) < 0.0f) body_frame[0] = -body_frame[0];  // as decompose() has the body
    const glm::mat4 local = glm::inverse(body_frame) * root_from_node_[frame];
    joint.anchor_m = glm::vec3(local[3]);
    if (axis >= 0) joint.axis = sign * glm::normalize(glm::vec3(local[axis]));
    e.joint = joint;
  }

  static constexpr std::size_t kMaxDepth = 1000;
  Node root_;
  std::string parent_;
  std::size_t count_ = 0;
  std::vector<int> parent_of_;
  std::vector<glm::mat4> root_from_node_;
  std::vector<Node> shapes_, materials_, joints_;
  std::vector<int> entity_of_node_;
  std::vector<EntityDesc> out_;
};

}  // namespace

std::expected<std::vector<EntityDesc>, JsonError> read_gltf_physics(const std::filesystem::path& file, const std::string& parent) {
  auto root = read_gltf_json(file);
  if (!root) return std::unexpected(root.error());
  try {
    return Reader(*root, parent).read();
  } catch (const JsonFailure& f) {
    return std::unexpected(JsonError{file.string(), f.json_path.empty() ? "/" : f.json_path, f.message});
  }
}

}  // namespace rhot
