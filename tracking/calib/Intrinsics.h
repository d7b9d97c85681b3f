#pragma once
// A camera's intrinsics (focal lengths, principal point, lens distortion) from pictures of a flat
// board: Zhang's method through OpenCV (board detection, cv::calibrateCamera), with the checks a
// person needs to trust the result: per-view and leave-one-out reprojection errors, how much of
// the image the corners covered, how differently the board was tilted, and warnings when either
// is too poor.
//
// The board frame is OpenCV's for calibration targets: metres, the board in its z = 0 plane, the
// origin at the first point the detector reports, x along a row of points, y from row to row.
// Pixels follow Camera.h: (0, 0) is the centre of the top-left pixel.

#include <array>
#include <cstdint>
#include <expected>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "tracking/camera/Camera.h"
#include "tracking/core/Rigid3.h"

namespace rhot {

enum class BoardKind {
  chess,               // "chess:COLSxROWS:SQUARE_MM"; COLS x ROWS inner corners, as OpenCV counts them
  circles,             // "circles:COLSxROWS:SPACING_MM"; dark circles, centres SPACING_MM apart
  asymmetric_circles,  // "acircles:COLSxROWS:SPACING_MM"; OpenCV's asymmetric grid, circle (i, j) at ((2 j + i % 2), i) x SPACING_MM
  charuco,             // "charuco:COLSxROWS:SQUARE_MM:MARKER_MM[:DICT]"; COLS x ROWS squares, ArUco markers in the white ones
};

struct BoardSpec {
  BoardKind kind = BoardKind::chess;
  int cols = 9;                       // chess: inner corners along a row; circles: circles per row; charuco: squares along a row
  int rows = 6;                       // chess: inner corners down a column; circles: rows of circles; charuco: squares down a column
  double square_mm = 25.0;            // chess, charuco: a square's side; circles: OpenCV's spacing (see BoardKind)
  double marker_mm = 0.0;             // charuco: a marker's side, less than square_mm
  std::string dictionary = "4X4_50";  // charuco: an OpenCV predefined dictionary without "DICT_"

  // The spec as parse_board_spec reads it ("chess:9x6:25").
  std::string to_string() const;
  // How many points one complete view gives (charuco: the inner corners).
  int point_count() const;
};

// Reads "chess:COLSxROWS:SQUARE_MM", "circles:COLSxROWS:SPACING_MM", "acircles:COLSxROWS:SPACING_MM"
// or "charuco:COLSxROWS:SQUARE_MM:MARKER_MM[:DICT]" (DICT e.g. 4X4_50, 5X5_100, 6X6_250, APRILTAG_36h11;
// default 4X4_50). The message quotes the spec and says which part was wrong and what was expected.
[[nodiscard]] std::expected<BoardSpec, std::string> parse_board_spec(const std::string& spec);

// Every point of the board in the board frame (metres, z = 0), indexed as BoardView::point_ids.
std::vector<Eigen::Vector3d> board_points_m(const BoardSpec& board);

// A picture of the board: the pattern with a white margin of one square (circles: one spacing)
// around it, anti-aliased, grey levels 0 (black) to 255 (white), row by row. For printing, and
// for tracking/sim to render a board it cannot draw itself (ChArUco). Pixel (0, 0)'s outer
// top-left corner lies at `corner_board_m` in the board frame; picture x runs along board x.
struct BoardPicture {
  int width_px = 0;
  int height_px = 0;
  double pixel_m = 0.0;  // the side of one picture pixel on the board
  Eigen::Vector2d corner_board_m{0, 0};
  std::vector<std::uint8_t> grey;
};
// `pixels_per_square`: the resolution, in pixels per square (circles: per spacing); 4 to 1000.
[[nodiscard]] std::expected<BoardPicture, std::string> board_picture(const BoardSpec& board, int pixels_per_square);

// The board as one picture shows it.
struct BoardView {
  std::string name;  // the picture's file name, for reports
  int width_px = 0;
  int height_px = 0;
  // The detected points (sub-pixel) and which board points they are (indices into
  // board_points_m); empty when the board was not found. ChArUco views may hold only some points.
  std::vector<Eigen::Vector2d> corners_px;
  std::vector<int> point_ids;
  std::vector<Eigen::Vector3d> points_board_m;  // board_points_m at point_ids

