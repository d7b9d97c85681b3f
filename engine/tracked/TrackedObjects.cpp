#include "engine/tracked/TrackedObjects.h"

#include <algorithm>
#include <numbers>

#include <Eigen/Geometry>

#include "engine/core/Transform.h"
#include "engine/core/World.h"
#include "engine/math/EigenGlm.h"
#include "engine/scene/Components.h"

namespace rhot {

namespace {

// How far the star's origin stands behind the object's origin (see the header).
double star_offset(const Mesh* mesh, const glm::vec3& scale) {
  const auto half = mesh ? shape_half_extents(mesh->shape) : std::nullopt;
  return half ? static_cast<double>(half->z * scale.z) + 0.004 : 0.05;
}

}  // namespace

const TrackedObject* TrackedObjects::by_star(int star_id) const {
  const auto it = std::find_if(objects.begin(), objects.end(), [&](const TrackedObject& o) { return o.star_id == star_id; });
  return it == objects.end() ? nullptr : &*it;
}

std::expected<TrackedObjects, std::string> find_tracked_objects(World& world, const StarSet& set, const std::filesystem::path& set_file) {
  TrackedObjects out;
  out.stars.rules = set.rules;
  std::string error;
  world.view<TrackedBy, Transform>().each([&](Entity e, TrackedBy& by, Transform& t) {
    if (!error.empty()) return;
    const auto it = std::find_if(set.stars.begin(), set.stars.end(), [&](const MarkerStar& s) { return s.id == by.star_id; });
    const Name* name = world.find<Name>(e);
    if (it == set.stars.end()) {
      error = (name ? name->value : std::string("an entity")) + ": tracked by star " + std::to_string(by.star_id) + ", which " +
              set_file.string() + " does not have";
      return;
    }
    out.stars.stars.push_back(*it);
    TrackedObject o;
    o.entity = e;
    o.star_id = by.star_id;
    o.name = name ? name->value : std::string();
    o.object_from_star.translation = Eigen::Vector3d(0.0, 0.0, -star_offset(world.find<Mesh>(e), t.scale));
    o.object_from_star.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d::UnitY()));
    out.objects.push_back(std::move(o));
  });
  if (!error.empty()) return std::unexpected(error);
  return out;
}

void create_tracking_entities(World& world, const SceneSettings& settings, const CameraRig* rig) {
  for (const HandSide side : {HandSide::kLeft, HandSide::kRight}) {
    const Entity e = world.create();
    world.add<Name>(e, Name{side == HandSide::kLeft ? "hand-left" : "hand-right"});
    Hand hand;
    hand.side = side;
    hand.shown = side == HandSide::kLeft ? settings.left_hand : settings.right_hand;
    world.add<Hand>(e, hand);
  }
  const Entity tracking = world.create();
  world.add<Name>(tracking, Name{"tracking"});
  world.add<TrackedMarkers>(tracking);
  world.add<TrackingCameras>(tracking, TrackingCameras{rig ? rig->cameras : std::vector<Camera>{}});
}

void apply_tracking_results(World& world, const TrackingResults& results, const TrackedObjects& objects) {
  for (const TrackedObject& o : objects.objects) {
    const auto pose = results.world_from_object.find(o.star_id);
    if (pose == results.world_from_object.end() || !world.alive(o.entity)) continue;
    Transform& t = world.get<Transform>(o.entity);
    t.position = to_glm(pose->second.translation);
    t.rotation = glm::normalize(to_glm(pose->second.rotation));
  }
  world.view<Hand>().each([&](Entity, Hand& hand) {
    const std::size_t h = hand.side == HandSide::kLeft ? 0 : 1;
    hand.tracked = results.hands[h];
    hand.gestures_measured = results.gestures_measured;
    hand.pinch = results.pinch[h];
    hand.grip = results.grip[h];
  });
  world.view<TrackedMarkers>().each([&](Entity, TrackedMarkers& m) {
    m.points = results.points;
    m.point_cameras = results.point_cameras;
  });
}

}  // namespace rhot
