// rhot-eval: measurements a user sizing a rig wants, as one JSON object on stdout.
//
//   rhot-eval triangulation --rig FILE [--sigma PX] [--frames N] [--seed S] [--markers M] [--spread wander|uniform]
//                           [--dropout P] [--volume-m X Y Z] [--volume-centre-m X Y Z] [--threads T] [--no-follow] --json
//   rhot-eval scale [--rig FILE] [--markers N] [--bodies B] [--hands H] [--threads T] [--rate-hz R] [--seconds S] [--no-follow] --json
//   rhot-eval demo [--scene FILE] [--placements N] [--seed S] [--hands tracked|perfect] [world flags] --json
//   rhot-eval hands --rig FILE [--layout FILE] [--motion NAME|all] [--calibrate-hand] [world flags] [--frames N] --json
//   rhot-eval hands --take FILE --labelled [--model FILE | --fit-fraction F] [--hide-gap-s S] [--hide-together N] [--seed K] --json
//   rhot-eval hands --take FILE --layout FILE [--map TAKE=LAYOUT ...] [--labelled | --rig FILE [world flags]]
//                   [--calibrate-seconds S [--calibrate-from labelled|cameras]] [--hide-gap-s S --hide-together N --seed K] [--hide
//                   MARKER@T0-T1 ...] --json
//   rhot-eval stars --rig FILE --set FILE [--bodies N] [--sigma PX] [--frames N] [--seed S] [--dropout P] [--threads T] --json
//   rhot-eval calibration --rig FILE [--wand-mm 500] [--sigma PX] [--frames 2000] [--seed S] [--dropout P] --json
//   rhot-eval nodes [--nodes N] [--markers M] [--rate-hz R] [--seconds S] [--kill-node-at T --restart-node-at T2]
//                   [--clock-offset-ms X --clock-drift-ppm Y] [--delay-ms D] --json
//   rhot-eval colour [--rig FILE] [--frames N] [--seed S] [--noise SIGMA] [--white-balance-k KELVIN]
//                    [--clutter on|off] [--colours FILE] [--device D] [--drawn] --json
//   rhot-eval wand --rig FILE [--length-mm 195] [--sigma PX] [--frames N] [--seed S] [--dropout P]
//                  [--volume-m X Y Z] [--volume-centre-m X Y Z] [--threads T] --json
//
// Every mode takes --threads T: the threads its tracking (or calibration's bundle adjustment) runs
// on, 0 (the default) every core there is. The results do not depend on it (docs/tracking.md
// "Threads"), but for calibration's last digits.
//
// Markers wander through a box: the flags', else the rig file's tracking volume, else a 1 m cube
// where the cameras' optical axes meet (least squares); the simulated rig sees them with Gaussian noise and dropouts; matching and
// triangulation recover them; the result is compared with ground truth and with the Cramer-Rao
// bound of each point for the cameras that saw it.

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <limits>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "base/Jobs.h"
#include "engine/sim/GraspScenarios.h"
#include "engine/scene/SceneLoader.h"
#include "tracking/camera/RigFile.h"
#include "tracking/geometry/Matching.h"
#include "tracking/sim/HandMotions.h"
#include "tracking/hand/HandTracker.h"
#include "tracking/rigid/StarTracker.h"
#include "tracking/sim/SimulatedRig.h"

#include "tools/eval/Eval.h"
#include "tools/common/CliExit.h"
#include "tools/common/NumberChecks.h"

using namespace rhot::eval;  // NOLINT: the subcommands

