#include "tracking/sim/BoardImages.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <numeric>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace rhot {

namespace {

std::unexpected<std::string> bad(const char* field, const char* expected, double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return std::unexpected(std::string(field) + ": expected " + expected + ", got " + text);
}

// OpenCV's distortion of normalised coordinates (x, y), and its inverse.
struct Distortion {
  double k1, k2, p1, p2, k3;

  explicit Distortion(const std::array<double, 5>& k) : k1(k[0]), k2(k[1]), p1(k[2]), p2(k[3]), k3(k[4]) {}

  Eigen::Vector2d apply(const Eigen::Vector2d& n) const {
    const double x = n.x(), y = n.y();
    const double r2 = x * x + y * y;
    const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
    return {x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x), y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y};
  }

  // The largest squared radius (normalised) out to which the radial part r (1 + k1 r^2 + ...) keeps
  // growing: beyond it the model folds back and one pixel has several rays. Searched out to r = 4
  // (104 degrees off axis), which is the answer for lenses that never fold.
  double fold_r2() const {
    constexpr double kMaxR2 = 16.0;
    constexpr int kSteps = 4000;
    for (int i = 1; i <= kSteps; ++i) {
      const double r2 = kMaxR2 * i / kSteps;
      if (1.0 + r2 * (3.0 * k1 + r2 * (5.0 * k2 + r2 * 7.0 * k3)) <= 0.0) return kMaxR2 * (i - 1) / kSteps;
    }
    return kMaxR2;
  }

  // Distorted (dx, dy) -> undistorted (nx, ny) normalised coordinates by Newton's method from
  // (nx, ny) as given (the caller's guess, e.g. a neighbour's answer). False when it does not
  // converge or lands where the model has folded over.
  bool invert(double dx, double dy, double& nx, double& ny, double max_r2) const {
    for (int iteration = 0; iteration < 30; ++iteration) {
      const double x = nx, y = ny;
      const double r2 = x * x + y * y;
      const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
      const double dradial_dr2 = k1 + r2 * (2.0 * k2 + r2 * 3.0 * k3);
      const double ex = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x) - dx;
      const double ey = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y - dy;
      const double j00 = radial + 2.0 * x * x * dradial_dr2 + 2.0 * p1 * y + 6.0 * p2 * x;
      const double j01 = 2.0 * x * y * dradial_dr2 + 2.0 * p1 * x + 2.0 * p2 * y;
      const double j10 = 2.0 * x * y * dradial_dr2 + 2.0 * p1 * x + 2.0 * p2 * y;
      const double j11 = radial + 2.0 * y * y * dradial_dr2 + 6.0 * p1 * y + 2.0 * p2 * x;
      const double det = j00 * j11 - j01 * j10;
      if (!(det > 1e-9)) return false;
      if (ex * ex + ey * ey < 1e-26) return r2 < max_r2;
      nx -= (j11 * ex - j01 * ey) / det;
      ny -= (j00 * ey - j10 * ex) / det;
      if (!std::isfinite(nx) || !std::isfinite(ny) || nx * nx + ny * ny > 4.0 * max_r2 + 1.0) return false;
    }
    return false;
  }
};

// The board's picture as functions of a board-plane point (u, v), metres: its grey level, and a
// lower bound on the distance to the nearest place the grey level jumps (0 where unknown).
class BoardShading {
 public:
  BoardShading(const BoardLayout& layout, const BoardRenderSettings& settings)
      : layout_(layout), settings_(settings), s_(layout.spacing_m), r_(layout.circle_diameter * layout.spacing_m / 2.0) {
    const auto [lo, hi] = board_extent_m(layout);
    lo_ = lo;
    hi_ = hi;
  }

  bool inside(double u, double v) const { return u >= lo_.x() && u < hi_.x() && v >= lo_.y() && v < hi_.y(); }

