#pragma once
// The composition root: a runtime (engine/runtime/Runtime.h) assembled from a scene, a source
// description, a renderer and settings. This is how an application starts rhot on its cameras:
//
//   video devices   one OpenCV capture per rig camera (tracking/source/VideoSource.h): a device
//                   index, a video file or an image sequence; bright blobs or coloured markers
//   camera nodes    rhot-node processes sending detections over ZeroMQ (tracking/net/NodeSource.h)
//   replay          a recording's tracking results (engine/tracked/ReplaySource.h)
//   a source of the application's own, given by a SourceFactory: the simulated rig of
//                   engine/sim/Demo.h is one (this folder never includes simulation code)
//
// Whatever the source, the frames go through the same live tracking (matching, marker stars,
// hands) with the rig file's cameras, the hand layouts of assets/hands and the scene's
// star-tracked objects; a replay enters where live results do.

#include <array>
#include <expected>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "engine/runtime/Runtime.h"
#include "engine/tracked/LiveTracking.h"
#include "tracking/camera/Camera.h"
#include "tracking/detect/BlobDetector.h"
#include "tracking/detect/ColourModel.h"
#include "tracking/hand/HandLayout.h"
#include "tracking/net/CurveKeys.h"
#include "tracking/rigid/StarSet.h"
#include "tracking/source/FrameSource.h"

namespace rhot {

struct LaunchSettings {
  std::filesystem::path asset_dir;  // where the defaults below are found (an installed rhot: share/rhot/assets)
  std::filesystem::path rig_file;   // empty: the scene's rig, else assets/rigs/seated-4.yaml (stereo-640.yaml with colour markers)
  std::filesystem::path star_set;   // empty: assets/stars/seed-case.json (the objects' stars)
  bool filter_hands = false;        // LiveTrackingSettings::filter_hands
  bool filter_hand_frames = true;   // LiveTrackingSettings::filter_hand_frames
  int threads = 0;                  // the tracker's threads (LiveTrackingSettings, VideoSourceSettings), 0: every core
  std::filesystem::path replay;     // play this recording instead of tracking
  double speed = 1.0;               // replay speed (2: twice as fast)
  bool predict = true;              // RuntimeSettings::predict: draw the hands at the display time
  std::size_t latency_window_frames = 65536;  // RuntimeSettings::latency_window_frames
  bool publish_hands = true;                  // RuntimeSettings::publish_hands: for rhot's OpenXR layer
  Rigid3d world_from_stage;                   // RuntimeSettings::world_from_stage (rhot-calib headset)
  std::filesystem::path record;               // write every frame's hands and tracked objects here
  std::string stream;                         // send every frame's hands and objects to osc://HOST:PORT[,vmc] (engine/stream)
  // Real cameras: one OpenCV device per rig camera, in rig order (an index such as "0", a video
  // file, or an image sequence such as "cams/cam0_%04d.png").
  std::vector<std::string> video_devices;
  BlobDetectorSettings detector;  // for video_devices
  // Coloured markers (tracking/detect/ColourDetector.h): the colour hand layouts
  // (assets/hands/colour-*.json) and, with video devices, colour images detected with the colour
  // model.
  bool colour_markers = false;
  std::filesystem::path colours;  // the colour model (empty: default_colour_model())
  // Camera nodes (rhot-node, docs/camera-nodes.md): their publish endpoints, each NAME@ENDPOINT
  // with keys. Each node says which rig cameras its frames are from.
  std::vector<std::string> node_endpoints;
  // The master's key folder for the nodes (tracking/net/CurveKeys.h), or none: no security.
  NetSecurity node_security;
  DebugViews debug;

  // Every value a user can set checked: "<name>: <what is wrong>" for the first bad one.
  [[nodiscard]] std::expected<void, std::string> check() const;
  // The rig file these settings name for `scene` (see rig_file).
  [[nodiscard]] std::filesystem::path rig_for(const SceneDesc& scene) const;
};

// What a source of the application's own is built from, once the scene's tracked objects and the
// hand layouts are known.
struct SourceRequest {
  const CameraRig& rig;  // the rig file's cameras
  const std::array<HandLayout, 2>& layouts;
  const TrackedObjects& objects;
  const ColourModel& colours;  // with colour markers
  double rate_hz = 90.0;       // the headset's refresh (the scene's)
};
struct CustomSource {
  std::unique_ptr<FrameSource> source;
  // The rig the tracker believes, when it is not the one the frames were taken with (a simulated
  // calibration error); empty: the rig file's.
  std::optional<CameraRig> tracker_rig;
};
using SourceFactory = std::function<std::expected<CustomSource, std::string>(const SourceRequest&)>;

// The two hand layouts of assets/hands (low-cost-*.json, or colour-*.json for coloured markers),
// checked against each other and the objects' stars (check_hand_stars).
[[nodiscard]] std::expected<std::array<HandLayout, 2>, std::string> default_hand_layouts(const std::filesystem::path& asset_dir,
                                                                                         const StarSet& object_stars,
                                                                                         bool colour_markers = false);

class Launch {
 public:
  Launch(const Launch&) = delete;
  Launch& operator=(const Launch&) = delete;

  // Fails naming what is wrong: bad settings, a rig, star set or hand layout that cannot be read,
  // video devices that cannot be opened or do not fit the rig, a recording that cannot be read or
  // written, a physics error, and no source at all (no replay, video devices or camera nodes, and
  // no `custom` factory). `custom` is asked only when the settings name none of the three.
  [[nodiscard]] static std::expected<std::unique_ptr<Launch>, std::string> create(const SceneDesc& scene, Renderer* renderer,
                                                                                  const LaunchSettings& settings,
                                                                                  const SourceFactory& custom = {});

  Runtime& runtime() { return *runtime_; }
  // Live tracking, unless replaying.
  LiveTracking* live() { return live_; }

 private:
  Launch() = default;
  LiveTracking* live_ = nullptr;
  std::unique_ptr<Runtime> runtime_;
};

}  // namespace rhot
