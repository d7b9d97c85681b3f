#pragma once
// Comparing a rendered frame with its golden image (test support: no runtime code uses this).

#include <string>

#include "engine/render/Image.h"

namespace rhot {

// Tolerance for comparing a rendered frame with its golden image. Rasterisers differ a little at
// edges (coverage, rounding), so a pixel counts as matching when some pixel of the other image
// within `search_radius_px` (a square window: diagonal neighbours count) has every channel,
// alpha included, within `channel_tolerance` (of 255). The check runs both ways (actual against
// expected and expected against actual; a position differs when either fails) so a missing thin
// line is caught as surely as an extra one. The images match when at most
// `max_differing_fraction` of the pixels differ.
struct ImageCompareSettings {
  int channel_tolerance = 8;
  int search_radius_px = 1;
  double max_differing_fraction = 0.001;
};

struct ImageCompareResult {
  bool matches = false;
  int differing_pixels = 0;
  double differing_fraction = 0.0;
  int max_channel_difference = 0;  // largest plain per-pixel difference, no search
  Image diff;                      // differing pixels in red over a dimmed grey copy of expected
  std::string summary;             // one line for a test failure message
};

// Precondition-free: images of different sizes, empty or malformed images simply do not match
// (the summary says why, `diff` is then empty). A negative tolerance or radius counts as 0.
// The diff image has the size of `expected`: differing pixels are pure red (255, 0, 0, 255), the
// others the expected pixel's luma at a third of its brightness, opaque.
// Cost: one pass over the pixels; only a pixel whose plain difference exceeds the tolerance
// searches its (2r+1)^2 neighbourhood, so near-identical frames cost about a plain comparison.
// 2160x1200 in a debug build: about 50 ms nearly identical, 0.25 s with every pixel differing.
ImageCompareResult compare_images(const Image& actual, const Image& expected, const ImageCompareSettings& settings = {});

}  // namespace rhot
