// One hand's inverse kinematics per frame: five fingertip targets (random reachable poses of the
// reference hand's chains, within their limits), solved by FABRIK (what rhot uses) and by damped
// least squares (the comparison), same targets, same iteration cap (20) and tolerance (0.1 mm).
// Counters: the mean and worst tip error reached. Results: docs/PERFORMANCE.md.

#include <random>

#include <benchmark/benchmark.h>

#include "tracking/hand/FingerFit.h"
#include "tracking/hand/HandSolver.h"

namespace {

using Targets = std::array<Eigen::Vector3d, rhot::kFingerCount>;

struct Data {
  std::array<rhot::FingerChain, rhot::kFingerCount> chains;
  std::vector<Targets> targets;
};

const Data& data() {
  static const Data d = [] {
    Data out;
    out.chains = rhot::hand_chains(rhot::reference_open_hand(rhot::HandSide::kRight), rhot::HandSide::kRight);
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int i = 0; i < 1024; ++i) {
      Targets t;
      for (std::size_t f = 0; f < out.chains.size(); ++f) {
        const rhot::FingerLimits& l = out.chains[f].limits;
        rhot::FingerAngles a;
        a.flexion_rad[0] = l.flexion_min_rad[0] + (l.flexion_max_rad[0] - l.flexion_min_rad[0]) * u(rng);
        a.flexion_rad[1] = l.flexion_min_rad[1] + (l.flexion_max_rad[1] - l.flexion_min_rad[1]) * u(rng);
        a.flexion_rad[2] = l.coupling * a.flexion_rad[1];
        a.abduction_rad = (2.0 * u(rng) - 1.0) * l.abduction_max_rad;
        t[f] = rhot::finger_forward(out.chains[f], rhot::clamp_to_limits(l, a))[3];
      }
      out.targets.push_back(t);
    }
    return out;
  }();
  return d;
}

template <typename Solve>
void run(benchmark::State& state, Solve solve) {
  const Data& d = data();
  std::size_t i = 0;
  double sum = 0.0, worst = 0.0;
  long n = 0;
  for (auto _ : state) {
    const Targets& t = d.targets[i++ % d.targets.size()];
    for (std::size_t f = 0; f < d.chains.size(); ++f) {
      const rhot::IkResult r = solve(d.chains[f], t[f]);
      benchmark::DoNotOptimize(r);
      sum += r.tip_error_m;
      worst = std::max(worst, r.tip_error_m);
      ++n;
    }
  }
  state.counters["mean_tip_error_mm"] = 1000.0 * sum / static_cast<double>(std::max(1L, n));
  state.counters["worst_tip_error_mm"] = 1000.0 * worst;
}

void BM_HandFabrik(benchmark::State& state) {
  run(state, [](const rhot::FingerChain& c, const Eigen::Vector3d& t) { return rhot::solve_fabrik(c, t); });
}
BENCHMARK(BM_HandFabrik)->Unit(benchmark::kMicrosecond);

void BM_HandDampedLeastSquares(benchmark::State& state) {
  run(state, [](const rhot::FingerChain& c, const Eigen::Vector3d& t) { return rhot::solve_dls(c, t); });
}
BENCHMARK(BM_HandDampedLeastSquares)->Unit(benchmark::kMicrosecond);

}  // namespace

namespace {

// One hand's fingers fitted to two markers each (FingerFit.h: a glove's nail marker and a marker on
// the proximal bone, assets/hands/glove-13-right.json's offsets), from the pose a frame before (each
// angle up to 0.05 rad off: a finger moving at 4.5 rad/s at 90 Hz). Counters: the mean fit
// iterations per finger and the markers' mean miss.
void BM_HandFitMarkers(benchmark::State& state) {
  const Data& d = data();
  struct Case {
    std::array<std::array<rhot::FingerPoint, 2>, rhot::kFingerCount> points;
    std::array<rhot::FingerAngles, rhot::kFingerCount> start;
  };
  std::vector<Case> cases;
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (std::size_t i = 0; i < 256; ++i) {
    Case c;
    for (std::size_t f = 0; f < d.chains.size(); ++f) {
      const rhot::FingerChain& chain = d.chains[f];
      rhot::FingerAngles truth = rhot::solve_fabrik(chain, d.targets[i][f]).angles;
      rhot::FingerAngles start = truth;
      start.abduction_rad += 0.05 * u(rng);
      for (double& v : start.flexion_rad) v += 0.05 * u(rng);
      c.start[f] = rhot::clamp_to_limits(chain.limits, start);
      rhot::FingerPoint tip{3, Eigen::Vector3d(0.0, 0.010, 0.006), Eigen::Vector3d::Zero(), 1.0};
      rhot::FingerPoint middle{0, Eigen::Vector3d(0.0, 0.014, -0.021), Eigen::Vector3d::Zero(), 0.25};
      tip.at_m = rhot::finger_point_at(chain, truth, tip);
      middle.at_m = rhot::finger_point_at(chain, truth, middle);
      c.points[f] = {tip, middle};
    }
    cases.push_back(c);
  }
  std::size_t i = 0;
  double miss = 0.0, iterations = 0.0;
  long n = 0;
  for (auto _ : state) {
    const Case& c = cases[i++ % cases.size()];
    for (std::size_t f = 0; f < d.chains.size(); ++f) {
      const rhot::FingerFit fit = rhot::fit_finger(d.chains[f], c.points[f], c.start[f]);
      benchmark::DoNotOptimize(fit);
      miss += fit.rms_m;
      iterations += fit.iterations;
      ++n;
    }
  }
  state.counters["mean_miss_mm"] = 1000.0 * miss / static_cast<double>(std::max(1L, n));
  state.counters["iterations"] = iterations / static_cast<double>(std::max(1L, n));
}
BENCHMARK(BM_HandFitMarkers)->Unit(benchmark::kMicrosecond);

}  // namespace
