#pragma once
// The demo's first pickup with the red cube placed anywhere on the table: how `rhot-eval demo`
// and the tests measure whether grasps work away from the one spot the scene puts the cube.
//
// A pickup runs the demo (engine/sim/Demo.h, no renderer) from the start for a few seconds: the
// right hand looks where the cube rests (DemoScript::reaim), reaches, grasps at 2.2 s and lifts
// 15 cm by 3.2 s. It counts as a success when the right hand grasped the cube and lifted it at
// least 10 cm. Every frame, each hand reported as seen is also compared with the simulated truth.

#include <expected>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "engine/scene/SceneDesc.h"
#include "engine/sim/Demo.h"

namespace rhot {

struct PickupResult {
  Eigen::Vector2d spot_xz{0, 0};  // where the cube was put (x, z)
  bool grasped = false;           // the right hand grasped the cube
  double lift_m = 0.0;            // the most the cube rose above where it rested at the start
  bool success = false;           // grasped and lifted at least kPickupLift_m
  int frames = 0;
  int hand_frames_seen = 0;       // hands reported as seen, over both hands and every frame
  int reported_wrong_frames = 0;  // of those, wrist more than 10 mm or the hand 5 degrees off the truth
  int hand_confusion_frames = 0;  // frames in which a hand was reported where the other is (hand_confused)
};

inline constexpr double kPickupLift_m = 0.10;

// The scene with the cube ("cube-red") at spot_xz on the table, run for `frames` frames at the
// headset's rate. Fails naming what is wrong: no cube in the scene, or what Demo::create refuses.
std::expected<PickupResult, std::string> run_pickup(const SceneDesc& scene, const Eigen::Vector2d& spot_xz, const DemoSettings& settings,
                                                    int frames = 330);

// `count` spots (x, z) on the scene's table, at random from the seed, where the cube lies clear of
// every other object (centres at least 11 cm apart) and the script's carry 15 cm right and 10 cm
// back stays on the table. Fails when the scene has no cube or no box "table".
std::expected<std::vector<Eigen::Vector2d>, std::string> pickup_spots(const SceneDesc& scene, int count, unsigned seed);

}  // namespace rhot
