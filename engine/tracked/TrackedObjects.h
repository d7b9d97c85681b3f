#pragma once
// The tracking system's side in the world: which entities tracking moves, and the copy of each
// frame's results into components (DESIGN: one system copies tracking results into components,
// objects and hands alike).
//
//   objects   an entity with TrackedBy follows its marker star: the star stands on the side of
//             the object facing away from the user (-Z), 4 mm clear of its surface, its tall side
//             pointing out (the hand closes on the object from above and from the user's side,
//             so a star on top or in front would be under the palm)
//   hands     two entities, "hand-left" and "hand-right", carry a Hand component
//   markers   one entity, "tracking", carries the triangulated points (TrackedMarkers) and the
//             cameras they came from (TrackingCameras), for the debug views

#include <expected>
#include <filesystem>
#include <string>
#include <vector>

#include "engine/core/Entity.h"
#include "engine/scene/SceneDesc.h"
#include "engine/tracked/TrackingResults.h"
#include "tracking/camera/Camera.h"
#include "tracking/rigid/StarSet.h"

namespace rhot {

class World;

struct TrackedObject {
  Entity entity;
  int star_id = 0;
  std::string name;  // the entity's Name ("" for none; a recording cannot name it then)
  Rigid3d object_from_star;
};

struct TrackedObjects {
  StarSet stars;                       // the set's stars some entity is tracked by, in entity order
  std::vector<TrackedObject> objects;  // one per tracked entity, in the world's order
  const TrackedObject* by_star(int star_id) const;
};

// Every entity with TrackedBy, its star from `set`. Fails naming the entity and `set_file` when
// the set lacks an entity's star.
[[nodiscard]] std::expected<TrackedObjects, std::string> find_tracked_objects(World& world, const StarSet& set,
                                                                              const std::filesystem::path& set_file);

struct TrackedMarkers {
  std::vector<Eigen::Vector3d> points;          // world
  std::vector<std::vector<int>> point_cameras;  // per point: indices into TrackingCameras::cameras
};
struct TrackingCameras {
  std::vector<Camera> cameras;  // empty when tracking has no cameras (a recording)
};

// Creates the hand entities and the "tracking" entity (with `rig`'s cameras, if any).
void create_tracking_entities(World& world, const SceneSettings& settings, const CameraRig* rig);

// The tracking system: each tracked object seen this frame is moved to its pose (its Transform;
// objects not seen keep theirs), each hand entity's Hand takes the frame's hand, and the
// "tracking" entity the frame's markers.
void apply_tracking_results(World& world, const TrackingResults& results, const TrackedObjects& objects);

}  // namespace rhot