namespace {

// --threads, on every mode: what runs on them (a job pool, base/Jobs.h).
constexpr const char* kMatchingThreads = "threads matching runs on (0: every core there is); the results do not depend on it";
constexpr const char* kTrackerThreads =
    "threads the tracker runs on: matching, stars and hands (0: every core there is); the results do not depend on it";
void add_threads_flag(CLI::App& cmd, int& threads, const char* help = kMatchingThreads) {
  cmd.add_option("--threads", threads, help)->capture_default_str()->check(CLI::Range(0, rhot::kMaxThreads));
}

// The simulated world's flags, shared by the subcommands that simulate one.
void add_world_flags(CLI::App& command, WorldFlags& flags, bool hands) {
  command.add_option("--world", flags.world, "the simulated world: ideal or realistic (docs/tracking.md); the flags below override it")
      ->capture_default_str()
      ->check(CLI::IsMember({"ideal", "realistic"}));
  command.add_option("--sigma", flags.sigma, "pixel noise, standard deviation per axis (ideal 0.3, realistic 0.5)")
      ->check(CLI::Range(1e-6, 50.0));
  command.add_option("--dropout", flags.dropout, "probability a camera misses a visible marker")->check(CLI::Range(0.0, 1.0));
  command.add_option("--strays", flags.strays, "false blobs per camera per frame, half fixed like lamps, half flickering")
      ->check(CLI::Range(0, 1000));
  command.add_option("--calib-error-px", flags.calib_error_px, "the tracker's rig is off the true one by about this reprojection error")
      ->check(CLI::Range(0.0, 20.0));
  command.add_option("--skew-ms", flags.skew_ms, "camera i exposes i times this later (unsynchronised cameras)")
      ->check(CLI::Range(-100.0, 100.0));
  command.add_option("--marker-mm", flags.marker_mm, "marker diameter: blobs merge when their discs overlap (0: never)")
      ->check(CLI::Range(0.0, 100.0));
  command
      .add_option("--bodies-hide", flags.bodies_hide,
                  "yes: the table and the objects hide markers too, not only the hands (realistic: yes)")
      ->check(CLI::IsMember({"yes", "no"}));
  if (hands) {
    command.add_option("--truth-hand", flags.truth_hand, "model (the solver's own hand) or independent (a user's own bones and angles)")
        ->check(CLI::IsMember({"model", "independent"}));
  }
}

// `rhot-eval demo`'s flags.
struct DemoArgs {
  std::string scene_file;
  int placements = 50;
  unsigned seed = 1;
  int frames = 330;
  std::string hands = "tracked";
  WorldFlags world;
  int threads = 0;
};

CLI::App* add_hands_command(CLI::App& app, HandsArgs& a, bool& json) {
  auto* cmd = app.add_subcommand("hands", "scripted hand motions with a hand layout: every joint against the truth");
  a.layout_file = std::string(RHOT_ASSET_DIR) + "/hands/low-cost-right.json";
  cmd->add_option("--rig", a.rig_file,
                  "camera rig (OpenCV YAML); with --take and --layout: the rig that photographs the take (or --labelled)");
  cmd->add_option("--take", a.take_file, "a labelled marker take (C3D or Qualisys TSV): hide its fingertips by rule and estimate them")
      ->check(CLI::ExistingFile);
  cmd->add_option("--model", a.model_file,
                  "with --take: a hidden-marker model (rhot-calib hand-model); default: fitted to the take's first part");
  cmd->add_option("--fit-fraction", a.fit_fraction, "with --take and no --model: the share of the take fitted (the rest is reported apart)")
      ->capture_default_str()
      ->check(rhot::number_check(rhot::NumberBound::kPositive))  // CLI::Range lets nan through
      ->check(CLI::Range(0.1, 0.9));
  cmd->add_option("--evaluate-from-s", a.evaluate_from_s, "with --take and --model: judge from this many seconds into the take on")
      ->check(rhot::number_check(rhot::NumberBound::kNonNegative));
  cmd->add_flag("--labelled", a.labelled, "with --take: feed the take's labelled 3D points to the estimator (no cameras)");
  cmd->add_option("--hide-gap-s", a.hide_gap_s, "with --take: seconds each fingertip is hidden (then as long seen)")
      ->capture_default_str()
      ->check(rhot::number_check(rhot::NumberBound::kPositive))
      ->check(CLI::Range(0.01, 60.0));
  cmd->add_option("--hide-together", a.hide_together, "with --take: fingertips hidden at once (1, or 2: a tip and its neighbour's)")
      ->capture_default_str()
      ->check(CLI::Range(1, 2));
  cmd->add_option("--layout", a.layout_file,
                  "hand marker layout (JSON); with --take, the take's markers drive the hand tracker through this layout")
      ->capture_default_str()
      ->each([&a](const std::string&) { a.layout_given = true; });
  cmd->add_option("--map", a.maps, "with --take and --layout: TAKE_NAME=LAYOUT_NAME, a take's marker under the layout's name (repeat)");
  cmd->add_option("--hide", a.hides,
                  "with --take and --layout: MARKER@T0-T1, the layout's marker hidden from T0 to T1 seconds into the take (repeat; "
                  "in place of the gaps of --hide-gap-s)");
  cmd->add_option("--calibrate-seconds", a.calibrate_seconds,
                  "with --take and --layout: fit the fingers' lengths to the take's first S seconds (judged after them)")
      ->check(rhot::number_check(rhot::NumberBound::kNonNegative))
      ->check(CLI::Range(0.0, 600.0));
  cmd->add_option("--calibrate-from", a.calibrate_from,
                  "with --take --rig and --calibrate-seconds: the markers fitted, the take's labelled ones (a labelled calibration "
                  "session) or those the tracker found through the cameras on the reference hand")
      ->capture_default_str()
      ->check(CLI::IsMember({"labelled", "cameras"}));
  cmd->add_option("--motion", a.motion, "open, fist, pinch, wave, power-grasp, precision-grasp or all")->capture_default_str();
  add_world_flags(*cmd, a.world, true);
  cmd->add_option("--frames", a.frames, "frames per motion")->capture_default_str()->check(CLI::Range(1, 1000000));
  cmd->add_option("--seed", a.seed, "random seed")->capture_default_str();
  cmd->add_option("--volume-centre-m", a.volume_centre, "where the hand moves, X Y Z metres (default: the rig's volume centre)")
      ->expected(3)
      ->check(rhot::number_check(rhot::NumberBound::kAny));
  cmd->add_flag("--filter", a.filter, "1-euro filter the hand frame and the fingertips before the IK");
  cmd->add_flag("--filter-frame,!--no-filter-frame", a.filter_frame,
                "1-euro filter the hand frame alone (on by default; a frame found from the cameras' points: not with --take --labelled)")
      ->each([&a](const std::string&) { a.filter_frame_given = true; });
  cmd->add_flag("--fingertip-model", a.fingertip_model,
                "hidden fingertips placed where the seen ones say, by a model of the hand's fingertips fitted as it runs");
  cmd->add_flag("--calibrate-hand", a.calibrate_hand,
                "first hold the hand flat for a second, through the cameras, and track with the finger lengths it gives");
  add_threads_flag(*cmd, a.threads);
  cmd->add_flag("--json", json, "print JSON (the only output format)");
  return cmd;
}

CLI::App* add_grasp_command(CLI::App& app, GraspArgs& a, bool& json) {
  auto* cmd =
      app.add_subcommand("grasp", "scripted grasps through the physics: lift, pinch, throw, push, hand-over, hidden markers, place");
  a.rig_file = std::string(RHOT_ASSET_DIR) + "/rigs/seated-4.yaml";
  cmd->add_option("--scenario", a.scenario, "a scenario name or all")->capture_default_str();
  cmd->add_option("--hands", a.hands, "perfect (the script's hands) or tracked (through cameras, matching and hand tracking)")
      ->capture_default_str()
      ->check(CLI::IsMember({"tracked", "perfect"}));
  cmd->add_option("--rig", a.rig_file, "tracked: the camera rig, moved to centre its volume over the pedestal")->capture_default_str();
  add_world_flags(*cmd, a.world, true);
  cmd->add_option("--seed", a.seed, "tracked: random seed of the simulated world")->capture_default_str();
  add_threads_flag(*cmd, a.threads, kTrackerThreads);
  cmd->add_flag("--json", json, "print JSON (the only output format)");
  return cmd;
}

CLI::App* add_interactions_command(CLI::App& app, InteractionsArgs& a, bool& json) {
  a.scene_file = std::string(RHOT_ASSET_DIR) + "/scenes/workbench.json";
  auto* cmd = app.add_subcommand(
      "interactions", "a scene's showcase script through tracked hands and physics, per seed: each interaction's success, time, events");
  cmd->add_option("--scene", a.scene_file, "scene file (JSON) with rules or place interactions to exercise")
      ->capture_default_str()
      ->check(CLI::ExistingFile);
  cmd->add_option("--seeds", a.seeds, "runs, each its own simulated world")->capture_default_str()->check(CLI::Range(1, 10000));
  cmd->add_option("--seed", a.seed, "the first run's seed (then +1 each)")->capture_default_str();
  cmd->add_option("--hands", a.hands, "tracked (through the cameras) or perfect (the script's)")
      ->capture_default_str()
      ->check(CLI::IsMember({"tracked", "perfect"}));
  add_world_flags(*cmd, a.world, true);
  add_threads_flag(*cmd, a.threads, kTrackerThreads);
  cmd->add_flag("--json", json, "print JSON (the only output format)");
  return cmd;
}

CLI::App* add_demo_command(CLI::App& app, DemoArgs& a, bool& json) {
  auto* cmd =
      app.add_subcommand("demo", "the demo's first pickup with the cube at random spots on the table: grasp success, lift, hand confusion");
  cmd->add_option("--scene", a.scene_file, "scene file (JSON) with a \"cube-red\" on a \"table\"")->capture_default_str();
  cmd->add_option("--placements", a.placements, "random spots for the cube")->capture_default_str()->check(CLI::Range(1, 100000));
  cmd->add_option("--seed", a.seed, "random seed (spots; each placement's world takes seed + its index)")->capture_default_str();
  cmd->add_option("--hands", a.hands, "tracked (through the cameras) or perfect (the script's)")
      ->capture_default_str()
      ->check(CLI::IsMember({"tracked", "perfect"}));
  cmd->add_option("--frames", a.frames, "frames per placement (the lift ends at 3.2 s)")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000000));
  add_world_flags(*cmd, a.world, true);
  add_threads_flag(*cmd, a.threads, kTrackerThreads);
  cmd->add_flag("--json", json, "print JSON (the only output format)");
  return cmd;
}

