#include "tracking/plan/PlanPictures.h"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace rhot {

namespace {

std::expected<void, std::string> write_png(const std::filesystem::path& file, const cv::Mat& image) {
  try {
    if (!cv::imwrite(file.string(), image)) return std::unexpected(file.string() + ": cannot write the picture");
  } catch (const cv::Exception& e) {
    return std::unexpected(file.string() + ": cannot write the picture: " + e.msg);
  }
  return {};
}

// The grid row (y index) nearest a height.
int slice_of(const CoverageGrid& g, double height_m) {
  const double i = std::round((height_m - g.origin_m.y()) / g.step_m.y());
  return static_cast<int>(std::clamp(i, 0.0, static_cast<double>(g.ny - 1)));
}

// A picture of nx x nz cells, each `cell` pixels, coloured by colour(x, z); text lines beneath.
cv::Mat slice_picture(const CoverageGrid& g, const std::function<cv::Scalar(std::size_t)>& colour, int y,
                      const std::vector<std::string>& lines) {
  const int cell = std::max(1, 720 / std::max(g.nx, g.nz));
  const int text_h = 22 * static_cast<int>(lines.size()) + 8;
  cv::Mat image(g.nz * cell + text_h, std::max(g.nx * cell, 360), CV_8UC3, cv::Scalar(30, 30, 30));
  for (int z = 0; z < g.nz; ++z) {
    for (int x = 0; x < g.nx; ++x) {
      cv::rectangle(image, cv::Rect(x * cell, z * cell, cell, cell), colour(g.index(x, y, z)), cv::FILLED);
    }
  }
  for (std::size_t n = 0; n < lines.size(); ++n) {
    cv::putText(image, lines[n], {6, g.nz * cell + 20 + 22 * static_cast<int>(n)}, cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(230, 230, 230),
                1, cv::LINE_AA);
  }
  return image;
}

}  // namespace

std::expected<void, std::string> write_coverage_slice(const std::filesystem::path& file, const CoverageReport& report, double height_m) {
  const CoverageGrid& g = report.grid;
  if (g.size() == 0) return std::unexpected(file.string() + ": an empty grid");
  const int y = slice_of(g, height_m);
  std::size_t seen[4] = {0, 0, 0, 0};
  for (int z = 0; z < g.nz; ++z) {
    for (int x = 0; x < g.nx; ++x) {
      const int v = report.views[g.index(x, y, z)];
      for (int k = 1; k <= 3; ++k) seen[k] += v >= k ? 1 : 0;
    }
  }
  const double n = static_cast<double>(g.nx) * g.nz;
  const auto colour = [&](std::size_t i) {
    const int v = report.views[i];
    if (v == 0) return cv::Scalar(45, 45, 45);
    if (v == 1) return cv::Scalar(40, 40, 200);
    if (v == 2) return cv::Scalar(30, 170, 230);
    return cv::Scalar(40, std::min(255.0, 140.0 + 15.0 * (v - 3)), 40);
  };
  const cv::Mat image = slice_picture(g, colour, y,
                                      {fmt::format("height {:.2f} m: seen by 1+ {:.1f} %, 2+ {:.1f} %, 3+ {:.1f} %",
                                                   g.origin_m.y() + y * g.step_m.y(), 100.0 * static_cast<double>(seen[1]) / n,
                                                   100.0 * static_cast<double>(seen[2]) / n, 100.0 * static_cast<double>(seen[3]) / n),
                                       "dark: none, red: 1, amber: 2, green: 3 or more (brighter: more)"});
  return write_png(file, image);
}

std::expected<void, std::string> write_error_slice(const std::filesystem::path& file, const CoverageReport& report, double height_m,
                                                   double scale_mm) {
  const CoverageGrid& g = report.grid;
  if (g.size() == 0) return std::unexpected(file.string() + ": an empty grid");
  if (!(scale_mm > 0.0) || !std::isfinite(scale_mm)) return std::unexpected(file.string() + ": the error scale must be positive");
  const int y = slice_of(g, height_m);
  const auto colour = [&](std::size_t i) {
    const double e = report.rms_error_mm[i];
    if (!(e >= 0.0)) return cv::Scalar(45, 45, 45);  // NaN: fewer than two cameras
    const double t = std::clamp(e / scale_mm, 0.0, 1.0);
    return cv::Scalar(30.0, 210.0 * (1.0 - t) + 30.0, 230.0 * t + 20.0);
  };
  const cv::Mat image = slice_picture(
      g, colour, y,
      {fmt::format("height {:.2f} m: predicted RMS 3D error at {:.2f} px", g.origin_m.y() + y * g.step_m.y(), report.sigma_px),
       fmt::format("green 0 mm -> red {:.2f} mm and more; dark: fewer than 2 cameras", scale_mm)});
  return write_png(file, image);
}

