#include "tracking/detect/BlobDetector.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <cmath>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace rhot {

namespace {

struct Blob {
  Eigen::Vector2d pixel;
  double weight = 0.0;  // summed intensity above the level it was cut at
  int area = 0;
  int peak = 0;
};

struct Region {
  Eigen::Vector2d centroid{0, 0};
  double weight = 0.0;
  double elongation = 1.0;
  int peak = 0;
  int area = 0;
};

struct Background {
  double median = 0.0;
  double sigma = 0.0;  // 1.4826 * the median absolute deviation: the standard deviation of Gaussian noise
};

// The background's level and noise from the image's histogram: robust, so however many markers
// (up to half the pixels) do not move it. Every second pixel of every second row is enough for a
// median (230 000 samples at 1280 x 720) and reads a quarter of the image.
Background background(const cv::Mat& gray) {
  std::array<std::int64_t, 256> histogram{};
  const int step = gray.rows >= 64 && gray.cols >= 64 ? 2 : 1;
  std::int64_t samples = 0;
  for (int y = 0; y < gray.rows; y += step) {
    const auto* g = gray.ptr<std::uint8_t>(y);
    for (int x = 0; x < gray.cols; x += step) ++histogram[g[x]];
    samples += (gray.cols + step - 1) / step;
  }
  const std::int64_t half = (samples + 1) / 2;
  const auto median_of = [&](const std::array<std::int64_t, 256>& h) {
    std::int64_t below = 0;
    for (int v = 0; v < 256; ++v) {
      below += h[static_cast<std::size_t>(v)];
      if (below >= half) return v;
    }
    return 255;
  };
  const int median = median_of(histogram);
  std::array<std::int64_t, 256> deviations{};
  for (int v = 0; v < 256; ++v) deviations[static_cast<std::size_t>(std::abs(v - median))] += histogram[static_cast<std::size_t>(v)];
  return {static_cast<double>(median), 1.4826 * median_of(deviations)};
}

// A region's weighted centroid, shape and peak. `mask` marks its pixels inside `gray` (same size);
// `offset` places them in the full image.
Region measure(const cv::Mat& gray, const cv::Mat& mask, const cv::Point& offset, int level) {
  double sw = 0.0, swx = 0.0, swy = 0.0, swxx = 0.0, swyy = 0.0, swxy = 0.0;
  Region r;
  for (int y = 0; y < gray.rows; ++y) {
    const auto* g = gray.ptr<std::uint8_t>(y);
    const auto* m = mask.ptr<std::uint8_t>(y);
    for (int x = 0; x < gray.cols; ++x) {
      if (m[x] == 0) continue;
      const double w = static_cast<double>(g[x] - level);
      const double px = x, py = y;
      sw += w;
      swx += w * px;
      swy += w * py;
      swxx += w * px * px;
      swyy += w * py * py;
      swxy += w * px * py;
      ++r.area;
      r.peak = std::max(r.peak, static_cast<int>(g[x]));
    }
  }
  if (r.area == 0 || sw <= 0.0) return r;
  r.weight = sw;
  const double mx = swx / sw, my = swy / sw;
  r.centroid = Eigen::Vector2d(mx + offset.x, my + offset.y);
  // Weighted second moments, each pixel a unit square (hence + 1/12): a lone pixel is round.
  const double cxx = swxx / sw - mx * mx + 1.0 / 12.0, cyy = swyy / sw - my * my + 1.0 / 12.0, cxy = swxy / sw - mx * my;
  const double half_trace = 0.5 * (cxx + cyy);
  const double root = std::sqrt(std::max(0.0, 0.25 * (cxx - cyy) * (cxx - cyy) + cxy * cxy));
  const double major = half_trace + root, minor = std::max(half_trace - root, 1e-12);
  r.elongation = std::sqrt(major / minor);
  return r;
}

// Measures one region; a round one becomes a blob, an elongated one is cut again halfway up to its
// peak and its parts measured in turn, `depth` more times at most.
void resolve(const cv::Mat& gray, const cv::Mat& mask, const cv::Point& offset, int level, int depth, const BlobDetectorSettings& s,
             std::vector<Blob>& out) {
  const Region r = measure(gray, mask, offset, level);
  if (r.weight <= 0.0) return;
  if (r.elongation <= s.max_elongation) {
    out.push_back({r.centroid, r.weight, r.area, r.peak});
    return;
  }
  if (depth <= 0 || r.peak - level < 2) return;
  const int higher = level + (r.peak - level) / 2;
  cv::Mat above;
  cv::threshold(gray, above, higher, 255, cv::THRESH_BINARY);
  above &= mask;
  cv::Mat labels, stats, centroids;
  const int count = cv::connectedComponentsWithStats(above, labels, stats, centroids, 8, CV_32S);
  for (int i = 1; i < count; ++i) {
    if (stats.at<int>(i, cv::CC_STAT_AREA) < s.min_area_px) continue;
    const cv::Rect box(stats.at<int>(i, cv::CC_STAT_LEFT), stats.at<int>(i, cv::CC_STAT_TOP), stats.at<int>(i, cv::CC_STAT_WIDTH),
                       stats.at<int>(i, cv::CC_STAT_HEIGHT));
    const cv::Mat part = labels(box) == i;
    resolve(gray(box), part, offset + box.tl(), higher, depth - 1, s, out);
  }
}

}  // namespace

