// Matching plus triangulation for 8 cameras x 100 markers with 10 % dropout (the room rig), single
// thread, beside the obvious baseline: OpenCV's cv::triangulatePoints on the same detections,
// pairwise (the first two cameras that see each marker), given the true correspondences, which
// the baseline cannot find by itself. Results: docs/PERFORMANCE.md.

#include <algorithm>
#include <filesystem>
#include <map>

#include <optional>

#include <benchmark/benchmark.h>
#include <opencv2/calib3d.hpp>

#include "tracking/camera/RigFile.h"
#include "base/Jobs.h"
#include "tracking/geometry/Matching.h"
#include "tracking/sim/SimulatedRig.h"

namespace {

struct Data {
  rhot::CameraRig rig;
  std::vector<rhot::RigFrame> frames;
};

const Data& data() {
  static const Data d = [] {
    Data out;
    out.rig = rhot::load_rig(std::filesystem::path(RHOT_ASSET_DIR) / "rigs" / "room-8.yaml").value();
    rhot::SimulatedRigSettings s;
    s.dropout = 0.1;
    rhot::SimulatedRig sim(out.rig, rhot::random_trajectories(100, {-1.5, 0.2, -1.5}, {1.5, 1.8, 1.5}, 2), s);
    for (int i = 0; i < 512; ++i) out.frames.push_back(sim.next());
    return out;
  }();
  return d;
}

void BM_MatchAndTriangulate(benchmark::State& state) {
  const Data& d = data();
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(rhot::match_and_triangulate(d.rig, d.frames[i++ % d.frames.size()]));
  }
}
BENCHMARK(BM_MatchAndTriangulate)->Unit(benchmark::kMicrosecond);

// How matching scales: a rig (0: room-8, 1: stage-32) and a marker count (args), markers wandering
// through the rig's volume, 0.3 px noise, 10 % dropout. Counters: per_marker (seconds per marker, shown with an SI prefix; time over
// markers) and found (matched points over markers seen by two cameras or more).
struct ScaleData {
  rhot::CameraRig rig;
  std::vector<rhot::RigFrame> frames;
  double seen = 0.0;  // markers seen by >= 2 cameras, mean per frame
};

const ScaleData& scale_data(int rig, int markers) {
  static std::map<std::pair<int, int>, ScaleData> cache;
  auto [it, inserted] = cache.try_emplace({rig, markers});
  if (!inserted) return it->second;
  ScaleData& d = it->second;
  d.rig = rhot::load_rig(std::filesystem::path(RHOT_ASSET_DIR) / "rigs" / (rig == 0 ? "room-8.yaml" : "stage-32.yaml")).value();
  const rhot::TrackingVolume volume = d.rig.volume.value();
  const Eigen::Vector3d lo = volume.centre_m - 0.5 * volume.size_m;
  const Eigen::Vector3d hi = volume.centre_m + 0.5 * volume.size_m;
  rhot::SimulatedRigSettings s;
  s.dropout = 0.1;
  s.sigma_px = 0.3;
  rhot::SimulatedRig sim(d.rig, rhot::random_trajectories(markers, lo, hi, 7), s);
  for (int i = 0; i < 64; ++i) {
    d.frames.push_back(sim.next());
    std::vector<int> views(static_cast<std::size_t>(markers), 0);
    for (const rhot::CameraFrame& c : d.frames.back().cameras) {
      for (const rhot::Detection& det : c.detections) {
        if (det.truth_marker >= 0) ++views[static_cast<std::size_t>(det.truth_marker)];
      }
    }
    d.seen += static_cast<double>(std::count_if(views.begin(), views.end(), [](int v) { return v >= 2; })) / 64.0;
  }
  return d;
}

