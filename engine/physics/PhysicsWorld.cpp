#include "engine/physics/PhysicsWorld.h"

#include <cmath>
#include <variant>

#include <BulletCollision/CollisionShapes/btShapeHull.h>
#include <glm/gtc/matrix_transform.hpp>
#include <spdlog/spdlog.h>

#include "engine/core/Transform.h"
#include "engine/core/World.h"
#include "engine/physics/BulletMath.h"
#include "engine/mesh/MeshData.h"

namespace rhot {

struct PhysicsWorld::Owned {
  std::unique_ptr<btCollisionShape> shape;
  std::unique_ptr<btCollisionShape> inner;  // a hull's full point cloud, kept while the hull lives
  std::unique_ptr<btDefaultMotionState> motion;
  std::unique_ptr<btRigidBody> body;
  double scale = 1.0;  // set_scale's factor
};

namespace {

struct Decomposed {
  glm::vec3 position{0.0f};
  glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};
  glm::vec3 scale{1.0f};
  bool finite = true;
};

Decomposed decompose(const glm::mat4& m) {
  Decomposed d;
  d.position = glm::vec3(m[3]);
  glm::mat3 r(m);
  for (int i = 0; i < 3; ++i) {
    d.scale[i] = glm::length(r[i]);
    if (d.scale[i] > 0.0f) r[i] /= d.scale[i];
  }
  if (glm::determinant(r) < 0.0f) {  // a mirror: keep it in the scale
    d.scale.x = -d.scale.x;
    r[0] = -r[0];
  }
  d.rotation = glm::normalize(glm::quat_cast(r));
  for (int i = 0; i < 3; ++i) d.finite = d.finite && std::isfinite(d.position[i]) && std::isfinite(d.scale[i]) && d.scale[i] != 0.0f;
  d.finite =
      d.finite && std::isfinite(d.rotation.w) && std::isfinite(d.rotation.x) && std::isfinite(d.rotation.y) && std::isfinite(d.rotation.z);
  return d;
}

// The shape for a mesh at a scale; for glTF meshes its convex hull (simplified to at most about
// 100 points, which is what Bullet's GJK wants).
std::expected<void, std::string> make_shape(const Mesh& mesh, const glm::vec3& scale, std::unique_ptr<btCollisionShape>& shape,
                                            std::unique_ptr<btCollisionShape>& inner, const std::string& name) {
  const glm::vec3 s = glm::abs(scale);
  if (const auto* box = std::get_if<BoxShape>(&mesh.shape)) {
    shape = std::make_unique<btBoxShape>(to_bt(0.5f * box->size_m * s));
  } else if (const auto* sphere = std::get_if<SphereShape>(&mesh.shape)) {
    shape = std::make_unique<btSphereShape>(sphere->radius_m * std::max({s.x, s.y, s.z}));
  } else if (const auto* capsule = std::get_if<CapsuleShape>(&mesh.shape)) {
    const float r = capsule->radius_m * std::max(s.x, s.z);
    const float h = capsule->height_m * s.y;
    shape = std::make_unique<btCapsuleShape>(r, std::max(0.0f, h - 2.0f * r));
  } else if (std::holds_alternative<PlaneShape>(mesh.shape)) {
    shape = std::make_unique<btStaticPlaneShape>(btVector3(0, 1, 0), 0);
  } else {
    const auto& file = std::get<GltfMeshShape>(mesh.shape).file;
    const auto data = load_gltf_mesh(file);
    if (!data) return std::unexpected(name + ": " + data.error());
    auto cloud = std::make_unique<btConvexHullShape>();
    for (const Vertex& v : data->vertices) cloud->addPoint(to_bt(v.position * scale), false);
    cloud->recalcLocalAabb();
    if (data->vertices.size() > 100) {
      btShapeHull hull(cloud.get());
      hull.buildHull(cloud->getMargin());
      auto simple = std::make_unique<btConvexHullShape>();
      for (int i = 0; i < hull.numVertices(); ++i) simple->addPoint(hull.getVertexPointer()[i], false);
      simple->recalcLocalAabb();
      shape = std::move(simple);
      inner = std::move(cloud);
    } else {
      shape = std::move(cloud);
    }
    // Bullet's default margin (4 cm) would float a hull that far above what it rests on.
    shape->setMargin(0.001f);
    btVector3 lo, hi;
    shape->getAabb(btTransform::getIdentity(), lo, hi);
    if (!((hi - lo).length() > btScalar(1e-4)))
      return std::unexpected(name + ": " + file.string() + ": the mesh has no extent to collide with");
  }
  return {};
}

// Bullet's solver keeps its working arrays from step to step and doubles one the first time a step
// has more contacts than ever before, which can be late in a long session: in the demo's soak the
// torsional friction constraints' array went from 32 to 64 (5 KiB of heap for good) after 5,000
// frames, when a hand held the cube differently. Room for kSolverRowsPresized rows of each kind is
// made up front (about 40 KiB an array), so a session's memory stays flat.
constexpr int kSolverRowsPresized = 256;
class PresizedSolver final : public btSequentialImpulseConstraintSolver {
 public:
  PresizedSolver() {
    for (btConstraintArray* rows : {&m_tmpSolverContactConstraintPool, &m_tmpSolverNonContactConstraintPool,
                                    &m_tmpSolverContactFrictionConstraintPool, &m_tmpSolverContactRollingFrictionConstraintPool})
      rows->reserve(kSolverRowsPresized);
    for (btAlignedObjectArray<int>* order : {&m_orderTmpConstraintPool, &m_orderNonContactConstraintPool, &m_orderFrictionConstraintPool})
      order->reserve(kSolverRowsPresized);
    m_tmpSolverBodyPool.reserve(kSolverRowsPresized);
  }
};

}  // namespace

