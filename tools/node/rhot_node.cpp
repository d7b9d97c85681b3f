// rhot-node: a camera node. Reads its cameras (capture devices, video files, image sequences:
// detected side by side on --threads) or simulated cameras of a rig, finds the markers on the node, and publishes each camera frame's
// detections to the master over ZeroMQ (docs/camera-nodes.md). Answers time and status requests
// beside its publish endpoint. Binds only the endpoints it is given.

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "base/Jobs.h"
#include "engine/scene/SceneLoader.h"
#include "engine/sim/Demo.h"
#include "tracking/camera/RigFile.h"
#include "tracking/net/NodeServer.h"
#include "tracking/net/NodeSource.h"
#include "tracking/sim/SimulatedRig.h"
#include "tracking/source/VideoSource.h"
#include "tools/common/CliExit.h"
#include "tools/common/NodeKeys.h"
#include "tools/common/NumberChecks.h"

namespace {

std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop = true; }

struct Options {
  std::string publish;
  std::string control;
  int node_id = 0;
  // simulated cameras
  std::string sim_rig;
  std::vector<int> sim_cameras;
  int sim_markers = 40;
  std::string sim_scene;  // the demo's world instead of loose markers
  unsigned seed = 1;
  double sigma = 0.3;
  std::optional<std::int64_t> sim_start_ns;
  // real cameras, one rig camera each
  std::vector<std::string> devices;
  std::string rig;
  std::vector<int> cameras;  // none: camera 0 (one device)
  int threshold = -1;
  int threads = 0;  // the devices' detection side by side (VideoSourceSettings::threads)
  // both
  double rate_hz = 90.0;
  double clock_offset_ms = 0.0;
  double clock_drift_ppm = 0.0;
  double delay_ms = 0.0;
  double seconds = 0.0;
  rhot::NodeKeyFlags keys;
  bool print_clock = false;
};

// Per-second rate and detection time for status replies.
class Meter {
 public:
  void frame(std::int64_t now, double detect_ms, int cameras) {
    times_.push_back(now);
    detect_.push_back(detect_ms / std::max(cameras, 1));
    while (!times_.empty() && now - times_.front() > 1'000'000'000) {
      times_.pop_front();
      detect_.pop_front();
    }
  }
  double rate_hz() const { return static_cast<double>(times_.size()); }
  double detect_ms() const {
    double s = 0.0;
    for (double d : detect_) s += d;
    return detect_.empty() ? 0.0 : s / static_cast<double>(detect_.size());
  }

 private:
  std::deque<std::int64_t> times_;
  std::deque<double> detect_;
};

// Frames waiting out --delay-ms before they are sent.
struct Outbox {
  std::deque<std::pair<std::int64_t, rhot::NodeFrameMessage>> queue;
  void send_due(rhot::NodeServer& server, std::int64_t now) {
    while (!queue.empty() && queue.front().first <= now) {
      server.publish(queue.front().second);
      queue.pop_front();
    }
  }
};

