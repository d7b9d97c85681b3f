#include "tracking/sim/SyntheticImages.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "tracking/core/MarkerColour.h"

namespace rhot {

std::expected<void, std::string> SyntheticImageSettings::check() const {
  const auto bad = [](const char* field, const char* expected, double value) {
    return std::unexpected(std::string(field) + ": expected " + expected + ", got " + std::to_string(value));
  };
  if (!std::isfinite(blob_sigma_px) || blob_sigma_px < 0.3 || blob_sigma_px > 20.0)
    return bad("blob_sigma_px", "0.3 to 20 pixels", blob_sigma_px);
  if (!std::isfinite(peak) || peak < 0.0 || peak > 255.0) return bad("peak", "0 to 255 grey levels", peak);
  if (!std::isfinite(background) || background < 0.0 || background > 255.0) return bad("background", "0 to 255 grey levels", background);
  if (!std::isfinite(noise_sigma) || noise_sigma < 0.0 || noise_sigma > 100.0)
    return bad("noise_sigma", "0 to 100 grey levels", noise_sigma);
  return {};
}

namespace {

// The pixel box a blob lights: its centre +- `radius`, inside the image; empty for a detection
// that is not a finite pixel.
cv::Rect blob_box(const CameraIntrinsics& camera, const Detection& d, double radius) {
  if (!d.pixel.allFinite()) return {};
  const int x0 = std::max(0, static_cast<int>(std::floor(d.pixel.x() - radius)));
  const int x1 = std::min(camera.width_px - 1, static_cast<int>(std::ceil(d.pixel.x() + radius)));
  const int y0 = std::max(0, static_cast<int>(std::floor(d.pixel.y() - radius)));
  const int y1 = std::min(camera.height_px - 1, static_cast<int>(std::ceil(d.pixel.y() + radius)));
  return x1 < x0 || y1 < y0 ? cv::Rect{} : cv::Rect(x0, y0, x1 - x0 + 1, y1 - y0 + 1);
}

}  // namespace

cv::Mat draw_blobs(const CameraIntrinsics& camera, const CameraFrame& frame, const SyntheticImageSettings& s) {
  const double radius = std::ceil(4.0 * s.blob_sigma_px);
  const double inv_two_var = 1.0 / (2.0 * s.blob_sigma_px * s.blob_sigma_px);
  std::vector<cv::Rect> boxes;
  boxes.reserve(frame.detections.size());
  for (const Detection& d : frame.detections) boxes.push_back(blob_box(camera, d, radius));
  // Blob b's light at a pixel.
  const auto blob_light = [&](std::size_t b, int x, int y) {
    const double dx = x - frame.detections[b].pixel.x(), dy = y - frame.detections[b].pixel.y();
    return s.peak * std::exp(-(dx * dx + dy * dy) * inv_two_var);
  };
  // The light at a pixel: the background, then each blob whose box holds it, in detection order.
  const auto light_at = [&](int x, int y, double background) {
    double light = background;
    for (std::size_t b = 0; b < boxes.size(); ++b) {
      if (boxes[b].contains({x, y})) light += blob_light(b, x, y);
    }
    return light;
  };
  if (s.noise_sigma <= 0.0) {
    // Without noise only the blobs' boxes differ from the background: an 8-bit image, each of
    // their pixels summed as below and rounded once (the same image, a ninth of the memory).
    cv::Mat image(camera.height_px, camera.width_px, CV_8UC1, cv::Scalar(cv::saturate_cast<std::uint8_t>(s.background)));
    for (const cv::Rect& box : boxes) {
      for (int y = box.y; y < box.y + box.height; ++y) {
        auto* row = image.ptr<std::uint8_t>(y);
        for (int x = box.x; x < box.x + box.width; ++x) row[x] = cv::saturate_cast<std::uint8_t>(light_at(x, y, s.background));
      }
    }
    return image;
  }
  // The noise drawn in single precision around the background (OpenCV draws its normal numbers as
  // floats), the blobs' light added over their boxes, then rounded to 8 bits: two passes over the
  // image instead of five over one of doubles (rhot-calib simulate --images: 64 -> 25 ms a
  // 1024 x 768 picture under the sanitizers, with the PNG written).
  cv::RNG rng(s.seed);  // OpenCV's generator: the same seed gives the same noise
  cv::Mat light(camera.height_px, camera.width_px, CV_32FC1);
  rng.fill(light, cv::RNG::NORMAL, s.background, s.noise_sigma);
  for (std::size_t b = 0; b < boxes.size(); ++b) {  // each blob over its own box (boxes overlap)
    const cv::Rect& box = boxes[b];
    for (int y = box.y; y < box.y + box.height; ++y) {
      auto* row = light.ptr<float>(y);
      for (int x = box.x; x < box.x + box.width; ++x) row[x] += static_cast<float>(blob_light(b, x, y));
    }
  }
  cv::Mat image;
  light.convertTo(image, CV_8UC1);  // rounds and saturates to 0-255
  return image;
}

}  // namespace rhot

