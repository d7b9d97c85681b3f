#pragma once
// Frames from real cameras: one OpenCV capture per camera of a rig, in rig order, each image
// turned into detections by the blob detector (tracking/detect/BlobDetector.h), or, for coloured
// markers on colour cameras, by a colour detector per camera following its markers from image to
// image (tracking/detect/ColourDetector.h).
//
// A device is a capture device's index ("0") or a file: a video file (FFmpeg, else GStreamer), or an image sequence
// whose name holds a printf pattern ("cams/cam0_%04d.png", OpenCV's CAP_IMAGES, numbered from 0
// or the first number present). Timestamps: for files, frame i is at i / rate_hz (image sequences
// carry no time of their own); for devices, the steady clock's time of the grab, from open().
//
// Failure modes. open() fails, naming the camera and the device, when the device count differs
// from the rig's camera count, when a device cannot be opened or gives no first frame, or when its
// image size differs from the camera's calibrated size. In next(), a camera whose read fails or
// whose image is unusable (wrong size, a pixel type the detector does not take) contributes no
// detections to that frame and is counted in stats(); the stream ends when no camera delivers an
// image (the files are over, or every device is gone).

#include <chrono>
#include <cstdint>
#include <expected>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "tracking/camera/Camera.h"
#include "tracking/core/Frames.h"
#include "tracking/detect/BlobDetector.h"
#include "tracking/detect/ColourDetector.h"
#include "tracking/source/FrameSource.h"

namespace rhot {

class JobPool;

struct VideoSourceSettings {
  BlobDetectorSettings detector;
  std::optional<ColourModel> colours;  // coloured markers: detect these colours instead of bright blobs
  ColourDetectorSettings colour_detector;
  double rate_hz = 90.0;          // files' frame rate, for their timestamps
  int threads = 0;                // the cameras' images detected on this many threads (base/Jobs.h), 0: every core
  std::shared_ptr<JobPool> jobs;  // or on this pool, shared with the rest of the tracker (threads is then unused)
};

struct VideoCameraStats {
  std::uint64_t frames = 0;        // images read and detected
  std::uint64_t failed_reads = 0;  // reads that gave no image while another camera gave one
  std::uint64_t bad_images = 0;    // images read but unusable
  std::string last_problem;        // the latest failed read or bad image, in words
};

// "0,1" or "a_%04d.png,b_%04d.png" -> the devices, in order. Fails on an empty list or an empty
// entry, quoting the text.
[[nodiscard]] std::expected<std::vector<std::string>, std::string> parse_video_devices(const std::string& list);

class VideoSource final : public FrameSource {
 public:
  [[nodiscard]] static std::expected<VideoSource, std::string> open(const CameraRig& rig, const std::vector<std::string>& devices,
                                                                    VideoSourceSettings settings = {});
  VideoSource(VideoSource&&) noexcept;
  VideoSource& operator=(VideoSource&&) noexcept;
  ~VideoSource() override;

  // The next frame: one CameraFrame per camera (camera i at index i), detections without truth
  // and no truth positions. Nothing once the stream has ended.
  std::optional<RigFrame> next();
  // FrameSource: the next frame whatever t_s is (files and devices keep their own time).
  std::optional<RigFrame> next(double) override { return next(); }
  const CameraRig& rig() const override;
  // A camera's failed reads and bad images, told at the 1st, 10th, 100th ... of each kind.
  std::vector<std::string> take_warnings() override;
  // "camera 0 (DEV): N frames, B bad images, F failed reads" per camera.
  std::vector<std::string> summary() const override;

  bool ended() const;
  const std::vector<VideoCameraStats>& stats() const;
  const std::vector<std::string>& devices() const;

 private:
  struct Impl;
  explicit VideoSource(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace rhot
