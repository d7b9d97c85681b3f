#pragma once
// Scripted grasp scenarios: a scene built in code, hands driven by scripted skeletons (no
// cameras), run through HandPhysics and measured. The physics tests assert on these results and
// `rhot-eval grasp` prints them.
//
//   lift            grasp a 5 cm cube on a pedestal (thumb against index and middle), lift it
//                   15 cm, hold it 2 s, open the hand; it falls
//   pinch           the same with a 3 cm sphere between thumb and index
//   throw           grasp the cube, swing it at 1.5 m/s and open the hand mid-swing
//   push            a pointing index finger pushes the cube 6 cm along the pedestal
//   hand-over       the right hand lifts the cube, the left grasps it, the right lets go
//   hidden-markers  as lift, the hand through the hand solver, every fingertip marker hidden for
//                   0.5 s while holding
//   place           grasp the cube, carry it into a zone on a second pedestal, let go: the scene's
//                   "place" interaction succeeds
//
// With ScenarioCameras the physics gets tracked hands instead: both hands' markers (their layouts
// on the script's hands) photographed by a simulated rig moved so that its tracking volume is
// centred above the pedestal, in the world the settings describe (noise, strays, calibration
// error; the hands' bones always hide markers, the pedestal and the object too with
// occluding_bodies), then matched, triangulated and tracked (LiveTracking) as in the demo. In
// hidden-markers every fingertip marker is covered for those 0.5 s instead.

#include <array>
#include <expected>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "engine/interact/GraspSystem.h"
#include "engine/scene/SceneDesc.h"
#include "tracking/camera/Camera.h"
#include "tracking/hand/HandLayout.h"
#include "tracking/sim/Realism.h"

namespace rhot {

struct GraspScenarioResult {
  std::string name;
  bool grasped = false;     // a grasp event for the object
  double lift_m = 0.0;      // highest the object rose above where it started
  double max_slip_m = 0.0;  // while held: largest drift of the object in the hand's frame
  double held_s = 0.0;      // how long it was held
  bool released = false;
  bool fell_after_release = false;     // dropped at least 5 cm after the release
  double hand_speed_mps = 0.0;         // throw: the hand's speed at release
  double throw_velocity_error = 0.0;   // throw: |v_object - v_hand| / |v_hand|, the object's velocity
                                       // measured one step after the release (gravity included)
  double pushed_m = 0.0;               // push: how far the object moved
  bool handed_over = false;            // a release with handed_over
  std::vector<std::string> successes;  // interactions that succeeded
  std::vector<InteractionEvent> events;
  std::vector<double> step_ms;  // HandPhysics::step per frame
  long frames = 0;
  // Tracked hands only: hands reported as seen (over both hands in the script and every frame), of
  // those the ones with the wrist more than 10 mm or the hand 5 degrees off the truth, and frames
  // with a hand reported where the other is (hand_confused).
  long hand_frames_seen = 0;
  long reported_wrong_frames = 0;
  long hand_confusion_frames = 0;
  double fingertip_mean_mm = 0.0;  // the seen hands' fingertip joints against the truth, mean
};

struct ScenarioCameras {
  CameraRig rig;                      // moved to the pedestal (its volume centre, else where its axes meet)
  std::array<HandLayout, 2> layouts;  // left, right
  WorldSettings world;
  unsigned seed = 1;
  int threads = 0;  // the tracker's (LiveTrackingSettings::threads; 0: every core)
};

std::span<const std::string_view> grasp_scenario_names();
// `scene`: the scene to run in instead of the one built in code (its grasped entity must be named
// "object", where the built scene has it; "place" also needs "zone"); its interactions raise
// the success events.
// `cameras`: track the hands through them (nothing: the script's hands go to the physics as they are).
[[nodiscard]] std::expected<GraspScenarioResult, std::string> run_grasp_scenario(std::string_view name, const SceneDesc* scene = nullptr,
                                                                                 const ScenarioCameras* cameras = nullptr);

}  // namespace rhot
