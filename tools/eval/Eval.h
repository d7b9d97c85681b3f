#pragma once
// rhot-eval's subcommands, one file each (triangulation.cpp, wand.cpp, stars.cpp, hands.cpp,
// grasp.cpp, frame.cpp, demo.cpp), and what they share. Each prints one JSON object on stdout and returns
// the process's exit code.

#include <cstdint>
#include <expected>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "engine/render/Renderer.h"
#include "tracking/camera/Camera.h"
#include "tracking/hand/HandJoints.h"
#include "tracking/sim/Realism.h"

namespace rhot {
struct InteractionEvent;
}

namespace rhot::eval {

// A matched point further than this from every true marker is a ghost.
inline constexpr double kGhostDistance_m = 0.005;

// The box simulated markers move in: the flags when given, else the rig file's tracking volume,
// else a 1 m cube where the optical axes meet.
struct Box {
  Eigen::Vector3d centre;
  Eigen::Vector3d size;
};
Box evaluation_box(const CameraRig& rig, const std::vector<double>& size, const std::vector<double>& centre);

// The q-quantile (0..1) of v, by rank; 0 for none.
double percentile(std::vector<double> v, double q);

// The simulated world's flags, shared by the modes that simulate one: --world names a preset
// (tracking/sim/Realism.h), the others override its values.
struct WorldFlags {
  std::string world = "ideal";
  std::optional<double> sigma, dropout, calib_error_px, skew_ms, marker_mm;
  std::optional<int> strays;
  std::optional<std::string> truth_hand;
  std::optional<std::string> bodies_hide;  // yes or no
};
std::expected<rhot::WorldSettings, std::string> world_settings(const WorldFlags& flags);
// The world's settings, for a report.
nlohmann::json world_json(const rhot::WorldSettings& world, const std::string& name);

// A grasp of one run: which hand held which object (its entity's index), from when to when (the
// run's end when it never let go).
struct GraspSpan {
  rhot::HandSide hand;
  std::uint32_t object;
  double begin_s;
  double end_s;
  bool released;  // false: still held at the end
};
// The grasps in a run's events (grasp and release events; the others are skipped).
std::vector<GraspSpan> grasp_spans(const std::vector<rhot::InteractionEvent>& events, double end_s);

// How a run's grasps through tracked hands compare with the perfect hands' of the same script:
// grasps the perfect hands made that the tracked ones never made (missed), releases the tracked
// hands made while the perfect ones held on (unintended releases), releases of the perfect hands
// that the tracked hands made late or never (late releases: an object carried on after the hand
// opened), grasps the perfect hands did not make (unintended grasps). A grasp or release within
// kSameMoment_s of the perfect hands' is theirs.
struct GraspComparison {
  int cycles = 0;  // the perfect hands' grasps: the cycles the script asks for
  int tracked_grasps = 0;
  int missed = 0;
  int unintended_releases = 0;
  int late_releases = 0;
  int unintended_grasps = 0;
  void add(const GraspComparison& o);
  void put(nlohmann::json& j) const;  // grasp_cycles, missed_grasp_count, unintended_release_count, late_release_count, ...
};
inline constexpr double kSameMoment_s = 0.25;
GraspComparison compare_grasps(const std::vector<GraspSpan>& tracked, const std::vector<GraspSpan>& perfect);

// uniform: markers standing still, spread uniformly through the box (else wandering through it).
// `rhot-eval scale`'s flags (scale.cpp): the defaults are the crowded stage (docs/tracking.md
// "Threads": six people, twelve hands, twelve props, 1,000 markers on stage-32 at 120 Hz).
struct ScaleArgs {
  std::string rig_file = std::string(RHOT_ASSET_DIR) + "/rigs/stage-32.yaml";
  std::string set_file = std::string(RHOT_ASSET_DIR) + "/stars/stage-props.json";       // the props' stars
  std::string hand_set_file = std::string(RHOT_ASSET_DIR) + "/stars/stage-hands.json";  // the hands' backs'
  int markers = 1000;
  int bodies = 12;
  int hands = 12;
  int threads = 0;
  double rate_hz = 120.0;
  double seconds = 10.0;
  unsigned seed = 1;
  double sigma = 0.3;
  double dropout = 0.0;
  bool follow = true;  // MatchSettings::follow_points
};
int scale(const ScaleArgs& args);
int triangulation(const std::string& rig_file, double sigma, int frames, unsigned seed, int markers, double dropout,
                  const std::vector<double>& volume, const std::vector<double>& volume_centre, bool uniform = false, int threads = 0,
                  bool follow = true);
int wand(const std::string& rig_file, double length_mm, double sigma, int frames, unsigned seed, double dropout,
         const std::vector<double>& volume, const std::vector<double>& volume_centre, int threads = 0);
int stars(const std::string& rig_file, const std::string& set_file, int bodies, const WorldFlags& world, int frames, unsigned seed,
          const std::vector<double>& volume, const std::vector<double>& volume_centre, int threads = 0);
// `rhot-eval hands`'s flags.
struct HandsArgs {
  std::string rig_file;
  std::string layout_file;
  std::string motion = "all";
  WorldFlags world;
  int frames = 450;
  unsigned seed = 1;
  std::vector<double> volume_centre;
  bool filter = false;
  bool filter_frame = true;
  bool filter_frame_given = false;  // --filter-frame or --no-filter-frame on the command line
  bool calibrate_hand = false;
  int threads = 0;  // matching's (0: every core)
  bool fingertip_model = false;
  // A recorded take instead (tools/eval/take.cpp): its fingertips hidden by rule, estimated from the rest.
  std::string take_file;
  std::string model_file;        // a hidden-marker model (rhot-calib hand-model); none: fitted to the take's first part
  double fit_fraction = 0.6;     // with no model: the share of the take fitted; the rest is the unfitted part
  bool labelled = false;         // the take's labelled 3D points straight to the estimator
  double evaluate_from_s = 0.0;  // with --model: judge from this time on (the part the model was not fitted to)
  double hide_gap_s = 0.5;
  int hide_together = 1;
  // With --layout given: the take's markers (renamed by --map TAKE_NAME=LAYOUT_NAME) fed to the hand
  // tracker, labelled, instead of the estimator alone; the skeleton's fingers fitted to the take's
  // first calibrate_seconds (0: the reference hand).
  bool layout_given = false;
  std::vector<std::string> maps;
  double calibrate_seconds = 0.0;
  // Through a rig (--rig with --take): the calibration's markers, the take's labelled ones or those
  // the tracker found through the cameras on the reference hand.
  std::string calibrate_from = "labelled";
  // --hide MARKER@T0-T1 (a layout marker hidden from T0 to T1 seconds of the take; repeat): in place
  // of the rule's gaps.
  std::vector<std::string> hides;
};
int hands(const HandsArgs& args);
// `rhot-eval hands --take`.
int hands_take(const HandsArgs& args);
// `rhot-eval nodes`'s flags.
struct NodesArgs {
  std::string rig_file;
  int nodes = 4;
  int markers = 40;
  double rate_hz = 90.0;
  double seconds = 5.0;
  double sigma = 0.3;
  unsigned seed = 1;
  double deadline_ms = 10.0;
  std::optional<double> kill_at, restart_at;  // seconds into the run: the last node killed, then started again
  double clock_offset_ms = 0.0;               // node 0's clock ahead of the truth
  double clock_drift_ppm = 0.0;
  double delay_ms = 0.0;  // node 0's frames held this long
  // The demo's world of this scene instead of loose markers: the nodes simulate its script's hands
  // and objects, and the master tracks the hands from the nodes and, side by side, from an
  // in-process simulated rig of the same world at the same moments.
  std::string scene_file;
  // Security: keys made for the run (CURVE between master and nodes) in keys_dir (kept; empty: a
  // temporary folder, removed), or none with insecure.
  std::string keys_dir;
  bool insecure = false;
  // --chaos SECONDS: faults thrown at the nodes and the master for this long (Chaos.h), the run's
  // length.
  std::optional<double> chaos_s;
  int threads = 0;  // the master's tracker's (0: every core); the simulated nodes have none
};
int nodes(const NodesArgs& args);
// `rhot-eval colour`'s flags.
struct ColourArgs {
  std::string rig_file;
  std::string scene_file;
  std::string colours_file;  // empty: the default model
  int frames = 90;
  double start_s = 0.5;  // into the script: the hands in view and moving
  unsigned seed = 1;
  double noise = 2.0;
  double kelvin = 6500.0;
  bool clutter = true;
  std::string device = "auto";
  std::string pictures_dir;  // non-empty: the first frame's images and what the model classifies in them
  bool drawn = false;        // also the demo's runtime on the same script and cameras: the drawn hands' fingertips
  int threads = 0;           // the tracker's (0: every core)
};
int colour(const ColourArgs& args);
int calibration(const std::string& rig_file, double length_mm, double sigma, int frames, unsigned seed, double dropout, int threads);
// `rhot-eval grasp`'s flags.
struct GraspArgs {
  std::string scenario = "all";
  std::string hands = "perfect";
  std::string rig_file;  // for tracked hands
  WorldFlags world;
  unsigned seed = 1;
  int threads = 0;  // tracked: the tracker's (0: every core)
};
int grasp(const GraspArgs& args);
// `rhot-eval interactions`'s flags.
struct InteractionsArgs {
  std::string scene_file;
  int seeds = 20;
  unsigned seed = 1;
  std::string hands = "tracked";
  WorldFlags world;
  int threads = 0;  // the tracker's (0: every core)
};
int interactions(const InteractionsArgs& args);
int demo(const std::string& scene_file, int placements, unsigned seed, const WorldFlags& world, const std::string& hands, int frames,
         int threads);
struct FrameOptions {
  std::string prediction = "on";
  bool gpu_timings = false;
  bool real_time = false;
  bool xr = false;  // on the OpenXR runtime's headset: paced by it, predicted to its display time
  int threads = 0;  // the tracker's (0: every core)
};
int frame(const std::string& scene_file, const std::string& eye, int frames, const std::string& device, Shading shading,
          const WorldFlags& world, const FrameOptions& options);

}  // namespace rhot::eval