int run_simulated(const Options& o, rhot::NodeServer& server) {
  auto rig = rhot::load_rig(o.sim_rig);
  if (!rig) {
    spdlog::error("{}", rig.error());
    return 1;
  }
  rhot::CameraRig mine;
  for (int c : o.sim_cameras) {
    if (c < 0 || c >= static_cast<int>(rig->cameras.size())) {
      spdlog::error("--sim-camera: camera {} is not in {} ({} cameras)", c, o.sim_rig, rig->cameras.size());
      return 1;
    }
    mine.cameras.push_back(rig->cameras[static_cast<std::size_t>(c)]);
  }
  rhot::SimulatedRigSettings settings;
  settings.sigma_px = o.sigma;
  settings.rate_hz = o.rate_hz;
  settings.seed = o.seed * 1000u + static_cast<unsigned>(o.sim_cameras.front());
  if (auto ok = settings.check(); !ok) {
    spdlog::error("{}", ok.error());
    return 1;
  }
  // The world is the rig's: every node of one rig and seed simulates the same markers, or the
  // same demo script.
  std::optional<rhot::DemoSimulation> demo;
  if (!o.sim_scene.empty()) {
    const auto scene = rhot::load_scene_file(o.sim_scene);
    if (!scene) {
      spdlog::error("{}", scene.error().to_string());
      return 1;
    }
    auto made = rhot::make_demo_simulation(*scene, RHOT_ASSET_DIR);
    if (!made) {
      spdlog::error("{}: {}", o.sim_scene, made.error());
      return 1;
    }
    demo = std::move(*made);
  }
  rhot::SimulatedRig sim(mine, demo ? std::vector<rhot::Trajectory>{} : rhot::wandering_markers(*rig, o.sim_markers, o.seed), settings);
  if (demo) sim.set_world(demo->world);
  const std::int64_t start = o.sim_start_ns.value_or(rhot::steady_now_ns());
  const auto period = static_cast<std::int64_t>(std::llround(1e9 / o.rate_hz));
  const std::int64_t now0 = rhot::steady_now_ns();
  std::int64_t k = now0 <= start ? 0 : (now0 - start + period - 1) / period;
  const std::int64_t end = o.seconds > 0.0 ? now0 + static_cast<std::int64_t>(o.seconds * 1e9) : INT64_MAX;
  const auto delay = static_cast<std::int64_t>(o.delay_ms * 1e6);
  std::uint64_t counter = 0;
  Outbox outbox;
  Meter meter;
  spdlog::info("node {}: simulating cameras of {} at {} Hz, publishing on {}", o.node_id, o.sim_rig, o.rate_hz, o.publish);
  while (!g_stop) {
    const std::int64_t exposure = start + k * period;
    if (exposure >= end) break;
    // Answer requests (and send delayed frames) until the exposure.
    while (!g_stop) {
      const std::int64_t now = rhot::steady_now_ns();
      outbox.send_due(server, now);
      const std::int64_t next = outbox.queue.empty() ? exposure : std::min(exposure, outbox.queue.front().first);
      if (now >= exposure) break;
      server.serve_until(next);
      for (const std::string& w : server.take_warnings()) spdlog::warn("{}", w);
    }
    const std::int64_t began = rhot::steady_now_ns();
    if (began - exposure > period) {
      // Behind by more than a frame (the machine is busy): skip to the present and count it.
      const std::int64_t skip = (began - exposure) / period;
      server.stats().frames_dropped += static_cast<std::uint64_t>(skip) * mine.cameras.size();
      k += skip;
      continue;
    }
    const rhot::RigFrame frame = *sim.next(static_cast<double>(exposure - start) / 1e9);
    const double detect_ms = static_cast<double>(rhot::steady_now_ns() - began) / 1e6;
    for (std::size_t j = 0; j < frame.cameras.size(); ++j) {
      rhot::NodeFrameMessage m;
      m.node = static_cast<std::uint16_t>(o.node_id);
      m.camera = static_cast<std::uint16_t>(o.sim_cameras[j]);
      m.counter = counter;
      m.capture_ns = server.clock().node_ns(exposure);
      m.width = static_cast<std::uint16_t>(mine.cameras[j].intrinsics.width_px);
      m.height = static_cast<std::uint16_t>(mine.cameras[j].intrinsics.height_px);
      m.detections = frame.cameras[j].detections;
      if (delay > 0)
        outbox.queue.emplace_back(rhot::steady_now_ns() + delay, std::move(m));
      else
        server.publish(m);
    }
    ++counter;
    meter.frame(rhot::steady_now_ns(), detect_ms, static_cast<int>(mine.cameras.size()));
    server.stats().frame_rate_hz = meter.rate_hz();
    server.stats().detect_mean_ms = meter.detect_ms();
    ++k;
  }
  return 0;
}