CLI::App* add_nodes_command(CLI::App& app, NodesArgs& a, bool& json) {
  auto* cmd = app.add_subcommand(
      "nodes", "real rhot-node processes on loopback serving a simulated rig: frames lost, assembly, latency, clock sync, node faults");
  a.rig_file = std::string(RHOT_ASSET_DIR) + "/rigs/room-8.yaml";
  cmd->add_option("--rig", a.rig_file, "camera rig; node n simulates its cameras c with c % N == n")->capture_default_str();
  cmd->add_option("--nodes", a.nodes, "node processes")->capture_default_str()->check(CLI::Range(1, 64));
  cmd->add_option("--markers", a.markers, "markers wandering through the volume")->capture_default_str()->check(CLI::Range(0, 4096));
  cmd->add_option("--rate-hz", a.rate_hz, "frames per second per camera")->capture_default_str()->check(CLI::Range(1.0, 1000.0));
  cmd->add_option("--seconds", a.seconds, "length of the run (simulated time, in real time)")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 3600.0));
  cmd->add_option("--sigma", a.sigma, "pixel noise")->capture_default_str()->check(CLI::Range(0.0, 10.0));
  cmd->add_option("--seed", a.seed, "the simulated world's seed")->capture_default_str();
  cmd->add_option("--deadline-ms", a.deadline_ms, "how long a frame waits for a missing camera")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 1000.0));
  cmd->add_option("--kill-node-at", a.kill_at, "kill the last node (SIGKILL) this many seconds in")->check(CLI::Range(0.0, 3600.0));
  cmd->add_option("--restart-node-at", a.restart_at, "start it again this many seconds in")->check(CLI::Range(0.0, 3600.0));
  cmd->add_option("--clock-offset-ms", a.clock_offset_ms, "node 0's clock runs ahead by this much")
      ->capture_default_str()
      ->check(CLI::Range(-1e6, 1e6));
  cmd->add_option("--clock-drift-ppm", a.clock_drift_ppm, "node 0's clock runs fast by this much")
      ->capture_default_str()
      ->check(CLI::Range(-1e4, 1e4));
  cmd->add_option("--scene", a.scene_file,
                  "simulate the demo's world of this scene (hands tracked through the nodes and, side by side, in process; use --rig "
                  "with the scene's rig)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--delay-ms", a.delay_ms, "node 0 holds each frame this long (a slow link)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 10000.0));
  cmd->add_option("--keys", a.keys_dir,
                  "make the run's keys (master/ and node<i>/ key folders, as rhot-node keygen writes them) in this folder and keep "
                  "them (default: a temporary folder); keys already there are used")
      ->excludes(cmd->add_flag("--insecure", a.insecure, "master and nodes without CURVE (to measure what security costs)"));
  cmd->add_option("--chaos", a.chaos_s,
                  "for this many seconds (the run's length), kill and restart nodes at random with new clocks and slow links, put an "
                  "impostor at a dead node's endpoint, send junk and oversized messages to the nodes, stall the master's receiving "
                  "thread (random from --seed); reports frames_lost_while_all_up, rejoin_p99_s, memory_growth_fraction, "
                  "wrong_markers_accepted")
      ->check(CLI::Range(5.0, 86400.0))
      ->check(rhot::number_check(rhot::NumberBound::kPositive));
  add_threads_flag(*cmd, a.threads,
                   "threads the master's tracker runs on (0: the cores the node processes leave, at least one); the results do not "
                   "depend on it");
  cmd->add_flag("--json", json, "print JSON (the only output format)");
  return cmd;
}

