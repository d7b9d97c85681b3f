// rhot-eval nodes: N real rhot-node processes on loopback, each simulating some cameras of a rig
// (node n serves the cameras c with c % N == n), and the master's node source assembling their
// frames. Measures frames lost, assembly cost, latency, clock synchronisation, and tracking while
// a node is killed and restarted.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <sys/resource.h>
#include <unistd.h>

#include <nlohmann/json.hpp>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include "base/Jobs.h"
#include "engine/scene/SceneLoader.h"
#include "engine/sim/Demo.h"
#include "engine/tracked/LiveTracking.h"
#include "tools/eval/Chaos.h"
#include "tools/eval/Eval.h"
#include "tracking/camera/RigFile.h"
#include "tracking/geometry/Matching.h"
#include "tracking/net/ChildProcess.h"
#include "tracking/net/CurveKeys.h"
#include "tracking/net/NodeSource.h"
#include "tracking/sim/SimulatedRig.h"

namespace rhot::eval {

namespace {

struct NodePlan {
  std::string name;      // its key's (node<i>)
  std::string endpoint;  // as the master names it: NAME@ENDPOINT with keys
  std::vector<std::string> argv;
  std::vector<int> cameras;
};

// The markers of a simulated frame within kGhostDistance_m of a triangulated point.
int markers_found(const std::vector<Eigen::Vector3d>& truth, const std::vector<MatchedPoint>& points) {
  int found = 0;
  for (const Eigen::Vector3d& t : truth) {
    for (const MatchedPoint& p : points) {
      if ((p.point.position_world - t).norm() < kGhostDistance_m) {
        ++found;
        break;
      }
    }
  }
  return found;
}

// A frame source that hands over the frame it was given (the node source's frames, one by one,
// to a LiveTracking).
class HeldFrames final : public FrameSource {
 public:
  explicit HeldFrames(CameraRig rig) : rig_(std::move(rig)) {}
  void hold(RigFrame frame) { frame_ = std::move(frame); }
  const CameraRig& rig() const override { return rig_; }
  std::optional<RigFrame> next(double) override { return frame_; }
  const RigFrame& held() const { return frame_; }

 private:
  CameraRig rig_;
  RigFrame frame_;
};

// The in-process rig's frames with the cameras the nodes' frame of the same moment lacked (late
// to the assembly deadline) left out too: the two trackers then compare the transport (decoding,
// clock mapping) on equal views, while cameras that miss the deadline are counted on their own
// (frames_complete, late).
class SameCamerasAs final : public FrameSource {
 public:
  SameCamerasAs(std::unique_ptr<FrameSource> source, const HeldFrames& nodes) : source_(std::move(source)), nodes_(nodes) {}
  const CameraRig& rig() const override { return source_->rig(); }
  std::optional<RigFrame> next(double t_s) override {
    std::optional<RigFrame> frame = source_->next(t_s);
    if (!frame) return frame;
    const std::vector<CameraFrame>& seen = nodes_.held().cameras;
    for (std::size_t c = 0; c < frame->cameras.size() && c < seen.size(); ++c) {
      if (seen[c].delivered) continue;
      frame->cameras[c].delivered = false;
      frame->cameras[c].detections.clear();
    }
    return frame;
  }