int run_device(const Options& o, rhot::NodeServer& server) {
  auto rig = rhot::load_rig(o.rig);
  if (!rig) {
    spdlog::error("{}", rig.error());
    return 1;
  }
  const std::vector<int> cameras = o.cameras.empty() ? std::vector<int>{0} : o.cameras;
  if (cameras.size() != o.devices.size()) {
    spdlog::error("--camera: {} cameras of --rig named for {} devices: one camera a --device, in the same order", cameras.size(),
                  o.devices.size());
    return 1;
  }
  rhot::CameraRig mine;
  for (std::size_t j = 0; j < cameras.size(); ++j) {
    const int c = cameras[j];
    if (c < 0 || c >= static_cast<int>(rig->cameras.size())) {
      spdlog::error("--camera: camera {} is not in {} ({} cameras)", c, o.rig, rig->cameras.size());
      return 1;
    }
    if (std::find(cameras.begin(), cameras.begin() + static_cast<std::ptrdiff_t>(j), c) !=
        cameras.begin() + static_cast<std::ptrdiff_t>(j)) {
      spdlog::error("--camera: camera {} is named twice: each device is another camera of the rig", c);
      return 1;
    }
    mine.cameras.push_back(rig->cameras[static_cast<std::size_t>(c)]);
  }
  rhot::VideoSourceSettings vs;
  vs.detector.threshold = o.threshold;
  vs.rate_hz = o.rate_hz;
  vs.threads = o.threads;
  auto source = rhot::VideoSource::open(mine, o.devices, vs);
  if (!source) {
    spdlog::error("{}", source.error());
    return 1;
  }
  const auto period = static_cast<std::int64_t>(std::llround(1e9 / o.rate_hz));
  const std::int64_t start = rhot::steady_now_ns();
  const std::int64_t end = o.seconds > 0.0 ? start + static_cast<std::int64_t>(o.seconds * 1e9) : INT64_MAX;
  const auto delay = static_cast<std::int64_t>(o.delay_ms * 1e6);
  std::uint64_t counter = 0;
  Outbox outbox;
  Meter meter;
  std::int64_t next_frame = start;
  for (std::size_t j = 0; j < cameras.size(); ++j)
    spdlog::info("node {}: camera {} of {} from {}, publishing on {}", o.node_id, cameras[j], o.rig, o.devices[j], o.publish);
  while (!g_stop && rhot::steady_now_ns() < end) {
    // Files and image sequences are paced at --rate-hz; a device delivers at its own rate.
    server.serve_until(next_frame);
    for (const std::string& w : server.take_warnings()) spdlog::warn("{}", w);
    outbox.send_due(server, rhot::steady_now_ns());
    const std::int64_t grabbed = rhot::steady_now_ns();
    auto frame = source->next();
    if (!frame) break;
    for (const std::string& w : source->take_warnings()) spdlog::warn("{}", w);
    const std::int64_t done = rhot::steady_now_ns();
    for (std::size_t j = 0; j < cameras.size(); ++j) {
      // A camera with no image this frame (its file ended first, a read failed) sends nothing: the
      // master counts it missing, not as a camera that saw no marker.
      if (!frame->cameras[j].delivered) continue;
      rhot::NodeFrameMessage m;
      m.node = static_cast<std::uint16_t>(o.node_id);
      m.camera = static_cast<std::uint16_t>(cameras[j]);
      m.counter = counter;
      m.capture_ns = server.clock().node_ns(grabbed);
      m.width = static_cast<std::uint16_t>(mine.cameras[j].intrinsics.width_px);
      m.height = static_cast<std::uint16_t>(mine.cameras[j].intrinsics.height_px);
      m.detections = frame->cameras[j].detections;
      if (delay > 0)
        outbox.queue.emplace_back(done + delay, std::move(m));
      else
        server.publish(m);
    }
    ++counter;
    meter.frame(done, static_cast<double>(done - grabbed) / 1e6, static_cast<int>(cameras.size()));
    server.stats().frame_rate_hz = meter.rate_hz();
    server.stats().detect_mean_ms = meter.detect_ms();
    next_frame = std::max(next_frame + period, grabbed);
  }
  for (const std::string& line : source->summary()) spdlog::info("{}", line);
  return 0;
}

