#include "tracking/plan/PlanPictures.h"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "base/Check.h"
#include "tracking/media/Media.h"

namespace rhot {

namespace {

std::expected<void, std::string> write_png(const std::filesystem::path& file, const cv::Mat& image) { return write_image(file, image); }

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

std::string slice_height_caption(const CoverageGrid& grid, double height_m) {
  const std::string asked = fmt::format("{:.2f}", height_m);
  const std::string row = fmt::format("{:.2f}", grid.origin_m.y() + slice_of(grid, height_m) * grid.step_m.y());
  return row == asked ? "height " + asked + " m" : "height " + asked + " m (the grid's nearest row: " + row + " m)";
}

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
                                      {fmt::format("{}: seen by 1+ {:.1f} %, 2+ {:.1f} %, 3+ {:.1f} %", slice_height_caption(g, height_m),
                                                   100.0 * static_cast<double>(seen[1]) / n, 100.0 * static_cast<double>(seen[2]) / n,
                                                   100.0 * static_cast<double>(seen[3]) / n),
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
  const cv::Mat image =
      slice_picture(g, colour, y,
                    {fmt::format("{}: predicted RMS 3D error at {:.2f} px", slice_height_caption(g, height_m), report.sigma_px),
                     fmt::format("green 0 mm -> red {:.2f} mm and more; dark: fewer than 2 cameras", scale_mm)});
  return write_png(file, image);
}

bool LabelBox::overlaps(const LabelBox& other) const {
  return min_px.x() < other.max_px.x() && other.min_px.x() < max_px.x() && min_px.y() < other.max_px.y() && other.min_px.y() < max_px.y();
}

std::vector<std::optional<LabelBox>> place_labels(const std::vector<Eigen::Vector2d>& points_px,
                                                  const std::vector<Eigen::Vector2d>& sizes_px, const Eigen::Vector2d& picture_px) {
  RHOT_PRECONDITION(points_px.size() == sizes_px.size(), "place_labels: one size per point");
  // The points themselves, a dot of 4 px radius each: a label must not hide another camera.
  std::vector<LabelBox> taken;
  for (const Eigen::Vector2d& p : points_px) taken.push_back({p - Eigen::Vector2d(4, 4), p + Eigen::Vector2d(4, 4)});
  std::vector<std::optional<LabelBox>> placed;
  for (std::size_t i = 0; i < points_px.size(); ++i) {
    const Eigen::Vector2d& p = points_px[i];
    const double w = sizes_px[i].x(), h = sizes_px[i].y();
    std::optional<LabelBox> chosen;
    for (const double gap : {6.0, 18.0}) {
      // Top-left corners: right (the usual place, a little above the point), below right, left,
      // below left, above, below.
      for (const Eigen::Vector2d& corner :
           {Eigen::Vector2d(p.x() + gap, p.y() - gap - h + 4.0), Eigen::Vector2d(p.x() + gap, p.y() + gap - 2.0),
            Eigen::Vector2d(p.x() - gap - w, p.y() - gap - h + 4.0), Eigen::Vector2d(p.x() - gap - w, p.y() + gap - 2.0),
            Eigen::Vector2d(p.x() - 0.5 * w, p.y() - gap - h), Eigen::Vector2d(p.x() - 0.5 * w, p.y() + gap)}) {
        const LabelBox box{corner, corner + Eigen::Vector2d(w, h)};
        if (box.min_px.x() < 0.0 || box.min_px.y() < 0.0 || box.max_px.x() > picture_px.x() || box.max_px.y() > picture_px.y()) continue;
        bool free = true;
        for (std::size_t t = 0; t < taken.size() && free; ++t) free = t == i || !box.overlaps(taken[t]);  // its own dot may touch it
        if (!free) continue;
        chosen = box;
        break;
      }
      if (chosen) break;
    }
    if (chosen) taken.push_back(*chosen);
    placed.push_back(chosen);
  }
  return placed;
}

namespace {

// How write_plan_top_view maps the world onto its picture: the cameras and the volume, 1 m around
// them, 100 px a metre or less to stay within 900 px, and at least 720 px wide for its caption.
struct TopView {
  Eigen::Vector2d lo, hi;  // world X and Z at the picture's top left and bottom right
  double scale = 1.0;      // pixels per metre
  int width_px = 0, height_px = 0;