namespace rhot {

std::array<double, 3> white_balance_gains(double kelvin) {
  const auto light = [](double k) {
    const double t = std::clamp(k, 1000.0, 40000.0) / 100.0;
    double r, g, b;
    if (t <= 66.0) {
      r = 255.0;
      g = 99.4708025861 * std::log(t) - 161.1195681661;
      b = t <= 19.0 ? 0.0 : 138.5177312231 * std::log(t - 10.0) - 305.0447927307;
    } else {
      r = 329.698727446 * std::pow(t - 60.0, -0.1332047592);
      g = 288.1221695283 * std::pow(t - 60.0, -0.0755148492);
      b = 255.0;
    }
    return std::array<double, 3>{std::clamp(r, 1.0, 255.0), std::clamp(g, 1.0, 255.0), std::clamp(b, 1.0, 255.0)};
  };
  const auto l = light(kelvin), d = light(6500.0);
  std::array<double, 3> gain{l[0] / d[0], l[1] / d[1], l[2] / d[2]};
  const double g = gain[1];
  for (double& v : gain) v /= g;
  return gain;
}

std::expected<void, std::string> ColourImageSettings::check() const {
  const auto bad = [](const char* field, const char* expected, double value) {
    return std::unexpected(std::string(field) + ": expected " + expected + ", got " + std::to_string(value));
  };
  if (!std::isfinite(noise_sigma) || noise_sigma < 0.0 || noise_sigma > 100.0) return bad("noise_sigma", "0 to 100 levels", noise_sigma);
  if (!std::isfinite(kelvin) || kelvin < 1500.0 || kelvin > 15000.0) return bad("kelvin", "1500 to 15000 K", kelvin);
  if (!std::isfinite(exposure) || exposure < 0.05 || exposure > 4.0) return bad("exposure", "0.05 to 4", exposure);
  return {};
}

namespace {

const std::array<double, 3>& display_colour(int colour) {
  return kMarkerColours[static_cast<std::size_t>(std::clamp(colour, 0, kMarkerColourCount - 1))].display_srgb;
}

// A grey-beige table, a little lighter towards the bottom right: linear-ish RGB 0-1.
cv::Mat table_image(int width_px, int height_px) {
  cv::Mat img(height_px, width_px, CV_32FC3);
  for (int y = 0; y < height_px; ++y) {
    auto* row = img.ptr<cv::Vec3f>(y);
    for (int x = 0; x < width_px; ++x) {
      const float shade = 0.85f + 0.15f * static_cast<float>(x + y) / static_cast<float>(width_px + height_px);
      row[x] = cv::Vec3f(0.62f, 0.60f, 0.55f) * shade;  // a grey-beige table
    }
  }
  return img;
}

// Wood grain: orange-brown stripes over the left third. Skin: two hands' worth of patches (hue
// 15-25 degrees, saturation 0.3-0.5).
void draw_wood_and_skin(cv::Mat& img, cv::RNG& rng) {
  const int width_px = img.cols, height_px = img.rows;
  const auto paint_ellipse = [&](cv::Point2f c, cv::Size2f axes, float angle, cv::Vec3f colour) {
    cv::ellipse(img, cv::RotatedRect(c, axes, angle),
                cv::Scalar(static_cast<double>(colour[0]), static_cast<double>(colour[1]), static_cast<double>(colour[2])), cv::FILLED,
                cv::LINE_AA);
  };
  for (int i = 0; i < 12; ++i) {
    const int y = static_cast<int>(rng.uniform(0, height_px));
    cv::line(img, {0, y}, {width_px / 3, y + static_cast<int>(rng.uniform(-20, 20))}, cv::Scalar(0.62, 0.40 + rng.uniform(0.0, 0.08), 0.20),
             static_cast<int>(rng.uniform(2, 9)), cv::LINE_AA);
  }
  for (int i = 0; i < 8; ++i) {
    const float sat = static_cast<float>(rng.uniform(0.3, 0.5)), v = static_cast<float>(rng.uniform(0.55, 0.9));
    const float hue = static_cast<float>(rng.uniform(12.0, 25.0));
    const float r = v, b = v * (1.0f - sat), g = b + (r - b) * hue / 60.0f;
    paint_ellipse({static_cast<float>(rng.uniform(0, width_px)), static_cast<float>(rng.uniform(0, height_px))},
                  {static_cast<float>(rng.uniform(30, 90)), static_cast<float>(rng.uniform(60, 160))},
                  static_cast<float>(rng.uniform(0, 180)), {r, g, b});
  }
}

// Cables: thin lines of marker colours, elongated, clear of the markers.
void draw_cables(cv::Mat& img, std::span<const ColourMarkerDrawing> markers, cv::RNG& rng) {
  const int width_px = img.cols, height_px = img.rows;
  for (int i = 0; i < 3; ++i) {
    const auto& c = display_colour((i * 3 + 1) % 8);
    for (int attempt = 0; attempt < 50; ++attempt) {
      const Eigen::Vector2d a(rng.uniform(0, width_px), rng.uniform(0, height_px)), b(rng.uniform(0, width_px), rng.uniform(0, height_px));
      if (std::any_of(markers.begin(), markers.end(), [&](const ColourMarkerDrawing& m) {
            const double t = std::clamp((m.pixel - a).dot(b - a) / std::max(1e-9, (b - a).squaredNorm()), 0.0, 1.0);
            return (a + t * (b - a) - m.pixel).norm() < m.radius_px + 6.0;
          })) {
        continue;
      }
      cv::line(img, cv::Point(static_cast<int>(a.x()), static_cast<int>(a.y())),
               cv::Point(static_cast<int>(b.x()), static_cast<int>(b.y())), cv::Scalar(c[0], c[1], c[2]), 3, cv::LINE_AA);
      break;
    }
  }
}

// Boxes and a mug painted in the markers' colours, far larger than a marker.
void draw_boxes(cv::Mat& img, std::span<const ColourMarkerDrawing> markers, cv::RNG& rng) {
  const int width_px = img.cols, height_px = img.rows;
  for (int i = 0; i < 4; ++i) {
    const auto& c = display_colour(i * 2 % 8);
    // Away from the markers: a marker on a box of its own colour is lost in it, as it would be.
    for (int attempt = 0; attempt < 50; ++attempt) {
      const cv::Rect box(static_cast<int>(rng.uniform(0, std::max(1, width_px - 80))),
                         static_cast<int>(rng.uniform(0, std::max(1, height_px - 80))), static_cast<int>(rng.uniform(80, 140)),
                         static_cast<int>(rng.uniform(80, 140)));
      if (std::any_of(markers.begin(), markers.end(), [&](const ColourMarkerDrawing& m) {
            const double dx = std::max({box.x - m.pixel.x(), 0.0, m.pixel.x() - (box.x + box.width)});
            const double dy = std::max({box.y - m.pixel.y(), 0.0, m.pixel.y() - (box.y + box.height)});
            return std::hypot(dx, dy) < m.radius_px + 6.0;
          })) {
        continue;
      }
      cv::rectangle(img, box, cv::Scalar(c[0] * 0.8, c[1] * 0.8, c[2] * 0.8), cv::FILLED);
      break;
    }
  }
}

// A marker: a shaded disc, its edge pixels mixed by coverage.
void draw_marker(cv::Mat& img, const ColourMarkerDrawing& m) {
  const auto& c = display_colour(m.colour);
  const int x0 = std::max(0, static_cast<int>(std::floor(m.pixel.x() - m.radius_px - 1)));
  const int x1 = std::min(img.cols - 1, static_cast<int>(std::ceil(m.pixel.x() + m.radius_px + 1)));
  const int y0 = std::max(0, static_cast<int>(std::floor(m.pixel.y() - m.radius_px - 1)));
  const int y1 = std::min(img.rows - 1, static_cast<int>(std::ceil(m.pixel.y() + m.radius_px + 1)));
  for (int y = y0; y <= y1; ++y) {
    auto* row = img.ptr<cv::Vec3f>(y);
    for (int x = x0; x <= x1; ++x) {
      int inside = 0;
      double shade = 0.0;
      for (int sy = 0; sy < 4; ++sy) {
        for (int sx = 0; sx < 4; ++sx) {
          const double dx = (x - 0.375 + 0.25 * sx - m.pixel.x()) / m.radius_px, dy = (y - 0.375 + 0.25 * sy - m.pixel.y()) / m.radius_px;
          const double rr = dx * dx + dy * dy;
          if (rr > 1.0) continue;
          ++inside;
          // A sphere lit from the upper left: Lambert on its normal, plus ambient.
          const double nz = std::sqrt(1.0 - rr);
          shade += 0.45 + 0.55 * std::max(0.0, -0.4 * dx - 0.5 * dy + 0.77 * nz);
        }
      }
      if (inside == 0) continue;
      const float a = static_cast<float>(inside) / 16.0f;
      const float k = static_cast<float>(shade / inside);
      row[x] = row[x] * (1.0f - a) + cv::Vec3f(static_cast<float>(c[0]), static_cast<float>(c[1]), static_cast<float>(c[2])) * (k * a);
    }
  }
}

// The working image as the camera gives it: exposed, white-balanced for s.kelvin, with noise,
// 8-bit BGR.
cv::Mat camera_image(const cv::Mat& img, const ColourImageSettings& s, cv::RNG& rng) {
  const int width_px = img.cols, height_px = img.rows;
  const auto gain = white_balance_gains(s.kelvin);
  cv::Mat out(height_px, width_px, CV_8UC3);
  cv::Mat noise(height_px, width_px, CV_32FC3);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, s.noise_sigma);
  for (int y = 0; y < height_px; ++y) {
    const auto* row = img.ptr<cv::Vec3f>(y);
    const auto* n = noise.ptr<cv::Vec3f>(y);
    auto* o = out.ptr<cv::Vec3b>(y);
    for (int x = 0; x < width_px; ++x) {
      for (int ch = 0; ch < 3; ++ch) {
        const double v =
            255.0 * s.exposure * gain[static_cast<std::size_t>(ch)] * static_cast<double>(row[x][ch]) + static_cast<double>(n[x][ch]);
        o[x][2 - ch] = static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
      }
    }
  }
  return out;
}

}  // namespace

cv::Mat draw_colour_markers(int width_px, int height_px, std::span<const ColourMarkerDrawing> markers, const ColourImageSettings& s) {
  cv::RNG rng(s.seed);
  // Linear-ish working image, RGB 0-1.
  cv::Mat img = table_image(width_px, height_px);
  if (s.clutter) {
    draw_wood_and_skin(img, rng);
    draw_cables(img, markers, rng);
    draw_boxes(img, markers, rng);
  }
  for (const ColourMarkerDrawing& m : markers) {
    if (!m.pixel.allFinite() || !(m.radius_px > 0.0)) continue;
    draw_marker(img, m);
  }
  return camera_image(img, s, rng);
}

}  // namespace rhot
