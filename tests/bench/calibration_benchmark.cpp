// The wand calibration's cost: a simulated wave of N frames through room-8 (8 cameras) or seated-4,
// calibrated from unknown extrinsics with the intrinsics given. The target: 2,000 frames,
// 8 cameras in 3 s or less.

#include <benchmark/benchmark.h>

#include "tracking/calib/WandCalibration.h"
#include "tracking/camera/RigFile.h"
#include "tracking/sim/CalibrationSessions.h"

namespace {

void wand_calibration(benchmark::State& state, const char* rig_name) {
  const auto rig = rhot::load_rig(std::string(RHOT_ASSET_DIR) + "/rigs/" + rig_name + ".yaml");
  if (!rig) {
    state.SkipWithError(rig.error().c_str());
    return;
  }
  rhot::WandSession session;
  session.frames = static_cast<int>(state.range(0));
  session.box_centre_m = rig->volume->centre_m;
  session.box_size_m = rig->volume->size_m;
  const rhot::Detections d = rhot::simulate_wand_session(*rig, session, rhot::SessionNoise{});
  rhot::WandSettings settings;
  settings.wand_length_m = session.wand_length_m;
  for (auto _ : state) {
    const auto result = rhot::calibrate_wand(*rig, d, settings);
    if (!result) state.SkipWithError(result.error().c_str());
    benchmark::DoNotOptimize(result);
  }
  state.counters["cameras"] = static_cast<double>(rig->cameras.size());
}

BENCHMARK_CAPTURE(wand_calibration, room8, "room-8")->Arg(500)->Arg(2000)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK_CAPTURE(wand_calibration, seated4, "seated-4")->Arg(500)->Arg(2000)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace
