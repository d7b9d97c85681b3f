// How rhot's hands reach another process (engine/stream/HandShare.h, read by rhot's OpenXR
// layer): shared memory with a seqlock against ZeroMQ over ipc://, the transport the issue left
// open. One-way delivery is half a ping-pong between two threads, each side waiting for the
// other's newest hands; reading is what the layer pays per xrLocateHandJointsEXT.
//
//   build/release/tests/bench/handshare_benchmark

#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include <benchmark/benchmark.h>
#include <zmq.hpp>

#include "base/SteadyClock.h"
#include "engine/stream/HandShare.h"

namespace rhot {
namespace {

// p50 and p99 of the per-iteration times (microseconds) as counters.
void percentiles(benchmark::State& state, std::vector<double>& us) {
  std::sort(us.begin(), us.end());
  if (us.empty()) return;
  state.counters["p50_us"] = us[us.size() / 2];
  state.counters["p99_us"] = us[std::min(us.size() - 1, us.size() * 99 / 100)];
}

std::string block_name(const char* what) { return std::string("/rhot-bench-") + what + "-" + std::to_string(getpid()); }

HandShareSnapshot hands(std::uint64_t frame) {
  HandShareSnapshot s{};
  s.frame = frame;
  s.published_s = steady_now_s();
  s.hands[0].tracked = s.hands[1].tracked = 1;
  return s;
}

// The layer's cost per call: the newest hands copied out of the block.
void BM_HandShareRead(benchmark::State& state) {
  auto writer = HandShareWriter::open(block_name("read"));
  if (!writer) {
    state.SkipWithError(writer.error().c_str());
    return;
  }
  (*writer)->publish(hands(1));
  HandShareReader reader((*writer)->name());
  for (auto _ : state) benchmark::DoNotOptimize(reader.read(steady_now_s()));
  shm_unlink((*writer)->name().c_str());
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(sizeof(HandShareSnapshot)));
}
BENCHMARK(BM_HandShareRead);

// One frame's hands from one thread to another through shared memory, and back: half of it is
// the delivery (the reader spinning, as the layer would read at once).
void BM_HandShareDelivery(benchmark::State& state) {
  auto there = HandShareWriter::open(block_name("there"));
  auto back = HandShareWriter::open(block_name("back"));
  if (!there || !back) {
    state.SkipWithError("cannot open shared memory");
    return;
  }
  std::atomic<bool> stop{false};
  std::thread echo([&] {
    HandShareReader in((*there)->name());
    std::uint64_t seen = 0;
    while (!stop.load(std::memory_order_relaxed)) {
      const auto s = in.read(steady_now_s());
      if (s && s->frame != seen) {
        seen = s->frame;
        (*back)->publish(*s);
      }
    }
  });
  HandShareReader reply((*back)->name());
  std::uint64_t frame = 0;
  std::vector<double> us;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    (*there)->publish(hands(++frame));
    bool replied = false;
    while (!replied && std::chrono::steady_clock::now() - start < std::chrono::seconds(1)) {
      const auto s = reply.read(steady_now_s());
      replied = s && s->frame == frame;
    }
    if (!replied) {
      state.SkipWithError("no reply within a second");
      break;
    }
    const double one_way = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / 2.0;
    state.SetIterationTime(one_way);
    us.push_back(1e6 * one_way);
  }
  stop = true;
  echo.join();
  percentiles(state, us);
  shm_unlink((*there)->name().c_str());
  shm_unlink((*back)->name().c_str());
}
BENCHMARK(BM_HandShareDelivery)->UseManualTime()->Unit(benchmark::kMicrosecond);

// The same over ZeroMQ PAIR sockets on ipc://, the snapshot as one message.
void BM_ZmqIpcDelivery(benchmark::State& state) {
  zmq::context_t context;
  const std::string endpoint = "ipc:///tmp/rhot-bench-" + std::to_string(getpid());
  zmq::socket_t a(context, zmq::socket_type::pair);
  zmq::socket_t b(context, zmq::socket_type::pair);
  a.bind(endpoint);
  b.connect(endpoint);
  std::atomic<bool> stop{false};
  std::thread echo([&] {
    zmq::message_t m;
    b.set(zmq::sockopt::rcvtimeo, 100);
    while (!stop.load(std::memory_order_relaxed)) {
      if (b.recv(m, zmq::recv_flags::none)) b.send(m, zmq::send_flags::none);
    }
  });
  std::uint64_t frame = 0;
  std::vector<double> us;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    const HandShareSnapshot s = hands(++frame);
    a.send(zmq::buffer(&s, sizeof(s)), zmq::send_flags::none);
    zmq::message_t m;
    if (!a.recv(m, zmq::recv_flags::none)) {
      state.SkipWithError("no reply");
      break;
    }
    const double one_way = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / 2.0;
    state.SetIterationTime(one_way);
    us.push_back(1e6 * one_way);
  }
  stop = true;
  echo.join();
  percentiles(state, us);
}
BENCHMARK(BM_ZmqIpcDelivery)->UseManualTime()->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace rhot