  cv::Point2d at(double x, double z) const { return cv::Point2d((x - lo.x()) * scale, (z - lo.y()) * scale); }
};

std::expected<TopView, std::string> top_view(const CameraRig& rig, const TrackingVolume& volume) {
  TopView v;
  v.lo = Eigen::Vector2d(volume.centre_m.x() - 0.5 * volume.size_m.x(), volume.centre_m.z() - 0.5 * volume.size_m.z());
  v.hi = Eigen::Vector2d(volume.centre_m.x() + 0.5 * volume.size_m.x(), volume.centre_m.z() + 0.5 * volume.size_m.z());
  for (const Camera& c : rig.cameras) {
    const Eigen::Vector3d o = c.centre_world();
    if (!o.allFinite()) return std::unexpected("camera " + c.name + " has no finite centre");
    v.lo = v.lo.cwiseMin(Eigen::Vector2d(o.x(), o.z()));
    v.hi = v.hi.cwiseMax(Eigen::Vector2d(o.x(), o.z()));
  }
  v.lo -= Eigen::Vector2d::Constant(1.0);
  v.hi += Eigen::Vector2d::Constant(1.0);
  v.scale = std::min(100.0, 900.0 / (v.hi - v.lo).maxCoeff());
  if ((v.hi.x() - v.lo.x()) * v.scale < 720.0) {
    const double widen = 0.5 * (720.0 / v.scale - (v.hi.x() - v.lo.x()));
    v.lo.x() -= widen;
    v.hi.x() += widen;
  }
  v.width_px = static_cast<int>((v.hi.x() - v.lo.x()) * v.scale);
  v.height_px = static_cast<int>((v.hi.y() - v.lo.y()) * v.scale);
  return v;
}

constexpr double kLabelFontScale = 0.35;

std::string camera_label(const Camera& c) { return fmt::format("{} {:.1f} m", c.name, c.centre_world().y()); }

// The labels' boxes in the picture of `view`, a pixel of margin around each text; the text's
// baseline lies `baseline` px above its box's bottom, less that pixel.
std::vector<std::optional<LabelBox>> camera_labels(const CameraRig& rig, const TopView& view, int& baseline) {
  std::vector<Eigen::Vector2d> points, sizes;
  baseline = 0;
  for (const Camera& c : rig.cameras) {
    const Eigen::Vector3d o = c.centre_world();
    const cv::Point2d p = view.at(o.x(), o.z());
    points.emplace_back(p.x, p.y);
    const cv::Size text = cv::getTextSize(camera_label(c), cv::FONT_HERSHEY_SIMPLEX, kLabelFontScale, 1, &baseline);
    sizes.emplace_back(text.width + 2, text.height + baseline + 2);  // a pixel around the text: anti-aliased edges
  }
  return place_labels(points, sizes, Eigen::Vector2d(view.width_px, view.height_px));
}

// Each camera's image border cast onto the plane Y = floor_y, and its optical axis down to it.
void draw_footprints(cv::Mat& image, const CameraRig& rig, const TopView& view, double floor_y) {
  for (const Camera& c : rig.cameras) {
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
      outline.push_back(view.at(hit.x(), hit.z()));
    }
    if (outline.size() >= 3) cv::polylines(image, outline, true, cv::Scalar(160, 120, 60), 1, cv::LINE_AA);
    // Where it looks: its optical axis down to that plane.
    const Eigen::Vector3d axis = c.ray_world(Eigen::Vector2d(k.cx, k.cy));
    if (axis.y() < -1e-6 && o.y() > floor_y) {
      const Eigen::Vector3d hit = o + axis * ((floor_y - o.y()) / axis.y());
      cv::line(image, view.at(o.x(), o.z()), view.at(hit.x(), hit.z()), cv::Scalar(0, 140, 200), 1, cv::LINE_AA);
    }
  }
}

}  // namespace

std::expected<std::vector<std::optional<LabelBox>>, std::string> plan_top_view_labels(const CameraRig& rig, const TrackingVolume& volume) {
  const auto view = top_view(rig, volume);
  if (!view) return std::unexpected(view.error());
  int baseline = 0;
  return camera_labels(rig, *view, baseline);
}

std::expected<void, std::string> write_plan_top_view(const std::filesystem::path& file, const CameraRig& rig,
                                                     const TrackingVolume& volume) {
  const auto framed = top_view(rig, volume);
  if (!framed) return std::unexpected(file.string() + ": " + framed.error());
  const TopView& view = *framed;
  const int w = view.width_px, h = view.height_px;
  cv::Mat image(h + 50, w, CV_8UC3, cv::Scalar(30, 30, 30));  // two lines of caption beneath
  // A line a metre, where there are few enough to see (a counted loop: far cameras make huge
  // coordinates, where adding 1 m changes nothing).
  const Eigen::Vector2d span = view.hi - view.lo;
  if (span.maxCoeff() < 1000.0) {
    for (int i = 0; i <= static_cast<int>(span.x()); ++i) {
      const double x = std::ceil(view.lo.x()) + i;
      cv::line(image, view.at(x, view.lo.y()), view.at(x, view.hi.y()), cv::Scalar(50, 50, 50), 1);
    }
    for (int i = 0; i <= static_cast<int>(span.y()); ++i) {
      const double z = std::ceil(view.lo.y()) + i;
      cv::line(image, view.at(view.lo.x(), z), view.at(view.hi.x(), z), cv::Scalar(50, 50, 50), 1);
    }
  }
  const double floor_y = volume.centre_m.y() - 0.5 * volume.size_m.y();
  draw_footprints(image, rig, view, floor_y);
  cv::rectangle(image, view.at(volume.centre_m.x() - 0.5 * volume.size_m.x(), volume.centre_m.z() - 0.5 * volume.size_m.z()),
                view.at(volume.centre_m.x() + 0.5 * volume.size_m.x(), volume.centre_m.z() + 0.5 * volume.size_m.z()),
                cv::Scalar(255, 255, 255), 2);
  int baseline = 0;
  const std::vector<std::optional<LabelBox>> labels = camera_labels(rig, view, baseline);
  std::size_t left_out = 0;
  for (std::size_t i = 0; i < rig.cameras.size(); ++i) {
    const Eigen::Vector3d o = rig.cameras[i].centre_world();
    cv::circle(image, view.at(o.x(), o.z()), 4, cv::Scalar(0, 200, 255), cv::FILLED, cv::LINE_AA);
    if (!labels[i]) {
      ++left_out;
      continue;
    }
    const cv::Point origin(static_cast<int>(std::lround(labels[i]->min_px.x())) + 1,
                           static_cast<int>(std::lround(labels[i]->max_px.y())) - 1 - baseline);
    cv::putText(image, camera_label(rig.cameras[i]), origin, cv::FONT_HERSHEY_SIMPLEX, kLabelFontScale, cv::Scalar(220, 220, 220), 1,
                cv::LINE_AA);
  }
  const std::string lines[2] = {
      fmt::format("{} cameras from above (X right, -Z up), each at its height; grid 1 m", rig.cameras.size()),
      fmt::format("lines: optical axes, outlines: images, to Y = {:.2f} m{}", floor_y,
                  left_out == 0 ? std::string() : fmt::format("; {} of the labels left out (no room)", left_out))};
  for (int n = 0; n < 2; ++n) {
    cv::putText(image, lines[n], {6, h + 20 + 20 * n}, cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(230, 230, 230), 1, cv::LINE_AA);
  }
  return write_png(file, image);
}

}  // namespace rhot