 private:
  std::unique_ptr<FrameSource> source_;
  const HeldFrames& nodes_;
};

// Both hands tracked from one source, against the script's truth.
struct HandComparison {
  LiveTracking* live = nullptr;
  double error_sum_m = 0.0;
  long joints = 0;
  long hand_frames = 0;
  long seen = 0;
  // Each seen hand's mean joint error in each frame, and when: a mean over the run hides a
  // stretch of frames where a hand went wrong.
  std::vector<double> frame_mm;
  double worst_mm = 0.0, worst_t_s = 0.0;
  void step(double t, const SceneTruth& truth) {
    live->read_source(t);
    live->match();
    live->track_stars(t);
    live->track_hands(t);
    for (std::size_t h = 0; h < 2; ++h) {
      ++hand_frames;
      const TrackedHand& hand = live->tracked_hand(h == 0 ? HandSide::kLeft : HandSide::kRight);
      if (!hand.hand_seen) continue;
      ++seen;
      double sum_m = 0.0;
      for (std::size_t j = 0; j < kHandJointCount; ++j)
        sum_m += (hand.joints_world[j] - truth.hands[h].world_from_hand * truth.hands[h].pose.position_m[j]).norm();
      error_sum_m += sum_m;
      joints += static_cast<long>(kHandJointCount);
      frame_mm.push_back(1000.0 * sum_m / static_cast<double>(kHandJointCount));
      if (frame_mm.back() > worst_mm) {
        worst_mm = frame_mm.back();
        worst_t_s = t;
      }
    }
  }
  // The worst hand-frame and the 95th percentile of the hand-frames' mean errors.
  void report(nlohmann::json& j, const std::string& prefix) const {
    j[prefix + "hand_frame_p95_mm"] = percentile(frame_mm, 0.95);
    j[prefix + "hand_frame_max_mm"] = worst_mm;
    j[prefix + "hand_frame_max_at_s"] = worst_t_s;
  }
  double mean_mm() const { return joints > 0 ? 1000.0 * error_sum_m / static_cast<double>(joints) : 0.0; }
  double seen_fraction() const { return hand_frames > 0 ? static_cast<double>(seen) / static_cast<double>(hand_frames) : 0.0; }
};

// A run's first checks, after the rig loaded: false after saying what was wrong.
bool check_args(const NodesArgs& a, const CameraRig& rig) {
  if (a.nodes > static_cast<int>(rig.cameras.size())) {
    std::cerr << "rhot-eval: --nodes " << a.nodes << ": " << a.rig_file << " has only " << rig.cameras.size() << " cameras\n";
    return false;
  }
  if (a.chaos_s && (a.kill_at || a.restart_at)) {
    std::cerr << "rhot-eval: --chaos kills and restarts nodes itself: not with --kill-node-at or --restart-node-at\n";
    return false;
  }
  if (a.restart_at && (!a.kill_at || *a.restart_at <= *a.kill_at)) {
    std::cerr << "rhot-eval: --restart-node-at needs --kill-node-at before it\n";
    return false;
  }
  return true;
}

// The demo's world of --scene into `demo` (left empty without --scene): false after saying what
// was wrong.
bool load_demo(const NodesArgs& a, std::optional<DemoSimulation>& demo) {
  if (a.scene_file.empty()) return true;
  const auto scene = load_scene_file(a.scene_file);
  if (!scene) {
    std::cerr << "rhot-eval: " << scene.error().to_string() << "\n";
    return false;
  }
  auto made = make_demo_simulation(*scene, RHOT_ASSET_DIR);
  if (!made) {
    std::cerr << "rhot-eval: " << a.scene_file << ": " << made.error() << "\n";
    return false;
  }
  demo = std::move(*made);
  return true;
}

// The command line of node n, which publishes on `endpoint` and simulates `cameras`; the world's
// time 0 is start_ns of the shared steady clock.
std::vector<std::string> node_argv(const NodesArgs& a, int n, const std::filesystem::path& node_program, const std::string& endpoint,
                                   const std::vector<int>& cameras, std::int64_t start_ns, const std::string& keys_dir) {
  std::string list;
  for (int c : cameras) list += (list.empty() ? "" : ",") + std::to_string(c);
  std::vector<std::string> argv = {node_program.string(),
                                   "--publish",
                                   endpoint,
                                   "--node-id",
                                   std::to_string(n),
                                   "--sim-rig",
                                   a.rig_file,
                                   "--sim-camera",
                                   list,
                                   "--sim-markers",
                                   std::to_string(a.markers),
                                   "--seed",
                                   std::to_string(a.seed),
                                   "--sigma",
                                   std::to_string(a.sigma),
                                   "--rate-hz",
                                   std::to_string(a.rate_hz),
                                   "--sim-start-ns",
                                   std::to_string(start_ns)};
  if (!a.scene_file.empty()) argv.insert(argv.end(), {"--sim-scene", a.scene_file});
  if (keys_dir.empty())
    argv.emplace_back("--insecure");
  else
    argv.insert(argv.end(), {"--keys", keys_dir + "/node" + std::to_string(n)});
  // Node 0 is the odd one: its clock and its link, as the flags say.
  if (n == 0) {
    argv.insert(argv.end(), {"--clock-offset-ms", std::to_string(a.clock_offset_ms), "--clock-drift-ppm", std::to_string(a.clock_drift_ppm),
                             "--delay-ms", std::to_string(a.delay_ms)});
  }
  return argv;
}

// Node n serves the cameras c with c % N == n and publishes on the n-th of `ports`.
std::vector<NodePlan> plan_nodes(const NodesArgs& a, std::size_t camera_count, const std::filesystem::path& node_program,
                                 const std::vector<int>& ports, std::int64_t start_ns, const std::string& keys_dir) {
  std::vector<NodePlan> plans(static_cast<std::size_t>(a.nodes));
  for (int n = 0; n < a.nodes; ++n) {
    NodePlan& p = plans[static_cast<std::size_t>(n)];
    for (int c = n; c < static_cast<int>(camera_count); c += a.nodes) p.cameras.push_back(c);
    const int port = ports[static_cast<std::size_t>(n)];
    p.name = "node" + std::to_string(n);
    const std::string endpoint = "tcp://127.0.0.1:" + std::to_string(port);
    p.endpoint = keys_dir.empty() ? endpoint : p.name + "@" + endpoint;
    p.argv = node_argv(a, n, node_program, endpoint, p.cameras, start_ns, keys_dir);
  }
  return plans;
}

// Starts every node, its output to `log`: false after saying which could not start (the ones
// already started are in `children`).
bool spawn_nodes(const std::vector<NodePlan>& plans, const std::filesystem::path& log, std::vector<ChildProcess>& children) {
  for (const NodePlan& p : plans) {
    auto child = ChildProcess::spawn(p.argv, log);
    if (!child) {
      std::cerr << "rhot-eval: " << child.error() << "\n";
      return false;
    }
    children.push_back(std::move(*child));
  }
  return true;
}

// The run's key folders in `dir`: master/ (trusting every node) and node<i>/ (trusting the master),
// each key made unless it is there already. False after saying what failed.
bool make_run_keys(const std::string& dir, int nodes) {
  namespace fs = std::filesystem;
  std::vector<std::string> names{"master"};
  for (int n = 0; n < nodes; ++n) names.push_back("node" + std::to_string(n));
  for (const std::string& name : names) {
    if (fs::exists(fs::path(dir) / name / (name + ".key_secret"))) continue;
    auto pair = make_key_pair(name);
    if (pair) {
      if (auto ok = write_certificates((fs::path(dir) / name).string(), *pair); !ok) pair = std::unexpected(ok.error());
    }
    if (!pair) {
      std::cerr << "rhot-eval: " << pair.error() << "\n";
      return false;
    }
  }
  std::error_code ec;
  for (const std::string& name : names) {
    // The master trusts every node; each node trusts the master.
    const std::vector<std::string> peers =
        name == "master" ? std::vector<std::string>(names.begin() + 1, names.end()) : std::vector<std::string>{"master"};
    // trusted/ holds exactly the run's peers, whatever was there before.
    fs::remove_all(fs::path(dir) / name / "trusted", ec);
    fs::create_directories(fs::path(dir) / name / "trusted", ec);
    for (const std::string& peer : peers)
      fs::copy_file(fs::path(dir) / peer / (peer + ".key"), fs::path(dir) / name / "trusted" / (peer + ".key"),
                    fs::copy_options::overwrite_existing, ec);
    if (ec) {
      std::cerr << "rhot-eval: " << dir << "/" << name << "/trusted: " << ec.message() << "\n";
      return false;
    }
  }
  return true;
}

// This process's CPU time so far (every thread: the receiving thread and ZeroMQ's I/O thread too).
double process_cpu_s() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec) / 1e6;
}

