// Image files and capture through the module opened on first use (tracking/media/Media.h): the
// images come back bit for bit, every failure names the file and why, and a program that has not
// asked for an image has not mapped OpenCV's imgcodecs.

#include <link.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "tests/support/TempDir.h"
#include "tracking/media/Media.h"

namespace rhot {
namespace {

namespace fs = std::filesystem;

bool mapped(const std::string& name) {
  struct Search {
    std::string name;
    bool found = false;
  } search{name};
  dl_iterate_phdr(
      [](dl_phdr_info* info, std::size_t, void* data) {
        auto* s = static_cast<Search*>(data);
        if (info->dlpi_name != nullptr && std::string(info->dlpi_name).find(s->name) != std::string::npos) s->found = true;
        return 0;
      },
      &search);
  return search.found;
}

bool same_pixels(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0.0;
}

TEST(Media, NothingOfImgcodecsIsMappedBeforeTheFirstImage) {
  // Each test is a process of its own under ctest; run alone, this one must come first.
  EXPECT_FALSE(mapped("libopencv_imgcodecs")) << "the program maps imgcodecs at start";
  EXPECT_FALSE(mapped("libopencv_videoio"));
  EXPECT_FALSE(mapped("librhot_media"));
  const fs::path dir = test::fresh_test_dir("Media");
  ASSERT_TRUE(write_image(dir / "x.png", cv::Mat(4, 4, CV_8UC1, cv::Scalar(7))).has_value());
  EXPECT_TRUE(mapped("librhot_media"));
  EXPECT_TRUE(mapped("libopencv_imgcodecs"));
}

TEST(Media, PngImagesComeBackBitForBit) {
  const fs::path dir = test::fresh_test_dir("Media");
  cv::Mat grey(48, 64, CV_8UC1);
  cv::Mat colour(48, 64, CV_8UC3);
  cv::Mat deep(48, 64, CV_16UC1);
  cv::RNG rng(7);
  rng.fill(grey, cv::RNG::UNIFORM, 0, 256);
  rng.fill(colour, cv::RNG::UNIFORM, 0, 256);
  rng.fill(deep, cv::RNG::UNIFORM, 0, 65536);
  ASSERT_TRUE(write_image(dir / "grey.png", grey).has_value());
  ASSERT_TRUE(write_image(dir / "colour.png", colour, 1).has_value());
  ASSERT_TRUE(write_image(dir / "deep.png", deep, 9).has_value());

  auto g = read_image(dir / "grey.png", ImageRead::kGrey);
  ASSERT_TRUE(g.has_value()) << g.error();
  EXPECT_TRUE(same_pixels(*g, grey));
  auto c = read_image(dir / "colour.png", ImageRead::kColour);
  ASSERT_TRUE(c.has_value()) << c.error();
  EXPECT_TRUE(same_pixels(*c, colour));
  auto d = read_image(dir / "deep.png", ImageRead::kUnchanged);
  ASSERT_TRUE(d.has_value()) << d.error();
  EXPECT_TRUE(same_pixels(*d, deep));
  // Read as grey, a colour image is converted (one channel, 8-bit), not refused.
  auto as_grey = read_image(dir / "colour.png", ImageRead::kGrey);
  ASSERT_TRUE(as_grey.has_value());
  EXPECT_EQ(as_grey->type(), CV_8UC1);
}

TEST(Media, FailuresNameTheFileAndWhy) {
  const fs::path dir = test::fresh_test_dir("Media");
  const fs::path missing = dir / "missing.png";
  EXPECT_EQ(read_image(missing, ImageRead::kGrey).error(), missing.string() + ": no such file");
  const fs::path text = dir / "text.png";
  std::ofstream(text) << "not an image\n";
  EXPECT_EQ(read_image(text, ImageRead::kColour).error(),
            text.string() + ": cannot read the image (not a format OpenCV reads, or damaged)");
  const fs::path nowhere = dir / "no-such-folder" / "x.png";
  const auto unwritable = write_image(nowhere, cv::Mat(4, 4, CV_8UC1, cv::Scalar(0)));
  ASSERT_FALSE(unwritable.has_value());
  EXPECT_EQ(unwritable.error().rfind(nowhere.string() + ": cannot write the image", 0), 0u) << unwritable.error();
  EXPECT_EQ(write_image(dir / "empty.png", cv::Mat()).error(),
            (dir / "empty.png").string() + ": cannot write the image: the image is empty");
  const auto no_encoder = write_image(dir / "x.nosuchformat", cv::Mat(4, 4, CV_8UC1, cv::Scalar(0)));
  ASSERT_FALSE(no_encoder.has_value());
  EXPECT_EQ(no_encoder.error().rfind((dir / "x.nosuchformat").string() + ": cannot write the image: ", 0), 0u) << no_encoder.error();
  EXPECT_FALSE(fs::exists(dir / "empty.png"));
}

TEST(Media, AnImageSequenceIsReadInOrderAndEnds) {
  const fs::path dir = test::fresh_test_dir("Media");
  for (int i = 0; i < 3; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "cam_%04d.png", i);
    ASSERT_TRUE(write_image(dir / name, cv::Mat(6, 8, CV_8UC1, cv::Scalar(10 * (i + 1)))).has_value());
  }
  auto capture = VideoCapture::open((dir / "cam_%04d.png").string(), VideoCapture::Kind::kImageSequence);
  ASSERT_TRUE(capture.has_value());
  VideoCapture moved = std::move(*capture);  // a capture moves: the handle goes with it
  for (int i = 0; i < 3; ++i) {
    cv::Mat image;
    ASSERT_TRUE(moved.read(image)) << "frame " << i;
    ASSERT_EQ(image.size(), cv::Size(8, 6));
    EXPECT_EQ(image.at<cv::Vec3b>(0, 0)[0], 10 * (i + 1)) << "frame " << i;  // CAP_IMAGES gives BGR
  }
  cv::Mat after;
  EXPECT_FALSE(moved.read(after));
  EXPECT_TRUE(after.empty());
  EXPECT_FALSE(VideoCapture::open((dir / "none_%04d.png").string(), VideoCapture::Kind::kImageSequence).has_value());
  EXPECT_FALSE(VideoCapture::open((dir / "none.avi").string(), VideoCapture::Kind::kVideoFile).has_value());
}

// The module is looked for once per process, so each way of missing it runs in a child process.
void expect_module_refused(const char* module, const std::string& why) {
  EXPECT_EXIT(
      {
        setenv("RHOT_MEDIA_MODULE", module, 1);
        const auto loaded = media_module();
        std::fprintf(stderr, "%s\n", loaded ? "loaded" : loaded.error().c_str());
        const auto read = read_image(RHOT_ASSET_DIR "/../README.md", ImageRead::kGrey);
        std::fprintf(stderr, "%s\n", read ? "read" : read.error().c_str());
        std::exit(loaded ? 1 : 0);
      },
      ::testing::ExitedWithCode(0), why);
}

TEST(Media, AModuleThatIsMissingOrNotRhotsIsRefusedWithTheReason) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  expect_module_refused("/nonexistent/librhot_media.so",
                        "image files and video capture need rhot's media module \\(librhot_media.so\\): /nonexistent/librhot_media.so: "
                        "cannot open shared object file: No such file or directory \\(the file RHOT_MEDIA_MODULE names\\)");
  expect_module_refused("libm.so.6", "libm.so.6: not rhot's media module \\(no rhot_media_module_api\\)");
  // A call that needs the module says why it failed, after the file it was for.
  expect_module_refused("libm.so.6", "README.md: cannot read the image: image files and video capture need rhot's media module");
}

}  // namespace
}  // namespace rhot
