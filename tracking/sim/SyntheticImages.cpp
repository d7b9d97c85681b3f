#include "tracking/sim/SyntheticImages.h"

#include <algorithm>
#include <cmath>

#include <opencv2/core.hpp>

namespace rhot {

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