  double grey(double u, double v) const {
    if (!inside(u, v)) return settings_.background;
    switch (layout_.pattern) {
      case BoardPattern::chess: {
        const int i = static_cast<int>(std::floor(u / s_)), j = static_cast<int>(std::floor(v / s_));
        if (i < -1 || i > layout_.cols - 1 || j < -1 || j > layout_.rows - 1) return settings_.white;
        return ((i + j) % 2 == 0) ? settings_.black : settings_.white;  // the (-1, -1) corner square is black
      }
      case BoardPattern::circles:
      case BoardPattern::asymmetric_circles:
        return nearest_centre_distance(u, v) < r_ ? settings_.black : settings_.white;
      case BoardPattern::texture:
        return texture_grey(u, v);
    }
    return settings_.background;
  }

  double edge_distance(double u, double v) const {
    const double border = std::min({std::abs(u - lo_.x()), std::abs(u - hi_.x()), std::abs(v - lo_.y()), std::abs(v - hi_.y())});
    switch (layout_.pattern) {
      case BoardPattern::chess:
        // Every square edge lies on a line u = k s or v = k s.
        return std::min({border, std::abs(u - s_ * std::round(u / s_)), std::abs(v - s_ * std::round(v / s_))});
      case BoardPattern::circles:
      case BoardPattern::asymmetric_circles:
        // The nearest circle's edge is the nearest edge: circles are at most 0.45 spacing in radius
        // and at least one spacing apart.
        return std::min(border, std::abs(nearest_centre_distance(u, v) - r_));
      case BoardPattern::texture:
        return 0.0;
    }
    return 0.0;
  }

 private:
  double nearest_centre_distance(double u, double v) const {
    if (layout_.pattern == BoardPattern::circles) {
      const double i = std::clamp(std::round(v / s_), 0.0, layout_.rows - 1.0);
      const double j = std::clamp(std::round(u / s_), 0.0, layout_.cols - 1.0);
      return std::hypot(u - j * s_, v - i * s_);
    }
    // Asymmetric: circle (i, j) at ((2 j + i % 2) s, i s); the nearest lies in one of three rows.
    const int i0 = static_cast<int>(std::clamp(std::round(v / s_), 0.0, layout_.rows - 1.0));
    double best = 1e300;
    for (int i = std::max(0, i0 - 1); i <= std::min(layout_.rows - 1, i0 + 1); ++i) {
      const double j = std::clamp(std::round((u / s_ - i % 2) / 2.0), 0.0, layout_.cols - 1.0);
      best = std::min(best, std::hypot(u - (2.0 * j + i % 2) * s_, v - i * s_));
    }
    return best;
  }

  double texture_grey(double u, double v) const {
    const cv::Mat& t = layout_.texture;
    // Texel centres at corner + (k + 0.5) texel; bilinear between them, clamped at the border.
    const double x = (u - layout_.texture_corner_m.x()) / layout_.texel_m - 0.5;
    const double y = (v - layout_.texture_corner_m.y()) / layout_.texel_m - 0.5;
    const double xc = std::clamp(x, 0.0, t.cols - 1.0), yc = std::clamp(y, 0.0, t.rows - 1.0);
    const int x0 = std::max(0, std::min(static_cast<int>(xc), t.cols - 2));
    const int y0 = std::max(0, std::min(static_cast<int>(yc), t.rows - 2));
    const int x1 = std::min(x0 + 1, t.cols - 1), y1 = std::min(y0 + 1, t.rows - 1);
    const double fx = xc - x0, fy = yc - y0;
    const auto* r0 = t.ptr<std::uint8_t>(y0);
    const auto* r1 = t.ptr<std::uint8_t>(y1);
    const double value = (1 - fy) * ((1 - fx) * r0[x0] + fx * r0[x1]) + fy * ((1 - fx) * r1[x0] + fx * r1[x1]);
    return settings_.black + (settings_.white - settings_.black) * value / 255.0;
  }

  const BoardLayout& layout_;
  const BoardRenderSettings& settings_;
  double s_, r_;
  Eigen::Vector2d lo_, hi_;
};

// The board point under every pixel corner of an image (pixel centres are at integer
// coordinates, so the corners are at half-integers): corner (x, y) at index y * per_row + x.
struct PixelCorners {
  int per_row = 0;           // the image's width + 1
  std::vector<double> u, v;  // board-plane coordinates, metres
  std::vector<std::uint8_t> ok;
};

