#pragma once
// How far the simulated world is from an ideal one: every imperfection of a real low-cost rig as
// one setting, with the two worlds rhot measures itself in (ideal, realistic), the camera rig the
// tracker is given when the calibration is off, and users' hands that are not the solver's model.

#include <expected>
#include <string>
#include <string_view>

#include "tracking/camera/Camera.h"
#include "tracking/hand/HandJoints.h"
#include "tracking/hand/HandSolver.h"
#include "tracking/sim/SimulatedRig.h"

namespace rhot {

struct WorldSettings {
  double sigma_px = 0.3;           // detection noise per axis
  double dropout = 0.0;            // probability a camera misses a visible marker
  int strays = 0;                  // false blobs per camera per frame, half fixed (lamps), half flickering
  double marker_diameter_m = 0.0;  // markers merge when their projected discs overlap (0: never)
  double camera_skew_s = 0.0;      // camera i exposes i * skew later (unsynchronised webcams)
  double calib_error_px = 0.0;     // the tracker's rig is off the true one by about this reprojection error
  bool independent_hands = false;  // truth hands with their own bone lengths, DIP angles and limits
  bool occluding_bodies = false;   // objects, the table and the other hand hide markers too (not only a hand's own bones)

  // Every value usable: "<flag>: <what was expected>, got <value>".
  [[nodiscard]] std::expected<void, std::string> check() const;
  // The simulated rig's settings for these (seed and rate given).
  SimulatedRigSettings rig_settings(unsigned seed, double rate_hz = 90.0) const;
};

// "ideal": 0.3 px, nothing else. "realistic": a room of webcams as users have them (docs/tracking.md):
// 0.5 px, 2 % dropout, 3 strays per camera, 6 mm markers, 2 ms between cameras' exposures, a 0.3 px
// calibration error, independent hands, every body occluding. Nothing for another name.
std::expected<WorldSettings, std::string> world_named(std::string_view name);

// The rig a tracker would have from an imperfect calibration: each camera's pose and focal length
// nudged at random so that points in the volume (the rig's, else a metre around the cameras' aim)
// reproject through it about rms_px (RMS over cameras and points) from where the true camera sees
// them. Deterministic for a seed; rms_px 0 gives the rig back.
CameraRig perturbed_rig(const CameraRig& truth, double rms_px, unsigned seed);

// The reprojection RMS (pixels) between two rigs of the same cameras over points spread through
// the true rig's volume: what perturbed_rig aims at.
double rig_difference_px(const CameraRig& truth, const CameraRig& other, unsigned seed = 1);

// A hand's own bones as what hides its markers: a capsule along each bone, 0.8 times its joint's
// radius (a finger is rounder than a capsule at its ends), world frame.
std::vector<Occluder> hand_bone_occluders(const Rigid3d& world_from_hand, const HandPose& pose);

// A user's hand that is not the solver's model: every bone of `model` (the reference hand)
// lengthened or shortened by up to +-10 % (per user, from the seed; the palm by one factor, each
// finger bone by its own), joint radii scaled alike.
HandPose independent_hand(const HandPose& model, unsigned seed);

// A user's finger angles from the model's: the last hinge no longer the solver's 2/3 of the
// middle one (up to +-35 % of its value, per finger from the seed), and the first hinge shifted by
// up to +-5 degrees per finger, past the solver's limits where it is at one (real limits differ).
std::array<FingerAngles, kFingerCount> independent_angles(const std::array<FingerAngles, kFingerCount>& angles, unsigned seed);

// Whether a hand reported as seen is the other hand: its wrist more than 10 mm from its own true
// wrist and nearer the other hand's. The evaluations' hand_confusion_frames count the frames with
// such a hand.
bool hand_confused(const Eigen::Vector3d& reported_wrist, const Eigen::Vector3d& true_wrist, const Eigen::Vector3d& other_true_wrist);

}  // namespace rhot