std::expected<void, std::string> write_plan_top_view(const std::filesystem::path& file, const CameraRig& rig,
                                                     const TrackingVolume& volume) {
  // The picture spans the cameras and the volume, 100 px a metre or less to stay within 900 px,
  // and at least 720 px wide for its caption.
  Eigen::Vector2d lo(volume.centre_m.x() - 0.5 * volume.size_m.x(), volume.centre_m.z() - 0.5 * volume.size_m.z());
  Eigen::Vector2d hi(volume.centre_m.x() + 0.5 * volume.size_m.x(), volume.centre_m.z() + 0.5 * volume.size_m.z());
  for (const Camera& c : rig.cameras) {
    const Eigen::Vector3d o = c.centre_world();
    if (!o.allFinite()) return std::unexpected(file.string() + ": camera " + c.name + " has no finite centre");
    lo = lo.cwiseMin(Eigen::Vector2d(o.x(), o.z()));
    hi = hi.cwiseMax(Eigen::Vector2d(o.x(), o.z()));
  }
  lo -= Eigen::Vector2d::Constant(1.0);
  hi += Eigen::Vector2d::Constant(1.0);
  const double scale = std::min(100.0, 900.0 / (hi - lo).maxCoeff());
  if ((hi.x() - lo.x()) * scale < 720.0) {
    const double widen = 0.5 * (720.0 / scale - (hi.x() - lo.x()));
    lo.x() -= widen;
    hi.x() += widen;
  }
  const int w = static_cast<int>((hi.x() - lo.x()) * scale), h = static_cast<int>((hi.y() - lo.y()) * scale);
  cv::Mat image(h + 30, w, CV_8UC3, cv::Scalar(30, 30, 30));
  const auto at = [&](double x, double z) { return cv::Point2d((x - lo.x()) * scale, (z - lo.y()) * scale); };
  // A line a metre, where there are few enough to see (a counted loop: far cameras make huge
  // coordinates, where adding 1 m changes nothing).
  const Eigen::Vector2d span = hi - lo;
  if (span.maxCoeff() < 1000.0) {
    for (int i = 0; i <= static_cast<int>(span.x()); ++i) {
      const double x = std::ceil(lo.x()) + i;
      cv::line(image, at(x, lo.y()), at(x, hi.y()), cv::Scalar(50, 50, 50), 1);
    }
    for (int i = 0; i <= static_cast<int>(span.y()); ++i) {
      const double z = std::ceil(lo.y()) + i;
      cv::line(image, at(lo.x(), z), at(hi.x(), z), cv::Scalar(50, 50, 50), 1);
    }
  }
  const double floor_y = volume.centre_m.y() - 0.5 * volume.size_m.y();
  for (const Camera& c : rig.cameras) {
    // The image's border, sampled, cast onto the plane Y = floor_y.
    std::vector<cv::Point> outline;
    const CameraIntrinsics& k = c.intrinsics;
    const Eigen::Vector3d o = c.centre_world();
    for (int n = 0; n < 64; ++n) {
      const double t = n / 16.0;
      const int side = n / 16;
      const double f = t - side;
      const Eigen::Vector2d pixel = side == 0   ? Eigen::Vector2d(f * (k.width_px - 1), 0)
                                    : side == 1 ? Eigen::Vector2d(k.width_px - 1, f * (k.height_px - 1))
                                    : side == 2 ? Eigen::Vector2d((1 - f) * (k.width_px - 1), k.height_px - 1)
                                                : Eigen::Vector2d(0, (1 - f) * (k.height_px - 1));
      const Eigen::Vector3d ray = c.ray_world(pixel);
      if (!(ray.y() < -1e-6) || !(o.y() > floor_y)) continue;  // rays that never reach the floor plane
      const Eigen::Vector3d hit = o + ray * ((floor_y - o.y()) / ray.y());
      if ((hit - o).norm() > 50.0) continue;
      outline.push_back(at(hit.x(), hit.z()));
    }
    if (outline.size() >= 3) cv::polylines(image, outline, true, cv::Scalar(160, 120, 60), 1, cv::LINE_AA);
    // Where it looks: its optical axis down to that plane.
    const Eigen::Vector3d axis = c.ray_world(Eigen::Vector2d(k.cx, k.cy));
    if (axis.y() < -1e-6 && o.y() > floor_y) {
      const Eigen::Vector3d hit = o + axis * ((floor_y - o.y()) / axis.y());
      cv::line(image, at(o.x(), o.z()), at(hit.x(), hit.z()), cv::Scalar(0, 140, 200), 1, cv::LINE_AA);
    }
  }
  cv::rectangle(image, at(volume.centre_m.x() - 0.5 * volume.size_m.x(), volume.centre_m.z() - 0.5 * volume.size_m.z()),
                at(volume.centre_m.x() + 0.5 * volume.size_m.x(), volume.centre_m.z() + 0.5 * volume.size_m.z()), cv::Scalar(255, 255, 255),
                2);
  for (const Camera& c : rig.cameras) {
    const Eigen::Vector3d o = c.centre_world();
    cv::circle(image, at(o.x(), o.z()), 4, cv::Scalar(0, 200, 255), cv::FILLED, cv::LINE_AA);
    cv::putText(image, fmt::format("{} {:.1f} m", c.name, o.y()), at(o.x(), o.z()) + cv::Point2d(6, -4), cv::FONT_HERSHEY_SIMPLEX, 0.35,
                cv::Scalar(220, 220, 220), 1, cv::LINE_AA);
  }
  cv::putText(
      image,
      fmt::format(
          "{} cameras from above (X right, -Z up); each at its height; lines: optical axes, outlines: images, to Y = {:.2f} m; grid 1 m",
          rig.cameras.size(), floor_y),
      {6, h + 20}, cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(230, 230, 230), 1, cv::LINE_AA);
  return write_png(file, image);
}

}  // namespace rhot
