#pragma once
// The 2D detections of a calibration session: per frame, the pixels where each camera saw a
// marker, with the marker's id where it is known (the ends of a wand told apart, the corners of
// an L-frame numbered). Read from rhot's CSV or a MultiCamSelfCal data folder, written as CSV.
//
// rhot's CSV, one detection a line (a header line and lines starting with # are skipped):
//
//   frame,camera,x,y[,marker]
//   0,0,412.31,208.77,0
//
// `frame` is a non-negative integer (the exposure; frames need not be consecutive), `camera` the
// 0-based index of the camera in the rig, `x`,`y` the distorted pixel (OpenCV's convention: (0, 0)
// is the centre of the top-left pixel), `marker` a non-negative id, or -1 / absent when unknown.
//
// A MultiCamSelfCal folder holds points.dat (3 rows per camera: x, y, 1, one column per frame),
// IdMat.dat (one row per camera: 1 where the camera saw the LED in that frame) and optionally
// Res.dat (one row per camera: image width and height). Its pixels are MATLAB's (1, 1) at the
// top-left pixel's centre; they are shifted by -1 into OpenCV's convention when read.

#include <expected>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace rhot {

struct MarkerObservation {
  int camera = 0;
  Eigen::Vector2d pixel{0, 0};
  int marker = -1;  // -1: unknown
};

struct DetectionFrame {
  long frame = 0;
  std::vector<MarkerObservation> observations;
};

struct Detections {
  int camera_count = 0;                         // 1 + the highest camera index seen, or the folder's camera count
  std::vector<DetectionFrame> frames;           // in increasing frame order, each frame once
  std::vector<Eigen::Vector2i> image_sizes_px;  // per camera, when the source says (MultiCamSelfCal's Res.dat)
  std::size_t count() const;                    // observations in all frames
};

// rhot's CSV. Errors name the file and line: "FILE:LINE: expected 4 or 5 comma-separated fields
// (frame,camera,x,y[,marker]), got 3".
[[nodiscard]] std::expected<Detections, std::string> read_detections_csv(const std::filesystem::path& file);
[[nodiscard]] std::expected<void, std::string> write_detections_csv(const Detections& detections, const std::filesystem::path& file);

// A MultiCamSelfCal data folder (points.dat, IdMat.dat, optionally Res.dat).
[[nodiscard]] std::expected<Detections, std::string> read_multicamselfcal(const std::filesystem::path& folder);

// Either of the above: a folder is read as MultiCamSelfCal's, a file as rhot's CSV.
[[nodiscard]] std::expected<Detections, std::string> read_detections(const std::filesystem::path& path);

// One marker in one frame as the cameras saw it: the unit of a calibration's 3D points.
struct PointTrack {
  long frame = 0;
  int marker = -1;
  std::vector<std::pair<int, Eigen::Vector2d>> views;  // (camera, distorted pixel), one per camera at most
};

struct TrackSplit {
  std::vector<PointTrack> tracks;
  std::size_t ambiguous = 0;  // observations dropped: a camera saw several unlabelled blobs in one frame
};

// Groups the observations into tracks: by (frame, marker) where markers are labelled; where they
// are not, a frame is one track. A camera that saw more than one blob of one marker (or more than
// one unlabelled blob) in a frame is left out of that track: its blobs cannot be told apart. In a
// frame with labelled markers, unlabelled blobs are strays and are dropped. Dropped blobs are
// counted as ambiguous. Tracks seen by fewer than two cameras are dropped.
TrackSplit split_tracks(const Detections& detections);

}  // namespace rhot