NodeSourceSettings source_settings(const NodesArgs& a, std::int64_t start_ns) {
  NodeSourceSettings settings;
  settings.assembly.deadline_ns = static_cast<std::int64_t>(a.deadline_ms * 1e6);
  settings.time_origin_ns = start_ns;
  settings.assembly.tolerance_ns = std::min<std::int64_t>(settings.assembly.deadline_ns, static_cast<std::int64_t>(0.4e9 / a.rate_hz));
  return settings;
}

// With the demo's world: the hands tracked from the nodes' frames and, at the same moments, from
// the nodes' own simulations run in process (AsOnTheNodes: the same detections, noise and all)
// seeing the same cameras.
struct DemoHands {
  std::unique_ptr<LiveTracking> from_nodes, in_process;
  HeldFrames* held = nullptr;
  HandComparison nodes_hands, local_hands;
};

// The nodes' own simulations, in process: node n's cameras (c % N == n) photographed by a
// simulated rig of those cameras alone, seeded as rhot-node seeds its own (the world's seed x 1000
// plus its first camera), so that each camera's noise is drawn as on its node and the two trackers
// see the same detections: what differs is the transport alone (clock mapping, late cameras).
class AsOnTheNodes final : public FrameSource {
 public:
  AsOnTheNodes(const NodesArgs& a, const CameraRig& rig, const std::shared_ptr<DemoWorld>& world) : rig_(rig) {
    for (int n = 0; n < a.nodes; ++n) {
      Part part;
      CameraRig mine;
      for (int c = n; c < static_cast<int>(rig.cameras.size()); c += a.nodes) {
        part.cameras.push_back(c);
        mine.cameras.push_back(rig.cameras[static_cast<std::size_t>(c)]);
      }
      SimulatedRigSettings settings;
      settings.sigma_px = a.sigma;
      settings.rate_hz = a.rate_hz;
      settings.seed = a.seed * 1000u + static_cast<unsigned>(part.cameras.front());
      part.sim = std::make_unique<SimulatedRig>(mine, std::vector<Trajectory>{}, settings);
      part.sim->set_world(world);
      parts_.push_back(std::move(part));
    }
  }
  const CameraRig& rig() const override { return rig_; }
  std::optional<RigFrame> next(double t_s) override {
    RigFrame out;
    out.time_s = t_s;
    out.cameras.resize(rig_.cameras.size());
    for (Part& part : parts_) {
      std::optional<RigFrame> f = part.sim->next(t_s);
      if (!f) return std::nullopt;
      for (std::size_t j = 0; j < part.cameras.size() && j < f->cameras.size(); ++j) {
        CameraFrame& c = out.cameras[static_cast<std::size_t>(part.cameras[j])];
        c = std::move(f->cameras[j]);
        c.camera = part.cameras[j];
      }
    }
    return out;
  }

 private:
  struct Part {
    std::vector<int> cameras;
    std::unique_ptr<SimulatedRig> sim;
  };
  CameraRig rig_;
  std::vector<Part> parts_;
};

// The master's threads: --threads, else the cores the node processes leave (they run on this
// machine too: on two cores, a second matching thread beside two nodes delayed the master's
// assembly enough to let frames it should have closed wait for a late node).
int master_threads(const NodesArgs& a) { return a.threads > 0 ? a.threads : std::max(1, threads_or_all(0) - a.nodes); }

void set_up_demo_hands(const NodesArgs& a, const CameraRig& rig, const DemoSimulation& demo, DemoHands& hands) {
  auto frames = std::make_unique<HeldFrames>(rig);
  hands.held = frames.get();
  LiveTrackingSettings settings;
  settings.threads = master_threads(a);
  hands.from_nodes = std::make_unique<LiveTracking>(std::move(frames), demo.objects, demo.layouts, settings);
  hands.in_process =
      std::make_unique<LiveTracking>(std::make_unique<SameCamerasAs>(std::make_unique<AsOnTheNodes>(a, rig, demo.world), *hands.held),
                                     demo.objects, demo.layouts, settings);
  hands.nodes_hands.live = hands.from_nodes.get();
  hands.local_hands.live = hands.in_process.get();
}

// What the master's loop reads and drives once the nodes run.
struct NodesRun {
  const NodesArgs& a;
  const CameraRig& rig;
  const std::optional<DemoSimulation>& demo;
  const std::vector<NodePlan>& plans;
  const std::filesystem::path& log;
  std::vector<ChildProcess>& children;
  NodeSource& source;
  const NodeSourceSettings& settings;
  const std::vector<Trajectory>& markers;  // without the demo's world
  DemoHands& hands;                        // with it
  MatchSettings match;
  const RigMatcher& matcher;  // the rig, prepared for matching once
  JobPool& jobs;              // matching's threads (--threads)
  std::int64_t start_ns;
  std::int64_t period_ns;
  std::int64_t frames_expected;
  int victim;              // the node killed and restarted
  Chaos* chaos = nullptr;  // with --chaos
};

