#include "engine/render/Image.h"
#include "engine/render/PngWriter.h"
#include "tests/support/ImageCompare.h"

#include <array>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>

#include <gtest/gtest.h>

namespace rhot {
namespace {

using Rgba = std::array<std::uint8_t, 4>;

Rgba at(const Image& im, int x, int y) {
  const std::uint8_t* p = im.pixel(x, y);
  return {p[0], p[1], p[2], p[3]};
}

Image filled(int w, int h, std::uint8_t grey) {
  Image im(w, h);
  for (std::size_t i = 0; i < im.rgba.size(); ++i) im.rgba[i] = (i % 4 == 3) ? 255 : grey;
  return im;
}

void set_grey(Image& im, int x, int y, std::uint8_t grey) {
  std::uint8_t* p = im.pixel(x, y);
  p[0] = p[1] = p[2] = grey;
}

// A fresh folder per test under GoogleTest's temporary folder.
std::filesystem::path temp_dir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::filesystem::path dir =
      std::filesystem::path(::testing::TempDir()) / "rhot_image_test" / (std::string(info->test_suite_name()) + "." + info->name());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

void write_bytes(const std::filesystem::path& file, const std::string& bytes) { std::ofstream(file, std::ios::binary) << bytes; }

// --- PNG files ---

TEST(Png, RoundTripKeepsEveryByte) {
  Image im(7, 5);
  for (std::size_t i = 0; i < im.rgba.size(); ++i) im.rgba[i] = static_cast<std::uint8_t>(i * 37 + 11);
  const auto file = temp_dir() / "round.png";
  const auto written = write_png(im, file);
  ASSERT_TRUE(written.has_value()) << written.error();
  EXPECT_FALSE(std::filesystem::exists(file.string() + ".partial"));
  const auto back = read_png(file);
  ASSERT_TRUE(back.has_value()) << back.error();
  EXPECT_EQ(back->width, 7);
  EXPECT_EQ(back->height, 5);
  EXPECT_EQ(back->rgba, im.rgba);  // alpha included, not premultiplied
}

TEST(Png, WriteCreatesMissingFoldersAndReplacesAFile) {
  const auto file = temp_dir() / "a" / "b" / "frame.png";
  ASSERT_TRUE(write_png(filled(3, 2, 10), file).has_value());
  ASSERT_TRUE(write_png(filled(4, 1, 99), file).has_value());
  const auto back = read_png(file);
  ASSERT_TRUE(back.has_value()) << back.error();
  EXPECT_EQ(back->rgba, filled(4, 1, 99).rgba);
}

TEST(Png, WriteRefusesEmptyAndMalformedImages) {
  const auto file = temp_dir() / "bad.png";
  EXPECT_EQ(write_png(Image{}, file).error(), file.string() + ": cannot write PNG: the image is empty (0x0)");
  Image short_buffer(4, 4);
  short_buffer.rgba.resize(10);
  EXPECT_EQ(write_png(short_buffer, file).error(),
            file.string() + ": cannot write PNG: the image is malformed (4x4 with 10 bytes of RGBA (64 expected))");
  Image negative;
  negative.width = -3;
  negative.height = 2;
  EXPECT_EQ(write_png(negative, file).error(), file.string() + ": cannot write PNG: the image is malformed (-3x2 with 0 bytes of RGBA)");
  EXPECT_FALSE(std::filesystem::exists(file));
}

TEST(Png, WriteOverAFolderFailsAndNamesTheFile) {
  const auto dir = temp_dir();
  std::filesystem::create_directories(dir / "taken.png");
  const auto result = write_png(filled(2, 2, 0), dir / "taken.png");
  ASSERT_FALSE(result.has_value());
  EXPECT_EQ(result.error().rfind((dir / "taken.png").string() + ": cannot write PNG: ", 0), 0u) << result.error();
  EXPECT_FALSE(std::filesystem::exists((dir / "taken.png").string() + ".partial"));
}

TEST(Png, WriteUnderAFileFailsAndNamesTheFile) {
  const auto dir = temp_dir();
  write_bytes(dir / "plain_file", "x");
  const auto file = dir / "plain_file" / "frame.png";
  const auto result = write_png(filled(2, 2, 0), file);
  ASSERT_FALSE(result.has_value());
  const std::string prefix = file.string() + ": cannot write PNG: cannot create folder " + (dir / "plain_file").string();
  EXPECT_EQ(result.error().rfind(prefix, 0), 0u) << result.error();
}

TEST(PngWriter, WritesEveryQueuedImageOffTheCallersThread) {
  const auto dir = temp_dir();
  {
    PngWriter writer(2, 3);  // a queue shorter than the images: write() waits for room, drops nothing
    for (int i = 0; i < 12; ++i) writer.write(filled(9, 4, static_cast<std::uint8_t>(20 * i)), dir / ("f" + std::to_string(i) + ".png"));
    EXPECT_FALSE(writer.finish().has_value());
    EXPECT_EQ(writer.written(), 12U);
  }
  for (int i = 0; i < 12; ++i) {
    const auto back = read_png(dir / ("f" + std::to_string(i) + ".png"));
    ASSERT_TRUE(back.has_value()) << back.error();
    EXPECT_EQ(at(*back, 8, 3),
              (Rgba{static_cast<std::uint8_t>(20 * i), static_cast<std::uint8_t>(20 * i), static_cast<std::uint8_t>(20 * i), 255}));
  }
}

TEST(PngWriter, KeepsTheFirstFailureAndWritesTheRest) {
  const auto dir = temp_dir();
  std::filesystem::create_directories(dir / "taken.png");  // a folder where a file should go
  PngWriter writer(1);
  writer.write(filled(2, 2, 1), dir / "taken.png");
  writer.write(filled(2, 2, 1), dir / "fine.png");
  const auto failed = writer.finish();
  ASSERT_TRUE(failed.has_value());
  EXPECT_EQ(failed->rfind((dir / "taken.png").string() + ": cannot write PNG: ", 0), 0U) << *failed;
  EXPECT_EQ(writer.error(), failed);
  EXPECT_TRUE(std::filesystem::exists(dir / "fine.png"));
  EXPECT_EQ(writer.written(), 1U);
}

TEST(Png, ReadMissingFile) {
  const auto file = temp_dir() / "missing.png";
  EXPECT_EQ(read_png(file).error(), file.string() + ": file not found");
}

TEST(Png, ReadRefusesOtherFilesWithTheReason) {
  const auto dir = temp_dir();
  write_bytes(dir / "text.png", "not a picture");
  EXPECT_EQ(read_png(dir / "text.png").error(), (dir / "text.png").string() + ": not a PNG image: no PNG signature");
  write_bytes(dir / "empty.png", "");
  EXPECT_EQ(read_png(dir / "empty.png").error(), (dir / "empty.png").string() + ": not a PNG image: no PNG signature");
  // A JPEG's first bytes: stb could decode a JPEG, read_png must not.
  write_bytes(dir / "photo.jpg", std::string("\xff\xd8\xff\xe0\x00\x10JFIF\x00", 11));
  EXPECT_EQ(read_png(dir / "photo.jpg").error(), (dir / "photo.jpg").string() + ": not a PNG image: no PNG signature");
  EXPECT_EQ(read_png(dir).error(), dir.string() + ": is a folder, not a PNG image");
}

std::string file_bytes(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

TEST(Png, ReadRefusesATruncatedPng) {
  const auto dir = temp_dir();
  ASSERT_TRUE(write_png(filled(16, 16, 7), dir / "whole.png").has_value());
  write_bytes(dir / "cut.png", file_bytes(dir / "whole.png").substr(0, 40));
  const auto result = read_png(dir / "cut.png");
  ASSERT_FALSE(result.has_value());
  const std::string prefix = (dir / "cut.png").string() + ": not a PNG image: file truncated (no IEND chunk; stb says";
  EXPECT_EQ(result.error().rfind(prefix, 0), 0u) << result.error();
}

TEST(Png, ReadRefusesACorruptPngWithStbsReason) {
  const auto dir = temp_dir();
  ASSERT_TRUE(write_png(filled(16, 16, 7), dir / "whole.png").has_value());
  std::string bytes = file_bytes(dir / "whole.png");
  bytes[12] = 'X';  // the first chunk's name: "XHDR" instead of "IHDR"
  write_bytes(dir / "bad.png", bytes);
  const auto result = read_png(dir / "bad.png");
  ASSERT_FALSE(result.has_value());
  const std::string prefix = (dir / "bad.png").string() + ": not a PNG image: ";
  EXPECT_EQ(result.error().rfind(prefix, 0), 0u) << result.error();
  EXPECT_GT(result.error().size(), prefix.size()) << "stb's reason is missing";
  EXPECT_EQ(result.error().find("truncated"), std::string::npos) << result.error();
}

TEST(Png, ReadConvertsGreyToRgba) {
  // A 2x1 8-bit greyscale PNG (colour type 0, no alpha) with the values 0 and 200.
  static constexpr unsigned char kGrey[] = {0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48,
                                            0x44, 0x52, 0x00, 0x00, 0x00, 0x02, 0x00, 0x00, 0x00, 0x01, 0x08, 0x00, 0x00, 0x00,
                                            0x00, 0xd1, 0x49, 0x20, 0x56, 0x00, 0x00, 0x00, 0x0b, 0x49, 0x44, 0x41, 0x54, 0x78,
                                            0xda, 0x63, 0x60, 0x38, 0x01, 0x00, 0x00, 0xcb, 0x00, 0xc9, 0xfa, 0x6c, 0xb4, 0x8b,
                                            0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82};
  const auto file = temp_dir() / "grey.png";
  write_bytes(file, std::string(reinterpret_cast<const char*>(kGrey), sizeof(kGrey)));
  const auto im = read_png(file);
  ASSERT_TRUE(im.has_value()) << im.error();
  ASSERT_EQ(im->width, 2);
  ASSERT_EQ(im->height, 1);
  EXPECT_EQ(at(*im, 0, 0), (Rgba{0, 0, 0, 255}));
  EXPECT_EQ(at(*im, 1, 0), (Rgba{200, 200, 200, 255}));
}

// --- side_by_side ---

TEST(SideBySide, PutsLeftThenRightRowByRow) {
  Image left(3, 2);
  Image right(4, 2);
  for (int y = 0; y < 2; ++y) {
    for (int x = 0; x < 3; ++x) set_grey(left, x, y, static_cast<std::uint8_t>(10 * y + x));
    for (int x = 0; x < 4; ++x) set_grey(right, x, y, static_cast<std::uint8_t>(100 + 10 * y + x));
  }
  left.pixel(2, 1)[3] = 77;
  const Image s = side_by_side(left, right);
  ASSERT_EQ(s.width, 7);
  ASSERT_EQ(s.height, 2);
  ASSERT_EQ(s.rgba.size(), 7u * 2u * 4u);
  for (int y = 0; y < 2; ++y) {
    for (int x = 0; x < 3; ++x) EXPECT_EQ(at(s, x, y), at(left, x, y)) << x << "," << y;
    for (int x = 0; x < 4; ++x) EXPECT_EQ(at(s, 3 + x, y), at(right, x, y)) << x << "," << y;
  }
}

TEST(SideBySide, AnEmptySideAddsNothing) {
  const Image right = filled(4, 0, 0);
  EXPECT_EQ(side_by_side(Image(0, 3), filled(2, 3, 50)).rgba, filled(2, 3, 50).rgba);
  EXPECT_EQ(side_by_side(Image{}, right).width, 4);
}

TEST(SideBySideDeathTest, UnequalHeightsAreAPreconditionFailure) {
  EXPECT_DEATH((void)side_by_side(filled(3, 2, 0), filled(3, 4, 0)), "precondition.*heights differ.*3x2.*3x4");
}

// --- compare_images ---

TEST(Compare, IdenticalImagesMatch) {
  const ImageCompareResult r = compare_images(filled(16, 16, 90), filled(16, 16, 90));
  EXPECT_TRUE(r.matches);
  EXPECT_EQ(r.differing_pixels, 0);
  EXPECT_EQ(r.differing_fraction, 0.0);
  EXPECT_EQ(r.max_channel_difference, 0);
  EXPECT_EQ(r.summary, "0 of 256 pixels differ (0.000%, allowed 0.100%); largest channel difference 0");
  ASSERT_EQ(r.diff.width, 16);
  ASSERT_EQ(r.diff.height, 16);
  // Grey 90 has luma 90; dimmed to a third.
  EXPECT_EQ(at(r.diff, 5, 5), (Rgba{30, 30, 30, 255}));
}

// An anti-aliased vertical edge: dark, two blended columns, bright, starting at `edge_x`.
Image soft_edge(int edge_x) {
  Image im = filled(64, 64, 0);
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 64; ++x) {
      const int k = x - edge_x;
      set_grey(im, x, y, k < 0 ? 0 : k == 0 ? 64 : k == 1 ? 192 : 255);
    }
  }
  return im;
}

TEST(Compare, OnePixelShiftOfAnAntiAliasedEdgeMatchesOnlyWithTheSearch) {
  const Image expected = soft_edge(30);
  const Image actual = soft_edge(31);
  const ImageCompareResult searched = compare_images(actual, expected, {8, 1, 0.001});
  EXPECT_TRUE(searched.matches) << searched.summary;
  EXPECT_EQ(searched.differing_pixels, 0);
  EXPECT_EQ(searched.max_channel_difference, 128);  // 192 against 64 at x = 31

  // Without the search the three columns where the ramp sits differ: 3 * 64 pixels.
  const ImageCompareResult strict = compare_images(actual, expected, {8, 0, 0.001});
  EXPECT_FALSE(strict.matches);
  EXPECT_EQ(strict.differing_pixels, 192);
  EXPECT_EQ(strict.summary, "192 of 4096 pixels differ (4.688%, allowed 0.100%); largest channel difference 128");
  for (int x = 29; x <= 33; ++x) {
    const bool red = x >= 30 && x <= 32;
    EXPECT_EQ(at(strict.diff, x, 40)[1] == 0 && at(strict.diff, x, 40)[0] == 255, red) << "x = " << x;
  }
}

TEST(Compare, AShiftOfTwoPixelsIsNotAbsorbedByRadiusOne) {
  const ImageCompareResult r = compare_images(soft_edge(32), soft_edge(30), {8, 1, 0.001});
  EXPECT_FALSE(r.matches);
  EXPECT_EQ(r.differing_pixels, 4 * 64);  // x = 30..33: each side has a value the other lacks nearby
}

// A thin, 1-px line of exactly 100 pixels on a dark background: 60 across, then 40 down.
Image with_thin_line(const Image& background) {
  Image im = background;
  for (int x = 2; x < 62; ++x) set_grey(im, x, 20, 255);
  for (int y = 22; y < 62; ++y) set_grey(im, 50, y, 255);
  return im;
}

void expect_only_the_line_differs(const ImageCompareResult& r) {
  EXPECT_FALSE(r.matches);
  EXPECT_EQ(r.differing_pixels, 100);
  EXPECT_NEAR(r.differing_fraction, 100.0 / 4096.0, 1e-12);
  EXPECT_EQ(r.max_channel_difference, 215);
  EXPECT_EQ(r.summary, "100 of 4096 pixels differ (2.441%, allowed 0.100%); largest channel difference 215");
  const Image line = with_thin_line(filled(64, 64, 0));
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 64; ++x) {
      const bool on_line = line.pixel(x, y)[0] == 255;
      if (on_line) {
        ASSERT_EQ(at(r.diff, x, y), (Rgba{255, 0, 0, 255})) << x << "," << y;
      } else {
        ASSERT_EQ(at(r.diff, x, y), (Rgba{13, 13, 13, 255})) << x << "," << y;  // background 40 / 3
      }
    }
  }
}

