#pragma once
// Where the engine's tracking results come from. Live tracking (LiveTracking.h: a frame source
// through matching, marker stars and hand fitting) and a recording played back (ReplaySource.h)
// are the two implementations; the runtime runs a source's stages in order each frame and never
// asks which kind it has.

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "engine/tracked/TrackingResults.h"
#include "tracking/camera/Camera.h"

namespace rhot {

// One timed step of a source's frame (the frame loop times each as a system of its own).
struct TrackingStage {
  std::string name;
  std::function<void(double t_s)> run;  // t_s: the runtime's clock
};

// A recording's playback speed, for sources that play something back.
class Playback {
 public:
  virtual ~Playback() = default;
  virtual double speed() const = 0;
  // From the next frame on. Precondition: finite and > 0.
  virtual void set_speed(double speed) = 0;
};

class ResultSource {
 public:
  ResultSource() = default;
  virtual ~ResultSource() = default;
  // Stages capture the source: it stays where it was made.
  ResultSource(const ResultSource&) = delete;
  ResultSource& operator=(const ResultSource&) = delete;

  // The stages of one frame, in order; after the last, results() holds the frame's results.
  virtual std::vector<TrackingStage> stages() = 0;

  // The last frame's results. Mutable: a system of the application may amend them before they are
  // copied into components (the demo's perfect hands replace the hands with the truth).
  virtual TrackingResults& results() = 0;

  // The cameras the results come from; nothing for a recording.
  virtual const CameraRig* rig() const { return nullptr; }

  // Whether the input is over (video files ran out); whoever runs the frame loop stops then
  // (rhot-demo does).
  virtual bool ended() const { return false; }

  // Playback controls, for a recording; nothing for live tracking.
  virtual Playback* playback() { return nullptr; }

  // Lines for the end of a run (per camera: frames delivered, bad images).
  virtual std::vector<std::string> summary() const { return {}; }
};

}  // namespace rhot