// The loops are written on plain doubles: they run a million times a picture, and so stay quick
// in the sanitizer builds too.
PixelCorners pixel_corners(const CameraIntrinsics& camera, const Rigid3d& camera_from_board) {
  const int w = camera.width_px, h = camera.height_px;
  const Distortion distortion(camera.distortion);
  const double max_r2 = distortion.fold_r2();
  // Board plane -> normalised image coordinates is the homography [r0 r1 t]; its inverse takes a
  // ray (x, y, 1) to (u, v, 1) / depth, so the third component is positive in front of the camera.
  const Eigen::Matrix3d r = camera_from_board.rotation.toRotationMatrix();
  Eigen::Matrix3d homography;
  homography << r.col(0), r.col(1), camera_from_board.translation;
  const Eigen::Matrix3d board_from_ray = homography.inverse();

  const double h00 = board_from_ray(0, 0), h01 = board_from_ray(0, 1), h02 = board_from_ray(0, 2);
  const double h10 = board_from_ray(1, 0), h11 = board_from_ray(1, 1), h12 = board_from_ray(1, 2);
  const double h20 = board_from_ray(2, 0), h21 = board_from_ray(2, 1), h22 = board_from_ray(2, 2);

  PixelCorners c;
  const int lw = w + 1;
  const std::size_t corner_count = static_cast<std::size_t>(lw) * (h + 1);
  c.per_row = lw;
  c.u.assign(corner_count, 0.0);
  c.v.assign(corner_count, 0.0);
  c.ok.assign(corner_count, 0);
  double row_start_x = 0.0, row_start_y = 0.0;
  bool row_start_ok = false;
  for (int y = 0; y <= h; ++y) {
    const double dy = (y - 0.5 - camera.cy) / camera.fy;
    double nx = 0.0, ny = 0.0;
    bool previous_ok = false;
    for (int x = 0; x <= w; ++x) {
      const double dx = (x - 0.5 - camera.cx) / camera.fx;
      if (!previous_ok) {
        nx = (x == 0 && row_start_ok) ? row_start_x : dx;
        ny = (x == 0 && row_start_ok) ? row_start_y : dy;
      }
      bool ok = distortion.invert(dx, dy, nx, ny, max_r2);
      if (!ok && previous_ok) {  // a bad warm start: try again from the distorted point itself
        nx = dx;
        ny = dy;
        ok = distortion.invert(dx, dy, nx, ny, max_r2);
      }
      previous_ok = ok;
      if (x == 0) {
        row_start_x = nx;
        row_start_y = ny;
        row_start_ok = ok;
      }
      if (!ok) continue;
      const double qz = h20 * nx + h21 * ny + h22;
      if (!(qz > 1e-12)) continue;
      const double u = (h00 * nx + h01 * ny + h02) / qz, v = (h10 * nx + h11 * ny + h12) / qz;
      if (!std::isfinite(u) || !std::isfinite(v)) continue;
      const std::size_t k = static_cast<std::size_t>(y) * lw + x;
      c.u[k] = u;
      c.v[k] = v;
      c.ok[k] = 1;
    }
  }
  return c;
}

// Sub-sample positions in the pixel: a rank-1 lattice with a golden-ratio generator (the
// Fibonacci lattice when the count is a Fibonacci number). Unlike a square grid of S x S points,
// which sees an edge parallel to the pixel rows in steps of 1/S, every point has its own row and
// column, so an edge at any angle is located to about 1/count of a pixel.
struct SubSamples {
  int count = 0;
  std::vector<double> x, y;  // 0-1 across the pixel
};

SubSamples sub_samples(int samples) {
  // The generator must share no factor with the count, or the rows repeat and leave the pattern
  // off centre.
  int generator = std::max(1, static_cast<int>(std::lround(samples / std::numbers::phi)));
  while (std::gcd(generator, samples) != 1) ++generator;
  SubSamples sub{samples, std::vector<double>(static_cast<std::size_t>(samples)), std::vector<double>(static_cast<std::size_t>(samples))};
  for (int i = 0; i < samples; ++i) {
    sub.x[static_cast<std::size_t>(i)] = (i + 0.5) / samples;
    sub.y[static_cast<std::size_t>(i)] = (static_cast<int>(static_cast<long>(i) * generator % samples) + 0.5) / samples;
  }
  return sub;
}