// The exposures assembled, a flag each, allocated once: a set would grow through a long run, which
// --chaos's memory figure would count as the master's.
class ExposureSet {
 public:
  explicit ExposureSet(std::int64_t exposures) : flags_(static_cast<std::size_t>(std::max<std::int64_t>(exposures, 0)), 0) {}
  void insert(std::int64_t k) {
    if (k < 0 || k >= static_cast<std::int64_t>(flags_.size()) || flags_[static_cast<std::size_t>(k)]) return;
    flags_[static_cast<std::size_t>(k)] = 1;
    ++count_;
  }
  bool contains(std::int64_t k) const {
    return k >= 0 && k < static_cast<std::int64_t>(flags_.size()) && flags_[static_cast<std::size_t>(k)];
  }
  std::size_t size() const { return count_; }
  bool empty() const { return count_ == 0; }

 private:
  std::vector<char> flags_;
  std::size_t count_ = 0;
};

// What the master's loop counts. Its per-frame records are allocated for the whole run at the
// start, so the run's memory is the master's.
struct NodesTally {
  NodesTally(std::int64_t exposures, std::size_t cameras) : assembled(exposures) {
    assembly_ms.reserve(static_cast<std::size_t>(exposures));
    latency_ms.reserve(static_cast<std::size_t>(exposures) * cameras);
  }
  ExposureSet assembled;
  // Per camera: the counter and exposure of its last message in a frame, and the exposures its
  // node never made (behind real time it skips to the present, or it was not running): the
  // counter counts the messages made, so a gap in exposures wider than the gap in counters is
  // exposures never made.
  struct CameraTrack {
    std::optional<std::uint64_t> counter;
    std::int64_t k = -1;
  };
  std::vector<CameraTrack> tracks;
  std::vector<std::vector<bool>> not_made;  // [camera][exposure]
  std::vector<double> assembly_ms, latency_ms;
  long found = 0, truth_total = 0, found_down = 0, truth_down = 0;
  bool killed = false, restarted = false, rejoined = false;
  std::int64_t complete = 0;
  long wrong_markers = 0;  // detections far from every true marker's image
  // The first camera frames with wrong markers: when, whose, and which exposure's markers they are
  // (placed in time one exposure or more off) if any within kShiftsTried is.
  struct WrongFrame {
    double t_s;
    int camera;
    long wrong, detections;
    std::optional<int> exposures_off;
  };
  std::vector<WrongFrame> wrong_frames;
  long memory_start_kb = 0, memory_end_kb = 0;  // the master's resident memory, after its start and at the end
  long heap_start_kb = 0, heap_end_kb = 0;      // and its heap in use
};

// A detection further than this from every true marker's image is not a marker (the nodes'
// noise is a fraction of a pixel).
constexpr double kWrongMarker_px = 5.0;

constexpr std::size_t kWrongFramesKept = 16;
constexpr int kShiftsTried = 10;  // exposures either side (a fit off by up to 0.11 s)

// Camera c's detections in `detections` not within kWrongMarker_px of any true marker's image at time t.
long wrong_in(const NodesRun& run, std::size_t c, const std::vector<Detection>& detections, double t) {
  std::vector<Eigen::Vector2d> images;
  for (const Trajectory& m : run.markers)
    if (const auto px = run.rig.cameras[c].project(m.at(t))) images.push_back(*px);
  return static_cast<long>(std::count_if(detections.begin(), detections.end(), [&](const Detection& d) {
    return std::none_of(images.begin(), images.end(), [&](const Eigen::Vector2d& i) { return (i - d.pixel).norm() < kWrongMarker_px; });
  }));
}

// Counts the detections of f at exposure k (time t) that are no marker's image then; the first
// camera frames with any are kept, with the exposure shift that explains them if one does.
void count_wrong_markers(const NodesRun& run, const AssembledFrame& f, std::int64_t k, NodesTally& tally) {
  const double t = static_cast<double>(k) / run.a.rate_hz;
  for (std::size_t c = 0; c < f.cameras.size() && c < run.rig.cameras.size(); ++c) {
    if (!f.cameras[c]) continue;
    const std::vector<Detection>& detections = f.cameras[c]->detections;
    const long wrong = wrong_in(run, c, detections, t);
    tally.wrong_markers += wrong;
    if (wrong == 0 || tally.wrong_frames.size() >= kWrongFramesKept) continue;
    NodesTally::WrongFrame w{t, static_cast<int>(c), wrong, static_cast<long>(detections.size()), std::nullopt};
    for (int shift = 1; shift <= kShiftsTried && !w.exposures_off; ++shift)
      for (const int s : {-shift, shift})
        if (!w.exposures_off && wrong_in(run, c, detections, static_cast<double>(k + s) / run.a.rate_hz) == 0) w.exposures_off = s;
    tally.wrong_frames.push_back(w);
  }
}

// Kills the victim node at --kill-node-at and starts it again at --restart-node-at, t_now seconds
// into the run.
void kill_or_restart_victim(const NodesRun& run, double t_now, NodesTally& tally) {
  const NodesArgs& a = run.a;
  if (a.kill_at && !tally.killed && t_now >= *a.kill_at) {
    run.children[static_cast<std::size_t>(run.victim)].kill();
    tally.killed = true;
  }
  if (a.restart_at && tally.killed && !tally.restarted && t_now >= *a.restart_at) {
    auto child = ChildProcess::spawn(run.plans[static_cast<std::size_t>(run.victim)].argv, run.log);
    if (child) run.children[static_cast<std::size_t>(run.victim)] = std::move(*child);
    tally.restarted = true;
  }
}

