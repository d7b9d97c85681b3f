#pragma once
// The simulated world behind the demo: where the user's hands and the star-tracked objects truly
// are at each moment. The simulated camera rig sees this; tracking has to recover it.
//
// In the default scene (assets/scenes/default.json) the right hand reaches for the red cube,
// grasps it, lifts it 15 cm, carries it 18 cm across the table, sets it down and lets go; then
// the left hand picks up the star-tracked mug, lifts it, moves it 11 cm and puts it down (the mug
// is a real object: it moves because the hand carries it, and tracking sees its star move). Then
// each hand carries its object back (12-26 s), and the 26 s script starts again. In other
// scenes a hand whose object is missing rests above the table.
//
// A scene with value_above, press or snap rules (assets/scenes/workbench.json, workshop.json) gets the
// showcase script instead (engine/sim/ShowcaseScript.cpp), one task after another, each derived
// from the scene's data:
//   value_above on a hinge or slider   a hand grasps the joint's handle (a grabbable entity fixed
//                                      to it, or the jointed entity itself) and swings it about the
//                                      hinge, or pulls it along the slider, past the threshold
//   press on a button                  a pointing index finger pushes it in and lifts off
//   snap on a socket                   a hand carries the object the rule names (or the first the
//                                      socket accepts) over the socket's attach pose and lets go
//   place interaction                  the object carried into its zone and put down; with both
//                                      hands, near its ends, when it is 30 cm or longer
//   hand_over interaction              the hand on the object's side takes it at its end and lifts
//                                      it between the hands, the other takes the other end, the
//                                      first lets go, and the second puts it down on its own side
//                                      (objects 16 cm or longer)
// The script plays once and then rests.

#include <array>
#include <map>
#include <optional>
#include <vector>

#include "engine/core/Entity.h"
#include "engine/sim/ScriptedHands.h"
#include "engine/scene/SceneDesc.h"
#include "tracking/core/Rigid3.h"
#include "tracking/hand/HandJoints.h"

namespace rhot {

struct HandTruth {
  Rigid3d world_from_hand;
  HandPose pose;  // hand frame
};

struct SceneTruth {
  std::array<HandTruth, 2> hands;            // 0 left, 1 right
  std::map<int, Rigid3d> world_from_object;  // by marker-star id, for objects tracked by a star
};

class DemoScript {
 public:
  explicit DemoScript(const SceneDesc& scene);
  SceneTruth at(double t_s) const;
  // Tells the script where the cube lies (its entity's position, after the physics step at t_s).
  // Like a user looking before reaching, the right hand's next pickup aims there: the first pickup
  // at 0.4 s (the cube settled where the scene put it), the return pickup at 10 s into each round
  // (the hand resting), the next round's at 20 s (the hand waiting above home). Without this each round would start from the last round's
  // small placement errors.
  void reaim(double t_s, const Eigen::Vector3d& cube_position);
  // One round of the script; at() repeats it (the showcase: plays once, then rests).
  double duration_s() const { return duration_s_; }

  // A showcase task: what it works ("hinge", "slider", "poke", "socket", "place", "hand_over"), on which
  // entity (the jointed entity, the button, the socket, the placed object), when.
  struct Task {
    std::string kind;
    std::string entity;
    double begin_s = 0.0;
    double end_s = 0.0;
  };
  // The showcase's tasks (empty for the demo script).
  const std::vector<Task>& tasks() const { return tasks_; }
  // Whether a scene gets the showcase script.
  static bool wants_showcase(const SceneDesc& scene);
  // The entity names the script acts on ("" when the scene lacks them).
  const std::string& right_target() const { return right_target_; }
  const std::string& left_target() const { return left_target_; }

 private:
  struct Key {
    double t;
    Eigen::Vector3d centre;
    double closure;
  };
  // A showcase key: the grasp's width and axis at it, the hand turned about the grip point, or a
  // pointing hand with its index tip at `centre`.
  struct ShowKey {
    double t;
    Eigen::Vector3d centre;
    double closure;
    double width_m;
    Eigen::Vector3d axis;
    Eigen::Quaterniond turn;
    bool pointing;
  };
  struct HandScript {
    HandSide side;
    std::vector<Key> keys;
    double width_m = 0.05;
    Eigen::Vector3d axis = Eigen::Vector3d::UnitX();
    std::vector<ShowKey> show;  // the showcase's keys (instead of keys)
  };
  HandTruth hand_at(const HandScript& s, double t) const;
  HandTruth show_hand_at(const HandScript& s, double t) const;
  HandTruth show_pose(HandSide side, const ShowKey& k, const Eigen::Vector3d& centre, double closure, const Eigen::Quaterniond& turn) const;
  void build_right_keys();
  void build_showcase(const SceneDesc& scene);
  struct Showcase;  // builds the showcase's keys (ShowcaseScript.cpp)

  double duration_s_ = 26.0;
  bool once_ = false;  // the showcase plays once
  std::vector<Task> tasks_;

  std::array<HandScript, 2> scripts_;
  std::string right_target_, left_target_;
  std::map<int, Rigid3d> objects_at_start_;
  std::optional<int> carried_star_;                 // the left hand carries this star's object ...
  std::vector<std::pair<double, double>> carries_;  // ... between these times
  // The right hand's cube: where it starts (and is brought back to), where it is carried, where
  // the next pickups aim, and the grip point's offset from the cube's origin.
  Eigen::Vector3d cube_home_{0, 0, 0}, cube_place_{0, 0, 0}, cube_pickup_{0, 0, 0}, cube_return_pickup_{0, 0, 0};
  Eigen::Vector3d round_start_{0, 0, 0};  // where a round's first key holds the hand (above the last aim)
  Eigen::Vector3d cube_grip_offset_{0, 0, 0};
  double last_reaim_t_ = 0.0;
  mutable std::map<std::pair<int, long>, GraspPose> grasps_;  // per hand and width (0.01 mm), built once
};

}  // namespace rhot
