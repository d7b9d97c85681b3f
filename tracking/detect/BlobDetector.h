#pragma once
// Bright round markers in a camera image -> sub-pixel 2D detections.
//
// 1. Threshold: a fixed grey level, or (the default) an automatic one per image: the background's
//    median + auto_k * its noise (1.4826 * median absolute deviation, from the histogram), never
//    below min_threshold. Median and MAD ignore the markers however many there are (up to half
//    the pixels), so the threshold sits just above the background's noise. (Otsu's method splits
//    the histogram into two large classes and, with markers covering well under 1 % of the
//    pixels, lands inside the background's noise; mean + k sigma rises with every marker.)
// 2. Connected components of the thresholded image (8-connected, found by tracing their outer
//    contours with cv::findContours, far cheaper than labelling every pixel).
// 3. Each component within [min_area_px, max_area_px] is measured from its pixels: the centroid
//    weighted by (intensity - threshold), so a weight fades to zero at the blob's edge and the
//    centroid does not jump when an edge pixel crosses the threshold; and its shape from the
//    weighted second moments: elongation = major / minor axis (1 for a round spot).
// 4. A component too elongated (two markers whose images touch) is thresholded again halfway
//    between its threshold and its peak, up to `split_depth` times; parts that come out round are
//    detections (weighted by intensity above that higher level). A component that never splits
//    into round parts is dropped: one wrong point harms matching more than one missing point.
// 5. At most max_blobs detections, the brightest (largest summed weight) kept.
//
// Pixel coordinates follow Camera.h: (0, 0) is the centre of the top-left pixel.
// Cost: one pass over the image for the statistics and threshold, one for the labels, and a pass
// over each blob's bounding box.

#include <expected>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "tracking/core/Frames.h"

namespace rhot {

struct BlobDetectorSettings {
  // A fixed threshold in grey levels (0-255): pixels brighter than it belong to blobs. Negative
  // (the default): automatic, background median + auto_k * background noise, at least min_threshold.
  int threshold = -1;
  double auto_k = 5.0;
  int min_threshold = 40;       // automatic threshold's floor: a black or dim image yields nothing
  int min_area_px = 3;          // smaller components are noise or hot pixels
  int max_area_px = 2000;       // larger ones are lamps, reflections, the sun
  double max_elongation = 1.5;  // major / minor axis; a round spot 1, two touching spots 1.7 or more
  int split_depth = 6;          // times an elongated component is re-thresholded before it is dropped
  int max_blobs = 256;          // brightest kept
};

// Whether settings make sense; the message names the field and what was expected.
[[nodiscard]] std::expected<void, std::string> check(const BlobDetectorSettings& settings);

// The blobs in an 8-bit grey (CV_8UC1) or colour (CV_8UC3, BGR: converted to grey) image, in no
// particular order, without truth. Fails on bad settings (see check), an empty image or any other
// pixel type, naming it.
[[nodiscard]] std::expected<std::vector<Detection>, std::string> detect_blobs(const cv::Mat& image,
                                                                              const BlobDetectorSettings& settings = {});

}  // namespace rhot