// The grey of the pixel whose corners are k00 (top left), k10, k01 and k11 (bottom right): the
// background where the board is not under all four, the board's grey at its centre where no edge
// passes through it, else the mean over the sub-samples.
double pixel_grey(const PixelCorners& c, std::size_t k00, std::size_t k10, std::size_t k01, std::size_t k11, const BoardShading& shading,
                  const SubSamples& sub, double background) {
  if (!(c.ok[k00] && c.ok[k10] && c.ok[k01] && c.ok[k11])) return background;
  const double u00 = c.u[k00], u10 = c.u[k10], u01 = c.u[k01], u11 = c.u[k11];
  const double v00 = c.v[k00], v10 = c.v[k10], v01 = c.v[k01], v11 = c.v[k11];
  const double uc = 0.25 * (u00 + u10 + u01 + u11), vc = 0.25 * (v00 + v10 + v01 + v11);
  // Over one pixel the map to the board is affine to a part in 1e3 of a pixel or better, so the
  // footprint lies within the disc through its farthest corner.
  const auto d2 = [&](double u, double v) { return (u - uc) * (u - uc) + (v - vc) * (v - vc); };
  const double reach = std::sqrt(std::max(std::max(d2(u00, v00), d2(u10, v10)), std::max(d2(u01, v01), d2(u11, v11))));
  if (shading.edge_distance(uc, vc) > 1.01 * reach) return shading.grey(uc, vc);
  double sum = 0.0;
  for (int i = 0; i < sub.count; ++i) {
    const double fx = sub.x[static_cast<std::size_t>(i)], fy = sub.y[static_cast<std::size_t>(i)];
    const double left_u = u00 + fy * (u01 - u00), left_v = v00 + fy * (v01 - v00);
    const double right_u = u10 + fy * (u11 - u10), right_v = v10 + fy * (v11 - v10);
    sum += shading.grey(left_u + fx * (right_u - left_u), left_v + fx * (right_v - left_v));
  }
  return sum / sub.count;
}

}  // namespace

std::expected<void, std::string> BoardLayout::check() const {
  if (pattern == BoardPattern::texture) {
    if (texture.empty() || texture.type() != CV_8UC1) return std::unexpected("texture: expected an 8-bit grey picture (CV_8UC1)");
    if (!std::isfinite(texel_m) || texel_m <= 0.0) return bad("texel_m", "a positive size in metres", texel_m);
    if (!texture_corner_m.allFinite()) return std::unexpected("texture_corner_m: expected finite coordinates");
    return {};
  }
  if (cols < 2 || cols > 1000) return bad("cols", "2 to 1000", cols);
  if (rows < 2 || rows > 1000) return bad("rows", "2 to 1000", rows);
  if (!std::isfinite(spacing_m) || spacing_m <= 0.0) return bad("spacing_m", "a positive size in metres", spacing_m);
  if (!std::isfinite(margin) || margin < 0.0 || margin > 100.0) return bad("margin", "0 to 100 spacings", margin);
  if (pattern != BoardPattern::chess && (!std::isfinite(circle_diameter) || circle_diameter <= 0.0 || circle_diameter > 0.9))
    return bad("circle_diameter", "more than 0 and at most 0.9 spacings", circle_diameter);
  return {};
}

std::expected<void, std::string> BoardRenderSettings::check() const {
  if (samples_per_pixel < 1 || samples_per_pixel > 4096) return bad("samples_per_pixel", "1 to 4096", samples_per_pixel);
  for (const auto& [field, value] : {std::pair{"black", black}, std::pair{"white", white}, std::pair{"background", background}}) {
    if (!std::isfinite(value) || value < 0.0 || value > 255.0) return bad(field, "0 to 255 grey levels", value);
  }
  if (!std::isfinite(blur_sigma_px) || blur_sigma_px < 0.0 || blur_sigma_px > 20.0)
    return bad("blur_sigma_px", "0 to 20 pixels", blur_sigma_px);
  if (!std::isfinite(noise_sigma) || noise_sigma < 0.0 || noise_sigma > 100.0)
    return bad("noise_sigma", "0 to 100 grey levels", noise_sigma);
  return {};
}

