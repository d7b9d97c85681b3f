#include "engine/sim/DemoScript.h"

#include "engine/math/EigenGlm.h"
#include <algorithm>

#include <glm/gtc/quaternion.hpp>

#include <cmath>

namespace rhot {

namespace {

Rigid3d pose_of(const EntityDesc& e) {
  // Scene-file transforms of root entities (the script's objects are roots).
  Rigid3d r;
  r.translation = to_eigen(e.transform.position);
  r.rotation = to_eigen(e.transform.rotation).normalized();
  return r;
}

// The width a hand grasps an object by, across world X.
double grip_width(const EntityDesc& e) {
  const auto half = e.mesh ? shape_half_extents(e.mesh->shape) : std::nullopt;
  return half ? 2.0 * static_cast<double>(half->x * e.transform.scale.x) : 0.05;
}

// Where a hand closes on an object: its centre, or for a tall object 2.5 cm below its top (the
// palm would land on the top otherwise).
Eigen::Vector3d grip_point(const EntityDesc& e) {
  Eigen::Vector3d c = to_eigen(e.transform.position);
  const auto half = e.mesh ? shape_half_extents(e.mesh->shape) : std::nullopt;
  if (half) c.y() += std::max(0.0, static_cast<double>(half->y * e.transform.scale.y) - 0.025);
  return c;
}

const EntityDesc* find(const SceneDesc& scene, const std::string& name) {
  for (const EntityDesc& e : scene.entities) {
    if (e.name == name && e.parent.empty()) return &e;
  }
  return nullptr;
}

}  // namespace

DemoScript::DemoScript(const SceneDesc& scene) {
  const Eigen::Vector3d up = Eigen::Vector3d::UnitY();
  // Hands rest above the table in front of the user when they have nothing to do.
  scripts_[0] = {HandSide::kLeft, {{0.0, Eigen::Vector3d(-0.25, 0.95, -0.3), 0.0}}, 0.05, -Eigen::Vector3d::UnitX(), {}};
  scripts_[1] = {HandSide::kRight, {{0.0, Eigen::Vector3d(0.25, 0.95, -0.3), 0.0}}, 0.05, Eigen::Vector3d::UnitX(), {}};
  if (wants_showcase(scene)) {
    build_showcase(scene);
    return;
  }
  for (const EntityDesc& e : scene.entities) {
    if (e.tracked_by) objects_at_start_[*e.tracked_by] = pose_of(e);
  }
  if (const EntityDesc* cube = find(scene, "cube-red"); cube && cube->grabbable) {
    right_target_ = cube->name;
    const Eigen::Vector3d c = grip_point(*cube);
    const Eigen::Vector3d place = c + Eigen::Vector3d(0.15, 0.0, -0.1);
    scripts_[1].width_m = grip_width(*cube);
    cube_home_ = c;
    cube_place_ = place;
    cube_pickup_ = c;
    round_start_ = c;
    cube_return_pickup_ = place;
    cube_grip_offset_ = c - pose_of(*cube).translation;
    build_right_keys();
  }
  if (const EntityDesc* mug = find(scene, "tracked-mug"); mug && mug->tracked_by) {
    left_target_ = mug->name;
    carried_star_ = *mug->tracked_by;
    const Eigen::Vector3d c = grip_point(*mug);
    const Eigen::Vector3d moved = c + Eigen::Vector3d(-0.05, 0.0, 0.1);
    scripts_[0].width_m = grip_width(*mug);
    // After the right hand is done with the cube.
    // ... and, after the right hand brought the cube back, carries the mug back and returns to rest.
    scripts_[0].keys = {{0.0, Eigen::Vector3d(-0.25, 0.95, -0.3), 0.0},
                        {5.0, c + 0.15 * up, 0.0},
                        {6.0, c, 0.0},
                        {6.5, c, 1.0},
                        {7.5, c + 0.12 * up, 1.0},
                        {9.0, moved + 0.12 * up, 1.0},
                        {10.0, moved, 1.0},
                        {10.5, moved, 0.0},
                        {11.3, moved + 0.15 * up, 0.0},
                        {18.5, moved + 0.15 * up, 0.0},
                        {19.3, moved, 0.0},
                        {19.8, moved, 1.0},
                        {20.8, moved + 0.12 * up, 1.0},
                        {22.3, c + 0.12 * up, 1.0},
                        {23.3, c, 1.0},
                        {23.8, c, 0.0},
                        {24.6, c + 0.15 * up, 0.0},
                        {26.0, Eigen::Vector3d(-0.25, 0.95, -0.3), 0.0}};
    carries_ = {{6.5, 10.0}, {19.8, 23.3}};
  }
}

void DemoScript::build_right_keys() {
  // Out to `place` and, after the left hand's first turn, back home; then over to where the cube
  // lies for the next round's pickup. Pickups aim where the cube was last seen lying (reaim()):
  // the round starts above where the last round aimed and moves over the cube as it lies now.
  const Eigen::Vector3d up = Eigen::Vector3d::UnitY();
  const Eigen::Vector3d rest(0.25, 0.95, -0.3);
  const Eigen::Vector3d& c = cube_pickup_;
  const Eigen::Vector3d& back = cube_return_pickup_;
  const Eigen::Vector3d& home = cube_home_;
  const Eigen::Vector3d& place = cube_place_;
  scripts_[1].keys = {{0.0, round_start_ + 0.15 * up, 0.0},
                      {0.8, c + 0.15 * up, 0.0},
                      {1.6, c, 0.0},
                      {2.2, c, 1.0},
                      {3.2, c + 0.15 * up, 1.0},
                      {4.4, place + 0.15 * up, 1.0},
                      {5.4, place + 0.002 * up, 1.0},
                      {5.8, place + 0.002 * up, 0.0},
                      {6.6, place + 0.15 * up, 0.0},
                      {7.6, rest, 0.0},
                      {11.5, rest, 0.0},
                      {12.5, back + 0.15 * up, 0.0},
                      {13.3, back, 0.0},
                      {13.9, back, 1.0},
                      {14.9, back + 0.15 * up, 1.0},
                      {16.1, home + 0.15 * up, 1.0},
                      {17.1, home + 0.002 * up, 1.0},
                      {17.5, home + 0.002 * up, 0.0},
                      {18.3, home + 0.15 * up, 0.0},
                      {25.9, c + 0.15 * up, 0.0}};
}

void DemoScript::reaim(double t_s, const Eigen::Vector3d& cube_position) {
  if (right_target_.empty() || !cube_position.allFinite()) return;
  const double t = std::fmod(std::max(0.0, t_s), duration_s());
  const double before = last_reaim_t_;
  last_reaim_t_ = t;
  const auto crossed = [&](double mark) { return before < mark && t >= mark; };
  // Before the first descent (0-0.8 s: the cube has settled where the scene dropped it), while
  // the right hand rests (7.6-11.5 s) and while it waits above home (18.3-25.9 s), it looks where
  // the cube lies: those keys are still ahead, so the hand's path stays continuous.
  if (crossed(0.4)) {
    cube_pickup_ = cube_position + cube_grip_offset_;
  } else if (crossed(10.0)) {
    cube_return_pickup_ = cube_position + cube_grip_offset_;
  } else if (crossed(20.0)) {
    cube_pickup_ = cube_position + cube_grip_offset_;
    round_start_ = cube_pickup_;
  } else {
    return;
  }
  build_right_keys();
}

HandTruth DemoScript::hand_at(const HandScript& s, double t) const {
  if (!s.show.empty()) return show_hand_at(s, t);
  Eigen::Vector3d centre = s.keys.back().centre;
  double closure = s.keys.back().closure;
  if (t <= s.keys.front().t) {
    centre = s.keys.front().centre;
    closure = s.keys.front().closure;
  }
  for (std::size_t i = 1; i < s.keys.size(); ++i) {
    if (t > s.keys[i - 1].t && t <= s.keys[i].t) {
      // Smooth within each segment: hands start and stop gently.
      double u = (t - s.keys[i - 1].t) / (s.keys[i].t - s.keys[i - 1].t);
      u = u * u * (3.0 - 2.0 * u);
      centre = s.keys[i - 1].centre + u * (s.keys[i].centre - s.keys[i - 1].centre);
      closure = s.keys[i - 1].closure + u * (s.keys[i].closure - s.keys[i - 1].closure);
      break;
    }
  }
  // A grasp pose per hand and width, built once.
  const auto key = std::make_pair(static_cast<int>(s.side), std::lround(s.width_m * 1e5));
  auto it = grasps_.find(key);
  if (it == grasps_.end()) it = grasps_.emplace(key, make_grasp(s.side, s.width_m)).first;
  return {it->second.place(centre, s.axis), it->second.pose(closure)};
}

SceneTruth DemoScript::at(double t_s) const {
  // The script repeats; each round ends where it began.
  const double t = t_s < 0.0 ? 0.0 : once_ ? t_s : std::fmod(t_s, duration_s());
  SceneTruth truth;
  truth.hands[0] = hand_at(scripts_[0], t);
  truth.hands[1] = hand_at(scripts_[1], t);
  truth.world_from_object = objects_at_start_;
  if (carried_star_) {
    // Carried rigidly by the left hand from the moment it closes until it opens, each time.
    Rigid3d pose = objects_at_start_.at(*carried_star_);
    for (const auto& [from, to] : carries_) {
      if (t <= from) break;
      const Rigid3d at_grasp = hand_at(scripts_[0], from).world_from_hand;
      const Rigid3d now = hand_at(scripts_[0], std::min(t, to)).world_from_hand;
      pose = now * at_grasp.inverse() * pose;
    }
    truth.world_from_object[*carried_star_] = pose;
  }
  return truth;
}

}  // namespace rhot
