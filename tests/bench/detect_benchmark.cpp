// Marker detection in one camera image (tracking/detect/BlobDetector.h): a 1280 x 720 image (the
// shipped rigs' cameras) with N Gaussian spots (sigma 1.5 px) and noise of 2 grey levels, against
// the plain way with OpenCV: a fixed threshold and cv::connectedComponentsWithStats with its
// centroids (no sub-pixel weighting, no automatic threshold, no splitting), which is what the
// detector itself did at first. Same images, same run. Labelling every pixel of the image costs
// far more than tracing the few components' contours, which the detector now does.

#include <random>

#include <benchmark/benchmark.h>
#include <opencv2/imgproc.hpp>

#include "tracking/detect/BlobDetector.h"
#include "tracking/net/NodeProtocol.h"
#include "tracking/sim/SyntheticImages.h"

namespace rhot {
namespace {

cv::Mat image_with_spots(int spots) {
  CameraIntrinsics camera;
  camera.width_px = 1280;
  camera.height_px = 720;
  CameraFrame frame;
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> x(10.0, 1270.0), y(10.0, 710.0);
  for (int i = 0; i < spots; ++i) frame.detections.push_back({Eigen::Vector2d{x(rng), y(rng)}, -1});
  SyntheticImageSettings s;
  s.noise_sigma = 2.0;
  return draw_blobs(camera, frame, s);
}

void BM_DetectBlobs(benchmark::State& state) {
  const cv::Mat image = image_with_spots(static_cast<int>(state.range(0)));
  std::size_t found = 0;
  for (auto _ : state) {
    auto blobs = detect_blobs(image);
    found = blobs ? blobs->size() : 0;
    benchmark::DoNotOptimize(blobs);
  }
  state.counters["found"] = static_cast<double>(found);
}
BENCHMARK(BM_DetectBlobs)->Arg(10)->Arg(40)->Arg(100)->Unit(benchmark::kMillisecond);

// A camera node's work per image (rhot-node --device): detection, then the frame message encoded
// for the wire, beside detection alone above.
void BM_NodeDetectAndEncode(benchmark::State& state) {
  const cv::Mat image = image_with_spots(static_cast<int>(state.range(0)));
  std::size_t bytes = 0;
  for (auto _ : state) {
    auto blobs = detect_blobs(image);
    NodeFrameMessage m;
    m.width = 1280;
    m.height = 720;
    if (blobs) m.detections = std::move(*blobs);
    const auto wire = encode(m);
    bytes = wire.size();
    benchmark::DoNotOptimize(wire.data());
  }
  state.counters["bytes"] = static_cast<double>(bytes);
}
BENCHMARK(BM_NodeDetectAndEncode)->Arg(40)->Unit(benchmark::kMillisecond);

// Baseline: threshold at a fixed level and label; OpenCV's centroids of the binary components.
void BM_ThresholdAndComponentsBaseline(benchmark::State& state) {
  const cv::Mat image = image_with_spots(static_cast<int>(state.range(0)));
  cv::Mat binary, labels, stats, centroids;
  int found = 0;
  for (auto _ : state) {
    cv::threshold(image, binary, 60, 255, cv::THRESH_BINARY);
    found = cv::connectedComponentsWithStats(binary, labels, stats, centroids, 8, CV_32S) - 1;
    benchmark::DoNotOptimize(centroids.data);
  }
  state.counters["found"] = found;
}
BENCHMARK(BM_ThresholdAndComponentsBaseline)->Arg(10)->Arg(40)->Arg(100)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace rhot