TEST(Compare, AMissingThinLineFails) {
  const Image background = filled(64, 64, 40);
  SCOPED_TRACE("line expected, missing in actual");
  expect_only_the_line_differs(compare_images(background, with_thin_line(background)));
}

TEST(Compare, AnExtraThinLineFailsToo) {
  // The same comparison the other way round: the check is symmetric, so both fail alike. (A
  // one-way search of actual in expected would miss the missing line: every dark pixel of the
  // actual image has a dark neighbour in the expected one.)
  const Image background = filled(64, 64, 40);
  SCOPED_TRACE("line in actual, not expected");
  const ImageCompareResult r = compare_images(with_thin_line(background), background);
  EXPECT_FALSE(r.matches);
  EXPECT_EQ(r.differing_pixels, 100);
  EXPECT_EQ(r.summary, "100 of 4096 pixels differ (2.441%, allowed 0.100%); largest channel difference 215");
  EXPECT_EQ(at(r.diff, 10, 20), (Rgba{255, 0, 0, 255}));
  EXPECT_EQ(at(r.diff, 10, 21), (Rgba{13, 13, 13, 255}));
}

TEST(Compare, UniformBrightnessChangeAgainstTheTolerance) {
  const Image expected = filled(32, 32, 100);
  const Image brighter = filled(32, 32, 105);
  const ImageCompareResult within = compare_images(brighter, expected, {8, 1, 0.001});
  EXPECT_TRUE(within.matches) << within.summary;
  EXPECT_EQ(within.max_channel_difference, 5);
  const ImageCompareResult beyond = compare_images(brighter, expected, {4, 1, 0.001});
  EXPECT_FALSE(beyond.matches);
  EXPECT_EQ(beyond.differing_pixels, 32 * 32);
  EXPECT_EQ(beyond.summary, "1024 of 1024 pixels differ (100.000%, allowed 0.100%); largest channel difference 5");
  // The tolerance is inclusive.
  EXPECT_TRUE(compare_images(brighter, expected, {5, 0, 0.0}).matches);
}