// The flags triangulation, wand, stars and calibration share (one subcommand runs).
struct SharedArgs {
  std::string rig_file;
  double sigma = 0.3;
  int frames = 100;
  unsigned seed = 1;
  double dropout = 0.0;
  std::vector<double> volume;
  std::vector<double> volume_centre;
  int threads = 0;  // wand and stars: matching's threads; calibration: the bundle adjustment's
};

constexpr const char* kVolumeHelp = "size of the box the markers move in, X Y Z metres (default: the rig file's volume_size, else 1 1 1)";
constexpr const char* kCentreHelp =
    "centre of that box, X Y Z metres (default: the rig file's volume_centre, else where the optical axes meet)";

// `rhot-eval triangulation`'s own flags.
struct TriangulationArgs {
  int markers = 100;
  std::string spread = "wander";
  int threads = 0;
  bool follow = true;
};

// `rhot-eval stars`' own flags.
struct StarsArgs {
  std::string set_file;
  int bodies = 25;
  WorldFlags world;
};

// `rhot-eval frame`'s flags.
struct FrameArgs {
  std::string scene_file = std::string(RHOT_ASSET_DIR) + "/scenes/default.json";
  std::string eye;
  int frame_count = 900;
  std::string device = "auto";
  std::string shading = "auto";
  WorldFlags world;
  FrameOptions options;
};