void add_options(CLI::App& cli, Options& o) {
  cli.add_option("--publish", o.publish, "Where to publish frames, e.g. tcp://127.0.0.1:5601 (bound here, and nowhere else)");
  cli.add_flag("--print-clock", o.print_clock, "Print this machine's steady clock (ns, as --sim-start-ns takes it) and exit");
  cli.add_option("--control", o.control, "Where to answer time and status requests (default: the publish port + 1)");
  cli.add_option("--node-id", o.node_id, "This node's number, in its messages")->capture_default_str()->check(CLI::Range(0, 65535));
  auto* sim_rig =
      cli.add_option("--sim-rig", o.sim_rig, "Simulate cameras of this rig (OpenCV YAML) instead of reading one")->check(CLI::ExistingFile);
  cli.add_option("--sim-camera", o.sim_cameras, "With --sim-rig: the rig's cameras this node serves (e.g. 0 or 0,4)")
      ->delimiter(',')
      ->check(CLI::Range(0, 65535))
      ->needs(sim_rig);
  cli.add_option("--sim-markers", o.sim_markers, "With --sim-rig: markers wandering through the rig's volume")
      ->capture_default_str()
      ->check(CLI::Range(0, 4096));
  cli.add_option("--sim-scene", o.sim_scene,
                 "With --sim-rig: the demo's world of this scene (its script's hands and objects) instead of loose markers")
      ->check(CLI::ExistingFile);
  cli.add_option("--seed", o.seed, "With --sim-rig: the simulated world's seed (the same on every node of one rig)")->capture_default_str();
  cli.add_option("--sigma", o.sigma, "With --sim-rig: pixel noise")->capture_default_str()->check(CLI::Range(0.0, 10.0));
  cli.add_option("--sim-start-ns", o.sim_start_ns,
                 "With --sim-rig: the simulated world's time 0 on this machine's steady clock (CLOCK_MONOTONIC, ns), shared by "
                 "every node of one rig (default: when this node starts)");
  auto* device = cli.add_option("--device", o.devices,
                                "The node's cameras: a capture device index, a video file or an image sequence (cam_%04d.png) each "
                                "(e.g. 0,2 or a.mp4,b.mp4)")
                     ->delimiter(',');
  cli.add_option("--rig", o.rig, "With --device: the rig file naming the cameras' calibration")->check(CLI::ExistingFile)->needs(device);
  cli.add_option("--camera", o.cameras, "With --device: which camera of --rig each device is, in the same order (default: 0)")
      ->delimiter(',')
      ->check(CLI::Range(0, 65535))
      ->needs(device);
  cli.add_option("--threads", o.threads,
                 "With --device: threads the cameras are detected on side by side (0: every core there is, at most one a camera); "
                 "the detections do not depend on it")
      ->capture_default_str()
      ->check(CLI::Range(0, rhot::kMaxThreads))
      ->needs(device);
  cli.add_option("--threshold", o.threshold, "With --device: blob threshold in grey levels (-1: automatic)")
      ->capture_default_str()
      ->check(CLI::Range(-1, 254));
  cli.add_option("--rate-hz", o.rate_hz, "Frames per second (simulated cameras; files and image sequences are paced at it)")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 1000.0));
  cli.add_option("--clock-offset-ms", o.clock_offset_ms, "Run this node's clock ahead by this much (to test synchronisation)")
      ->capture_default_str()
      ->check(CLI::Range(-1e6, 1e6));
  cli.add_option("--clock-drift-ppm", o.clock_drift_ppm, "Run this node's clock fast by this much (to test synchronisation)")
      ->capture_default_str()
      ->check(CLI::Range(-1e4, 1e4));
  cli.add_option("--delay-ms", o.delay_ms, "Hold every frame this long before sending it (a slow link)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 10000.0));
  cli.add_option("--seconds", o.seconds, "Stop after this long (0: until stopped)")
      ->capture_default_str()
      ->check(rhot::number_check(rhot::NumberBound::kNonNegative))  // CLI::Range lets nan through: a node that never stops
      ->check(CLI::Range(0.0, 1e7));
  rhot::add_node_key_flags(cli, o.keys);
}

