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
// line is caught as surely as an extra one.
//
// The images match when all three hold:
// - at most `max_differing_fraction` of the pixels differ;
// - at most `max_differing_pixels` differ (the fraction alone allows thousands in a large frame);
// - no 8-connected cluster of *unexplained* differing pixels is larger than `max_cluster_px`. A
//   differing pixel is explained when the same two-way check passes with the wider
//   `displacement_radius_px`: an edge that moved by a pixel or two (an object a little elsewhere)
//   then counts against the two limits above only. What cannot be found nearby at all is missing
//   or extra: scattered single pixels of noise pass, but a missing small object (one debug point,
//   3x3 pixels, makes a cluster of 7 to 9) or a missing thin line (a cluster as long as the line)
//   fails however few pixels it has.
// The defaults pass the goldens of tests/golden as rendered at 2026-11-25 (the demo's frames
// differ from theirs by up to 31 pixels, their largest unexplained cluster 4 pixels: the red
// cube's edge a pixel or two from where it was, its side face no longer seen) and fail the
// debug-layer golden with its ten points missing (82 pixels in clusters of 7 to 9).
struct ImageCompareSettings {
  int channel_tolerance = 8;
  int search_radius_px = 1;
  double max_differing_fraction = 0.001;
  int max_differing_pixels = 100;
  int displacement_radius_px = 3;
  int max_cluster_px = 6;
};

struct ImageCompareResult {
  bool matches = false;
  int differing_pixels = 0;
  double differing_fraction = 0.0;
  int max_channel_difference = 0;  // largest plain per-pixel difference, no search
  // The largest 8-connected cluster of unexplained differing pixels (see above). Measured only
  // when the differing pixels are within both count limits; -1 when not measured (the images
  // do not match anyway).
  int largest_cluster_px = -1;
  Image diff;           // differing pixels in red over a dimmed grey copy of expected
  std::string summary;  // one line for a test failure message
};

// Precondition-free: images of different sizes, empty or malformed images simply do not match
// (the summary says why, `diff` is then empty). A negative tolerance or radius counts as 0, a
// displacement radius below the search radius as the search radius.
// The diff image has the size of `expected`: differing pixels are pure red (255, 0, 0, 255), the
// others the expected pixel's luma at a third of its brightness, opaque.
// The summary always gives the count and fraction of differing pixels against the fraction
// allowed and the largest channel difference; where the fraction is within its limit but another
// limit is not, it adds that limit, e.g. "; a cluster of 9 unexplained differing pixels (allowed 6)".
// Cost: one pass over the pixels; only a pixel whose plain difference exceeds the tolerance
// searches its (2r+1)^2 neighbourhood, so near-identical frames cost about a plain comparison.
// 2160x1200 in a debug build: about 50 ms nearly identical, 0.25 s with every pixel differing.
// The clusters cost a second pass only when the count is within its limits (at most
// max_differing_pixels pixels to search and group).
ImageCompareResult compare_images(const Image& actual, const Image& expected, const ImageCompareSettings& settings = {});

}  // namespace rhot