PhysicsWorld::PhysicsWorld(PhysicsSettings settings)
    : settings_(settings),
      config_(std::make_unique<btDefaultCollisionConfiguration>()),
      dispatcher_(std::make_unique<btCollisionDispatcher>(config_.get())),
      broadphase_(std::make_unique<btDbvtBroadphase>()),
      solver_(std::make_unique<PresizedSolver>()),
      world_(std::make_unique<btDiscreteDynamicsWorld>(dispatcher_.get(), broadphase_.get(), solver_.get(), config_.get())) {
  if (!(settings_.rate_hz > 0.0) || !std::isfinite(settings_.rate_hz)) settings_.rate_hz = 90.0;
  settings_.substeps = std::max(1, settings_.substeps);
  world_->setGravity(to_bt(settings_.gravity_mps2));
  // Push penetrations out without adding energy (split impulse) from 1 mm deep, not Bullet's
  // default 4 cm: hand bones pressing on a surface would otherwise sit millimetres inside it.
  btContactSolverInfo& info = world_->getSolverInfo();
  info.m_splitImpulse = 1;
  info.m_splitImpulsePenetrationThreshold = -0.001f;
}

PhysicsWorld::~PhysicsWorld() {
  for (auto& o : owned_) world_->removeRigidBody(o->body.get());
}