TEST(Compare, AlphaCounts) {
  Image actual = filled(8, 8, 50);
  actual.pixel(3, 3)[3] = 0;
  const ImageCompareResult r = compare_images(actual, filled(8, 8, 50), {8, 1, 0.0});
  EXPECT_FALSE(r.matches);
  EXPECT_EQ(r.differing_pixels, 1);
  EXPECT_EQ(r.max_channel_difference, 255);
}

TEST(Compare, DifferingFractionUpToTheLimitMatches) {
  Image actual = filled(100, 10, 0);  // 1000 pixels: a limit of 0.001 allows one
  set_grey(actual, 50, 5, 255);
  EXPECT_TRUE(compare_images(actual, filled(100, 10, 0)).matches);
  set_grey(actual, 10, 2, 255);
  const ImageCompareResult r = compare_images(actual, filled(100, 10, 0));
  EXPECT_FALSE(r.matches);
  EXPECT_EQ(r.summary, "2 of 1000 pixels differ (0.200%, allowed 0.100%); largest channel difference 255");
}

TEST(Compare, DifferentSizesDoNotMatch) {
  const ImageCompareResult r = compare_images(filled(64, 64, 0), filled(32, 32, 0));
  EXPECT_FALSE(r.matches);
  EXPECT_EQ(r.summary, "size 64x64 differs from expected 32x32");
  EXPECT_EQ(r.diff.width, 0);
  EXPECT_TRUE(r.diff.rgba.empty());
}

