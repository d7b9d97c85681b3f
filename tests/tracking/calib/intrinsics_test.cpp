// Intrinsics from rendered board pictures (tracking/sim/BoardImages) against the camera they were
// rendered with, and the messages bad input gets.

#include "tracking/media/Media.h"
#include "tracking/calib/Intrinsics.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "tracking/sim/BoardImages.h"

namespace rhot {
namespace {

namespace fs = std::filesystem;

fs::path temp_dir() {
  const fs::path d = fs::path(::testing::TempDir()) / "rhot_intrinsics" / ::testing::UnitTest::GetInstance()->current_test_info()->name();
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// A webcam-like lens: barrel distortion, a little tangential, the principal point off centre.
CameraIntrinsics webcam(int width, int height, double fx) {
  CameraIntrinsics k;
  k.width_px = width;
  k.height_px = height;
  k.fx = fx;
  k.fy = fx * 1.002;
  k.cx = 0.5 * width + 7.3;
  k.cy = 0.5 * height - 4.6;
  k.distortion = {-0.15, 0.06, 0.0008, -0.0005, 0.0};
  return k;
}

BoardLayout chess_layout() {
  BoardLayout layout;
  layout.pattern = BoardPattern::chess;
  layout.cols = 9;
  layout.rows = 6;
  layout.spacing_m = 0.025;
  return layout;
}

std::vector<fs::path> render_views(const fs::path& dir, const CameraIntrinsics& camera, const BoardLayout& layout, int views,
                                   const BoardRenderSettings& base = {}) {
  std::vector<fs::path> files;
  const std::vector<Rigid3d> poses = board_poses(camera, layout, views, 7);
  EXPECT_EQ(static_cast<int>(poses.size()), views);
  for (std::size_t i = 0; i < poses.size(); ++i) {
    BoardRenderSettings settings = base;
    settings.seed = 100 + i;
    char name[32];
    std::snprintf(name, sizeof name, "view_%02zu.png", i);
    files.push_back(dir / name);
    EXPECT_TRUE(rhot::write_image(files.back().string(), render_board(camera, poses[i], layout, settings)).has_value());
  }
  return files;
}

// The largest difference, over a grid across the image, between the pixel displacements the two
// distortion models apply to the same ray (each scaled by its own focal lengths).
double max_distortion_difference_px(const CameraIntrinsics& truth, const CameraIntrinsics& estimate) {
  const Camera camera{"truth", truth, Rigid3d::identity()};
  double worst = 0.0;
  for (int gy = 0; gy <= 18; ++gy) {
    for (int gx = 0; gx <= 32; ++gx) {
      const Eigen::Vector2d pixel(gx * (truth.width_px - 1) / 32.0, gy * (truth.height_px - 1) / 18.0);
      const Eigen::Vector2d n = camera.undistort(pixel);
      const Eigen::Vector2d dt = distort_normalised(truth.distortion, n) - n;
      const Eigen::Vector2d de = distort_normalised(estimate.distortion, n) - n;
      const Eigen::Vector2d difference(truth.fx * dt.x() - estimate.fx * de.x(), truth.fy * dt.y() - estimate.fy * de.y());
      worst = std::max(worst, difference.norm());
    }
  }
  return worst;
}

TEST(Intrinsics, RecoversTheRenderedCameraFromChessboardPictures) {
  const fs::path dir = temp_dir();
  const CameraIntrinsics truth = webcam(1280, 720, 1000.0);
  BoardRenderSettings settings;
  settings.noise_sigma = 1.0;
  settings.blur_sigma_px = 0.7;
  const std::vector<fs::path> files = render_views(dir, truth, chess_layout(), 20, settings);
  const auto board = parse_board_spec("chess:9x6:25");
  ASSERT_TRUE(board.has_value()) << board.error();
  int progress_calls = 0;
  const auto views = detect_boards(files, *board, [&](int index, int count, const std::string& name) {
    ++progress_calls;
    EXPECT_EQ(count, 20);
    EXPECT_EQ(name, files[static_cast<std::size_t>(index - 1)].filename().string());
  });
  ASSERT_TRUE(views.has_value()) << views.error();
  EXPECT_EQ(progress_calls, 20);
  const auto report = calibrate_intrinsics(*views);
  ASSERT_TRUE(report.has_value()) << report.error();
  ASSERT_EQ(report->views.size(), 20u) << "the board is found in every picture";

  const CameraIntrinsics& k = report->intrinsics;
  const double fx_error = std::abs(k.fx / truth.fx - 1.0), fy_error = std::abs(k.fy / truth.fy - 1.0);
  const double distortion_error_px = max_distortion_difference_px(truth, k);
  std::printf("fx error %.4f %%, fy error %.4f %%, cx %+.3f px, cy %+.3f px, distortion %.4f px, rms %.4f px, leave-one-out %.4f px\n",
              100 * fx_error, 100 * fy_error, k.cx - truth.cx, k.cy - truth.cy, distortion_error_px, report->rms_px,
              report->leave_one_out_rms_px.value_or(-1.0));
  EXPECT_LT(fx_error, 0.001);
  EXPECT_LT(fy_error, 0.001);
  EXPECT_NEAR(k.cx, truth.cx, 1.0);
  EXPECT_NEAR(k.cy, truth.cy, 1.0);
  EXPECT_LT(distortion_error_px, 0.1);
  EXPECT_EQ(k.distortion[4], 0.0) << "k3 is fixed by default";
  EXPECT_TRUE(report->k3_fixed);
  EXPECT_EQ(k.width_px, 1280);
  EXPECT_EQ(k.height_px, 720);

  // Noise of 1 grey level and slight blur: corners to a few hundredths of a pixel.
  EXPECT_LT(report->rms_px, 0.1);
  ASSERT_TRUE(report->leave_one_out_rms_px.has_value());
  EXPECT_TRUE(std::isfinite(*report->leave_one_out_rms_px));
  EXPECT_GE(*report->leave_one_out_rms_px, report->rms_px * 0.99) << "a held-out view cannot fit better than the views fitted";
  EXPECT_LT(*report->leave_one_out_rms_px, 0.15);
  for (const ViewResult& v : report->views) {
    ASSERT_TRUE(v.held_out_rms_px.has_value()) << v.name;
    EXPECT_TRUE(std::isfinite(v.rms_px));
    EXPECT_EQ(v.residuals_px.size(), 54u);
    EXPECT_EQ(v.corners_px.size(), 54u);
    EXPECT_GT(v.tilt_deg, 5.0) << v.name;
    EXPECT_LT(v.tilt_deg, 50.0) << v.name;
  }
  EXPECT_EQ(report->worst_views.size(), 3u);
  EXPECT_GT(report->orientation_spread_deg, 40.0);
  EXPECT_GT(report->coverage, 0.5);
  EXPECT_TRUE(report->warnings.empty()) << report->warnings.front();
  EXPECT_GT(report->fx_sigma, 0.0);
  EXPECT_LT(report->fx_sigma, 1.0);
}

TEST(Intrinsics, CircleGridsAndCharucoBoardsCalibrateToo) {
  const fs::path dir = temp_dir();
  const CameraIntrinsics truth = webcam(800, 600, 700.0);
  struct Case {
    const char* spec;
    double fx_tolerance;          // relative
    double distortion_tolerance;  // pixels, across the image
  };
  // Looser than for the chessboard: circle centres carry perspective bias (an ellipse's centre is
  // not the projected circle centre), and these boards give fewer points (ChArUco: 24 a view, some
  // views only part of them), so the image's edges are extrapolated from further away.
  for (const Case c :
       {Case{"circles:7x6:20", 0.005, 0.3}, Case{"acircles:4x11:15", 0.005, 0.3}, Case{"charuco:7x5:30:20:4X4_50", 0.002, 0.5}}) {
    SCOPED_TRACE(c.spec);
    const auto board = parse_board_spec(c.spec);
    ASSERT_TRUE(board.has_value()) << board.error();
    BoardLayout layout;
    layout.cols = board->cols;
    layout.rows = board->rows;
    layout.spacing_m = board->square_mm / 1000.0;
    layout.circle_diameter = 0.5;
    if (board->kind == BoardKind::charuco) {
      const auto picture = board_picture(*board, 60);
      ASSERT_TRUE(picture.has_value()) << picture.error();
      layout.pattern = BoardPattern::texture;
      layout.texture = cv::Mat(picture->height_px, picture->width_px, CV_8UC1, const_cast<std::uint8_t*>(picture->grey.data())).clone();
      layout.texture_corner_m = picture->corner_board_m;
      layout.texel_m = picture->pixel_m;
    } else {
      layout.pattern = board->kind == BoardKind::circles ? BoardPattern::circles : BoardPattern::asymmetric_circles;
    }
    const fs::path sub = dir / std::string(c.spec).substr(0, 4);
    fs::create_directories(sub);
    const std::vector<fs::path> files = render_views(sub, truth, layout, 12);
    const auto views = detect_boards(files, *board);
    ASSERT_TRUE(views.has_value()) << views.error();
    IntrinsicsSettings settings;
    settings.leave_one_out = false;
    const auto report = calibrate_intrinsics(*views, settings);
    ASSERT_TRUE(report.has_value()) << report.error();
    EXPECT_GE(report->views.size(), 10u);
    EXPECT_FALSE(report->leave_one_out_rms_px.has_value());
    const double fx_error = std::abs(report->intrinsics.fx / truth.fx - 1.0);
    const double distortion_error_px = max_distortion_difference_px(truth, report->intrinsics);
    std::printf("%s: %zu views, fx error %.4f %%, rms %.4f px, distortion %.4f px\n", c.spec, report->views.size(), 100 * fx_error,
                report->rms_px, distortion_error_px);
    EXPECT_LT(fx_error, c.fx_tolerance);
    EXPECT_LT(distortion_error_px, c.distortion_tolerance);
    EXPECT_LT(report->rms_px, 0.3);
  }
}

TEST(Intrinsics, PoorViewsAreCalibratedButWarnedAbout) {
  const fs::path dir = temp_dir();
  const CameraIntrinsics truth = webcam(640, 480, 600.0);
  const BoardLayout layout = chess_layout();
  // Five views, the board facing the camera near the image centre: too few, too little of the
  // image, too little tilt.
  std::vector<fs::path> files;
  for (int i = 0; i < 5; ++i) {
    Rigid3d camera_from_board;
    camera_from_board.rotation =
        Eigen::AngleAxisd(0.06 * i, Eigen::Vector3d(1, 1, 0).normalized()) * Eigen::AngleAxisd(0.1 * i, Eigen::Vector3d::UnitZ());
    camera_from_board.translation = Eigen::Vector3d(-0.1 + 0.005 * i, -0.06, 0.9);
    files.push_back(dir / ("v" + std::to_string(i) + ".png"));
    ASSERT_TRUE(rhot::write_image(files.back().string(), render_board(truth, camera_from_board, layout)).has_value());
  }
  // And one without the board.
  files.push_back(dir / "empty.png");
  ASSERT_TRUE(rhot::write_image(files.back().string(), cv::Mat(480, 640, CV_8UC1, cv::Scalar(128))).has_value());
  const auto views = detect_boards(files, *parse_board_spec("chess:9x6:25"));
  ASSERT_TRUE(views.has_value()) << views.error();
  const auto report = calibrate_intrinsics(*views);
  ASSERT_TRUE(report.has_value()) << report.error();
  ASSERT_EQ(report->skipped, std::vector<std::string>{"empty.png"});
  std::string all;
  for (const std::string& w : report->warnings) all += w + "\n";
  EXPECT_NE(all.find("the board was not found in 1 of 6 images (empty.png); they were left out"), std::string::npos) << all;
  EXPECT_NE(all.find("only 5 views found the board; 8 or more"), std::string::npos) << all;
  EXPECT_NE(all.find("% of the image (cells of a 16 x 16 grid)"), std::string::npos) << all;
  EXPECT_NE(all.find("the board's orientations span only"), std::string::npos) << all;
  EXPECT_LT(report->orientation_spread_deg, 20.0);
  EXPECT_LT(report->coverage, 0.5);
  EXPECT_TRUE(std::isfinite(report->intrinsics.fx));
}

TEST(Intrinsics, BadPicturesGetMessagesNamingTheFile) {
  const fs::path dir = temp_dir();
  const BoardSpec board = *parse_board_spec("chess:9x6:25");

  auto r = detect_boards({}, board);
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error(), "no images: give the pictures of the board (files, or folders of them)");
  EXPECT_EQ(calibrate_intrinsics({}).error(), "no images: give the pictures of the board (files, or folders of them)");

  r = detect_boards({dir / "missing.png"}, board);
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error(), (dir / "missing.png").string() + ": no such file");
  std::ofstream(dir / "text.png") << "not a picture";
  r = detect_boards({dir / "text.png"}, board);
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error(), (dir / "text.png").string() + ": cannot read the image (not a format OpenCV reads, or damaged)");