// The exposure (frame index) of a capture time: 0 at start_ns.
std::int64_t exposure_of(const NodesRun& run, std::int64_t capture_ns) {
  const std::int64_t rel = capture_ns - run.start_ns;
  return (rel >= 0 ? rel + run.period_ns / 2 : rel - run.period_ns / 2) / run.period_ns;
}

// Marks the exposures of f's cameras that their nodes never made (see NodesTally::CameraTrack).
void track_cameras(const NodesRun& run, const AssembledFrame& f, NodesTally& tally) {
  if (tally.tracks.size() < f.cameras.size()) {
    tally.tracks.resize(f.cameras.size());
    tally.not_made.assign(f.cameras.size(), std::vector<bool>(static_cast<std::size_t>(run.frames_expected), false));
  }
  for (std::size_t c = 0; c < f.cameras.size(); ++c) {
    if (!f.cameras[c]) continue;
    NodesTally::CameraTrack& t = tally.tracks[c];
    const std::int64_t k = exposure_of(run, f.cameras[c]->capture_ns);
    const std::uint64_t counter = f.cameras[c]->counter;
    // A node's first message (counter 0, also after a restart) follows exposures it never made.
    // Between two messages, counter - last counter - 1 were made and lost on the way (taken to
    // be the exposures right after the last; the counts per camera are exact, not which ones),
    // and the other exposures of the gap never made. A node's first message (counter 0, also
    // after a restart) follows exposures it never made.
    const std::int64_t made = !t.counter || counter == 0 || counter <= *t.counter ? 0 : static_cast<std::int64_t>(counter - *t.counter - 1);
    for (std::int64_t i = std::max<std::int64_t>(0, t.k + 1 + made); i < std::min(k, run.frames_expected); ++i)
      tally.not_made[c][static_cast<std::size_t>(i)] = true;
    t.counter = counter;
    t.k = std::max(t.k, k);
  }
}

// Counts one frame the node source closed: its assembly, its cameras' latency and, from its
// points or its hands, what was tracked.
void tally_frame(const NodesRun& run, const AssembledFrame& f, NodesTally& tally) {
  const NodesArgs& a = run.a;
  track_cameras(run, f, tally);
  const std::int64_t k = exposure_of(run, f.capture_ns);
  if (k < 0 || k >= run.frames_expected) return;
  const double t = static_cast<double>(k) / a.rate_hz;
  tally.assembled.insert(k);
  double cost_ns = static_cast<double>(f.close_cpu_ns);
  bool all = true;
  for (const auto& cam : f.cameras) {
    if (!cam) {
      all = false;
      continue;
    }
    cost_ns += static_cast<double>(cam->decode_ns);
    tally.latency_ms.push_back(static_cast<double>(cam->arrival_ns - cam->capture_ns) / 1e6);
  }
  tally.complete += all ? 1 : 0;
  tally.assembly_ms.push_back(cost_ns / 1e6);
  if (tally.restarted && t > *a.restart_at) {
    for (int c : run.plans[static_cast<std::size_t>(run.victim)].cameras)
      if (f.cameras[static_cast<std::size_t>(c)]) tally.rejoined = true;
  }
  RigFrame frame = run.source.to_rig_frame(f);
  if (run.demo) {
    const SceneTruth truth = run.demo->script->at(t);
    run.hands.held->hold(frame);
    run.hands.nodes_hands.step(t, truth);
    run.hands.local_hands.step(t, truth);
    return;
  }
  count_wrong_markers(run, f, k, tally);
  const std::vector<MatchedPoint> points = run.matcher.match(frame, run.match, run.jobs.threads() > 1 ? &run.jobs : nullptr);
  std::vector<Eigen::Vector3d> truth;
  for (const Trajectory& m : run.markers) truth.push_back(m.at(t));
  const int got = markers_found(truth, points);
  tally.found += got;
  tally.truth_total += static_cast<long>(truth.size());
  if (a.kill_at && t >= *a.kill_at + run.settings.lost_after_s && (!a.restart_at || t < *a.restart_at)) {
    tally.found_down += got;
    tally.truth_down += static_cast<long>(truth.size());
  }
}

