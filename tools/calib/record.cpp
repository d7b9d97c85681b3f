// rhot-calib record: detections of a waved marker recorded live from cameras, video files or image
// sequences (one per rig camera, as rhot-demo --source video:...) or from camera nodes
// (--source nodes:..., as rhot-demo), written as rhot's CSV for
// `wand`. The blob detector finds the marker in every image; nothing is labelled.

#include <memory>
#include <string>

#include <spdlog/spdlog.h>

#include "tools/calib/Calib.h"
#include "tracking/calib/Detections.h"
#include "tracking/camera/RigFile.h"
#include "tracking/net/NodeSource.h"
#include "tracking/source/VideoSource.h"

namespace rhot::calib_tool {

namespace {

struct RecordOptions {
  std::vector<std::string> rig;
  std::string source;
  std::string out;
  int frames = 0;
  int blob_threshold = -1;
  NodeKeyFlags keys;
};

int run(const RecordOptions& o) {
  const auto rig = load_cameras(o.rig);
  if (!rig) {
    spdlog::error("{}", rig.error());
    return 1;
  }
  auto opened = open_frame_source(*rig, o.source, o.blob_threshold, o.keys);
  if (!opened) {
    spdlog::error("{}", opened.error());
    return 1;
  }
  std::unique_ptr<FrameSource> source = std::move(*opened);
  Detections d;
  d.camera_count = static_cast<int>(rig->cameras.size());
  long frame = 0;
  stop_on_signals();
  spdlog::info("recording{}; Ctrl-C stops and writes what was recorded",
               o.frames > 0 ? fmt::format(" {} frames", o.frames) : std::string());
  while ((o.frames <= 0 || frame < o.frames) && !stop_asked()) {
    const auto f = source->next(0.0);
    if (!f) break;
    DetectionFrame df;
    df.frame = frame;
    for (const CameraFrame& c : f->cameras) {
      for (const Detection& det : c.detections) df.observations.push_back({c.camera, det.pixel, -1});
    }
    if (!df.observations.empty()) d.frames.push_back(std::move(df));
    for (const std::string& w : source->take_warnings()) spdlog::warn("{}", w);
    if (++frame % 300 == 0) spdlog::info("{} frames, {} detections", frame, d.count());
  }
  for (const std::string& line : source->summary()) spdlog::info("{}", line);
  if (d.frames.empty()) {
    spdlog::error("no camera saw a marker in {} frames: is the marker bright enough (--blob-threshold), and in view?", frame);
    return 1;
  }
  make_parent_folder(o.out);
  if (const auto ok = write_detections_csv(d, o.out); !ok) {
    spdlog::error("{}", ok.error());
    return 1;
  }
  spdlog::info("{}: {} detections in {} of {} frames", o.out, d.count(), d.frames.size(), frame);
  return 0;
}

}  // namespace

std::expected<std::unique_ptr<FrameSource>, std::string> open_frame_source(const CameraRig& rig, const std::string& source,
                                                                           int blob_threshold, const NodeKeyFlags& keys) {
  const bool nodes_named = source.rfind("nodes:", 0) == 0;
  auto security = node_security_from(keys, nodes_named);
  if (!security) return std::unexpected(security.error());
  if (nodes_named) {
    const auto endpoints = parse_node_endpoints(source.substr(6));
    if (!endpoints) return std::unexpected("--source: " + endpoints.error());
    NodeSourceSettings settings;
    settings.security = std::move(*security);
    auto nodes = NodeSource::open(rig, *endpoints, settings);
    if (!nodes) return std::unexpected(nodes.error());
    return std::unique_ptr<FrameSource>(std::move(*nodes));
  }
  if (source.rfind("video:", 0) == 0) {
    const auto devices = parse_video_devices(source.substr(6));
    if (!devices) return std::unexpected("--source: " + devices.error());
    VideoSourceSettings settings;
    settings.detector.threshold = blob_threshold;
    auto video = VideoSource::open(rig, *devices, settings);
    if (!video) return std::unexpected(video.error());
    return std::unique_ptr<FrameSource>(std::make_unique<VideoSource>(std::move(*video)));
  }
  return std::unexpected("--source: expected video:DEV[,DEV...] or nodes:NAME@ENDPOINT[,...], got \"" + source + "\"");
}

void add_record(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<RecordOptions>();
  CLI::App* cmd = app.add_subcommand("record", "record a waved marker's detections from cameras, videos or image sequences, for `wand`");
  cmd->add_option("--rig", o->rig, "the cameras' intrinsics (OpenCV YAML): one file per camera or one with them all, in device order")
      ->required();
  cmd->add_option("--source", o->source,
                  "video:DEV[,DEV...]: a capture device index, video file or image sequence (cam0_%04d.png) per camera; or "
                  "nodes:NAME@ENDPOINT[,...]: camera nodes (rhot-node, docs/camera-nodes.md) serving the rig's cameras, NAME.key each "
                  "one's certificate in --keys DIR/trusted/ (nodes:ENDPOINT[,...] with --insecure)")
      ->required();
  cmd->add_option("--out", o->out, "detections CSV to write")->required();
  add_node_key_flags(*cmd, o->keys);
  cmd->add_option("--frames", o->frames, "frames to record (default: until the files end or Ctrl-C)")->check(CLI::Range(0, 10000000));
  cmd->add_option("--blob-threshold", o->blob_threshold, "grey level of a marker pixel (default -1: automatic)")
      ->capture_default_str()
      ->check(CLI::Range(-1, 255));
  cmd->callback([o, &exit_code] { exit_code = run(*o); });
}

}  // namespace rhot::calib_tool