  bool found() const { return !corners_px.empty(); }
};

// Finds the board in one picture (read as grey). Errors: no such file ("<file>: no such file"), or
// not an image ("<file>: cannot read the image ..."). A picture without the whole board (for ChArUco: without
// at least 6 corners off one line) gives a view with no corners: the board was not found. Cost:
// tens of milliseconds for 1280 x 720; about a second where the chessboard's classic detector
// fails and the sector-based one is tried (a tilted or blurred board, or none, or another count of
// corners).
[[nodiscard]] std::expected<BoardView, std::string> detect_board(const std::filesystem::path& image, const BoardSpec& board);

// Called before each picture is read: index from 1, the count, and the picture's file name.
using DetectProgress = std::function<void(int index, int count, const std::string& name)>;

// detect_boards stops when the board is in none of this many first pictures (and more follow).
inline constexpr int kBoardSearchGiveUpViews = 3;

// detect_board over pictures of one camera. Errors: no pictures; a picture that cannot be read;
// a picture of another size than the first (naming both files and sizes); the board found in none
// of them (quoting the spec and how its numbers count), said after the first
// kBoardSearchGiveUpViews pictures when none of them shows it (the others are not searched, nor
// checked but for being files).
[[nodiscard]] std::expected<std::vector<BoardView>, std::string> detect_boards(const std::vector<std::filesystem::path>& images,
                                                                               const BoardSpec& board, const DetectProgress& progress = {});

struct IntrinsicsSettings {
  bool fix_k3 = true;         // k3 only helps wide lenses, and over-fits the rest
  bool leave_one_out = true;  // recalibrates once per view: N times the work
  int worst_view_count = 3;
  // Warnings (the result stands, but should not be trusted blindly) when:
  double min_coverage = 0.5;                 // the corners fall in fewer of a 16 x 16 grid's cells,
  double min_orientation_spread_deg = 20.0;  // the board's orientations span a smaller angle,
  int recommended_views = 8;                 // fewer views found the board,
  double outlier_view_factor = 3.0;          // a view's RMS exceeds this many times the median (and 0.5 px).

  [[nodiscard]] std::expected<void, std::string> check() const;
};

struct ViewResult {
  std::string name;
  double rms_px = 0.0;  // reprojection error of this view's points, root mean square of the error length
  // The same for this view with intrinsics calibrated without it (its pose solved afresh): how well
  // the intrinsics predict a picture they did not see. Empty when leave-one-out was not run.
  std::optional<double> held_out_rms_px;
  double tilt_deg = 0.0;  // between the board's normal and the optical axis
  Rigid3d camera_from_board;
  std::vector<Eigen::Vector2d> corners_px;    // as detected (BoardView::corners_px)
  std::vector<Eigen::Vector2d> residuals_px;  // observed - predicted, per corner
};

struct IntrinsicsReport {
  CameraIntrinsics intrinsics;  // distortion[4] (k3) is 0 when fixed
  // One-sigma uncertainties from OpenCV's covariance (0 for a fixed parameter).
  double fx_sigma = 0.0, fy_sigma = 0.0, cx_sigma = 0.0, cy_sigma = 0.0;
  std::array<double, 5> distortion_sigma{};
  bool k3_fixed = true;

  double rms_px = 0.0;  // over every point of every view
  // Over every point of every view, each view measured with intrinsics calibrated without it.
  std::optional<double> leave_one_out_rms_px;
  std::vector<ViewResult> views;         // the views that found the board, in input order
  std::vector<std::string> skipped;      // names of the views that did not
  std::vector<std::string> worst_views;  // highest RMS first
  double coverage = 0.0;                 // fraction of a 16 x 16 grid over the image holding a corner
  double tilt_min_deg = 0.0, tilt_max_deg = 0.0;
  double orientation_spread_deg = 0.0;  // the largest angle between two views' board normals
  std::vector<std::string> warnings;    // one sentence each, saying what to do about it
};

// Zhang's method over the views that found the board (OpenCV's 5-coefficient model, k3 fixed at 0
// unless settings say otherwise). Errors: bad settings; no views; views of different image sizes;
// fewer than 3 views with the board; a calibration that fails or gives non-finite or impossible
// values (focal length <= 0, principal point outside the image). Cost: a few milliseconds per view,
// times the number of views again for leave-one-out.
[[nodiscard]] std::expected<IntrinsicsReport, std::string> calibrate_intrinsics(const std::vector<BoardView>& views,
                                                                                const IntrinsicsSettings& settings = {});

}  // namespace rhot