// The master's loop: until the run's end, and then until every frame closed by then is read (a
// slow master, such as a sanitizer build, reads behind real time).
void run_master(const NodesRun& run, NodesTally& tally) {
  const NodesArgs& a = run.a;
  const std::int64_t end_ns = run.start_ns + static_cast<std::int64_t>(a.seconds * 1e9) + run.settings.assembly.deadline_ns + 50'000'000;
  double next_progress_s = 1.0;
  bool more = true;
  // Memory is first read once the run is past its start: the clock fits' 10 s windows filled, the
  // nodes each restarted once or so.
  const double memory_at_s = std::min(15.0, 0.25 * a.seconds);
  // The heap in use, read every half second from then: what is in flight at one instant (frames
  // queued behind a stall, a node's messages being decoded) moves it by a tenth under load, so its
  // start and end are the medians of the first and the last few readings.
  std::vector<long> heap_kb;
  heap_kb.reserve(static_cast<std::size_t>(2.0 * a.seconds) + 8);  // made ready here, so as not to grow what it measures
  double next_heap_s = memory_at_s;
  while (steady_now_ns() < end_ns || more) {
    const double t_now = static_cast<double>(steady_now_ns() - run.start_ns) / 1e9;
    if (run.chaos)
      run.chaos->step(t_now);
    else
      kill_or_restart_victim(run, t_now, tally);
    if (tally.memory_start_kb == 0 && t_now >= memory_at_s) tally.memory_start_kb = resident_kb();
    if (t_now >= memory_at_s && t_now >= next_heap_s) {
      heap_kb.push_back(heap_in_use_kb());
      next_heap_s = t_now + 0.5;
    }
    if (t_now >= next_progress_s) {
      spdlog::info("{:.0f} of {:.0f} s", next_progress_s, a.seconds);
      next_progress_s += 1.0;
    }
    for (const std::string& w : run.source.take_warnings()) spdlog::warn("{}", w);
    const std::vector<AssembledFrame> closed = run.source.take_frames(0.01);
    more = !closed.empty();
    for (const AssembledFrame& f : closed) {
      tally_frame(run, f, tally);
      if (run.chaos) run.chaos->on_frame(f, static_cast<double>(steady_now_ns() - run.start_ns) / 1e9);
    }
  }
  tally.memory_end_kb = resident_kb();
  heap_kb.push_back(heap_in_use_kb());
  const auto median_of = [](std::vector<long> v) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  const std::size_t readings = std::max<std::size_t>(1, std::min<std::size_t>(5, heap_kb.size() / 2));  // the two never overlap
  tally.heap_start_kb = median_of({heap_kb.begin(), heap_kb.begin() + static_cast<std::ptrdiff_t>(readings)});
  tally.heap_end_kb = median_of({heap_kb.end() - static_cast<std::ptrdiff_t>(readings), heap_kb.end()});
}

nlohmann::json per_node_report(const NodesArgs& a, const NodeSourceStats& stats) {
  nlohmann::json per_node = nlohmann::json::array();
  for (const NodeStats& n : stats.nodes) {
    per_node.push_back({{"endpoint", n.endpoint},
                        {"frames", n.frames},
                        {"bytes_per_second", static_cast<double>(n.bytes) / a.seconds},
                        {"clock_offset_ms", n.clock_offset_ms},
                        {"clock_drift_ppm", n.clock_drift_ppm},
                        {"clock_residual_us", n.clock_residual_us},
                        {"min_rtt_us", n.min_rtt_us},
                        {"lost", n.lost},
                        {"rejoined", n.rejoined},
                        {"node_detect_ms", n.node_detect_ms},
                        {"node_dropped", n.node_dropped},
                        {"handshake_ms", n.handshake_ms},
                        {"handshakes_failed", n.handshakes_failed},
                        {"refused_by_node", n.refused_by_node}});
  }
  return per_node;
}

// Security's keys: which, the handshakes' times (first connection, over the nodes) and failures.
void security_report(const NodesArgs& a, const NodeSourceStats& stats, nlohmann::json& j) {
  j["security"] = a.insecure ? "none" : "curve";
  std::vector<double> handshakes;
  std::uint64_t failed = 0;
  for (const NodeStats& n : stats.nodes) {
    if (n.handshake_ms >= 0.0) handshakes.push_back(n.handshake_ms);
    failed += n.handshakes_failed;
  }
  std::sort(handshakes.begin(), handshakes.end());
  j["handshake_median_ms"] = handshakes.empty() ? -1.0 : handshakes[handshakes.size() / 2];
  j["handshake_max_ms"] = handshakes.empty() ? -1.0 : handshakes.back();
  j["handshakes_failed"] = failed;
}

// With --chaos: frames lost while every node served (none may be: an exposure a node did not make,
// being behind real time on a stalled machine, is not one), frames a camera missed, memory, and
// the faults.
void chaos_report(const NodesRun& run, const NodesTally& tally, nlohmann::json& j) {
  std::int64_t lost_all_up = 0;
  nlohmann::json lost_at = nlohmann::json::array();  // when (the first ten), to look into
  for (std::int64_t k = 0; k < run.frames_expected; ++k) {
    const double t = static_cast<double>(k) / run.a.rate_hz;
    if (tally.assembled.contains(k) || !run.chaos->all_up(t) || !run.chaos->all_up(t + 0.05)) continue;
    // Every camera made this exposure (and its neighbours: a counter gap says how many were
    // skipped, not which): one behind real time, skipping exposures on a stalled machine, was not
    // up for it.
    bool made = true;
    for (std::size_t c = 0; c < tally.not_made.size(); ++c)
      for (std::int64_t i = std::max<std::int64_t>(0, k - 1); i <= std::min(run.frames_expected - 1, k + 1); ++i)
        made = made && !(tally.tracks[c].counter && tally.not_made[c][static_cast<std::size_t>(i)]);
    lost_all_up += made ? 1 : 0;
    if (made && lost_at.size() < 10) lost_at.push_back(t);
  }
  j["frames_lost_while_all_up_at_s"] = lost_at;
  j["chaos_seconds"] = run.a.seconds;
  j["seed"] = run.a.seed;
  j["frames_lost_while_all_up"] = lost_all_up;
  j["frames_with_camera_missing"] = static_cast<std::int64_t>(tally.assembled.size()) - tally.complete;
  // The growth is the heap's: resident memory also holds what the allocator keeps after a free (a
  // sanitizer's quarantine of a few hundred MB, glibc's arenas), which is not the program's.
  j["memory_start_kb"] = tally.memory_start_kb;
  j["memory_end_kb"] = tally.memory_end_kb;
  j["heap_start_kb"] = tally.heap_start_kb;
  j["heap_end_kb"] = tally.heap_end_kb;
  j["memory_growth_fraction"] =
      tally.heap_start_kb > 0 ? static_cast<double>(tally.heap_end_kb - tally.heap_start_kb) / static_cast<double>(tally.heap_start_kb)
                              : 0.0;
  run.chaos->report(j);
}