std::expected<void, std::string> PhysicsWorld::add_scene_bodies(World& world) {
  std::vector<std::unique_ptr<Owned>> fresh;
  std::vector<Entity> fresh_entities;
  std::string error;
  world.view<Mesh, PhysicsBody, WorldTransform>().each([&](Entity e, Mesh& mesh, PhysicsBody& pb, WorldTransform& wt) {
    if (!error.empty() || bodies_.contains(e)) return;
    const Name* name = world.find<Name>(e);
    const std::string label = name ? name->value : "entity";
    const Decomposed d = decompose(wt.world_from_local);
    if (!d.finite) {
      error = label + ": its world transform is not finite";
      return;
    }
    auto o = std::make_unique<Owned>();
    if (auto made = make_shape(mesh, d.scale, o->shape, o->inner, label); !made) {
      error = made.error();
      return;
    }
    const bool dynamic = pb.type == BodyType::kDynamic;
    btVector3 inertia(0, 0, 0);
    const btScalar mass = dynamic ? pb.mass_kg : 0.0f;
    if (dynamic) o->shape->calculateLocalInertia(mass, inertia);
    o->motion = std::make_unique<btDefaultMotionState>(btTransform(to_bt(d.rotation), to_bt(d.position)));
    btRigidBody::btRigidBodyConstructionInfo info(mass, o->motion.get(), o->shape.get(), inertia);
    info.m_friction = pb.friction;
    info.m_restitution = pb.restitution;
    // Round things roll, but not forever on a flat surface (Bullet's rolling resistance).
    const bool round = std::holds_alternative<SphereShape>(mesh.shape) || std::holds_alternative<CapsuleShape>(mesh.shape);
    info.m_rollingFriction = round ? 0.05f * pb.friction : 0.0f;
    info.m_spinningFriction = round ? 0.05f * pb.friction : 0.0f;
    o->body = std::make_unique<btRigidBody>(info);
    if (pb.type == BodyType::kKinematic) {
      o->body->setCollisionFlags(o->body->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
      o->body->setActivationState(DISABLE_DEACTIVATION);
    }
    if (dynamic) {
      // Small fast objects (a thrown sphere) must not pass through thin ones.
      btVector3 centre;
      btScalar radius = 0;
      o->shape->getBoundingSphere(centre, radius);
      o->body->setCcdMotionThreshold(0.5f * radius);
      o->body->setCcdSweptSphereRadius(0.4f * radius);
    }
    fresh_entities.push_back(e);
    fresh.push_back(std::move(o));
  });
  if (!error.empty()) return std::unexpected(error);
  for (std::size_t i = 0; i < fresh.size(); ++i) {
    btRigidBody* b = fresh[i]->body.get();
    world_->addRigidBody(b, kSceneGroup, kSceneGroup | kHandGroup);
    bodies_[fresh_entities[i]] = b;
    entity_by_object_[b] = fresh_entities[i];
    owned_by_entity_[fresh_entities[i]] = fresh[i].get();
    entities_.push_back(fresh_entities[i]);
    owned_.push_back(std::move(fresh[i]));
  }
  return {};
}

btRigidBody* PhysicsWorld::body(Entity e) const {
  const auto it = bodies_.find(e);
  return it == bodies_.end() ? nullptr : it->second;
}

std::optional<Entity> PhysicsWorld::entity_of(const btCollisionObject* object) const {
  const auto it = entity_by_object_.find(object);
  if (it == entity_by_object_.end()) return std::nullopt;
  return it->second;
}

void PhysicsWorld::set_enabled(Entity e, bool enabled) {
  btRigidBody* b = body(e);
  if (!b) return;
  const bool in_world = b->getBroadphaseHandle() != nullptr;
  if (enabled && !in_world) {
    world_->addRigidBody(b, kSceneGroup, kSceneGroup | kHandGroup);
    b->activate(true);
  } else if (!enabled && in_world) {
    world_->removeRigidBody(b);
  }
}

void PhysicsWorld::set_scale(World& world, Entity e, double factor) {
  const auto it = owned_by_entity_.find(e);
  if (it == owned_by_entity_.end() || !std::isfinite(factor) || factor <= 0.0) return;
  Owned& o = *it->second;
  btRigidBody* b = o.body.get();
  if (b->isStaticOrKinematicObject() || factor == o.scale) return;
  const btScalar f = static_cast<btScalar>(factor);
  o.shape->setLocalScaling(btVector3(f, f, f));
  if (b->getInvMass() > 0) {
    const btScalar mass = 1 / b->getInvMass();
    btVector3 inertia(0, 0, 0);
    o.shape->calculateLocalInertia(mass, inertia);
    b->setMassProps(mass, inertia);
    b->updateInertiaTensor();
  }
  if (b->getBroadphaseHandle()) world_->updateSingleAabb(b);
  const float ratio = static_cast<float>(factor / o.scale);
  o.scale = factor;
  if (WorldTransform* wt = world.find<WorldTransform>(e))
    wt->world_from_local = wt->world_from_local * glm::scale(glm::mat4(1.0f), glm::vec3(ratio));
  if (Transform* t = world.find<Transform>(e)) t->scale *= ratio;
}

double PhysicsWorld::scale(Entity e) const {
  const auto it = owned_by_entity_.find(e);
  return it == owned_by_entity_.end() ? 1.0 : it->second->scale;
}

void PhysicsWorld::add_external(btRigidBody* body, int group, int mask) { world_->addRigidBody(body, group, mask); }
void PhysicsWorld::remove_external(btRigidBody* body) { world_->removeRigidBody(body); }

void PhysicsWorld::step(World& world) {
  // Kinematic bodies follow their entities.
  for (const Entity e : entities_) {
    btRigidBody* b = bodies_.at(e);
    if (!b->isKinematicObject() || !world.alive(e)) continue;
    const WorldTransform* wt = world.find<WorldTransform>(e);
    if (!wt) continue;
    const Decomposed d = decompose(wt->world_from_local);
    if (!d.finite) {
      if (!warned_non_finite_) spdlog::warn("physics: a kinematic body's pose is not finite; it keeps its last pose");
      warned_non_finite_ = true;
      continue;
    }
    b->getMotionState()->setWorldTransform(btTransform(to_bt(d.rotation), to_bt(d.position)));
  }
  const btScalar h = static_cast<btScalar>(step_s() / settings_.substeps);
  for (int i = 0; i < settings_.substeps; ++i) world_->stepSimulation(h, 0);
  time_s_ = static_cast<double>(++steps_) * step_s();
  // Dynamic bodies move their entities.
  for (const Entity e : entities_) {
    btRigidBody* b = bodies_.at(e);
    if (b->isStaticOrKinematicObject() || !world.alive(e)) continue;
    Transform* t = world.find<Transform>(e);
    WorldTransform* wt = world.find<WorldTransform>(e);
    if (!t || !wt) continue;
    const btTransform& pose = b->getWorldTransform();
    const glm::vec3 scale = decompose(wt->world_from_local).scale;
    const glm::mat4 world_from_local = glm::translate(glm::mat4(1.0f), to_glm(pose.getOrigin())) *
                                       glm::mat4_cast(to_glm(pose.getRotation())) * glm::scale(glm::mat4(1.0f), scale);
    wt->world_from_local = world_from_local;
    glm::mat4 local = world_from_local;
    if (const Parent* p = world.find<Parent>(e); p && world.alive(p->entity)) {
      if (const WorldTransform* pw = world.find<WorldTransform>(p->entity)) local = glm::inverse(pw->world_from_local) * world_from_local;
    }
    const Decomposed d = decompose(local);
    t->position = d.position;
    t->rotation = d.rotation;
  }
}

}  // namespace rhot
