#pragma once
// Pictures of a flat calibration board seen by a camera whose intrinsics and distortion are known:
// the ground truth for intrinsic calibration (tracking/calib/Intrinsics.h) and what
// `rhot-calib simulate board` writes.
//
// The board frame is OpenCV's for calibration targets: metres, the board in its z = 0 plane, the
// origin at the first point a detector reports (a chessboard's first inner corner, a grid's first
// circle centre), x along a row of points, y from row to row. Every pixel is drawn by tracing the
// pixel back through the distortion model (Newton's method on OpenCV's model, to 1e-12) onto the
// board plane, so the picture is exactly what the camera model predicts, anti-aliased by
// averaging sub-samples over each pixel's footprint on the board.

#include <cstdint>
#include <expected>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>

#include "tracking/camera/Camera.h"
#include "tracking/core/Rigid3.h"

namespace rhot {

enum class BoardPattern {
  chess,               // black and white squares; cols x rows inner corners, as OpenCV counts them
  circles,             // black circles on white, cols x rows, centres `spacing_m` apart
  asymmetric_circles,  // OpenCV's asymmetric grid: cols circles per row, row i shifted by i % 2
  texture,             // any picture (e.g. a ChArUco board): `texture` laid on the board plane
};

struct BoardLayout {
  BoardPattern pattern = BoardPattern::chess;
  int cols = 9;  // chess: inner corners along a row; circles: circles per row
  int rows = 6;  // chess: inner corners down a column; circles: rows of circles
  // chess: the side of a square; circles: centre to centre along a row and down a column;
  // asymmetric circles: OpenCV's unit, circle (i, j) at ((2 j + i % 2) spacing, i spacing).
  double spacing_m = 0.025;
  // The circles' diameter as a fraction of `spacing_m` (circles patterns only).
  double circle_diameter = 0.5;
  // The white border around the pattern, in units of `spacing_m` (chess, circles).
  double margin = 1.0;
  // texture: an 8-bit grey picture (CV_8UC1) of the board; its top-left corner (the outer corner
  // of texel (0, 0)) lies at `texture_corner_m` in the board frame, texel columns along board x
  // and rows along board y, each texel `texel_m` square.
  cv::Mat texture;
  Eigen::Vector2d texture_corner_m{0, 0};
  double texel_m = 0.001;

  // Every value usable: "<field>: expected <what>, got <value>" for the first that is not.
  [[nodiscard]] std::expected<void, std::string> check() const;
};

// The points a detector reports, in its order (row by row), in the board frame (z = 0). Empty for
// a texture, whose points only its maker knows.
std::vector<Eigen::Vector3d> board_points_m(const BoardLayout& layout);

// The board's outer rectangle (pattern and margin) in the board frame: min corner, max corner.
std::pair<Eigen::Vector2d, Eigen::Vector2d> board_extent_m(const BoardLayout& layout);

struct BoardRenderSettings {
  // Sub-samples averaged in a pixel an edge crosses (texture: in every pixel, at most 16); edges
  // land within about 1/samples_per_pixel of a pixel of where the camera model puts them.
  int samples_per_pixel = 144;
  double black = 25.0;         // grey levels of the pattern's dark parts,
  double white = 225.0;        // its light parts,
  double background = 110.0;   // and of whatever is not the board
  double blur_sigma_px = 0.0;  // Gaussian blur of the picture (a lens slightly out of focus), pixels; 0: none
  double noise_sigma = 0.0;    // Gaussian noise added to every pixel after the blur, grey levels
  std::uint64_t seed = 1;      // for the noise

  [[nodiscard]] std::expected<void, std::string> check() const;
};

// An 8-bit grey picture (CV_8UC1) of the camera's calibrated size showing the board at
// `camera_from_board`. Pixels whose ray misses the board plane, or lies beyond where the
// distortion model can be inverted (the model folds over), show the background. Cost: one
// distortion inversion per pixel corner, plus samples_per_pixel look-ups for each pixel an edge
// crosses (every pixel for a texture): about 0.1 s for 1280 x 720 in an optimised build.
// Preconditions: layout.check() and settings.check() pass; the camera has a positive size and
// focal lengths.
cv::Mat render_board(const CameraIntrinsics& camera, const Rigid3d& camera_from_board, const BoardLayout& layout,
                     const BoardRenderSettings& settings = {});

// `count` board poses (camera_from_board) a careful person would photograph for calibration: the
// whole board in view with a margin of 1 % of the image width, its centre spread over a 3 x 3
// grid reaching towards the image's edges and corners, filling 25-60 % of the image width, tilted
// 10-45 degrees about axes in varied directions and rolled up to 20 degrees. The same seed gives
// the same poses. A pose whose board cannot be fitted in view by pulling it back and towards the
// centre (where the lens model folds over inside the image) is dropped, so fewer may come back;
// none for a camera without a size or focal length.
std::vector<Rigid3d> board_poses(const CameraIntrinsics& camera, const BoardLayout& layout, int count, std::uint64_t seed = 1);

}  // namespace rhot
