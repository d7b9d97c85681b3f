#pragma once
// Camera images drawn from detections: each detection a Gaussian spot, as an infrared marker
// looks through a slightly defocused lens. For tests of the blob detector and the video source,
// and for rhot-simvideo (the demo's simulated cameras written as image sequences).

#include <cstdint>
#include <expected>
#include <string>

#include <opencv2/core/mat.hpp>

#include "tracking/camera/Camera.h"
#include "tracking/core/Frames.h"

namespace rhot {

struct SyntheticImageSettings {
  double blob_sigma_px = 1.5;  // the spot's Gaussian standard deviation
  double peak = 200.0;         // the spot's peak above the background, grey levels
  double background = 10.0;    // grey level where there is no spot
  double noise_sigma = 0.0;    // Gaussian noise added to every pixel, grey levels
  std::uint64_t seed = 1;      // for the noise

  // Every value usable: "<field>: <what was expected>, got <value>" for the first that is not.
  [[nodiscard]] std::expected<void, std::string> check() const;
};

// An 8-bit grey image (CV_8UC1) of the camera's calibrated size with a spot at every detection's
// pixel (pixel (0, 0) is the top-left pixel's centre, as in Camera.h). Overlapping spots add up;
// values are rounded and clipped to 0-255. Cost: (8 sigma)^2 pixels per spot, plus the noise.
cv::Mat draw_blobs(const CameraIntrinsics& camera, const CameraFrame& frame, const SyntheticImageSettings& settings = {});

}  // namespace rhot