// `rhot-eval calibration`'s own flags.
struct CalibrationArgs {
  int frames = 2000;
  double wand_mm = 500.0;
};

// --follow / --no-follow: the runtime's matching, frame after frame, following the last frame's
// points (the default), or every frame seeded afresh.
void add_follow_flag(CLI::App& cmd, bool& follow) {
  cmd.add_flag("--follow,!--no-follow", follow,
               "follow the last frame's points into the next before seeding (the runtime's default), or seed every frame afresh")
      ->capture_default_str();
}

CLI::App* add_triangulation_command(CLI::App& app, SharedArgs& s, TriangulationArgs& a, bool& json) {
  auto* tri = app.add_subcommand("triangulation", "matching and triangulation accuracy against the Cramer-Rao bound");
  tri->add_option("--rig", s.rig_file, "camera rig (OpenCV YAML)")->required();
  tri->add_option("--sigma", s.sigma, "pixel noise, standard deviation per axis")->capture_default_str()->check(CLI::Range(1e-6, 50.0));
  tri->add_option("--frames", s.frames, "frames to simulate")->capture_default_str()->check(CLI::Range(1, 1000000));
  tri->add_option("--seed", s.seed, "random seed")->capture_default_str();
  tri->add_option("--markers", a.markers, "markers in the volume")->capture_default_str()->check(CLI::Range(1, 10000));
  add_threads_flag(*tri, a.threads);
  tri->add_option("--dropout", s.dropout, "probability a camera misses a visible marker")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  tri->add_option("--spread", a.spread,
                  "how the markers fill the box: wander (moving smoothly, less often near its faces) or uniform (standing still, "
                  "every place as likely: what rhot-plan predicts over)")
      ->capture_default_str()
      ->check(CLI::IsMember({"wander", "uniform"}));
  tri->add_option("--volume-m", s.volume, kVolumeHelp)->expected(3)->check(rhot::number_check(rhot::NumberBound::kPositive));
  tri->add_option("--volume-centre-m", s.volume_centre, kCentreHelp)->expected(3)->check(rhot::number_check(rhot::NumberBound::kAny));
  add_follow_flag(*tri, a.follow);
  tri->add_flag("--json", json, "print JSON (the only output format)");
  return tri;
}

CLI::App* add_wand_command(CLI::App& app, SharedArgs& s, double& length_mm, bool& json) {
  auto* cmd = app.add_subcommand("wand", "length of a two-marker wand waved through the volume (mean and RMS error)");
  cmd->add_option("--rig", s.rig_file, "camera rig (OpenCV YAML)")->required();
  cmd->add_option("--length-mm", length_mm, "true wand length")->capture_default_str()->check(CLI::Range(1.0, 5000.0));
  cmd->add_option("--sigma", s.sigma, "pixel noise, standard deviation per axis")->capture_default_str()->check(CLI::Range(1e-6, 50.0));
  cmd->add_option("--frames", s.frames, "frames to simulate")->capture_default_str()->check(CLI::Range(1, 1000000));
  cmd->add_option("--seed", s.seed, "random seed")->capture_default_str();
  cmd->add_option("--dropout", s.dropout, "probability a camera misses a visible marker")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--volume-m", s.volume, kVolumeHelp)->expected(3)->check(rhot::number_check(rhot::NumberBound::kPositive));
  cmd->add_option("--volume-centre-m", s.volume_centre, kCentreHelp)->expected(3)->check(rhot::number_check(rhot::NumberBound::kAny));
  add_threads_flag(*cmd, s.threads);
  cmd->add_flag("--json", json, "print JSON (the only output format)");
  return cmd;
}

