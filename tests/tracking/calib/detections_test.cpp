// Detections: rhot's CSV and MultiCamSelfCal folders read, written and split into point tracks.

#include "tracking/calib/Detections.h"

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

namespace {

namespace fs = std::filesystem;

fs::path temp_dir() {
  const fs::path d = fs::path(::testing::TempDir()) / "rhot_detections" / ::testing::UnitTest::GetInstance()->current_test_info()->name();
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

fs::path write_file(const fs::path& file, const std::string& text) {
  std::ofstream(file) << text;
  return file;
}

TEST(Detections, CsvRoundTripsWithAndWithoutMarkers) {
  const fs::path dir = temp_dir();
  const fs::path file =
      write_file(dir / "d.csv", "frame,camera,x,y,marker\n# a comment\n3,0,10.5,20.25,0\n3,1,11,21,1\n1,2,5,6\n7,0,1,2,-1\n");
  const auto d = rhot::read_detections_csv(file);
  ASSERT_TRUE(d) << d.error();
  EXPECT_EQ(d->camera_count, 3);
  ASSERT_EQ(d->frames.size(), 3u);
  EXPECT_EQ(d->frames[0].frame, 1);  // sorted by frame
  EXPECT_EQ(d->frames[1].frame, 3);
  ASSERT_EQ(d->frames[1].observations.size(), 2u);
  EXPECT_EQ(d->frames[1].observations[1].marker, 1);
  EXPECT_DOUBLE_EQ(d->frames[1].observations[0].pixel.y(), 20.25);
  EXPECT_EQ(d->frames[0].observations[0].marker, -1);
  EXPECT_EQ(d->count(), 4u);
  ASSERT_TRUE(rhot::write_detections_csv(*d, dir / "again.csv"));
  const auto again = rhot::read_detections_csv(dir / "again.csv");
  ASSERT_TRUE(again) << again.error();
  ASSERT_EQ(again->frames.size(), d->frames.size());
  for (std::size_t f = 0; f < d->frames.size(); ++f) {
    ASSERT_EQ(again->frames[f].observations.size(), d->frames[f].observations.size());
    for (std::size_t i = 0; i < d->frames[f].observations.size(); ++i) {
      EXPECT_NEAR((again->frames[f].observations[i].pixel - d->frames[f].observations[i].pixel).norm(), 0.0, 1e-4);
      EXPECT_EQ(again->frames[f].observations[i].marker, d->frames[f].observations[i].marker);
    }
  }
}

TEST(Detections, BrokenCsvLinesAreNamedByLine) {
  const fs::path dir = temp_dir();
  struct Case {
    std::string text;
    std::string message;
  };
  const std::vector<Case> cases{
      {"frame,camera,x,y\n0,0,1,2\n0,1,3\n", ":3: expected 4 or 5 comma-separated fields (frame,camera,x,y[,marker]), got 3"},
      {"0,0,1,2\n-1,0,1,2\n", ":2: frame: expected a non-negative integer, got \"-1\""},
      {"0,0,1,2\n1,x,1,2\n", ":2: camera: expected a camera index 0 to 255, got \"x\""},
      {"0,0,nan,2\n", ":1: x: expected a finite number, got \"nan\""},
      {"0,0,1,inf\n", ":1: y: expected a finite number, got \"inf\""},
      {"0,0,1,2,-2\n", ":1: marker: expected -1 (unknown) or a marker id 0 to 1000000, got \"-2\""},
      {"0,0,1e300,2\n", ":1: x,y: expected a pixel within 1e6 of the image, got 1e300,2"},
  };
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const fs::path file = write_file(dir / ("bad" + std::to_string(i) + ".csv"), cases[i].text);
    const auto d = rhot::read_detections_csv(file);
    ASSERT_FALSE(d) << cases[i].text;
    EXPECT_EQ(d.error(), file.string() + cases[i].message);
  }
  EXPECT_EQ(rhot::read_detections_csv(dir / "missing.csv").error(), (dir / "missing.csv").string() + ": detections file not found");
  const fs::path empty = write_file(dir / "empty.csv", "frame,camera,x,y\n");
  EXPECT_EQ(rhot::read_detections_csv(empty).error(), empty.string() + ": no detections (expected lines frame,camera,x,y[,marker])");
}

TEST(Detections, MultiCamSelfCalFolderIsReadInOpenCvPixels) {
  const fs::path dir = temp_dir();
  // Two cameras, three frames; camera 1 misses frame 0 (its NaN is masked by IdMat).
  write_file(dir / "points.dat", "11 12 13\n21 22 23\n1 1 1\nNaN 32 33\n41 42 43\n1 1 1\n");
  write_file(dir / "IdMat.dat", "1 1 1\n0 1 1\n");
  write_file(dir / "Res.dat", "640 480\n752 480\n");
  const auto d = rhot::read_detections(dir);
  ASSERT_TRUE(d) << d.error();
  EXPECT_EQ(d->camera_count, 2);
  ASSERT_EQ(d->frames.size(), 3u);
  ASSERT_EQ(d->frames[0].observations.size(), 1u);
  EXPECT_DOUBLE_EQ(d->frames[0].observations[0].pixel.x(), 10.0);  // MATLAB's (1, 1) is OpenCV's (0, 0)
  EXPECT_DOUBLE_EQ(d->frames[0].observations[0].pixel.y(), 20.0);
  ASSERT_EQ(d->frames[2].observations.size(), 2u);
  EXPECT_DOUBLE_EQ(d->frames[2].observations[1].pixel.x(), 32.0);
  ASSERT_EQ(d->image_sizes_px.size(), 2u);
  EXPECT_EQ(d->image_sizes_px[1], Eigen::Vector2i(752, 480));

  write_file(dir / "IdMat.dat", "1 1 1\n0 1\n");
  EXPECT_EQ(rhot::read_detections(dir).error(), (dir / "IdMat.dat").string() + ": row 2 has 2 frames, row 1 has 3");
  write_file(dir / "IdMat.dat", "1 1 1\n1 1 1\n");
  EXPECT_EQ(rhot::read_detections(dir).error(),
            (dir / "points.dat").string() + ": camera 1 frame 0: IdMat.dat marks it seen but its pixel is not finite");
  fs::remove(dir / "points.dat");
  EXPECT_EQ(rhot::read_detections(dir).error(), dir.string() + ": no points.dat (not a MultiCamSelfCal folder)");
}

TEST(Detections, TracksGroupLabelledMarkersAndDropAmbiguousBlobs) {
  rhot::Detections d;
  d.camera_count = 3;
  // Frame 0: a labelled wand (markers 0 and 1) in cameras 0 and 1, marker 0 also in camera 2.
  d.frames.push_back({0, {{0, {1, 1}, 0}, {0, {2, 2}, 1}, {1, {3, 3}, 0}, {1, {4, 4}, 1}, {2, {5, 5}, 0}}});
  // Frame 1: one unlabelled marker; camera 2 sees two blobs and cannot tell which is the marker.
  d.frames.push_back({1, {{0, {1, 1}, -1}, {1, {2, 2}, -1}, {2, {3, 3}, -1}, {2, {4, 4}, -1}}});
  // Frame 2: seen by one camera only.
  d.frames.push_back({2, {{0, {1, 1}, -1}}});
  // Frame 3: marker 0 twice in camera 0 (a reflection labelled like it): neither is kept; a stray
  // unlabelled blob in a labelled frame is dropped.
  d.frames.push_back({3, {{0, {1, 1}, 0}, {0, {9, 9}, 0}, {1, {2, 2}, 0}, {2, {3, 3}, 0}, {1, {7, 7}, -1}}});
  const rhot::TrackSplit split = rhot::split_tracks(d);
  ASSERT_EQ(split.tracks.size(), 4u);
  EXPECT_EQ(split.ambiguous, 2u + 2u + 1u);
  int views = 0;
  for (const auto& t : split.tracks) views += static_cast<int>(t.views.size());
  EXPECT_EQ(views, 3 + 2 + 2 + 2);
  const rhot::PointTrack& last = split.tracks.back();
  EXPECT_EQ(last.frame, 3);
  for (const auto& [camera, pixel] : last.views) EXPECT_NE(camera, 0);
}

}  // namespace