std::vector<Eigen::Vector3d> board_points_m(const BoardLayout& layout) {
  std::vector<Eigen::Vector3d> points;
  if (layout.pattern == BoardPattern::texture) return points;
  const double s = layout.spacing_m;
  for (int i = 0; i < layout.rows; ++i) {
    for (int j = 0; j < layout.cols; ++j) {
      const double x = layout.pattern == BoardPattern::asymmetric_circles ? (2.0 * j + i % 2) * s : j * s;
      points.emplace_back(x, i * s, 0.0);
    }
  }
  return points;
}

std::pair<Eigen::Vector2d, Eigen::Vector2d> board_extent_m(const BoardLayout& layout) {
  const double s = layout.spacing_m;
  const double m = layout.margin * s;
  switch (layout.pattern) {
    case BoardPattern::chess:
      // (cols + 1) x (rows + 1) squares around the inner corners.
      return {{-s - m, -s - m}, {layout.cols * s + m, layout.rows * s + m}};
    case BoardPattern::circles:
    case BoardPattern::asymmetric_circles: {
      const double r = layout.circle_diameter * s / 2.0;
      const double width = layout.pattern == BoardPattern::circles ? (layout.cols - 1) * s : (2.0 * (layout.cols - 1) + 1) * s;
      return {{-r - m, -r - m}, {width + r + m, (layout.rows - 1) * s + r + m}};
    }
    case BoardPattern::texture:
      return {layout.texture_corner_m,
              layout.texture_corner_m + layout.texel_m * Eigen::Vector2d(layout.texture.cols, layout.texture.rows)};
  }
  return {};
}

cv::Mat render_board(const CameraIntrinsics& camera, const Rigid3d& camera_from_board, const BoardLayout& layout,
                     const BoardRenderSettings& settings) {
  const int w = camera.width_px, h = camera.height_px;
  const PixelCorners corners = pixel_corners(camera, camera_from_board);
  const int lw = corners.per_row;
  const BoardShading shading(layout, settings);
  const SubSamples sub =
      sub_samples(layout.pattern == BoardPattern::texture ? std::min(settings.samples_per_pixel, 16) : settings.samples_per_pixel);
  cv::Mat light(h, w, CV_64FC1);
  for (int y = 0; y < h; ++y) {
    auto* row = light.ptr<double>(y);
    const std::size_t top = static_cast<std::size_t>(y) * lw, bottom = top + lw;
    for (int x = 0; x < w; ++x) {
      const std::size_t k00 = top + x, k10 = k00 + 1, k01 = bottom + x, k11 = k01 + 1;
      row[x] = pixel_grey(corners, k00, k10, k01, k11, shading, sub, settings.background);
    }
  }
  if (settings.blur_sigma_px > 0.0)
    cv::GaussianBlur(light, light, cv::Size(0, 0), settings.blur_sigma_px, settings.blur_sigma_px, cv::BORDER_REPLICATE);
  if (settings.noise_sigma > 0.0) {
    cv::RNG rng(settings.seed);  // OpenCV's generator: the same seed gives the same noise everywhere
    cv::Mat noise(light.size(), CV_64FC1);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, settings.noise_sigma);
    light += noise;
  }
  cv::Mat image;
  light.convertTo(image, CV_8UC1);  // rounds and saturates to 0-255
  return image;
}