// Matching per frame on room-8 (rig 0) and stage-32 (rig 1), one thread (no job pool) or a job
// pool of `threads` (the same points: tests/tracking/geometry/matching_threads_test.cpp); the rig
// prepared once and its working storage kept from frame to frame (RigMatcher::match_frame), as the
// runtime does, following the last frame's points (MatchSettings::follow_points; the 64 frames
// replayed in a loop, so every 64th frame is seeded afresh). BM_MatchScalingUnfollowed: every
// frame seeded afresh. BM_MatchScalingFresh: the same with fresh storage each frame
// (RigMatcher::match, which returns the points as a vector of their own, and follows nothing).
void match_scaling(benchmark::State& state, bool kept_storage, bool follow = true) {
  const ScaleData& d = scale_data(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  const int threads = static_cast<int>(state.range(2));
  std::optional<rhot::JobPool> jobs;
  if (threads > 1) jobs.emplace(threads);
  rhot::RigMatcher matcher(d.rig);
  rhot::MatchSettings settings;
  settings.follow_points = follow;
  std::size_t i = 0;
  double found = 0.0;
  std::int64_t runs = 0;
  for (auto _ : state) {
    const rhot::RigFrame& frame = d.frames[i++ % d.frames.size()];
    if (kept_storage) {
      const auto points = matcher.match_frame(frame, settings, jobs ? &*jobs : nullptr);
      found += static_cast<double>(points.size());
      benchmark::DoNotOptimize(points.data());
    } else {
      const auto points = matcher.match(frame, {}, jobs ? &*jobs : nullptr);
      found += static_cast<double>(points.size());
      benchmark::DoNotOptimize(points.data());
    }
    ++runs;
  }
  state.counters["found"] = found / static_cast<double>(std::max<std::int64_t>(runs, 1)) / d.seen;
  state.counters["per_marker"] =
      benchmark::Counter(static_cast<double>(state.range(1)), benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
void BM_MatchScaling(benchmark::State& state) { match_scaling(state, true); }
void BM_MatchScalingFresh(benchmark::State& state) { match_scaling(state, false); }
void BM_MatchScalingUnfollowed(benchmark::State& state) { match_scaling(state, true, false); }
BENCHMARK(BM_MatchScaling)
    ->ArgNames({"rig", "markers", "threads"})
    ->ArgsProduct({{0, 1}, {100, 300, 1000}, {1, 2, 4, 8, 16}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_MatchScalingUnfollowed)
    ->ArgNames({"rig", "markers", "threads"})
    ->ArgsProduct({{0, 1}, {100, 1000}, {1, 2}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_MatchScalingFresh)
    ->ArgNames({"rig", "markers", "threads"})
    ->ArgsProduct({{0, 1}, {100, 1000}, {1, 2}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

void BM_PairwiseCvTriangulatePoints(benchmark::State& state) {
  const Data& d = data();
  std::vector<cv::Matx34d> projection;
  std::vector<cv::Matx33d> k;
  std::vector<cv::Vec<double, 5>> dist;
  for (const rhot::Camera& c : d.rig.cameras) {
    const Eigen::Matrix3d r = c.cam_from_world.rotation.toRotationMatrix();
    const Eigen::Vector3d t = c.cam_from_world.translation;
    projection.emplace_back(r(0, 0), r(0, 1), r(0, 2), t.x(), r(1, 0), r(1, 1), r(1, 2), t.y(), r(2, 0), r(2, 1), r(2, 2), t.z());
    const rhot::CameraIntrinsics& in = c.intrinsics;
    k.emplace_back(in.fx, 0, in.cx, 0, in.fy, in.cy, 0, 0, 1);
    dist.emplace_back(in.distortion.data());
  }
  std::size_t f = 0;
  for (auto _ : state) {
    const rhot::RigFrame& frame = d.frames[f++ % d.frames.size()];
    // Group detections by true marker: camera and pixel of the first two cameras that see it.
    std::vector<std::array<int, 2>> cam(frame.truth_position_m.size(), {-1, -1});
    std::vector<std::array<cv::Point2d, 2>> px(frame.truth_position_m.size());
    for (const rhot::CameraFrame& cf : frame.cameras) {
      for (const rhot::Detection& det : cf.detections) {
        auto& c = cam[static_cast<std::size_t>(det.truth_marker)];
        const int slot = c[0] < 0 ? 0 : (c[1] < 0 ? 1 : -1);
        if (slot < 0) continue;
        c[static_cast<std::size_t>(slot)] = cf.camera;
        px[static_cast<std::size_t>(det.truth_marker)][static_cast<std::size_t>(slot)] = {det.pixel.x(), det.pixel.y()};
      }
    }
    for (std::size_t m = 0; m < cam.size(); ++m) {
      if (cam[m][1] < 0) continue;
      std::array<std::vector<cv::Point2d>, 2> undistorted;
      for (std::size_t s = 0; s < 2; ++s) {
        const auto c = static_cast<std::size_t>(cam[m][s]);
        cv::undistortPoints(std::vector<cv::Point2d>{px[m][s]}, undistorted[s], k[c], dist[c]);
      }
      cv::Mat x;
      cv::triangulatePoints(projection[static_cast<std::size_t>(cam[m][0])], projection[static_cast<std::size_t>(cam[m][1])],
                            undistorted[0], undistorted[1], x);
      benchmark::DoNotOptimize(x);
    }
  }
}
BENCHMARK(BM_PairwiseCvTriangulatePoints)->Unit(benchmark::kMicrosecond);

}  // namespace