CLI::App* add_stars_command(CLI::App& app, SharedArgs& s, StarsArgs& a, bool& json) {
  auto* cmd = app.add_subcommand("stars", "marker stars moving through the volume: identification and pose against the truth");
  cmd->add_option("--rig", s.rig_file, "camera rig (OpenCV YAML)")->required();
  cmd->add_option("--set", a.set_file, "marker star set (JSON, from rhot-stars)")->required();
  cmd->add_option("--bodies", a.bodies, "stars moving at once (the set's first ones)")->capture_default_str()->check(CLI::Range(1, 10000));
  add_world_flags(*cmd, a.world, false);
  cmd->add_option("--frames", s.frames, "frames to simulate")->capture_default_str()->check(CLI::Range(1, 1000000));
  cmd->add_option("--seed", s.seed, "random seed")->capture_default_str();
  cmd->add_option("--volume-m", s.volume, kVolumeHelp)->expected(3)->check(rhot::number_check(rhot::NumberBound::kPositive));
  cmd->add_option("--volume-centre-m", s.volume_centre, kCentreHelp)->expected(3)->check(rhot::number_check(rhot::NumberBound::kAny));
  add_threads_flag(*cmd, s.threads);
  cmd->add_flag("--json", json, "print JSON (the only output format)");
  return cmd;
}

// --clutter's text ("on" or "off") goes to `clutter`, for main to turn into a ColourArgs::clutter.
CLI::App* add_colour_command(CLI::App& app, ColourArgs& a, std::string& clutter, bool& json) {
  CLI::App* cmd = app.add_subcommand(
      "colour", "coloured markers on simulated colour cameras drawn by the renderer: detection against the truth, fingertips end to end");
  a.rig_file = std::string(RHOT_ASSET_DIR) + "/rigs/stereo-640.yaml";
  a.scene_file = std::string(RHOT_ASSET_DIR) + "/scenes/default.json";
  cmd->add_option("--rig", a.rig_file, "camera rig (every camera one image size)")->capture_default_str()->check(CLI::ExistingFile);
  cmd->add_option("--scene", a.scene_file, "scene: its script's hands, its objects as clutter")
      ->capture_default_str()
      ->check(CLI::ExistingFile);
  cmd->add_option("--colours", a.colours_file, "colour model (default: rhot's six colours)")->check(CLI::ExistingFile);
  cmd->add_option("--frames", a.frames, "frames (90 per second of the script)")->capture_default_str()->check(CLI::Range(1, 100000));
  cmd->add_option("--start-s", a.start_s, "where in the script to start")->capture_default_str()->check(CLI::Range(0.0, 1e6));
  cmd->add_option("--seed", a.seed, "seed of the image noise")->capture_default_str();
  cmd->add_option("--noise", a.noise, "image noise, levels per channel")->capture_default_str()->check(CLI::Range(0.0, 50.0));
  cmd->add_option("--white-balance-k", a.kelvin, "the light's colour temperature; the cameras stay balanced for 6500 K")
      ->capture_default_str()
      ->check(CLI::Range(1500.0, 15000.0));
  cmd->add_option("--clutter", clutter, "the scene's objects in view")->capture_default_str()->check(CLI::IsMember({"on", "off"}));
  cmd->add_option("--device", a.device, "Vulkan device: auto, gpu, cpu, an index or part of its name")->capture_default_str();
  cmd->add_option("--pictures", a.pictures_dir,
                  "write the first frame's images (cam<i>.png) and what the colour model takes in them (cam<i>_colours.png) here");
  add_threads_flag(*cmd, a.threads, kTrackerThreads);
  cmd->add_flag("--drawn", a.drawn,
                "also run the demo's runtime (physics, grasps, hidden fingers placed against what a hand holds or carries) on the "
                "same script and cameras: the physical hands' fingertips (drawn, before prediction to display time) against the truth "
                "(drawn_* keys; the default 90 frames hold no grasp: pass --frames 2700 for the whole script)");
  cmd->add_flag("--json", json, "print JSON (the only output format)");
  return cmd;
}

