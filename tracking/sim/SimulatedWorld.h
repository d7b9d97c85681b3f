#pragma once
// What a simulated camera rig photographs: the world's markers and what hides them, at any moment.
// The owner of a simulated scene (a demo script, an evaluation) implements this and hands it to
// the SimulatedRig, so the rig never reads back into whoever runs the tracking.

#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace rhot {

// Something that hides markers behind it: a sphere (a == b) or a capsule from a to b; or, with a
// positive box_half_m, the box of those half extents centred at a_m, turned by box_rotation (a
// table top, a cube).
struct Occluder {
  Eigen::Vector3d a_m{0, 0, 0};
  Eigen::Vector3d b_m{0, 0, 0};
  double radius_m = 0.0;
  Eigen::Vector3d box_half_m{0, 0, 0};
  Eigen::Quaterniond box_rotation = Eigen::Quaterniond::Identity();

  static Occluder box(const Eigen::Vector3d& centre_m, const Eigen::Quaterniond& rotation, const Eigen::Vector3d& half_m) {
    Occluder o;
    o.a_m = o.b_m = centre_m;
    o.box_half_m = half_m;
    o.box_rotation = rotation;
    return o;
  }
  bool is_box() const { return box_half_m.x() > 0.0; }
  // Whether the segment from p to q passes through it.
  bool blocks(const Eigen::Vector3d& p, const Eigen::Vector3d& q) const;
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
