// Marker stars on the seated rig: 25 stars of the seed-case set moving through the volume, seen by
// the simulated cameras at 0.3 px, matched and triangulated once (outside the timing); then timed:
// identification from scratch of every frame's points (a cold start, the worst case), and the
// tracker's per-frame update (prediction first, identification for what is left). Results:
// docs/PERFORMANCE.md; rhot-eval stars measures the same update alongside accuracy.

#include <filesystem>

#include <benchmark/benchmark.h>

#include "tracking/camera/RigFile.h"
#include "tracking/geometry/Matching.h"
#include "tracking/rigid/StarTracker.h"
#include "tracking/sim/SimulatedRig.h"

namespace {

struct Data {
  rhot::StarSet set;
  std::vector<double> time_s;
  std::vector<std::vector<Eigen::Vector3d>> points;
};

const Data& data() {
  static const Data d = [] {
    Data out;
    const auto rig = rhot::load_rig(std::filesystem::path(RHOT_ASSET_DIR) / "rigs" / "seated-4.yaml").value();
    out.set = rhot::load_star_set(std::filesystem::path(RHOT_ASSET_DIR) / "stars" / "seed-case.json").value();
    out.set.stars.resize(25);
    const auto motions =
        rhot::random_motions(25, rig.volume->centre_m - rig.volume->size_m / 2, rig.volume->centre_m + rig.volume->size_m / 2, 2);
    std::vector<rhot::SimulatedBody> bodies;
    for (std::size_t b = 0; b < 25; ++b) {
      rhot::SimulatedBody body{motions[b], {}};
      for (const Eigen::Vector3d& m : out.set.stars[b].markers_mm) body.markers_body_m.push_back(m * 1e-3);
      bodies.push_back(body);
    }
    rhot::SimulatedRig sim(rig, {}, {});
    sim.set_bodies(bodies);
    const rhot::RigMatcher matcher(rig);
    for (int f = 0; f < 128; ++f) {
      const rhot::RigFrame frame = sim.next();
      std::vector<Eigen::Vector3d> pts;
      for (const rhot::MatchedPoint& m : matcher.match(frame)) pts.push_back(m.point.position_world);
      out.time_s.push_back(frame.time_s);
      out.points.push_back(std::move(pts));
    }
    return out;
  }();
  return d;
}

void BM_IdentifyStarsFromScratch(benchmark::State& state) {
  const Data& d = data();
  const rhot::StarLibrary library(d.set);
  std::size_t f = 0;
  for (auto _ : state) benchmark::DoNotOptimize(rhot::identify_stars(library, d.points[f++ % d.points.size()]));
}
BENCHMARK(BM_IdentifyStarsFromScratch)->Unit(benchmark::kMicrosecond);

void BM_TrackerUpdate(benchmark::State& state) {
  const Data& d = data();
  rhot::StarTracker tracker{rhot::StarLibrary(d.set)};
  std::size_t f = 0;
  double offset = 0.0;  // time keeps increasing when the frames wrap around
  for (auto _ : state) {
    if (f > 0 && f % d.points.size() == 0) offset += d.time_s.back() + 1.0;
    const std::size_t i = f++ % d.points.size();
    benchmark::DoNotOptimize(tracker.update(offset + d.time_s[i], d.points[i]));
  }
}
BENCHMARK(BM_TrackerUpdate)->Unit(benchmark::kMicrosecond);

}  // namespace