// The JSON rhot-eval nodes prints.
nlohmann::json report(const NodesRun& run, const NodesTally& tally, const NodeSourceStats& stats) {
  const NodesArgs& a = run.a;
  nlohmann::json j;
  j["rig"] = a.rig_file;
  j["nodes"] = a.nodes;
  j["markers"] = a.markers;
  j["rate_hz"] = a.rate_hz;
  j["threads"] = run.jobs.threads();
  j["seconds"] = a.seconds;
  j["deadline_ms"] = a.deadline_ms;
  j["frames_expected"] = run.frames_expected;
  j["frames_assembled"] = static_cast<std::int64_t>(tally.assembled.size());
  j["frames_lost"] = run.frames_expected - static_cast<std::int64_t>(tally.assembled.size());
  // Of those, the exposures no node made (each was behind real time, or not running): the
  // machine's doing, not the transport's. Cameras never in a frame (every message late) are not
  // asked.
  std::int64_t not_made = 0;
  for (std::int64_t k = 0; k < run.frames_expected; ++k) {
    if (tally.assembled.contains(k) || tally.not_made.empty()) continue;
    bool none = true;  // of the cameras that were in frames (one whose every message came late made none)
    for (std::size_t c = 0; c < tally.not_made.size(); ++c)
      if (tally.tracks[c].counter) none = none && tally.not_made[c][static_cast<std::size_t>(k)];
    not_made += none ? 1 : 0;
  }
  j["frames_not_made"] = not_made;
  j["frames_lost_in_transport"] = run.frames_expected - static_cast<std::int64_t>(tally.assembled.size()) - not_made;
  j["wrong_markers_accepted"] = tally.wrong_markers;
  nlohmann::json wrong_frames = nlohmann::json::array();
  for (const NodesTally::WrongFrame& w : tally.wrong_frames) {
    nlohmann::json e = {{"t_s", w.t_s}, {"camera", w.camera}, {"wrong", w.wrong}, {"detections", w.detections}};
    e["markers_of_exposures_off"] = w.exposures_off ? nlohmann::json(*w.exposures_off) : nlohmann::json(nullptr);
    wrong_frames.push_back(e);
  }
  j["wrong_marker_frames"] = wrong_frames;
  if (run.chaos) chaos_report(run, tally, j);
  j["frames_complete"] = tally.complete;
  j["assembly_p50_ms"] = percentile(tally.assembly_ms, 0.5);
  j["assembly_p99_ms"] = percentile(tally.assembly_ms, 0.99);
  j["latency_p50_ms"] = percentile(tally.latency_ms, 0.5);
  j["latency_p99_ms"] = percentile(tally.latency_ms, 0.99);
  double residual = 0.0;
  for (const NodeStats& n : stats.nodes) residual = std::max(residual, n.clock_residual_us);
  j["clock_residual_us"] = residual;
  // Node 0's clock is start-relative: true offset = offset + drift * (t - start).
  const double true_offset_ms = a.clock_offset_ms + a.clock_drift_ppm * 1e-6 * (a.seconds * 1e3);
  if (!run.chaos)  // chaos gives restarted nodes clocks of its own
    j["clock_offset_error_us"] = stats.nodes.empty() ? 0.0 : std::abs(stats.nodes[0].clock_offset_ms - true_offset_ms) * 1e3;
  j["found_fraction"] = tally.truth_total > 0 ? static_cast<double>(tally.found) / static_cast<double>(tally.truth_total) : 0.0;
  if (a.kill_at)
    j["found_fraction_while_node_down"] =
        tally.truth_down > 0 ? static_cast<double>(tally.found_down) / static_cast<double>(tally.truth_down) : 0.0;
  if (a.restart_at) j["rejoined"] = tally.rejoined;
  if (run.demo) {
    j["scene"] = a.scene_file;
    j["hand_joint_mean_mm"] = run.hands.nodes_hands.mean_mm();
    j["hands_seen_fraction"] = run.hands.nodes_hands.seen_fraction();
    j["in_process_hand_joint_mean_mm"] = run.hands.local_hands.mean_mm();
    j["in_process_hands_seen_fraction"] = run.hands.local_hands.seen_fraction();
    run.hands.nodes_hands.report(j, "");
    run.hands.local_hands.report(j, "in_process_");
  }
  j["late"] = stats.assembly.late;
  j["duplicates"] = stats.assembly.duplicates;
  j["out_of_order"] = stats.assembly.out_of_order;
  j["deadline_frames"] = stats.assembly.deadline_frames;
  j["bad_messages"] = stats.bad_messages;
  security_report(a, stats, j);
  j["per_node"] = per_node_report(a, stats);
  return j;
}

// Where the run's keys are made (empty with --insecure): --keys DIR, or a new private temporary
// folder (mkdtemp: no other user can have put keys there first), removed at the end.
struct RunKeys {
  std::string dir;
  std::filesystem::path remove;
  explicit RunKeys(const NodesArgs& a) {
    if (a.insecure) return;
    if (!a.keys_dir.empty()) {
      dir = a.keys_dir;
      return;
    }
    std::string pattern = (std::filesystem::temp_directory_path() / "rhot-eval-nodes-keys-XXXXXX").string();
    if (::mkdtemp(pattern.data()) == nullptr) return;  // dir stays empty: refused below
    dir = pattern;
    remove = pattern;
  }
  ~RunKeys() {
    std::error_code ec;
    if (!remove.empty()) std::filesystem::remove_all(remove, ec);
  }
  RunKeys(const RunKeys&) = delete;
  RunKeys& operator=(const RunKeys&) = delete;
};