CLI::App* add_frame_command(CLI::App& app, FrameArgs& a, bool& json) {
  auto* cmd = app.add_subcommand(
      "frame", "the demo's whole frame headless (cameras, tracking, physics, both eyes): p50, p99, budget misses, per stage");
  cmd->add_option("--scene", a.scene_file, "scene file (JSON)")->capture_default_str();
  cmd->add_option("--eye", a.eye, "pixels per eye, WxH (default: the scene's headset, 1080x1200)");
  cmd->add_option("--frames", a.frame_count, "frames to run")->capture_default_str()->check(CLI::Range(1, 1000000));
  cmd->add_option("--device", a.device, "Vulkan device: auto, gpu, cpu, an index or part of its name")->capture_default_str();
  cmd->add_option("--shading", a.shading, "light per pixel, per vertex, or auto (per vertex on a CPU driver)")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "pixel", "vertex"}));
  add_world_flags(*cmd, a.world, true);
  cmd->add_option("--prediction", a.options.prediction, "draw the hands where they will be at display time (on) or where tracked (off)")
      ->capture_default_str()
      ->check(CLI::IsMember({"on", "off"}));
  cmd->add_flag("--gpu-timings", a.options.gpu_timings, "GPU timestamps around each eye's pass: the GPU's time per eye");
  cmd->add_flag("--real-time", a.options.real_time, "pace frames to the headset's refresh as a headset would (default: back to back)");
  cmd->add_flag("--xr", a.options.xr,
                "on the headset of the OpenXR runtime (XR_RUNTIME_JSON): paced by it, at its eye size, the hands predicted to its display "
                "time; --frames counts frames shown");
  add_threads_flag(*cmd, a.options.threads, kTrackerThreads);
  cmd->add_flag("--json", json, "print JSON (the only output format)");
  return cmd;
}

CLI::App* add_calibration_command(CLI::App& app, SharedArgs& s, CalibrationArgs& a, bool& json) {
  auto* cmd = app.add_subcommand("calibration", "a simulated wand session calibrated from unknown extrinsics, against the true rig");
  cmd->add_option("--rig", s.rig_file, "the true rig (OpenCV YAML); its intrinsics are given to the calibration")->required();
  cmd->add_option("--wand-mm", a.wand_mm, "wand length")->capture_default_str()->check(CLI::Range(10.0, 5000.0));
  cmd->add_option("--sigma", s.sigma, "pixel noise, standard deviation per axis")->capture_default_str()->check(CLI::Range(1e-6, 50.0));
  cmd->add_option("--frames", a.frames, "frames of the wave")->capture_default_str()->check(CLI::Range(10, 1000000));
  cmd->add_option("--seed", s.seed, "random seed")->capture_default_str();
  cmd->add_option("--dropout", s.dropout, "probability a camera misses a visible marker")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  add_threads_flag(*cmd, s.threads,
                   "threads the bundle adjustment runs on (0: every core there is); the results' last digits may differ with the "
                   "count (Ceres)");
  cmd->add_flag("--json", json, "print JSON (the only output format)");
  return cmd;
}

