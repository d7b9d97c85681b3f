// rhot's OpenXR layer in an application (tests/xr/XrTestApp.h) on the runtime the tests use
// (tests/support/XrRuntime.h), with published hands: what one xrLocateHandJointsEXT costs the
// application, beside the one xrLocateSpace the layer makes inside it. Without a runtime the
// benchmarks say so and measure nothing.
//
//   build/release/tests/bench/xr_layer_benchmark --benchmark_repetitions=5

#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <vector>
#include <string>

#include <benchmark/benchmark.h>

#include "base/SteadyClock.h"
#include "engine/stream/HandShare.h"
#include "tests/support/XrRuntime.h"
#include "tests/xr/XrTestApp.h"

#pragma GCC diagnostic ignored "-Wmissing-field-initializers"  // XrFoo info{XR_TYPE_FOO};

namespace rhot {
namespace {

struct Setup {
  std::unique_ptr<HandShareWriter> writer;
  test::XrTestApp app;
  std::string error;
};

void publish(HandShareWriter& writer) {
  HandShareSnapshot s{};
  s.capture_s = s.published_s = steady_now_s();
  for (int c = 0; c < 4; ++c) s.world_from_stage[5 * c] = 1.0f;
  for (HandShareHand& h : s.hands) {
    h.tracked = 1;
    for (HandShareJoint& j : h.joints) {
      j.orientation[3] = 1.0f;
      j.position[1] = 1.0f;
      j.radius = 0.01f;
    }
  }
  writer.publish(s);
}

// Made once, on first use: the runtime, the block the hands are published in, the application.
Setup& setup() {
  static const std::unique_ptr<Setup> s = [] {
    auto made = std::make_unique<Setup>();
    const auto runtime = test::xr_test_runtime();
    if (!runtime) {
      made->error = "no OpenXR runtime (set XR_RUNTIME_JSON)";
      return made;
    }
    test::set_xr_test_environment(*runtime);
    const std::string shm = "/rhot-bench-layer-" + std::to_string(getpid());
    test::enable_layers(shm);
    auto writer = HandShareWriter::open(shm);
    if (!writer) {
      made->error = writer.error();
      return made;
    }
    made->writer = std::move(*writer);
    made->error = made->app.open();
    if (made->error.empty()) {
      // The layer maps the block at its first read; after that the name can go (nothing left in /dev/shm).
      publish(*made->writer);
      XrHandJointLocationsEXT locations;
      XrHandJointLocationEXT joints[XR_HAND_JOINT_COUNT_EXT];
      made->app.locate_hand(0, made->app.xr_time(steady_now_s()), made->app.stage, locations, joints, nullptr);
    }
    shm_unlink(shm.c_str());
    return made;
  }();
  return *s;
}

void BM_LocateHandJoints(benchmark::State& state) {
  Setup& s = setup();
  if (!s.error.empty()) {
    state.SetLabel("not measured: " + s.error);
    for (auto _ : state) {
    }
    return;
  }
  XrHandJointLocationsEXT locations;
  XrHandJointLocationEXT joints[XR_HAND_JOINT_COUNT_EXT];
  XrHandJointVelocityEXT velocities[XR_HAND_JOINT_COUNT_EXT];
  int active = 0;
  std::vector<double> us;
  for (auto _ : state) {
    publish(*s.writer);  // fresh hands, as a running rhot keeps them
    const XrTime t = s.app.xr_time(steady_now_s());
    const auto start = std::chrono::steady_clock::now();
    s.app.locate_hand(0, t, s.app.stage, locations, joints, velocities);
    const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    state.SetIterationTime(took);
    us.push_back(1e6 * took);
    active += locations.isActive ? 1 : 0;
  }
  // Hands can go stale when this machine stalls the thread between publishing and the call: counted, not an error.
  state.counters["untracked"] = static_cast<double>(static_cast<int>(state.iterations()) - active);
  // The call's spread: what an application's frame sees at worst, not only on average.
  std::sort(us.begin(), us.end());
  if (!us.empty()) {
    state.counters["p50_us"] = us[us.size() / 2];
    state.counters["p99_us"] = us[std::min(us.size() - 1, us.size() * 99 / 100)];
    state.counters["max_us"] = us.back();
  }
}
BENCHMARK(BM_LocateHandJoints)->UseManualTime()->Unit(benchmark::kMicrosecond);

// The runtime's own call the layer makes once per xrLocateHandJointsEXT.
void BM_LocateSpace(benchmark::State& state) {
  Setup& s = setup();
  if (!s.error.empty()) {
    state.SetLabel("not measured: " + s.error);
    for (auto _ : state) {
    }
    return;
  }
  XrReferenceSpaceCreateInfo rci{XR_TYPE_REFERENCE_SPACE_CREATE_INFO};
  rci.referenceSpaceType = XR_REFERENCE_SPACE_TYPE_LOCAL;
  rci.poseInReferenceSpace.orientation.w = 1.0f;
  XrSpace local = XR_NULL_HANDLE;
  xrCreateReferenceSpace(s.app.session, &rci, &local);
  XrSpaceLocation location{XR_TYPE_SPACE_LOCATION};
  std::vector<double> us;
  for (auto _ : state) {
    const XrTime t = s.app.xr_time(steady_now_s());
    const auto start = std::chrono::steady_clock::now();
    xrLocateSpace(s.app.stage, local, t, &location);
    const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    state.SetIterationTime(took);
    us.push_back(1e6 * took);
  }
  xrDestroySpace(local);
  std::sort(us.begin(), us.end());
  if (!us.empty()) {
    state.counters["p50_us"] = us[us.size() / 2];
    state.counters["p99_us"] = us[std::min(us.size() - 1, us.size() * 99 / 100)];
  }
}
BENCHMARK(BM_LocateSpace)->UseManualTime()->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace rhot
