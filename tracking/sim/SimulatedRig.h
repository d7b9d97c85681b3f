#pragma once
// The built-in frame source: markers moving along scripted trajectories, seen by a rig of
// simulated cameras with Gaussian pixel noise, sensor bounds, per-camera dropout, occlusion by
// spheres and capsules, and per-camera timestamps. Seeded and deterministic: the same settings
// and seed give the same frames. Ground truth stays in every frame for evaluation.

#include <array>
#include <expected>
#include <string>
#include <functional>
#include <memory>
#include <optional>
#include <random>
#include <vector>

#include "tracking/camera/Camera.h"
#include "tracking/core/Frames.h"
#include "tracking/sim/SimulatedWorld.h"
#include "tracking/source/FrameSource.h"

namespace rhot {

// A marker's path: centre + amplitude * sin(2 pi frequency t + phase) + a second "drift" term of
// the same form, per axis. Amplitude 0 is a fixed marker; equal x/z frequencies with a
// quarter-period phase shift give a circle; markers sharing a drift move together (a wand).
struct Trajectory {
  Eigen::Vector3d centre_m{0, 0, 0};
  Eigen::Vector3d amplitude_m{0, 0, 0};
  Eigen::Vector3d frequency_hz{0, 0, 0};
  Eigen::Vector3d phase_rad{0, 0, 0};
  Eigen::Vector3d drift_amplitude_m{0, 0, 0};
  Eigen::Vector3d drift_frequency_hz{0, 0, 0};
  Eigen::Vector3d drift_phase_rad{0, 0, 0};

  Eigen::Vector3d at(double t_s) const;
};

// A rigid body's path: its origin follows `position`; it turns from `base_orientation` by the
// rotation vector turn_amplitude * sin(2 pi turn_frequency t + turn_phase) (per axis, world frame).
struct RigidMotion {
  Trajectory position;
  Eigen::Quaterniond base_orientation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d turn_amplitude_rad{0, 0, 0};
  Eigen::Vector3d turn_frequency_hz{0, 0, 0};
  Eigen::Vector3d turn_phase_rad{0, 0, 0};

  Rigid3d world_from_body(double t_s) const;
};

// Markers fixed to a rigid body (a marker star on an object), in the body's frame.
struct SimulatedBody {
  RigidMotion motion;
  std::vector<Eigen::Vector3d> markers_body_m;
};

struct SimulatedRigSettings {
  double sigma_px = 0.3;       // Gaussian pixel noise per axis
  double dropout = 0.0;        // probability that a camera misses a visible marker in a frame
  double rate_hz = 90.0;       // frames per second
  double camera_skew_s = 0.0;  // camera i's exposure is offset by i * camera_skew_s (unsynchronised cameras)
  // Detections of one camera closer than this merge into one blob at their mean pixel, credited to
  // the marker nearest the camera, as a blob detector sees markers whose images overlap. 0: never.
  double merge_distance_px = 0.0;
  // Markers' diameter: detections merge when the discs they project to overlap (0: only by
  // merge_distance_px), as real blobs do, more often the nearer the markers are to a camera.
  double marker_diameter_m = 0.0;
  // Stray detections per camera per frame (lamps, shiny surfaces): a stray_fixed_fraction of them
  // stay put like a lamp (with the pixel noise), the rest appear anywhere each frame like
  // reflections. They carry no marker (truth_marker -1).
  int strays = 0;
  double stray_fixed_fraction = 0.5;
  unsigned seed = 1;

  // Every value usable: "<field>: <what was expected>, got <value>" for the first that is not.
  [[nodiscard]] std::expected<void, std::string> check() const;
};

class SimulatedRig final : public FrameSource {
 public:
  // Precondition: settings.check() passes.
  SimulatedRig(CameraRig rig, std::vector<Trajectory> markers, SimulatedRigSettings settings = {});

  // Rigid bodies from the next frame on. Their markers follow the loose markers in each frame's
  // marker numbering: body 0's first, then body 1's, and so on.
  void set_bodies(std::vector<SimulatedBody> bodies);

