#pragma once
// Where camera frames come from. Every kind of input is one implementation of this interface: the
// simulated rig (tracking/sim/SimulatedRig.h), OpenCV video devices, video files and image
// sequences (VideoSource.h), and the coming camera nodes and colour cameras. The runtime asks for
// one multi-camera frame per tracking frame and never asks which kind it has.
//
// A frame carries, per camera of the rig, the 2D marker detections of one exposure with its
// capture timestamp; a source that reads images runs its detector before handing the frame over.
// A source with ground truth (the simulated rig) also fills the frame's truth fields, which the
// tracker never reads.

#include <optional>
#include <string>
#include <vector>

#include "tracking/camera/Camera.h"
#include "tracking/core/Frames.h"

namespace rhot {

class FrameSource {
 public:
  virtual ~FrameSource() = default;

  // The cameras the frames are from (the frame's camera i is rig().cameras[i]).
  virtual const CameraRig& rig() const = 0;

  // The frame for the runtime's clock at t_s (seconds since it started). Sources that follow a
  // clock of their own (devices, files) take their next frame whatever t_s is. Nothing once the
  // stream has ended (the files are over, every device is gone); a simulation never ends.
  virtual std::optional<RigFrame> next(double t_s) = 0;

  // Problems met since the last call that a user should hear of (bad images, failed reads), one
  // line each, already rate-limited by the source. Empty for sources that cannot have any.
  virtual std::vector<std::string> take_warnings() { return {}; }

  // One line per camera on what the stream delivered (frames, bad images), for the end of a run.
  virtual std::vector<std::string> summary() const { return {}; }
};

}  // namespace rhot
