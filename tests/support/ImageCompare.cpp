#include "tests/support/ImageCompare.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <string>
#include <vector>

namespace rhot {

namespace {

// Largest absolute difference over the four channels of two RGBA pixels.
inline int channel_difference(const std::uint8_t* p, const std::uint8_t* q) {
  const int d0 = std::abs(p[0] - q[0]);
  const int d1 = std::abs(p[1] - q[1]);
  const int d2 = std::abs(p[2] - q[2]);
  const int d3 = std::abs(p[3] - q[3]);
  const int d01 = d0 > d1 ? d0 : d1;
  const int d23 = d2 > d3 ? d2 : d3;
  return d01 > d23 ? d01 : d23;
}

// channel_difference(p, q) <= tolerance for 0 <= tolerance <= 255, without branches: the search
// runs this up to 2 (2r+1)^2 times per pixel, and on noisy content unpredictable branches made a
// debug build four times slower (1.1 s instead of 0.25 s for 2160x1200, every pixel differing).
inline bool within(const std::uint8_t* p, const std::uint8_t* q, unsigned tolerance) {
  const unsigned span = 2 * tolerance;
  return (static_cast<unsigned>(p[0] - q[0] + static_cast<int>(tolerance)) <= span) &
         (static_cast<unsigned>(p[1] - q[1] + static_cast<int>(tolerance)) <= span) &
         (static_cast<unsigned>(p[2] - q[2] + static_cast<int>(tolerance)) <= span) &
         (static_cast<unsigned>(p[3] - q[3] + static_cast<int>(tolerance)) <= span);
}

// True when some pixel of `other` in the window [x0, x1] x [y0, y1] (already clipped to it) has
// every channel within `tolerance` of the pixel `p`.
bool has_match_in(const std::uint8_t* p, const Image& other, int x0, int x1, int y0, int y1, unsigned tolerance) {
  for (int y = y0; y <= y1; ++y) {
    const std::uint8_t* q = other.pixel(x0, y);
    for (int x = x0; x <= x1; ++x, q += 4) {
      if (within(p, q, tolerance)) return true;
    }
  }
  return false;
}

// True when the pixel at (x, y) has a match within `radius` both ways: actual's pixel somewhere
// near in expected, and expected's somewhere near in actual.
bool matched_within(const Image& actual, const Image& expected, int x, int y, int radius, unsigned tolerance) {
  const int x0 = std::max(x - radius, 0);
  const int x1 = std::min(x + radius, expected.width - 1);
  const int y0 = std::max(y - radius, 0);
  const int y1 = std::min(y + radius, expected.height - 1);
  return has_match_in(actual.pixel(x, y), expected, x0, x1, y0, y1, tolerance) &&
         has_match_in(expected.pixel(x, y), actual, x0, x1, y0, y1, tolerance);
}

// The largest 8-connected cluster of the differing pixels (`differing`: their indices y * w + x in
// increasing order) that do not match within `displacement_radius` either.
int largest_unexplained_cluster(const Image& actual, const Image& expected, const std::vector<std::size_t>& differing,
                                int displacement_radius, unsigned tolerance) {
  const auto w = static_cast<std::size_t>(expected.width);
  std::vector<std::size_t> unexplained;
  for (const std::size_t i : differing) {
    if (!matched_within(actual, expected, static_cast<int>(i % w), static_cast<int>(i / w), displacement_radius, tolerance)) {
      unexplained.push_back(i);
    }
  }
  // Still in increasing order: neighbours are found by binary search.
  std::vector<bool> seen(unexplained.size(), false);
  std::vector<std::size_t> stack;
  int largest = 0;
  for (std::size_t start = 0; start < unexplained.size(); ++start) {
    if (seen[start]) continue;
    seen[start] = true;
    stack.assign(1, start);
    int size = 0;
    while (!stack.empty()) {
      const std::size_t i = unexplained[stack.back()];
      stack.pop_back();
      ++size;
      const int x = static_cast<int>(i % w);
      const int y = static_cast<int>(i / w);
      for (int ny = std::max(y - 1, 0); ny <= std::min(y + 1, expected.height - 1); ++ny) {
        for (int nx = std::max(x - 1, 0); nx <= std::min(x + 1, expected.width - 1); ++nx) {
          const std::size_t j = static_cast<std::size_t>(ny) * w + static_cast<std::size_t>(nx);
          const auto it = std::lower_bound(unexplained.begin(), unexplained.end(), j);
          if (it == unexplained.end() || *it != j) continue;
          const auto k = static_cast<std::size_t>(it - unexplained.begin());
          if (seen[k]) continue;
          seen[k] = true;
          stack.push_back(k);
        }
      }
    }
    largest = std::max(largest, size);
  }
  return largest;
}

std::string percent(double fraction) {
  const double pc = 100.0 * fraction;
  if (pc > 0.0 && pc < 0.0005) return "<0.001%";
  std::array<char, 64> text{};
  std::snprintf(text.data(), text.size(), "%.3f%%", pc);
  return text.data();
}

}  // namespace

ImageCompareResult compare_images(const Image& actual, const Image& expected, const ImageCompareSettings& settings) {
  ImageCompareResult r;
  if (!well_formed(actual) || !well_formed(expected)) {
    r.summary = std::string(!well_formed(actual) ? "actual" : "expected") +
                " image is malformed: " + describe(!well_formed(actual) ? actual : expected);
    return r;
  }
  if (actual.width != expected.width || actual.height != expected.height) {
    r.summary = "size " + describe(actual) + " differs from expected " + describe(expected);
    return r;
  }
  if (expected.rgba.empty()) {
    r.summary = "both images are empty (" + describe(expected) + ")";
    return r;
  }

  // A tolerance of 255 or more accepts every pixel; clamping keeps within()'s arithmetic exact.
  const int tolerance = std::clamp(settings.channel_tolerance, 0, 255);
  const int radius = std::max(settings.search_radius_px, 0);
  const int w = expected.width;
  const int h = expected.height;
  const auto tol = static_cast<unsigned>(tolerance);
  const long long total = static_cast<long long>(w) * h;
  // Beyond either count limit the images do not match whatever the clusters: differing positions
  // are kept only up to it (the fraction's rounded down, plus one for rounding), so an image
  // differing everywhere costs no more than before.
  const double fraction_limit = std::floor(settings.max_differing_fraction * static_cast<double>(total)) + 1.0;
  const long long kept_limit = fraction_limit < static_cast<double>(settings.max_differing_pixels)
                                   ? static_cast<long long>(std::max(fraction_limit, 0.0))
                                   : std::max(0LL, static_cast<long long>(settings.max_differing_pixels));
  std::vector<std::size_t> differing;
  r.diff = Image(w, h);
  for (int y = 0; y < h; ++y) {
    const int y0 = std::max(y - radius, 0);
    const int y1 = std::min(y + radius, h - 1);
    const std::uint8_t* a = actual.pixel(0, y);
    const std::uint8_t* e = expected.pixel(0, y);
    std::uint8_t* d = r.diff.pixel(0, y);
    for (int x = 0; x < w; ++x, a += 4, e += 4, d += 4) {
      const int plain = channel_difference(a, e);
      r.max_channel_difference = std::max(r.max_channel_difference, plain);
      bool differs = false;
      if (plain > tolerance) {
        const int x0 = std::max(x - radius, 0);
        const int x1 = std::min(x + radius, w - 1);
        differs = !has_match_in(a, expected, x0, x1, y0, y1, tol) || !has_match_in(e, actual, x0, x1, y0, y1, tol);
      }
      if (differs) {
        if (r.differing_pixels < kept_limit)
          differing.push_back(static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x));
        ++r.differing_pixels;
        d[0] = 255;
        d[1] = 0;
        d[2] = 0;
      } else {
        // Rec. 601 luma in 8-bit fixed point (weights sum to 256), then a third of it.
        const int luma = (77 * e[0] + 150 * e[1] + 29 * e[2]) >> 8;
        d[0] = d[1] = d[2] = static_cast<std::uint8_t>(luma / 3);
      }
      d[3] = 255;
    }
  }

