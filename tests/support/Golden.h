#pragma once
// Golden-image checks for frame-capture tests.
//
// Goldens live in tests/golden/NAME.png and are rendered on the CPU driver (lavapipe), so they
// are the same on every machine. A pixel differs when it is more than 8 (of 255) in some channel
// from every pixel within 1 px of the same place in the golden (and the other way round). A
// capture matches when at most 0.1 % and at most 100 of its pixels differ and no cluster of
// differing pixels that cannot be found within 3 px either is larger than 6 pixels
// (ImageCompare.h): that absorbs rasterisation differences at edges and an edge moved by a pixel,
// not a missing object, point or line. On a mismatch the capture and a diff image (differing pixels in red)
// are written to build/<preset>/test-output/.
//
// Regenerate deliberately, after checking the new pictures: RHOT_UPDATE_GOLDENS=1 ctest -R Golden

#include <cstdlib>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "tests/support/ImageCompare.h"

namespace rhot::testing {

inline void expect_matches_golden(const Image& actual, const std::string& name) {
  const std::filesystem::path golden = std::filesystem::path(RHOT_SOURCE_DIR) / "tests" / "golden" / (name + ".png");
  const char* update = std::getenv("RHOT_UPDATE_GOLDENS");
  if (update != nullptr && std::string(update) == "1") {
    const auto written = write_png(actual, golden);
    ASSERT_TRUE(written.has_value()) << written.error();
    GTEST_LOG_(INFO) << "updated golden " << golden;
    return;
  }
  const auto expected = read_png(golden);
  ASSERT_TRUE(expected.has_value()) << expected.error() << "\n(create it with RHOT_UPDATE_GOLDENS=1)";
  const ImageCompareResult r = compare_images(actual, *expected);
  if (!r.matches) {
    const std::filesystem::path out = std::filesystem::path(RHOT_BINARY_DIR) / "test-output";
    (void)write_png(actual, out / (name + "_actual.png"));
    if (r.diff.width > 0) (void)write_png(r.diff, out / (name + "_diff.png"));
    ADD_FAILURE() << name << ": " << r.summary << "\n  capture and diff written to " << out;
  }
}

}  // namespace rhot::testing
