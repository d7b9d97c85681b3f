#pragma once
// Camera images drawn from detections: each detection a Gaussian spot, as an infrared marker
// looks through a slightly defocused lens. For tests of the blob detector and the video source,
// and for rhot-simvideo (the demo's simulated cameras written as image sequences).

#include <array>
#include <cstdint>
#include <span>
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

// How a camera balanced for daylight (6500 K) sees a scene lit at `kelvin`: per channel (R, G, B)
// the factor its pixels are multiplied by, green 1. From the colour of a black body at that
// temperature (Tanner Helland's fit to Mitchell Charity's table), relative to 6500 K's: 3000 K
// gives about (1.6, 1, 0.5), a warm indoor light on a camera left at daylight.
std::array<double, 3> white_balance_gains(double kelvin);

// A coloured marker as a colour camera sees it: a shaded disc of a marker colour (MarkerColour.h).
struct ColourMarkerDrawing {
  Eigen::Vector2d pixel{0, 0};  // its centre (pixel (0, 0) the top-left pixel's centre)
  double radius_px = 4.0;
  int colour = 0;
};

struct ColourImageSettings {
  double noise_sigma = 2.0;  // per channel, levels
  double kelvin = 6500.0;    // the light (white_balance_gains); the camera stays balanced for 6500 K
  double exposure = 1.0;     // every pixel scaled by this before clipping
  bool clutter = true;       // skin, wood, cables and painted objects of the markers' colours
  std::uint64_t seed = 1;

  // Every value usable: "<field>: <what was expected>, got <value>" for the first that is not.
  [[nodiscard]] std::expected<void, std::string> check() const;
};

// An 8-bit BGR image (CV_8UC3) of markers over a table-coloured background: each marker a disc
// shaded like a lit sphere, its edge pixels mixed by their coverage (4 x 4 samples); with clutter
// also skin-coloured hands' patches, wood grain, thin cables and large boxes painted in the
// markers' own colours, none of them a marker; then the light's colour, exposure and noise. The
// markers' centres are the truth for a detector.
cv::Mat draw_colour_markers(int width_px, int height_px, std::span<const ColourMarkerDrawing> markers,
                            const ColourImageSettings& settings = {});

}  // namespace rhot
