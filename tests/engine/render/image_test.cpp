#include "engine/render/Image.h"

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

namespace rhot {
namespace {

Image filled(int w, int h, std::uint8_t v) {
  Image im(w, h);
  for (std::size_t i = 0; i < im.rgba.size(); ++i) im.rgba[i] = (i % 4 == 3) ? 255 : v;
  return im;
}

void set(Image& im, int x, int y, std::uint8_t v) {
  std::uint8_t* p = im.pixel(x, y);
  p[0] = p[1] = p[2] = v;
}

std::filesystem::path temp(const std::string& name) {
  return std::filesystem::path(::testing::TempDir()) / "rhot_image_test" / name;
}

TEST(Png, RoundTripIsExact) {
  Image im(7, 5);
  for (std::size_t i = 0; i < im.rgba.size(); ++i) im.rgba[i] = static_cast<std::uint8_t>(i * 37);
  ASSERT_TRUE(write_png(im, temp("round.png")).has_value());
  const auto back = read_png(temp("round.png"));
  ASSERT_TRUE(back.has_value()) << back.error();
  EXPECT_EQ(back->width, 7);
  EXPECT_EQ(back->height, 5);
  EXPECT_EQ(back->rgba, im.rgba);
}

TEST(Png, ErrorsNameTheFile) {
  EXPECT_EQ(read_png(temp("missing.png")).error(), temp("missing.png").string() + ": file not found");
  std::filesystem::create_directories(temp(""));
  std::ofstream(temp("text.png")) << "not a picture";
  EXPECT_EQ(read_png(temp("text.png")).error().rfind(temp("text.png").string() + ": not a PNG image: ", 0), 0u);
  EXPECT_EQ(write_png(Image{}, temp("empty.png")).error(),
            temp("empty.png").string() + ": cannot write an empty or malformed image (0x0, 0 bytes)");
}

TEST(Image, SideBySidePutsLeftThenRight) {
  const Image s = side_by_side(filled(3, 2, 10), filled(4, 2, 200));
  EXPECT_EQ(s.width, 7);
  EXPECT_EQ(s.height, 2);
  EXPECT_EQ(s.pixel(2, 1)[0], 10);
  EXPECT_EQ(s.pixel(3, 0)[0], 200);
}

TEST(Compare, IdenticalImagesMatch) {
  const ImageCompareResult r = compare_images(filled(16, 16, 90), filled(16, 16, 90));
  EXPECT_TRUE(r.matches);
  EXPECT_EQ(r.differing_pixels, 0);
  EXPECT_EQ(r.summary, "0 of 256 pixels differ (0.000%, allowed 0.100%); largest channel difference 0");
}

TEST(Compare, OnePixelShiftOfAnEdgePassesOnlyWithTheSearch) {
  Image a = filled(64, 64, 0);
  Image b = filled(64, 64, 0);
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 64; ++x) {
      if (x >= 32) set(a, x, y, 255);
      if (x >= 33) set(b, x, y, 255);
    }
  }
  EXPECT_TRUE(compare_images(a, b, {8, 1, 0.001}).matches);
  const ImageCompareResult strict = compare_images(a, b, {8, 0, 0.001});
  EXPECT_FALSE(strict.matches);
  EXPECT_EQ(strict.differing_pixels, 64);
}

TEST(Compare, MissingOrExtraThinLineFailsBothWays) {
  const Image plain = filled(64, 64, 0);
  Image line = plain;
  for (int x = 0; x < 64; ++x) set(line, x, 20, 255);
  using Pair = std::pair<const Image*, const Image*>;
  for (const auto& [actual, expected] : {Pair{&plain, &line}, Pair{&line, &plain}}) {
    const ImageCompareResult r = compare_images(*actual, *expected);
    EXPECT_FALSE(r.matches);
    EXPECT_EQ(r.differing_pixels, 64);
    EXPECT_EQ(r.max_channel_difference, 255);
    EXPECT_EQ(r.diff.pixel(10, 20)[0], 255);
    EXPECT_EQ(r.diff.pixel(10, 20)[1], 0);
    EXPECT_EQ(r.diff.pixel(10, 21)[0], r.diff.pixel(10, 21)[1]) << "matching pixels are grey";
  }
}

TEST(Compare, ToleranceOnBrightness) {
  EXPECT_TRUE(compare_images(filled(8, 8, 105), filled(8, 8, 100), {8, 1, 0.001}).matches);
  EXPECT_FALSE(compare_images(filled(8, 8, 105), filled(8, 8, 100), {4, 1, 0.001}).matches);
}

TEST(Compare, DifferentSizesDoNotMatch) {
  const ImageCompareResult r = compare_images(filled(64, 64, 0), filled(32, 32, 0));
  EXPECT_FALSE(r.matches);
  EXPECT_EQ(r.summary, "size 64x64 differs from expected 32x32");
}

}  // namespace
}  // namespace rhot
