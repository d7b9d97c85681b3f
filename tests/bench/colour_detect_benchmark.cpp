// Coloured marker detection in one 640 x 480 colour image (tracking/detect/ColourDetector.h): six
// colours, four markers of each (radius 3-7 px) on a cluttered table (skin, wood grain, cables and
// boxes in the markers' colours; tracking/sim/SyntheticImages.h), noise of 2 levels. Side by side
// in one run:
//   ColourDetect/full      the detector searching the whole image (lookup table, runs, union-find)
//   ColourDetect/tracked   the detector following the markers of the frame before (regions of interest)
//   OpenCvHsv              the usual OpenCV way: cvtColor to HSV, then per colour inRange, a 3 x 3
//                          opening and connectedComponentsWithStats (RHOT's seed did this per colour)
// Each iteration is one image; the images differ by their noise.

#include <random>

#include <benchmark/benchmark.h>
#include <opencv2/imgproc.hpp>

#include "tracking/detect/ColourDetector.h"
#include "tracking/sim/SyntheticImages.h"

namespace rhot {
namespace {

std::vector<ColourMarkerDrawing> markers() {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> ux(20.0, 620.0), uy(20.0, 460.0), ur(3.0, 7.0);
  std::vector<ColourMarkerDrawing> out;
  for (const int colour : {0, 2, 3, 4, 5, 7}) {
    for (int i = 0; i < 4; ++i) {
      for (;;) {
        const Eigen::Vector2d p{ux(rng), uy(rng)};
        if (std::all_of(out.begin(), out.end(), [&](const ColourMarkerDrawing& m) { return (m.pixel - p).norm() > 30.0; })) {
          out.push_back({p, ur(rng), colour});
          break;
        }
      }
    }
  }
  return out;
}

const std::vector<cv::Mat>& images() {
  static const std::vector<cv::Mat> images = [] {
    std::vector<cv::Mat> out;
    const auto m = markers();
    for (std::uint64_t seed = 1; seed <= 8; ++seed) {
      ColourImageSettings s;
      s.seed = seed;
      out.push_back(draw_colour_markers(640, 480, m, s));
    }
    return out;
  }();
  return images;
}

void ColourDetectFull(benchmark::State& state) {
  ColourDetector detector(default_colour_model());
  std::size_t i = 0, found = 0;
  for (auto _ : state) {
    const auto d = detector.detect(images()[i++ % images().size()]);
    found = d->size();
    benchmark::DoNotOptimize(found);
  }
  state.counters["markers"] = static_cast<double>(found);
}
BENCHMARK(ColourDetectFull)->Unit(benchmark::kMicrosecond);

void ColourDetectTracked(benchmark::State& state) {
  ColourDetectorSettings settings;
  settings.full_scan_every = 30;
  ColourDetector detector(default_colour_model(), settings);
  std::size_t i = 0, found = 0, full = 0, frames = 0;
  for (auto _ : state) {
    const auto d = detector.track(images()[i++ % images().size()]);
    found = d->size();
    full += detector.last_full_scan() ? 1 : 0;
    ++frames;
    benchmark::DoNotOptimize(found);
  }
  state.counters["markers"] = static_cast<double>(found);
  state.counters["full_scan_fraction"] = static_cast<double>(full) / static_cast<double>(frames);
}
BENCHMARK(ColourDetectTracked)->Unit(benchmark::kMicrosecond);

void OpenCvHsv(benchmark::State& state) {
  const ColourModel model = default_colour_model();
  const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_RECT, {3, 3});
  std::size_t i = 0, found = 0;
  cv::Mat hsv, mask, labels, stats, centroids, lo_mask;
  for (auto _ : state) {
    cv::cvtColor(images()[i++ % images().size()], hsv, cv::COLOR_BGR2HSV);  // H 0-180, S and V 0-255
    found = 0;
    for (const ColourClass& c : model.classes) {
      const double lo = (c.hue_deg - c.hue_tolerance_deg) / 2.0, hi = (c.hue_deg + c.hue_tolerance_deg) / 2.0;
      const cv::Scalar smin(0, 255.0 * c.min_saturation, 255.0 * c.min_value);
      if (lo < 0.0) {  // red wraps around 0
        cv::inRange(hsv, cv::Scalar(lo + 180.0, smin[1], smin[2]), cv::Scalar(180, 255, 255), lo_mask);
        cv::inRange(hsv, cv::Scalar(0, smin[1], smin[2]), cv::Scalar(hi, 255, 255), mask);
        mask |= lo_mask;
      } else {
        cv::inRange(hsv, cv::Scalar(lo, smin[1], smin[2]), cv::Scalar(hi, 255, 255), mask);
      }
      cv::morphologyEx(mask, mask, cv::MORPH_OPEN, kernel);
      found += static_cast<std::size_t>(cv::connectedComponentsWithStats(mask, labels, stats, centroids) - 1);
    }
    benchmark::DoNotOptimize(found);
  }
  state.counters["components"] = static_cast<double>(found);
}
BENCHMARK(OpenCvHsv)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace rhot