  r.differing_fraction = static_cast<double>(r.differing_pixels) / static_cast<double>(total);
  const bool fraction_ok = r.differing_fraction <= settings.max_differing_fraction;
  const bool count_ok = r.differing_pixels <= settings.max_differing_pixels;
  bool clusters_ok = false;
  if (fraction_ok && count_ok) {
    const int displacement = std::max(settings.displacement_radius_px, radius);
    r.largest_cluster_px = largest_unexplained_cluster(actual, expected, differing, displacement, tol);
    clusters_ok = r.largest_cluster_px <= settings.max_cluster_px;
  }
  r.matches = fraction_ok && count_ok && clusters_ok;
  r.summary = std::to_string(r.differing_pixels) + " of " + std::to_string(total) + " pixels differ (" + percent(r.differing_fraction) +
              ", allowed " + percent(settings.max_differing_fraction) + "); largest channel difference " +
              std::to_string(r.max_channel_difference);
  if (fraction_ok && !count_ok) {
    r.summary += "; at most " + std::to_string(settings.max_differing_pixels) + " pixels may differ";
  } else if (fraction_ok && !clusters_ok) {
    r.summary += "; a cluster of " + std::to_string(r.largest_cluster_px) + " unexplained differing pixels (allowed " +
                 std::to_string(settings.max_cluster_px) + ")";
  }
  return r;
}

}  // namespace rhot