// rhot-node keygen: a key pair written as DIR/NAME.key and DIR/NAME.key_secret.
int make_keys(const std::string& out, const std::string& name) {
  auto pair = rhot::make_key_pair(name);
  if (pair) {
    if (auto ok = rhot::write_certificates(out, *pair); !ok) pair = std::unexpected(ok.error());
  }
  if (!pair) {
    spdlog::error("keygen: {}", pair.error());
    return 1;
  }
  std::printf("%s/%s.key (public: give it to the peers that are to trust it)\n%s/%s.key_secret (keep it here)\n", out.c_str(), name.c_str(),
              out.c_str(), name.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{
      "rhot-node: a camera node. Finds the markers of its cameras and publishes their detections to the master over "
      "ZeroMQ (docs/camera-nodes.md); answers time and status requests on the control endpoint beside it."};
  Options o;
  add_options(cli, o);
  std::string keygen_out, keygen_name;
  CLI::App* keygen = cli.add_subcommand(
      "keygen",
      "Make a key pair for the camera network: DIR/NAME.key (public: give it to the peers that are to trust it, into their "
      "trusted/) and DIR/NAME.key_secret (this machine's only), in ZeroMQ's certificate format");
  keygen->add_option("--out", keygen_out, "The folder to write them to (made if needed)")->required();
  keygen->add_option("--name", keygen_name, "The key's name: letters, digits, _ . - (e.g. node0, master)")->required();
  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return rhot::cli_exit_status(cli, e);
  }
  if (keygen->parsed()) return make_keys(keygen_out, keygen_name);
  if (o.print_clock) {
    std::printf("%lld\n", static_cast<long long>(rhot::steady_now_ns()));
    return 0;
  }
  if (o.publish.empty()) {
    spdlog::error("--publish is required: where to publish frames, e.g. tcp://127.0.0.1:5601");
    return 1;
  }

  if (o.sim_rig.empty() == o.devices.empty()) {
    spdlog::error("give either --sim-rig FILE --sim-camera I or --device DEV --rig FILE --camera I");
    return 1;
  }
  if (!o.sim_rig.empty() && o.sim_cameras.empty()) {
    spdlog::error("--sim-rig needs --sim-camera: the rig's cameras this node serves");
    return 1;
  }
  if (!o.devices.empty() && o.rig.empty()) {
    spdlog::error("--device needs --rig: the rig file with the cameras' calibration");
    return 1;
  }
  if (auto ok = rhot::check_endpoint(o.publish); !ok) {
    spdlog::error("--publish: {}", ok.error());
    return 1;
  }
  if (o.control.empty()) o.control = rhot::control_endpoint_for(o.publish);
  rhot::NodeClock clock;
  clock.offset_ns = static_cast<std::int64_t>(std::llround(o.clock_offset_ms * 1e6));
  clock.drift_ppm = o.clock_drift_ppm;
  // A simulated node's clock error starts with the simulated world, so a test knows its true offset.
  clock.start_ns = o.sim_start_ns.value_or(rhot::steady_now_ns());
  const auto security = rhot::node_security_from(o.keys, true);
  if (!security) {
    spdlog::error("{}", security.error());
    return 1;
  }
  const auto cameras = static_cast<std::uint16_t>(o.sim_rig.empty() ? o.devices.size() : o.sim_cameras.size());
  auto server = rhot::NodeServer::open(o.publish, o.control, static_cast<std::uint16_t>(o.node_id), cameras, clock, *security);
  if (!server) {
    spdlog::error("{}", server.error());
    return 1;
  }
  std::signal(SIGTERM, on_signal);
  std::signal(SIGINT, on_signal);
  const int rc = o.sim_rig.empty() ? run_device(o, **server) : run_simulated(o, **server);
  const auto& s = (*server)->stats();
  for (const std::string& w : (*server)->take_warnings()) spdlog::warn("{}", w);
  spdlog::info("node {}: {} frames published, {} dropped, {} requests answered ({} not understood)", o.node_id, s.frames_published,
               s.frames_dropped, s.requests, s.bad_requests);
  if (*security)
    spdlog::info("node {}: {} master connections admitted, {} peers refused (key not trusted), {} failed handshakes", o.node_id,
                 s.masters_admitted, s.peers_refused, s.handshakes_failed);
  return rc;
}