  // Pictures of a 9 x 6 board looked for as 8 x 6: not found anywhere.
  const CameraIntrinsics camera = webcam(640, 480, 600.0);
  const std::vector<fs::path> files = render_views(dir, camera, chess_layout(), 3);
  r = detect_boards(files, *parse_board_spec("chess:8x6:25"));
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error(),
            "board chess:8x6:25 not found in any of the 3 images; chess COLSxROWS counts inner corners (a board of 10 x 7 squares is "
            "chess:9x6)");

  // Two resolutions.
  ASSERT_TRUE(rhot::write_image((dir / "small.png").string(), cv::Mat(240, 320, CV_8UC1, cv::Scalar(128))).has_value());
  r = detect_boards({files[0], dir / "small.png"}, board);
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error(),
            "small.png: the image is 320x240 but view_00.png is 640x480; every image must come from one camera at one resolution");

  // Too few views for Zhang's method.
  r = detect_boards({files[0], files[1]}, board);
  ASSERT_TRUE(r.has_value()) << r.error();
  const auto report = calibrate_intrinsics(*r);
  ASSERT_FALSE(report.has_value());
  EXPECT_EQ(report.error(),
            "the board was found in only 2 of 2 images; Zhang's method needs at least 3 views, and 10 to 20 with the board tilted "
            "differently give intrinsics worth trusting");
}

