#pragma once
// Calibration sessions seen by the simulated rig, written as the detections a real session gives
// (tracking/calib/Detections.h), so every calibration step can be checked against the truth: a
// marker or two-marker wand waved through the volume, an L-frame lying on the floor, a marker
// touched on the floor at several places. Noise, dropout, stray blobs and gross outliers as asked;
// seeded and deterministic.

#include <vector>

#include <Eigen/Core>

#include "tracking/calib/Detections.h"
#include "tracking/calib/WorldFrame.h"
#include "tracking/camera/Camera.h"
#include "tracking/sim/SimulatedRig.h"

namespace rhot {

struct SessionNoise {
  SimulatedRigSettings rig;  // pixel noise, dropout, rate, seed
  double strays = 0.0;       // per camera and frame: the probability of one stray blob anywhere in the image (unlabelled)
  double outliers = 0.0;     // per detection: the probability it is displaced 3 to 30 px (a reflection merged into it)
};

struct WandSession {
  int frames = 2000;
  double wand_length_m = 0.5;
  int markers = 2;  // 2: a wand with its ends labelled 0 and 1; 1: one unlabelled marker (an LED)
  Eigen::Vector3d box_centre_m{0, 1, 0};
  Eigen::Vector3d box_size_m{1, 1, 1};
};

// The wave: the wand's middle drifts through the box while it spins (SimulatedRig's
// wand_trajectories); a single marker follows the wand's first end.
Detections simulate_wand_session(const CameraRig& rig, const WandSession& session, const SessionNoise& noise);

// The L-frame at world_from_frame (identity: the frame defines the rig's own world), still for
// `frames` frames; unlabelled detections.
Detections simulate_lframe_session(const CameraRig& rig, const LFrame& frame, const Rigid3d& world_from_frame, int frames,
                                   const SessionNoise& noise);

// One marker `height_m` above each place on the floor (or a desk: a place's y is its surface's
// height), held still at each in turn for `frames_per_place` frames and carried to the next
// between them (30 frames, lifted up to 10 cm).
Detections simulate_floor_session(const CameraRig& rig, const std::vector<Eigen::Vector3d>& places_on_floor, double height_m,
                                  int frames_per_place, const SessionNoise& noise);

// The RMS error (mm) of a wand's length over every frame with both ends (markers 0 and 1) seen,
// each end triangulated by `rig` on its own: with the true rig, the floor the pixel noise sets for
// any calibration's wand figure.
double wand_length_rms_mm(const CameraRig& rig, const Detections& detections, double wand_length_m);

// The box a rig is meant to track: its volume when it has one, else a metre cube where the
// cameras' optical axes pass closest (least squares).
TrackingVolume session_box(const CameraRig& rig);

}  // namespace rhot