std::expected<void, std::string> check(const BlobDetectorSettings& s) {
  if (s.threshold > 254)
    return std::unexpected("blob detector: threshold " + std::to_string(s.threshold) +
                           " above 254 (grey levels 0-255; negative: automatic)");
  if (!(s.auto_k >= 0.0) || !std::isfinite(s.auto_k)) return std::unexpected("blob detector: auto_k must be a finite number >= 0");
  if (s.min_threshold < 0 || s.min_threshold > 254)
    return std::unexpected("blob detector: min_threshold " + std::to_string(s.min_threshold) + " outside 0-254");
  if (s.min_area_px < 1) return std::unexpected("blob detector: min_area_px must be at least 1");
  if (s.max_area_px < s.min_area_px)
    return std::unexpected("blob detector: max_area_px " + std::to_string(s.max_area_px) + " below min_area_px " +
                           std::to_string(s.min_area_px));
  if (!(s.max_elongation >= 1.0)) return std::unexpected("blob detector: max_elongation must be at least 1 (a disc)");
  if (s.split_depth < 0) return std::unexpected("blob detector: split_depth must be >= 0");
  if (s.max_blobs < 0) return std::unexpected("blob detector: max_blobs must be >= 0");
  return {};
}

std::expected<std::vector<Detection>, std::string> detect_blobs(const cv::Mat& image, const BlobDetectorSettings& s) {
  if (auto ok = check(s); !ok) return std::unexpected(ok.error());
  if (image.empty()) return std::unexpected(std::string("blob detector: empty image"));
  cv::Mat gray;
  if (image.type() == CV_8UC1) {
    gray = image;
  } else if (image.type() == CV_8UC3) {
    cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
  } else {
    return std::unexpected("blob detector: " + std::to_string(image.cols) + "x" + std::to_string(image.rows) + " image of type " +
                           cv::typeToString(image.type()) + ", expected 8-bit grey (CV_8UC1) or BGR (CV_8UC3)");
  }

  int threshold = s.threshold;
  if (threshold < 0) {
    const Background b = background(gray);
    threshold = std::clamp(static_cast<int>(std::ceil(b.median + s.auto_k * b.sigma)), s.min_threshold, 254);
  }
  cv::Mat mask;
  cv::threshold(gray, mask, threshold, 255, cv::THRESH_BINARY);
  // The 8-connected components by their outer contours: markers cover a tiny part of the image,
  // and tracing their borders (cv::findContours) is some 25 times faster here than labelling
  // every pixel of the image (cv::connectedComponentsWithStats writes a 32-bit label per pixel);
  // measured in tests/bench/detect_benchmark.cpp. Each component's pixels are then its filled
  // contour within the thresholded image, inside its bounding box.
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(mask, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);

  std::vector<Blob> blobs;
  cv::Mat component;
  for (std::vector<cv::Point>& contour : contours) {
    const cv::Rect box = cv::boundingRect(contour);
    if (box.area() < s.min_area_px) continue;
    component = cv::Mat::zeros(box.size(), CV_8UC1);
    for (cv::Point& p : contour) p -= box.tl();
    cv::drawContours(component, std::vector<std::vector<cv::Point>>{contour}, 0, cv::Scalar(255), cv::FILLED);
    component &= mask(box);
    const int area = cv::countNonZero(component);
    if (area < s.min_area_px || area > s.max_area_px) continue;
    resolve(gray(box), component, box.tl(), threshold, s.split_depth, s, blobs);
  }
  if (static_cast<int>(blobs.size()) > s.max_blobs) {
    std::nth_element(blobs.begin(), blobs.begin() + s.max_blobs, blobs.end(),
                     [](const Blob& a, const Blob& b) { return a.weight > b.weight; });
    blobs.resize(static_cast<std::size_t>(s.max_blobs));
  }
  std::vector<Detection> out;
  out.reserve(blobs.size());
  for (const Blob& b : blobs) out.push_back({b.pixel, -1, static_cast<float>(b.area), static_cast<float>(b.peak)});
  return out;
}

}  // namespace rhot
