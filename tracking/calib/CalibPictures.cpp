#include "tracking/calib/CalibPictures.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "tracking/media/Media.h"

namespace rhot {

namespace {

constexpr int kGrid = 16;

std::expected<void, std::string> write_png(const std::filesystem::path& file, const cv::Mat& image) { return write_image(file, image); }

cv::Scalar error_colour(double error_px) {
  const double t = std::clamp(error_px / 2.0, 0.0, 1.0);  // 0 px green -> 2 px red (BGR)
  return {0.0, 220.0 * (1.0 - t), 255.0 * t};
}

}  // namespace

double image_coverage(int width_px, int height_px, const std::vector<Eigen::Vector2d>& pixels) {
  if (width_px <= 0 || height_px <= 0) return 0.0;
  std::vector<bool> hit(kGrid * kGrid, false);
  for (const Eigen::Vector2d& p : pixels) {
    if (!p.allFinite() || p.x() < 0 || p.y() < 0 || p.x() >= width_px || p.y() >= height_px) continue;
    const int gx = std::min(kGrid - 1, static_cast<int>(p.x() * kGrid / width_px));
    const int gy = std::min(kGrid - 1, static_cast<int>(p.y() * kGrid / height_px));
    hit[static_cast<std::size_t>(gy * kGrid + gx)] = true;
  }
  return static_cast<double>(std::count(hit.begin(), hit.end(), true)) / (kGrid * kGrid);
}

std::expected<void, std::string> write_residual_picture(const std::filesystem::path& file, int width_px, int height_px,
                                                        const std::vector<ResidualSample>& samples, double magnify,
                                                        const std::string& title) {
  if (width_px <= 0 || height_px <= 0) return std::unexpected(file.string() + ": no image size to draw on");
  double scale = 1.0;
  while (width_px * scale > 1280) scale /= 2.0;
  const int w = std::max(1, static_cast<int>(width_px * scale));
  const int h = std::max(1, static_cast<int>(height_px * scale));
  cv::Mat image(h, w, CV_8UC3, cv::Scalar(40, 40, 40));
  // Coverage: cells with an observation light, the others dark.
  std::vector<bool> hit(kGrid * kGrid, false);
  for (const ResidualSample& s : samples) {
    if (!s.pixel.allFinite() || s.pixel.x() < 0 || s.pixel.y() < 0 || s.pixel.x() >= width_px || s.pixel.y() >= height_px) continue;
    const int gx = std::min(kGrid - 1, static_cast<int>(s.pixel.x() * kGrid / width_px));
    const int gy = std::min(kGrid - 1, static_cast<int>(s.pixel.y() * kGrid / height_px));
    hit[static_cast<std::size_t>(gy * kGrid + gx)] = true;
  }
  for (int gy = 0; gy < kGrid; ++gy) {
    for (int gx = 0; gx < kGrid; ++gx) {
      const cv::Rect cell(gx * w / kGrid, gy * h / kGrid, (gx + 1) * w / kGrid - gx * w / kGrid, (gy + 1) * h / kGrid - gy * h / kGrid);
      cv::rectangle(image, cell, hit[static_cast<std::size_t>(gy * kGrid + gx)] ? cv::Scalar(90, 90, 90) : cv::Scalar(25, 25, 60),
                    cv::FILLED);
      cv::rectangle(image, cell, cv::Scalar(60, 60, 60), 1);
    }
  }
  for (const ResidualSample& s : samples) {
    if (!s.pixel.allFinite() || !s.residual_px.allFinite()) continue;
    const cv::Point2d p(s.pixel.x() * scale, s.pixel.y() * scale);
    if (!s.inlier) {
      // An outlier's residual is off any useful scale: a red cross where it was seen.
      cv::drawMarker(image, p, cv::Scalar(0, 0, 255), cv::MARKER_TILTED_CROSS, 7, 1, cv::LINE_AA);
      continue;
    }
    // The magnified residual, at most 40 picture pixels long.
    cv::Point2d d = cv::Point2d(s.residual_px.x(), s.residual_px.y()) * (magnify * scale);
    const double length = std::hypot(d.x, d.y);
    if (length > 40.0) d *= 40.0 / length;
    cv::line(image, p, p + d, error_colour(s.residual_px.norm()), 1, cv::LINE_AA);
    cv::circle(image, p, 1, cv::Scalar(230, 230, 230), cv::FILLED, cv::LINE_AA);
  }
  char caption[256];
  std::snprintf(caption, sizeof caption, "residuals x%.0f, green 0 px .. red 2 px; red crosses: outliers; dark cells: not covered",
                magnify);
  cv::putText(image, title, cv::Point(8, 20), cv::FONT_HERSHEY_SIMPLEX, 0.55, cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  cv::putText(image, caption, cv::Point(8, 40), cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(220, 220, 220), 1, cv::LINE_AA);
  return write_png(file, image);
}

std::expected<void, std::string> write_rig_top_view(const std::filesystem::path& file, const CameraRig& rig,
                                                    const std::vector<Eigen::Vector3d>& points_world, const std::string& title) {
  // The extent of cameras and points in X and Z.
  double min_x = 1e300, max_x = -1e300, min_z = 1e300, max_z = -1e300;
  auto grow = [&](const Eigen::Vector3d& p) {
    if (!p.allFinite()) return;
    min_x = std::min(min_x, p.x());
    max_x = std::max(max_x, p.x());
    min_z = std::min(min_z, p.z());
    max_z = std::max(max_z, p.z());
  };
  for (const Camera& c : rig.cameras) grow(c.centre_world());
  for (const Eigen::Vector3d& p : points_world) grow(p);
  if (!(max_x >= min_x)) return std::unexpected(file.string() + ": nothing to draw");
  const double span = std::max({max_x - min_x, max_z - min_z, 0.1}) * 1.25;
  const double mid_x = (min_x + max_x) / 2, mid_z = (min_z + max_z) / 2;
  const int size = 800;
  const double px_per_m = size / span;
  auto to_image = [&](const Eigen::Vector3d& p) {
    return cv::Point2d(size / 2.0 + (p.x() - mid_x) * px_per_m, size / 2.0 + (p.z() - mid_z) * px_per_m);
  };
  cv::Mat image(size, size, CV_8UC3, cv::Scalar(250, 250, 250));
  // A wave's thousands of points as small grey dots; a few (an L-frame's markers, floor points)
  // as numbered red discs.
  const bool few = points_world.size() <= 16;
  for (std::size_t i = 0; i < points_world.size(); ++i) {
    const Eigen::Vector3d& p = points_world[i];
    if (!p.allFinite()) continue;
    if (few) {
      cv::circle(image, to_image(p), 5, cv::Scalar(40, 40, 220), cv::FILLED, cv::LINE_AA);
      cv::putText(image, std::to_string(i), to_image(p) + cv::Point2d(7, 5), cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(40, 40, 220), 1,
                  cv::LINE_AA);
    } else {
      cv::circle(image, to_image(p), 1, cv::Scalar(160, 160, 160), cv::FILLED);
    }
  }
  for (const Camera& c : rig.cameras) {
    const Eigen::Vector3d centre = c.centre_world();
    const Eigen::Matrix3d world_from_cam = c.cam_from_world.rotation.conjugate().toRotationMatrix();
    const double reach = 0.08 * span;
    // The image's left and right edges at mid-height, as a wedge from the centre.
    const double half_w = c.intrinsics.width_px / (2.0 * c.intrinsics.fx);
    const Eigen::Vector3d left = centre + world_from_cam * Eigen::Vector3d(-half_w, 0, 1).normalized() * reach;
    const Eigen::Vector3d right = centre + world_from_cam * Eigen::Vector3d(half_w, 0, 1).normalized() * reach;
    const std::vector<cv::Point> wedge{to_image(centre), to_image(left), to_image(right)};
    cv::fillConvexPoly(image, wedge, cv::Scalar(230, 180, 120), cv::LINE_AA);
    cv::polylines(image, wedge, true, cv::Scalar(140, 80, 20), 1, cv::LINE_AA);
    cv::circle(image, to_image(centre), 4, cv::Scalar(140, 80, 20), cv::FILLED, cv::LINE_AA);
    cv::putText(image, c.name, to_image(centre) + cv::Point2d(6, -6), cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  }
  // A scale bar of a round length.
  double bar_m = 0.1;
  for (const double m : {0.1, 0.2, 0.5, 1.0, 2.0, 5.0}) {
    if (m * px_per_m < size / 4.0) bar_m = m;
  }
  const cv::Point a(20, size - 20), b(20 + static_cast<int>(bar_m * px_per_m), size - 20);
  cv::line(image, a, b, cv::Scalar(0, 0, 0), 2);
  char label[64];
  std::snprintf(label, sizeof label, "%.1f m", bar_m);
  cv::putText(image, label, a + cv::Point(0, -8), cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  cv::putText(image, title + " (from above: X right, -Z up)", cv::Point(10, 22), cv::FONT_HERSHEY_SIMPLEX, 0.55, cv::Scalar(0, 0, 0), 1,
              cv::LINE_AA);
  return write_png(file, image);
}

}  // namespace rhot
