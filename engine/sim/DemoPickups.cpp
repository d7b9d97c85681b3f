#include "engine/sim/DemoPickups.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include <Eigen/Geometry>

#include "engine/core/Transform.h"
#include "engine/core/World.h"
#include "engine/math/EigenGlm.h"
#include "engine/scene/SceneLoader.h"
#include "tracking/sim/Realism.h"

namespace rhot {

namespace {

constexpr const char* kCube = "cube-red";

EntityDesc* find_entity(std::vector<EntityDesc>& entities, std::string_view name) {
  for (EntityDesc& e : entities) {
    if (e.name == name) return &e;
  }
  return nullptr;
}

// Half the entity's box in x, y, z (scaled); nothing for a shape without one.
std::optional<Eigen::Vector3d> half_extents(const EntityDesc& e) {
  if (!e.mesh) return std::nullopt;
  const auto half = shape_half_extents(e.mesh->shape);
  if (!half) return std::nullopt;
  return to_eigen(*half * e.transform.scale);
}

}  // namespace

std::expected<PickupResult, std::string> run_pickup(const SceneDesc& scene, const Eigen::Vector2d& spot_xz, const DemoSettings& settings,
                                                    int frames) {
  SceneDesc placed = scene;
  EntityDesc* cube = find_entity(placed.entities, kCube);
  if (!cube) return std::unexpected(std::string("the scene has no entity \"") + kCube + "\" to pick up");
  cube->transform.position.x = static_cast<float>(spot_xz.x());
  cube->transform.position.z = static_cast<float>(spot_xz.y());
  auto created = Demo::create(placed, nullptr, settings);
  if (!created) return std::unexpected(created.error());
  Demo& demo = **created;
  Runtime& runtime = demo.runtime();
  World& world = runtime.world();
  const Entity block = find_named(world, kCube);
  PickupResult r;
  r.spot_xz = spot_xz;
  r.frames = frames;
  std::optional<double> rest_y;
  const double rate_hz = placed.settings.headset.refresh_hz;
  for (int f = 0; f < frames; ++f) {
    const double t = f / rate_hz;
    runtime.run_frame(t);
    for (const InteractionEvent& e : runtime.physics().events()) {
      if (e.object == block && e.hand == HandSide::kRight && e.type == InteractionEventType::kGrasp) r.grasped = true;
    }
    const auto y = static_cast<double>(world.get<Transform>(block).position.y);
    if (t >= 0.4 && !rest_y) rest_y = y;  // where the cube rests once it has settled (the script looks then too)
    if (rest_y) r.lift_m = std::max(r.lift_m, y - *rest_y);
    const DemoWorld* sim = demo.simulated();
    if (!sim || !sim->truth()) continue;
    const SceneTruth& truth = *sim->truth();
    const auto wrist = static_cast<std::size_t>(HandJoint::kWrist);
    std::array<Eigen::Vector3d, 2> true_wrist;
    for (std::size_t h = 0; h < 2; ++h) true_wrist[h] = truth.hands[h].world_from_hand * truth.hands[h].pose.position_m[wrist];
    bool confused = false;
    for (std::size_t h = 0; h < 2; ++h) {
      const HandInput& hand = runtime.tracking().results().hands[h];
      if (!hand.seen) continue;
      ++r.hand_frames_seen;
      const double turn = Eigen::AngleAxisd(hand.world_from_hand.rotation * truth.hands[h].world_from_hand.rotation.conjugate()).angle();
      if ((hand.joints_world[wrist] - true_wrist[h]).norm() > 0.010 || turn > 5.0 * std::numbers::pi / 180.0) {
        ++r.reported_wrong_frames;
      }
      confused = confused || hand_confused(hand.joints_world[wrist], true_wrist[h], true_wrist[1 - h]);
    }
    r.hand_confusion_frames += confused ? 1 : 0;
  }
  r.success = r.grasped && r.lift_m >= kPickupLift_m;
  return r;
}

std::expected<std::vector<Eigen::Vector2d>, std::string> pickup_spots(const SceneDesc& scene, int count, unsigned seed) {
  SceneDesc copy = scene;
  const EntityDesc* cube = find_entity(copy.entities, kCube);
  const EntityDesc* table = find_entity(copy.entities, "table");
  if (!cube) return std::unexpected(std::string("the scene has no entity \"") + kCube + "\" to pick up");
  const auto cube_half = cube ? half_extents(*cube) : std::nullopt;
  const auto table_half = table ? half_extents(*table) : std::nullopt;
  if (!table_half || !cube_half) return std::unexpected(std::string("the scene has no box \"table\" with a box \"") + kCube + "\" on it");
  // Obstacles: every other body that is not the table (or a leg under it) or the floor.
  struct Obstacle {
    Eigen::Vector2d xz;
    double radius_m;
  };
  std::vector<Obstacle> obstacles;
  const double top_y = static_cast<double>(table->transform.position.y) + table_half->y();
  for (const EntityDesc& e : copy.entities) {
    if (&e == cube || &e == table || !e.body) continue;
    const auto half = half_extents(e);
    if (!half || static_cast<double>(e.transform.position.y) < top_y) continue;  // the floor, the legs
    obstacles.push_back({{e.transform.position.x, e.transform.position.z}, std::max(half->x(), half->z())});
  }
  const double cube_radius = std::hypot(cube_half->x(), cube_half->z());
  const Eigen::Vector2d centre(table->transform.position.x, table->transform.position.z);
  const Eigen::Vector2d extent(table_half->x(), table_half->z());
  // The carry goes 15 cm to +x and 10 cm to -z: both ends on the table, 5 cm in from its edge.
  const Eigen::Vector2d lo = centre - extent + Eigen::Vector2d(0.05 + cube_radius, 0.15 + cube_radius);
  const Eigen::Vector2d hi = centre + extent - Eigen::Vector2d(0.20 + cube_radius, 0.05 + cube_radius);
  if ((hi - lo).minCoeff() <= 0.0) return std::unexpected(std::string("the table is too small for the cube's carry"));
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(lo.x(), hi.x()), uz(lo.y(), hi.y());
  std::vector<Eigen::Vector2d> spots;
  for (int tries = 0; static_cast<int>(spots.size()) < count && tries < 100000; ++tries) {
    const Eigen::Vector2d p{ux(rng), uz(rng)};
    const bool clear = std::all_of(obstacles.begin(), obstacles.end(),
                                   [&](const Obstacle& o) { return (p - o.xz).norm() >= std::max(0.11, o.radius_m + cube_radius + 0.02); });
    if (clear) spots.push_back(p);
  }
  if (static_cast<int>(spots.size()) < count)
    return std::unexpected(std::string("the table has no room for the cube clear of the other objects"));
  return spots;
}

}  // namespace rhot
