// One hand's inverse kinematics per frame: five fingertip targets (random reachable poses of the
// reference hand's chains, within their limits), solved by FABRIK (what rhot uses) and by damped
// least squares (the comparison), same targets, same iteration cap (20) and tolerance (0.1 mm).
// Counters: the mean and worst tip error reached. Results: docs/PERFORMANCE.md.

#include <random>

#include <benchmark/benchmark.h>

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
