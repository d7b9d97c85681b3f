// What streaming costs the frame thread (OscStream::send at 90 Hz, with a receiver on loopback),
// and what building one frame's messages costs the sender thread.
//   build/release/tests/bench/stream_benchmark

#include <algorithm>
#include <chrono>
#include <thread>
#include <vector>

#include <benchmark/benchmark.h>
#include <lo/lo.h>

#include "engine/stream/OscStream.h"

namespace {

using Clock = std::chrono::steady_clock;

rhot::TrackingResults frame_results() {
  rhot::TrackingResults r;
  for (int h = 0; h < 2; ++h) {
    const rhot::HandSide side = h == 0 ? rhot::HandSide::kLeft : rhot::HandSide::kRight;
    rhot::Rigid3d at;
    at.translation = {h == 0 ? -0.2 : 0.2, 1.0, -0.3};
    r.hands[static_cast<std::size_t>(h)] = rhot::hand_input(at, rhot::reference_open_hand(side));
  }
  rhot::Rigid3d mug;
  mug.translation = {0.0, 0.8, -0.4};
  r.world_from_object[1] = mug;
  r.world_from_object[2] = mug;
  return r;
}

// The frame thread's call, once every 11.1 ms (90 Hz), timed alone; p99 and max as counters.
void BM_StreamSendAt90Hz(benchmark::State& state) {
  const bool vmc = state.range(0) != 0;
  lo_server_thread receiver = lo_server_thread_new_with_proto(nullptr, LO_UDP, nullptr);
  lo_server_thread_add_method(
      receiver, nullptr, nullptr, [](const char*, const char*, lo_arg**, int, lo_message, void*) { return 0; }, nullptr);
  lo_server_thread_start(receiver);
  auto stream = rhot::OscStream::open({"127.0.0.1", std::to_string(lo_server_thread_get_port(receiver)), vmc});
  if (!stream) {
    state.SkipWithError(stream.error().c_str());
    return;
  }
  const rhot::TrackingResults results = frame_results();
  const std::map<int, std::string> names{{1, "mug"}, {2, "cube"}};
  std::vector<double> ms;
  auto next = Clock::now();
  for (auto _ : state) {
    next += std::chrono::microseconds(11111);
    std::this_thread::sleep_until(next);
    const auto start = Clock::now();
    (*stream)->send(results, names);
    const double s = std::chrono::duration<double>(Clock::now() - start).count();
    state.SetIterationTime(s);
    ms.push_back(1000.0 * s);
  }
  (*stream)->flush();
  const rhot::OscStream::Stats stats = (*stream)->stats();
  std::sort(ms.begin(), ms.end());
  state.counters["p50_ms"] = ms[ms.size() / 2];
  state.counters["p99_ms"] = ms[std::min(ms.size() - 1, ms.size() * 99 / 100)];
  state.counters["max_ms"] = ms.back();
  state.counters["sent"] = static_cast<double>(stats.sent);
  state.counters["skipped"] = static_cast<double>(stats.skipped);
  state.counters["errors"] = static_cast<double>(stats.errors);
  stream->reset();
  lo_server_thread_free(receiver);
}
BENCHMARK(BM_StreamSendAt90Hz)->ArgName("vmc")->Arg(0)->Arg(1)->Iterations(450)->UseManualTime()->Unit(benchmark::kMicrosecond);

// The sender thread's share before liblo: one frame's messages (joint orientations included).
void BM_StreamMessages(benchmark::State& state) {
  const bool vmc = state.range(0) != 0;
  const rhot::TrackingResults r = frame_results();
  rhot::StreamFrame frame;
  frame.hands = r.hands;
  frame.bodies = {{"mug", r.world_from_object.at(1)}, {"cube", r.world_from_object.at(2)}};
  for (auto _ : state) benchmark::DoNotOptimize(rhot::stream_messages(frame, vmc));
}
BENCHMARK(BM_StreamMessages)->ArgName("vmc")->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

}  // namespace