  // Markers placed by a script, from the next frame on: the function gives every such marker's
  // position at a time (the same count each call). They follow the loose and the bodies' markers
  // in each frame's numbering. For motions no trajectory describes, such as a hand's.
  void set_scripted_markers(std::function<std::vector<Eigen::Vector3d>(double t_s)> script) { script_ = std::move(script); }

  // Occluders for the following frames (for example a hand's bones).
  void set_occluders(std::vector<Occluder> occluders) { occluders_ = std::move(occluders); }

  // A simulated world from the next frame on: each frame asks it for its markers (numbered after
  // the loose, the bodies' and the scripted markers) and its occluders (replacing set_occluders').
  void set_world(std::shared_ptr<SimulatedWorld> world) { world_ = std::move(world); }

  // The next frame on the rig's own clock (frame i at i / rate_hz): each camera's detections of
  // the markers it sees, shuffled.
  RigFrame next();
  // FrameSource: the next frame, exposed at t_s instead (for a runtime whose clock drives the
  // world). Never ends.
  std::optional<RigFrame> next(double t_s) override { return frame_at(t_s); }

  const CameraRig& rig() const override { return rig_; }
  const std::vector<Trajectory>& markers() const { return markers_; }

  // Whether a camera sees a world point: in front, inside the image, and not behind an occluder.
  bool visible(int camera, const Eigen::Vector3d& p_world) const;

 private:
  RigFrame frame_at(double t_s);
  Eigen::Vector3d marker_at(std::size_t marker, double t_s) const;
  void merge_blobs(int camera, const std::vector<Eigen::Vector3d>& positions, std::vector<Detection>& detections) const;
  void add_strays(int camera, std::vector<Detection>& detections);

  CameraRig rig_;
  std::vector<Trajectory> markers_;
  std::vector<SimulatedBody> bodies_;
  std::vector<std::pair<int, int>> body_markers_;  // per body marker: (body, marker of that body)
  std::function<std::vector<Eigen::Vector3d>(double)> script_;
  std::shared_ptr<SimulatedWorld> world_;
  SimulatedRigSettings settings_;
  std::vector<Occluder> occluders_;
  std::mt19937_64 rng_;
  std::uint64_t frame_ = 0;
  std::vector<std::vector<Eigen::Vector2d>> stray_lamps_;  // per camera
};

// `count` rigid motions whose origins wander through the box as random_trajectories' markers do,
// each from a random orientation turning by up to 90 degrees about each axis at 0.1 to 0.4 Hz.
std::vector<RigidMotion> random_motions(int count, const Eigen::Vector3d& box_min_m, const Eigen::Vector3d& box_max_m, unsigned seed);

// The two ends of a rigid wand of length_m, held level and spinning about the vertical axis while
// its middle drifts through the box. The two markers stay exactly length_m apart.
std::array<Trajectory, 2> wand_trajectories(double length_m, const Eigen::Vector3d& box_min_m, const Eigen::Vector3d& box_max_m);

// `count` markers wandering smoothly through an axis-aligned box (random centres, amplitudes up
// to a quarter of the box, frequencies 0.1 to 0.5 Hz), from a seed. They spend less time near the
// box's faces than in its middle.
std::vector<Trajectory> random_trajectories(int count, const Eigen::Vector3d& box_min_m, const Eigen::Vector3d& box_max_m, unsigned seed);
// `count` markers standing still, spread uniformly through the box (every place as likely), from
// a seed: what a prediction over the whole volume is compared with (rhot-plan).
std::vector<Trajectory> scattered_markers(int count, const Eigen::Vector3d& box_min_m, const Eigen::Vector3d& box_max_m, unsigned seed);
// random_trajectories in a rig's tracking volume: its file's volume, else a 1 m cube centred where
// the cameras' optical axes meet (what rhot-eval's modes and rhot-node's simulated cameras share).
std::vector<Trajectory> wandering_markers(const CameraRig& rig, int count, unsigned seed);

}  // namespace rhot