// Pictures of a 9 x 6 board looked for as 10 x 7: the classic detector used to search such a picture
// for 20 to 40 s. Now it gives up at once, and after the first three pictures without the board the
// search stops with the reason, the rest unsearched.
TEST(Intrinsics, ABoardInNoneOfTheFirstPicturesStopsTheSearchThere) {
  const fs::path dir = temp_dir();
  const std::vector<fs::path> files = render_views(dir, webcam(640, 480, 600.0), chess_layout(), 6);
  std::vector<int> searched;
  const auto r =
      detect_boards(files, *parse_board_spec("chess:10x7:25"), [&](int index, int, const std::string&) { searched.push_back(index); });
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error(),
            "board chess:10x7:25 not found in any of the first 3 of 6 images, so the others were not searched; is the board's size "
            "right? chess COLSxROWS counts inner corners (a board of 10 x 7 squares is chess:9x6)");
  EXPECT_EQ(searched, (std::vector<int>{1, 2, 3}));

  // The board in a later picture only: every picture is searched, and those without it are skipped.
  const fs::path empty = dir / "empty.png";
  ASSERT_TRUE(rhot::write_image(empty.string(), cv::Mat(480, 640, CV_8UC1, cv::Scalar(128))).has_value());
  const auto later = detect_boards({empty, files[0], files[1], files[2]}, *parse_board_spec("chess:9x6:25"));
  ASSERT_TRUE(later.has_value()) << later.error();
  EXPECT_EQ(later->size(), 4u);
  EXPECT_FALSE((*later)[0].found());
  EXPECT_TRUE((*later)[3].found());
}

