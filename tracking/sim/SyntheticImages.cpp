#include "tracking/sim/SyntheticImages.h"

#include <algorithm>
#include <cmath>

#include <opencv2/core.hpp>

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

cv::Mat draw_blobs(const CameraIntrinsics& camera, const CameraFrame& frame, const SyntheticImageSettings& s) {
  cv::Mat light(camera.height_px, camera.width_px, CV_64FC1, cv::Scalar(s.background));
  const double radius = std::ceil(4.0 * s.blob_sigma_px);
  const double inv_two_var = 1.0 / (2.0 * s.blob_sigma_px * s.blob_sigma_px);
  for (const Detection& d : frame.detections) {
    if (!d.pixel.allFinite()) continue;
    const int x0 = std::max(0, static_cast<int>(std::floor(d.pixel.x() - radius)));
    const int x1 = std::min(camera.width_px - 1, static_cast<int>(std::ceil(d.pixel.x() + radius)));
    const int y0 = std::max(0, static_cast<int>(std::floor(d.pixel.y() - radius)));
    const int y1 = std::min(camera.height_px - 1, static_cast<int>(std::ceil(d.pixel.y() + radius)));
    for (int y = y0; y <= y1; ++y) {
      auto* row = light.ptr<double>(y);
      const double dy = y - d.pixel.y();
      for (int x = x0; x <= x1; ++x) {
        const double dx = x - d.pixel.x();
        row[x] += s.peak * std::exp(-(dx * dx + dy * dy) * inv_two_var);
      }
    }
  }
  if (s.noise_sigma > 0.0) {
    cv::RNG rng(s.seed);  // OpenCV's generator: the same seed gives the same noise
    cv::Mat noise(light.size(), CV_64FC1);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, s.noise_sigma);
    light += noise;
  }
  cv::Mat image;
  light.convertTo(image, CV_8UC1);  // rounds and saturates to 0-255
  return image;
}

}  // namespace rhot
