#pragma once
// Coloured markers in a colour camera image -> sub-pixel detections that carry their colour.
//
// 1. One pass over the image (or over the regions of interest, below): each pixel's colour from
//    the ColourTable (ColourModel.h) in one load, collected into runs of one colour per row.
// 2. Connected components of runs of the same colour (8-connected, union-find over the runs of
//    neighbouring rows), so two markers of different colours that touch stay two blobs.
// 3. Each component is measured over its runs' pixels: the centroid weighted by each pixel's
//    membership (a pixel at the edge of the colour's window, a mixed edge pixel, counts little),
//    its shape from the unweighted second moments. It is a marker when its area is within
//    [min_area_px, max_area_px], its elongation (major / minor axis) at most max_elongation, its
//    fill (its pixels over the ellipse of its moments) at least min_fill, and its confidence (the
//    mean membership) at least min_confidence: skin, wood and painted objects that reach a colour
//    window do so in large, ragged or pale regions, and a partly hidden marker is not round.
//    A blob too elongated for one marker but no more than two discs side by side (two markers of
//    one colour whose images touch) is cut across its major axis where it is narrowest within
//    3 px of its centroid: when both halves are round, full and of similar size, with a waist
//    between them, each is a marker. A blob not one round disc that the cut does not part (three
//    or more markers touching: a star seen edge-on) is tried as several discs: one peak of its
//    distance transform per disc, a waist between neighbours, the discs covering the blob and
//    lying inside it; each marker at a circle fitted to the outline nearest its peak.
//    A partly hidden marker (behind its own finger, an edge) is a disc with a bite: a blob that
//    is not quite round (elongation above 1.15) or fails the shape tests is tried as one. A
//    circle fitted to its edge pixels on the far side from the bite must hold the whole blob,
//    carry edge pixels along one arc of at least 120 degrees and be covered at least 30 % by the
//    blob; the marker is then at the circle's centre, not at the visible part's centroid (which
//    leans away from the bite by a pixel or two). Thinner slivers are not markers.
// 4. At most max_blobs detections, the largest kept.
//
// Tracking (track()): each frame searches first in a region around each marker of the last frame,
// moved by its last motion; when fewer markers of a colour are found than were there, or every
// full_scan_every frames (new markers coming into view), the whole image is searched instead.
//
// Pixel coordinates follow Camera.h: (0, 0) is the centre of the top-left pixel.

#include <cstdint>
#include <expected>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "tracking/core/Frames.h"
#include "tracking/detect/ColourModel.h"

namespace rhot {

struct ColourDetectorSettings {
  int min_area_px = 6;
  int max_area_px = 700;  // a 14 mm marker 0.3 m from a 640 x 480 camera (f 630 px) covers about 680
  double max_elongation = 2.1;
  double min_fill = 0.55;
  double min_confidence = 0.5;
  int roi_margin_px = 12;    // a region of interest: the marker's last box grown by this, plus its motion
  int full_scan_every = 30;  // frames; 1: every frame searches the whole image
  int max_blobs = 128;
  // Follow the light (for a model with a white reference): on every whole-image search, compare
  // the image's median R, G and B with the model's white reference and, where they differ by
  // more than 2 %, rebuild the table with
  // the gains that balance one to the other (about 2 ms, on the first image and after the light
  // changes).
  bool white_balance = true;

  // Every value usable: "<field>: <what was expected>, got <value>" for the first that is not.
  [[nodiscard]] std::expected<void, std::string> check() const;
};

class ColourDetector {
 public:
  // Preconditions: model.check() and settings.check() pass.
  explicit ColourDetector(const ColourModel& model, ColourDetectorSettings settings = {});

  // The markers in a whole 8-bit BGR image (CV_8UC3), in no particular order, without truth.
  // Fails on an empty image or another pixel type, naming it. Forgets what was tracked.
  [[nodiscard]] std::expected<std::vector<Detection>, std::string> detect(const cv::Mat& bgr);
  // The next image of a sequence (same size), searched around the last image's markers first.
  [[nodiscard]] std::expected<std::vector<Detection>, std::string> track(const cv::Mat& bgr);
  // Forgets the markers tracked: the next track() searches the whole image.
  void reset();

  // Whether the last detect() or track() searched the whole image, and how many pixels it read.
  bool last_full_scan() const { return last_full_; }
  std::int64_t last_pixels_read() const { return last_pixels_; }
  const ColourTable& table() const { return table_; }
  const ColourDetectorSettings& settings() const { return settings_; }

 private:
  struct Run {
    int y, x0, x1;  // pixels [x0, x1) of row y
    int klass;      // 1 + index into the model's classes
    int parent;
  };
  struct Tracked {
    Eigen::Vector2d pixel;
    Eigen::Vector2d velocity{0, 0};
    double radius_px;
    int colour;
  };
  void scan(const cv::Mat& bgr, const cv::Rect& rect);
  std::vector<Detection> measure(const cv::Mat& bgr, const std::vector<cv::Rect>& rects);
  void remember(const std::vector<Detection>& detections);

  void balance(const cv::Mat& bgr);

  ColourTable table_;
  ColourDetectorSettings settings_;
  std::vector<Run> runs_;
  std::vector<Tracked> tracked_;
  cv::Size size_{0, 0};
  int frames_since_full_ = 0;
  bool last_full_ = true;
  std::int64_t last_pixels_ = 0;
};

}  // namespace rhot