TEST(Compare, MalformedOrEmptyImagesDoNotMatch) {
  Image broken(8, 8);
  broken.rgba.resize(5);
  EXPECT_EQ(compare_images(broken, filled(8, 8, 0)).summary, "actual image is malformed: 8x8 with 5 bytes of RGBA (256 expected)");
  EXPECT_EQ(compare_images(filled(8, 8, 0), broken).summary, "expected image is malformed: 8x8 with 5 bytes of RGBA (256 expected)");
  const ImageCompareResult empty = compare_images(Image{}, Image{});
  EXPECT_FALSE(empty.matches);
  EXPECT_EQ(empty.summary, "both images are empty (0x0)");
}

TEST(Compare, LargeFrameWithManyDifferencesStaysCorrect) {
  // A headset-sized frame (2160x1200) where every pixel differs: the worst case for the search.
  // (Speed is measured by hand, not asserted here; see Image.h.)
  const ImageCompareResult r = compare_images(filled(2160, 1200, 0), filled(2160, 1200, 255));
  EXPECT_FALSE(r.matches);
  EXPECT_EQ(r.differing_pixels, 2160 * 1200);
  EXPECT_EQ(r.summary, "2592000 of 2592000 pixels differ (100.000%, allowed 0.100%); largest channel difference 255");
}

}  // namespace
}  // namespace rhot