CLI::App* add_scale_command(CLI::App& app, ScaleArgs& a, bool& json) {
  auto* cmd = app.add_subcommand("scale",
                                 "a crowded stage at the cameras' rate: people walking with tracked hands and props among loose markers; "
                                 "each stage's time, frames over the camera period, bodies and hands against the truth, the speed-up over "
                                 "one thread (defaults: the crowded stage)");
  cmd->add_option("--rig", a.rig_file, "camera rig (OpenCV YAML)")->capture_default_str()->check(CLI::ExistingFile);
  cmd->add_option("--set", a.set_file, "marker star set for the props (JSON, from rhot-stars)")
      ->capture_default_str()
      ->check(CLI::ExistingFile);
  cmd->add_option("--hand-set", a.hand_set_file, "marker star set for the backs of the hands, one star a hand")
      ->capture_default_str()
      ->check(CLI::ExistingFile);
  cmd->add_option("--markers", a.markers, "markers in all: the hands' nine each, the props' four each, the rest loose")
      ->capture_default_str()
      ->check(CLI::Range(0, 10000));
  cmd->add_option("--bodies", a.bodies, "props (rigid marker stars), carried by the people")
      ->capture_default_str()
      ->check(CLI::Range(0, 40));
  cmd->add_option("--hands", a.hands, "tracked hands, two a person")->capture_default_str()->check(CLI::Range(0, 40));
  add_threads_flag(*cmd, a.threads, "threads (0: every core there is); the results do not depend on it");
  add_follow_flag(*cmd, a.follow);
  cmd->add_option("--rate-hz", a.rate_hz, "the cameras' rate: frames a second, and the period a frame must fit")
      ->capture_default_str()
      ->check(rhot::number_check(rhot::NumberBound::kPositive))
      ->check(CLI::Range(1.0, 1000.0));
  cmd->add_option("--seconds", a.seconds, "how long the crowd walks (the first half second is not judged)")
      ->capture_default_str()
      ->check(rhot::number_check(rhot::NumberBound::kPositive))
      ->check(CLI::Range(0.6, 3600.0));
  cmd->add_option("--seed", a.seed, "random seed")->capture_default_str();
  cmd->add_option("--sigma", a.sigma, "pixel noise, standard deviation per axis")
      ->capture_default_str()
      ->check(rhot::number_check(rhot::NumberBound::kNonNegative))  // CLI::Range lets nan through
      ->check(CLI::Range(0.0, 10.0));
  cmd->add_option("--dropout", a.dropout, "probability a camera misses a visible marker")
      ->capture_default_str()
      ->check(rhot::number_check(rhot::NumberBound::kNonNegative))
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_flag("--json", json, "print JSON (the only output format)");
  return cmd;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rhot-eval: accuracy and speed of rhot's tracking on simulated data, as JSON"};
  app.require_subcommand(1);
  bool json = false;
  SharedArgs shared;
  TriangulationArgs tri_args;
  CLI::App* tri = add_triangulation_command(app, shared, tri_args, json);
  double length_mm = 195.0;
  CLI::App* wand_cmd = add_wand_command(app, shared, length_mm, json);
  StarsArgs stars_args;
  CLI::App* stars_cmd = add_stars_command(app, shared, stars_args, json);
  HandsArgs hands_args;
  CLI::App* hands_cmd = add_hands_command(app, hands_args, json);
  GraspArgs grasp_args;
  CLI::App* grasp_cmd = add_grasp_command(app, grasp_args, json);
  NodesArgs nodes_args;
  CLI::App* nodes_cmd = add_nodes_command(app, nodes_args, json);
  ColourArgs colour_args;
  std::string clutter = "on";
  CLI::App* colour_cmd = add_colour_command(app, colour_args, clutter, json);
  FrameArgs frame_args;
  CLI::App* frame_cmd = add_frame_command(app, frame_args, json);
  DemoArgs demo_args;
  demo_args.scene_file = frame_args.scene_file;
  CLI::App* demo_cmd = add_demo_command(app, demo_args, json);
  InteractionsArgs inter_args;
  CLI::App* inter_cmd = add_interactions_command(app, inter_args, json);
  ScaleArgs scale_args;
  CLI::App* scale_cmd = add_scale_command(app, scale_args, json);
  CalibrationArgs calib_args;
  CLI::App* calib_cmd = add_calibration_command(app, shared, calib_args, json);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return rhot::cli_exit_status(app, e);
  }
  const SharedArgs& s = shared;
  if (grasp_cmd->parsed()) return grasp(grasp_args);
  if (inter_cmd->parsed()) return interactions(inter_args);
  if (nodes_cmd->parsed()) return nodes(nodes_args);
  if (colour_cmd->parsed()) {
    colour_args.clutter = clutter == "on";
    return colour(colour_args);
  }
  if (calib_cmd->parsed()) return calibration(s.rig_file, calib_args.wand_mm, s.sigma, calib_args.frames, s.seed, s.dropout, s.threads);
  if (demo_cmd->parsed())
    return demo(demo_args.scene_file, demo_args.placements, demo_args.seed, demo_args.world, demo_args.hands, demo_args.frames,
                demo_args.threads);
  if (frame_cmd->parsed()) {
    return frame(frame_args.scene_file, frame_args.eye, frame_args.frame_count, frame_args.device,
                 *rhot::shading_from_string(frame_args.shading), frame_args.world, frame_args.options);
  }
  if (tri->parsed())
    return triangulation(s.rig_file, s.sigma, s.frames, s.seed, tri_args.markers, s.dropout, s.volume, s.volume_centre,
                         tri_args.spread == "uniform", tri_args.threads, tri_args.follow);
  if (hands_cmd->parsed()) return hands(hands_args);
  if (scale_cmd->parsed()) return scale(scale_args);
  if (stars_cmd->parsed())
    return stars(s.rig_file, stars_args.set_file, stars_args.bodies, stars_args.world, s.frames, s.seed, s.volume, s.volume_centre,
                 s.threads);
  if (wand_cmd->parsed()) return wand(s.rig_file, length_mm, s.sigma, s.frames, s.seed, s.dropout, s.volume, s.volume_centre, s.threads);
  return 1;
}