std::vector<Rigid3d> board_poses(const CameraIntrinsics& camera, const BoardLayout& layout, int count, std::uint64_t seed) {
  std::vector<Rigid3d> poses;
  if (count <= 0 || camera.width_px <= 0 || camera.height_px <= 0 || !(camera.fx > 0.0) || !(camera.fy > 0.0)) return poses;
  const auto [lo, hi] = board_extent_m(layout);
  const Eigen::Vector2d size = hi - lo;
  const Eigen::Vector3d centre_board(0.5 * (lo.x() + hi.x()), 0.5 * (lo.y() + hi.y()), 0.0);
  // The outline, sampled finely enough to follow the distortion's curvature.
  std::vector<Eigen::Vector3d> outline;
  constexpr int kPerSide = 16;
  for (int i = 0; i < kPerSide; ++i) {
    const double f = static_cast<double>(i) / kPerSide;
    outline.emplace_back(lo.x() + f * size.x(), lo.y(), 0.0);
    outline.emplace_back(hi.x(), lo.y() + f * size.y(), 0.0);
    outline.emplace_back(hi.x() - f * size.x(), hi.y(), 0.0);
    outline.emplace_back(lo.x(), hi.y() - f * size.y(), 0.0);
  }
  const double max_r2 = 0.9 * Distortion(camera.distortion).fold_r2();
  const double margin_px = 0.01 * camera.width_px;
  Camera view{"board", camera, Rigid3d::identity()};
  const auto fits = [&](const Rigid3d& camera_from_board) {
    for (const Eigen::Vector3d& p : outline) {
      const Eigen::Vector3d p_cam = camera_from_board * p;
      if (p_cam.z() < 0.01 || p_cam.head<2>().squaredNorm() > max_r2 * p_cam.z() * p_cam.z()) return false;
      const Eigen::Vector2d n = p_cam.head<2>() / p_cam.z();
      const Eigen::Vector2d d = Distortion(camera.distortion).apply(n);
      const double px = camera.fx * d.x() + camera.cx, py = camera.fy * d.y() + camera.cy;
      if (px < margin_px || py < margin_px || px > camera.width_px - 1 - margin_px || py > camera.height_px - 1 - margin_px) return false;
    }
    return true;
  };

  cv::RNG rng(seed);
  const double deg = std::numbers::pi / 180.0;
  const Eigen::Vector2d image_centre(camera.cx, camera.cy);
  for (int k = 0; k < count; ++k) {
    // Board centres on a 3 x 3 grid over the image, jittered, visiting the cells in a scattered order.
    const int cell = (k * 4) % 9;
    // Aimed at the image's edge for the outer cells, then pulled in until the board fits: corners
    // near the edges are what pins the distortion down there.
    Eigen::Vector2d target((0.5 * (cell % 3) + (cell % 3 == 1 ? rng.uniform(-0.05, 0.05) : 0.0)) * camera.width_px,
                           (0.5 * (cell / 3) + (cell / 3 == 1 ? rng.uniform(-0.05, 0.05) : 0.0)) * camera.height_px);
    const double tilt = rng.uniform(10.0, 45.0) * deg;
    const double axis_angle = k * 137.5 * deg + rng.uniform(-20.0, 20.0) * deg;  // golden-angle steps
    const double roll = rng.uniform(-20.0, 20.0) * deg;
    const double fill = cell == 4 ? rng.uniform(0.4, 0.6) : rng.uniform(0.25, 0.45);
    const Eigen::Quaterniond rotation = Eigen::AngleAxisd(tilt, Eigen::Vector3d(std::cos(axis_angle), std::sin(axis_angle), 0.0)) *
                                        Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ());
    double depth_m = camera.fx * size.x() / (fill * camera.width_px);
    for (int attempt = 0; attempt < 150; ++attempt) {
      view.cam_from_world = Rigid3d::identity();
      const Eigen::Vector2d n = view.undistort(target);
      Rigid3d camera_from_board;
      camera_from_board.rotation = rotation.normalized();
      camera_from_board.translation = depth_m * Eigen::Vector3d(n.x(), n.y(), 1.0) - camera_from_board.rotation * centre_board;
      if (fits(camera_from_board)) {
        poses.push_back(camera_from_board);
        break;
      }
      target += 0.05 * (image_centre - target);
      depth_m *= 1.01;
    }
  }
  return poses;
}

}  // namespace rhot
