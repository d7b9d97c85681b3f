// The golden-image comparison itself (tests/support/ImageCompare.h), on the CPU: what it must
// catch (a missing small object, a missing thin line, too many scattered differences) and what it
// must let through (isolated noise, an edge moved by a pixel or two), on images of the goldens'
// sizes and on the debug-layer golden itself.

#include "tests/support/ImageCompare.h"

#include <array>
#include <climits>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace rhot {
namespace {

using Rgba = std::array<std::uint8_t, 4>;

// The debug-layer golden's background (the clear colour) and its size (two 240 x 240 eyes).
constexpr Rgba kBackground{196, 206, 218, 255};
constexpr int kWidth = 480;
constexpr int kHeight = 240;

Image filled(int w, int h, Rgba colour) {
  Image im(w, h);
  for (std::size_t i = 0; i < im.rgba.size(); ++i) im.rgba[i] = colour[i % 4];
  return im;
}

void set(Image& im, int x, int y, Rgba colour) {
  std::uint8_t* p = im.pixel(x, y);
  for (int c = 0; c < 4; ++c) p[c] = colour[static_cast<std::size_t>(c)];
}

Image golden(const std::string& name) {
  const auto image = read_png(std::filesystem::path(RHOT_SOURCE_DIR) / "tests" / "golden" / (name + ".png"));
  EXPECT_TRUE(image.has_value()) << image.error();
  return image.value_or(Image{});
}

// The old rule, before counts and clusters: only the fraction of differing pixels.
ImageCompareSettings fraction_only() {
  ImageCompareSettings s;
  s.max_differing_pixels = INT_MAX;
  s.max_cluster_px = INT_MAX;
  return s;
}

TEST(ImageCompare, AGoldenMatchesItself) {
  const Image expected = golden("debug_layer");
  ASSERT_EQ(expected.width, kWidth);
  ASSERT_EQ(expected.height, kHeight);
  const ImageCompareResult r = compare_images(expected, expected);
  EXPECT_TRUE(r.matches) << r.summary;
  EXPECT_EQ(r.differing_pixels, 0);
  EXPECT_EQ(r.largest_cluster_px, 0);
  EXPECT_EQ(r.summary, "0 of 115200 pixels differ (0.000%, allowed 0.100%); largest channel difference 0");
}

// The debug layer's ten magenta points (3 x 3 pixels drawn, 7 to 9 pixels each with their
// anti-aliased rims), one group per point, left to right. (The counts below are the committed
// golden's; a regenerated golden moves them a little.)
std::vector<std::vector<std::array<int, 2>>> debug_points(const Image& im) {
  std::vector<std::array<int, 2>> magenta;
  for (int x = 0; x < im.width; ++x) {
    for (int y = 0; y < im.height; ++y) {
      const std::uint8_t* p = im.pixel(x, y);
      if (p[0] > 120 && p[1] < 80 && p[2] > 120) magenta.push_back({x, y});
    }
  }
  // The points stand 17 pixels apart along a row: a gap of more than 2 columns starts a new one.
  std::vector<std::vector<std::array<int, 2>>> points;
  for (const auto& p : magenta) {
    if (points.empty() || p[0] - points.back().back()[0] > 2) points.emplace_back();
    points.back().push_back(p);
  }
  return points;
}

TEST(ImageCompare, TheDebugLayerWithoutItsPointsFails) {
  const Image expected = golden("debug_layer");
  const auto points = debug_points(expected);
  ASSERT_EQ(points.size(), 10u);
  Image without = expected;
  std::size_t painted = 0;
  for (const auto& point : points) {
    for (const auto& p : point) set(without, p[0], p[1], kBackground);
    painted += point.size();
  }
  ASSERT_EQ(painted, 82u);
  // 82 differing pixels were within the old 0.1 % (115 of 115 200): the fraction alone let the
  // picture through with every point missing.
  EXPECT_TRUE(compare_images(without, expected, fraction_only()).matches);
  const ImageCompareResult r = compare_images(without, expected);
  EXPECT_FALSE(r.matches);
  EXPECT_EQ(r.differing_pixels, 82);
  EXPECT_EQ(r.largest_cluster_px, 9);
  EXPECT_EQ(r.summary,
            "82 of 115200 pixels differ (0.071%, allowed 0.100%); largest channel difference 206; a cluster of 9 unexplained "
            "differing pixels (allowed 6)");
  // Any one point missing fails on its own, the smallest (7 pixels) included; and the other way
  // round, a point drawn that the golden lacks.
  for (std::size_t i = 0; i < points.size(); ++i) {
    Image one = expected;
    for (const auto& p : points[i]) set(one, p[0], p[1], kBackground);
    const ImageCompareResult missing = compare_images(one, expected);
    EXPECT_FALSE(missing.matches) << "point " << i << ": " << missing.summary;
    EXPECT_EQ(missing.largest_cluster_px, static_cast<int>(points[i].size())) << "point " << i;
    EXPECT_FALSE(compare_images(expected, one).matches) << "point " << i << " extra";
  }
}

// A thin line of exactly 100 pixels, 8-connected: 100 columns from (140, 60), one row lower
// every second column. On the debug layer's background, in its colour of the camera frustum.
Image with_line(const Image& background) {
  Image im = background;
  for (int i = 0; i < 100; ++i) set(im, 140 + i, 60 + i / 2, {255, 255, 0, 255});
  return im;
}

TEST(ImageCompare, AMissingThinLineFailsThoughFewPixelsDiffer) {
  const Image background = filled(kWidth, kHeight, kBackground);
  const Image line = with_line(background);
  // 100 pixels: within the fraction (115) and the count (100); only the cluster catches it.
  EXPECT_TRUE(compare_images(background, line, fraction_only()).matches);
  const ImageCompareResult missing = compare_images(background, line);
  EXPECT_FALSE(missing.matches);
  EXPECT_EQ(missing.differing_pixels, 100);
  EXPECT_EQ(missing.largest_cluster_px, 100);
  EXPECT_EQ(missing.summary,
            "100 of 115200 pixels differ (0.087%, allowed 0.100%); largest channel difference 218; a cluster of 100 unexplained "
            "differing pixels (allowed 6)");
  const ImageCompareResult extra = compare_images(line, background);
  EXPECT_FALSE(extra.matches);
  EXPECT_EQ(extra.largest_cluster_px, 100);
}

TEST(ImageCompare, ScatteredSinglePixelsPassUpToTheCount) {
  const Image expected = filled(kWidth, kHeight, kBackground);
  Image actual = expected;
  // 100 isolated pixels, 46 columns and 23 rows apart, each far off (white).
  for (int i = 0; i < 10; ++i) {
    for (int j = 0; j < 10; ++j) set(actual, 20 + 46 * i, 10 + 23 * j, {255, 255, 255, 255});
  }
  const ImageCompareResult r = compare_images(actual, expected);
  EXPECT_TRUE(r.matches) << r.summary;
  EXPECT_EQ(r.differing_pixels, 100);
  EXPECT_EQ(r.largest_cluster_px, 1);
  EXPECT_EQ(r.max_channel_difference, 59);
  // One more is beyond the count.
  set(actual, 3, 3, {255, 255, 255, 255});
  const ImageCompareResult over = compare_images(actual, expected);
  EXPECT_FALSE(over.matches);
  EXPECT_EQ(over.largest_cluster_px, -1) << "not measured beyond the count";
  EXPECT_EQ(over.summary,
            "101 of 115200 pixels differ (0.088%, allowed 0.100%); largest channel difference 59; at most 100 pixels may differ");
}

TEST(ImageCompare, TheCountHoldsWhereTheFractionWouldAllowThousands) {
  // A headset's eye, 1080 x 1200: 0.1 % is 1296 pixels, the count still 100.
  const Image expected = filled(1080, 1200, kBackground);
  Image actual = expected;
  for (int i = 0; i < 101; ++i) set(actual, 10 + 10 * i, 7 + 11 * i, {0, 0, 0, 255});
  const ImageCompareResult r = compare_images(actual, expected);
  EXPECT_FALSE(r.matches);
  EXPECT_EQ(r.differing_pixels, 101);
  EXPECT_TRUE(compare_images(actual, expected, fraction_only()).matches);
}

TEST(ImageCompare, ClustersOfUpToSixPixelsPass) {
  const Image expected = filled(kWidth, kHeight, kBackground);
  Image actual = expected;
  for (int x = 200; x < 202; ++x) {
    for (int y = 100; y < 103; ++y) set(actual, x, y, {255, 0, 255, 255});
  }
  const ImageCompareResult six = compare_images(actual, expected);
  EXPECT_TRUE(six.matches) << six.summary;
  EXPECT_EQ(six.largest_cluster_px, 6);
  set(actual, 202, 103, {255, 0, 255, 255});  // diagonal neighbours join a cluster
  const ImageCompareResult seven = compare_images(actual, expected);
  EXPECT_FALSE(seven.matches);
  EXPECT_EQ(seven.largest_cluster_px, 7);
  // Two clusters of four, a pixel apart, are two clusters.
  Image two = expected;
  for (int y = 100; y < 104; ++y) {
    set(two, 200, y, {255, 0, 255, 255});
    set(two, 202, y, {255, 0, 255, 255});
  }
  const ImageCompareResult apart = compare_images(two, expected);
  EXPECT_TRUE(apart.matches) << apart.summary;
  EXPECT_EQ(apart.largest_cluster_px, 4);
}

// A dark bar 40 x 10 pixels with its left edge at `left`.
Image with_bar(int left) {
  Image im = filled(kWidth, kHeight, kBackground);
  for (int x = left; x < left + 40; ++x) {
    for (int y = 100; y < 110; ++y) set(im, x, y, {60, 60, 60, 255});
  }
  return im;
}

TEST(ImageCompare, AnEdgeMovedByAPixelOrTwoIsNotMissingButOneMovedFourIs) {
  const Image expected = with_bar(100);
  // Moved by 2: more differs than the search radius of 1 absorbs, in clusters larger than 6, but
  // every colour is found within 3 pixels: nothing is missing.
  const ImageCompareResult two = compare_images(with_bar(102), expected);
  EXPECT_TRUE(two.matches) << two.summary;
  EXPECT_GT(two.differing_pixels, 6);
  EXPECT_EQ(two.largest_cluster_px, 0);
  const ImageCompareResult four = compare_images(with_bar(104), expected);
  EXPECT_FALSE(four.matches);
  EXPECT_GT(four.largest_cluster_px, 6);
}

}  // namespace
}  // namespace rhot
