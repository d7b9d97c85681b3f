#pragma once
// What a simulated camera rig photographs: the world's markers and what hides them, at any moment.
// The owner of a simulated scene (a demo script, an evaluation) implements this and hands it to
// the SimulatedRig, so the rig never reads back into whoever runs the tracking.

#include <vector>

#include <Eigen/Core>

namespace rhot {

// Something that hides markers behind it: a sphere (a == b) or a capsule from a to b.
struct Occluder {
  Eigen::Vector3d a_m{0, 0, 0};
  Eigen::Vector3d b_m{0, 0, 0};
  double radius_m = 0.0;
};

struct WorldSnapshot {
  std::vector<Eigen::Vector3d> markers_m;  // world positions; the same count and order at every time
  std::vector<Occluder> occluders;
};

class SimulatedWorld {
 public:
  virtual ~SimulatedWorld() = default;
  // The world at t_s (seconds on the rig's clock). Called once per frame, and once more per camera
  // when the rig's cameras are unsynchronised (their exposure times differ).
  virtual WorldSnapshot at(double t_s) = 0;
};

}  // namespace rhot