TEST(Intrinsics, BoardSpecsAreReadOrRefusedWithTheReason) {
  auto b = parse_board_spec("chess:9x6:25");
  ASSERT_TRUE(b.has_value());
  EXPECT_EQ(b->kind, BoardKind::chess);
  EXPECT_EQ(b->cols, 9);
  EXPECT_EQ(b->rows, 6);
  EXPECT_EQ(b->square_mm, 25.0);
  EXPECT_EQ(b->point_count(), 54);
  EXPECT_EQ(b->to_string(), "chess:9x6:25");
  b = parse_board_spec("acircles:4x11:17.5");
  ASSERT_TRUE(b.has_value());
  EXPECT_EQ(b->kind, BoardKind::asymmetric_circles);
  EXPECT_EQ(b->to_string(), "acircles:4x11:17.5");
  const std::vector<Eigen::Vector3d> points = board_points_m(*b);
  ASSERT_EQ(points.size(), 44u);
  EXPECT_TRUE(points[5].isApprox(Eigen::Vector3d(3 * 0.0175, 0.0175, 0.0))) << "row 1 is shifted by one spacing";
  b = parse_board_spec("charuco:11x8:20:15");
  ASSERT_TRUE(b.has_value());
  EXPECT_EQ(b->dictionary, "4X4_50");
  EXPECT_EQ(b->point_count(), 70);
  EXPECT_EQ(board_points_m(*b).size(), 70u);
  b = parse_board_spec("charuco:11x8:20:15:dict_5x5_100");
  ASSERT_TRUE(b.has_value());
  EXPECT_EQ(b->dictionary, "5X5_100");
  EXPECT_EQ(b->to_string(), "charuco:11x8:20:15:5X5_100");

  const auto refused = [](const std::string& spec) {
    const auto r = parse_board_spec(spec);
    return r.has_value() ? std::string("accepted") : r.error();
  };
  EXPECT_EQ(refused("checkers:9x6:25"),
            "board \"checkers:9x6:25\": expected chess:COLSxROWS:SQUARE_MM (e.g. chess:9x6:25), circles:COLSxROWS:SPACING_MM (e.g. "
            "circles:7x6:20), acircles:COLSxROWS:SPACING_MM (e.g. acircles:4x11:20) or charuco:COLSxROWS:SQUARE_MM:MARKER_MM[:DICT] "
            "(e.g. charuco:11x8:20:15:4X4_50)");
  EXPECT_EQ(refused("chess:9x6"), "board \"chess:9x6\": expected chess:COLSxROWS:SQUARE_MM (e.g. chess:9x6:25)");
  EXPECT_EQ(refused("chess:9by6:25"),
            "board \"chess:9by6:25\": COLSxROWS must be two whole numbers joined by 'x' (e.g. 9x6), got \"9by6\"");
  EXPECT_EQ(refused("chess:1x6:25"),
            "board \"chess:1x6:25\": COLS and ROWS must each be 2 to 100, got 1x6; chess COLSxROWS counts inner corners (a board of 10 x 7 "
            "squares is chess:9x6)");
  EXPECT_EQ(refused("chess:9x6:-25"), "board \"chess:9x6:-25\": SQUARE_MM must be a positive number of millimetres, got \"-25\"");
  EXPECT_EQ(refused("circles:7x6:abc"), "board \"circles:7x6:abc\": SPACING_MM must be a positive number of millimetres, got \"abc\"");
  EXPECT_EQ(refused("charuco:11x8:20"),
            "board \"charuco:11x8:20\": expected charuco:COLSxROWS:SQUARE_MM:MARKER_MM[:DICT] (e.g. charuco:11x8:20:15:4X4_50)");
  EXPECT_EQ(refused("charuco:11x8:20:25"),
            "board \"charuco:11x8:20:25\": MARKER_MM must be a positive number of millimetres less than SQUARE_MM (20), got \"25\"");
  EXPECT_TRUE(
      refused("charuco:11x8:20:15:9X9_50")
          .starts_with("board \"charuco:11x8:20:15:9X9_50\": unknown dictionary \"9X9_50\"; expected one of 4X4_50, 4X4_100, 4X4_250, "))
      << refused("charuco:11x8:20:15:9X9_50");
  EXPECT_EQ(refused("charuco:12x10:20:15"),
            "board \"charuco:12x10:20:15\": 12x10 squares hold 60 markers but dictionary 4X4_50 has 50; name a larger one, e.g. 4X4_100");
  EXPECT_EQ(
      refused("charuco:30x30:20:15:APRILTAG_16h5"),
      "board \"charuco:30x30:20:15:APRILTAG_16h5\": 30x30 squares hold 450 markers but dictionary APRILTAG_16h5 has 30; name a larger "
      "one, e.g. APRILTAG_36h11");
  EXPECT_EQ(refused("").substr(0, 44), "board \"\": expected chess:COLSxROWS:SQUARE_MM");
}

TEST(Intrinsics, BoardPicturesPutSquareEdgesOnPixelEdges) {
  const auto board = parse_board_spec("chess:4x3:20");
  const auto picture = board_picture(*board, 10);
  ASSERT_TRUE(picture.has_value()) << picture.error();
  // 5 x 4 squares and a margin of one square each side: 7 x 6 squares of 10 pixels.
  EXPECT_EQ(picture->width_px, 70);
  EXPECT_EQ(picture->height_px, 60);
  EXPECT_NEAR(picture->pixel_m, 0.002, 1e-12);
  EXPECT_TRUE(picture->corner_board_m.isApprox(Eigen::Vector2d(-0.04, -0.04)));
  const auto grey = [&](int x, int y) { return picture->grey[static_cast<std::size_t>(y * picture->width_px + x)]; };
  EXPECT_EQ(grey(5, 5), 255) << "margin";
  EXPECT_EQ(grey(10, 10), 0) << "the first square is black, pure up to its edge";
  EXPECT_EQ(grey(19, 19), 0);
  EXPECT_EQ(grey(20, 10), 255);
  EXPECT_FALSE(board_picture(*board, 2).has_value());
}

}  // namespace
}  // namespace rhot