// The master's node source on the planned nodes, with the run's keys: nullptr after saying why not.
std::unique_ptr<NodeSource> open_master(const CameraRig& rig, const std::vector<NodePlan>& plans, NodeSourceSettings settings,
                                        const RunKeys& keys) {
  std::vector<std::string> endpoints;
  for (const NodePlan& p : plans) endpoints.push_back(p.endpoint);
  if (!keys.dir.empty()) {
    auto ring = load_key_ring(keys.dir + "/master");
    if (!ring) {
      std::cerr << "rhot-eval: " << ring.error() << "\n";
      return nullptr;
    }
    settings.security = std::move(*ring);
  }
  auto source = NodeSource::open(rig, endpoints, settings);
  if (!source) {
    std::cerr << "rhot-eval: " << source.error() << "\n";
    return nullptr;
  }
  return std::move(*source);
}

std::unique_ptr<Chaos> make_chaos(const NodesArgs& a, const std::vector<NodePlan>& plans, std::vector<ChildProcess>& children,
                                  const std::filesystem::path& log, NodeSource& source, bool secure) {
  if (!a.chaos_s) return nullptr;
  std::vector<ChaosNode> nodes;
  for (const NodePlan& p : plans) nodes.push_back({p.argv, parse_node_address(p.endpoint)->endpoint, p.cameras});
  return std::make_unique<Chaos>(a.seed, a.seconds, std::move(nodes), children, log, source, secure);
}

}  // namespace

int nodes(const NodesArgs& given) {
  spdlog::set_default_logger(spdlog::stderr_color_mt("rhot-eval"));  // stdout is the JSON's
  NodesArgs a = given;
  if (a.chaos_s) a.seconds = *a.chaos_s;
  auto rig = rhot::load_rig(a.rig_file);
  if (!rig) {
    std::cerr << "rhot-eval: " << rig.error() << "\n";
    return 1;
  }
  if (!check_args(a, *rig)) return 1;
  std::optional<DemoSimulation> demo;
  if (!load_demo(a, demo)) return 1;
  const std::filesystem::path node_program = this_program_dir() / "rhot-node";
  if (!std::filesystem::exists(node_program)) {
    std::cerr << "rhot-eval: " << node_program.string() << " not found (build the rhot-node target)\n";
    return 1;
  }
  auto ports = free_tcp_port_pairs(a.nodes);
  if (!ports) {
    std::cerr << "rhot-eval: " << ports.error() << "\n";
    return 1;
  }
  // Time 0 of the simulated world, on the steady clock every process here shares, far enough
  // ahead for the nodes to start and subscribe (a sanitizer build on a busy 2-core machine takes
  // over a second to start four processes).
  const std::int64_t start_ns = steady_now_ns() + 3'000'000'000;
  const RunKeys keys(a);
  if (!a.insecure && keys.dir.empty()) {
    std::cerr << "rhot-eval: cannot make a temporary folder for the run's keys\n";
    return 1;
  }
  if (!keys.dir.empty() && !make_run_keys(keys.dir, a.nodes)) return 1;
  const std::vector<NodePlan> plans = plan_nodes(a, rig->cameras.size(), node_program, *ports, start_ns, keys.dir);
  const std::filesystem::path log = std::filesystem::temp_directory_path() / ("rhot-eval-nodes-" + std::to_string(::getpid()) + ".log");
  std::vector<ChildProcess> children;
  if (!spawn_nodes(plans, log, children)) return 1;
  const NodeSourceSettings settings = source_settings(a, start_ns);
  const std::unique_ptr<NodeSource> source = open_master(*rig, plans, settings, keys);
  if (!source) return 1;
  const std::vector<Trajectory> markers = demo ? std::vector<Trajectory>{} : wandering_markers(*rig, a.markers, a.seed);
  DemoHands hands;
  if (demo) set_up_demo_hands(a, *rig, *demo, hands);
  const std::unique_ptr<Chaos> chaos = make_chaos(a, plans, children, log, *source, !keys.dir.empty());
  const RigMatcher matcher(*rig);
  JobPool jobs(master_threads(a));
  const NodesRun run{.a = a,
                     .rig = *rig,
                     .demo = demo,
                     .plans = plans,
                     .log = log,
                     .children = children,
                     .source = *source,
                     .settings = settings,
                     .markers = markers,
                     .hands = hands,
                     .match = match_settings_for(a.sigma),
                     .matcher = matcher,
                     .jobs = jobs,
                     .start_ns = start_ns,
                     .period_ns = static_cast<std::int64_t>(std::llround(1e9 / a.rate_hz)),
                     .frames_expected = static_cast<std::int64_t>(std::floor(a.seconds * a.rate_hz)),
                     .victim = a.nodes - 1,
                     .chaos = chaos.get()};
  NodesTally tally(run.frames_expected, rig->cameras.size());
  const double cpu0 = process_cpu_s();
  run_master(run, tally);
  const double master_cpu_s = process_cpu_s() - cpu0;
  const NodeSourceStats stats = source->stats();
  for (ChildProcess& c : children) c.stop(2.0);
  nlohmann::json j = report(run, tally, stats);
  // The master's CPU per assembled frame (decryption is ZeroMQ's I/O thread's), beside the run's.
  j["master_cpu_ms_per_frame"] = tally.assembled.empty() ? 0.0 : master_cpu_s * 1e3 / static_cast<double>(tally.assembled.size());
  std::cout << j.dump(2) << std::endl;
  std::error_code ec;
  std::filesystem::remove(log, ec);
  return 0;
}

}  // namespace rhot::eval
