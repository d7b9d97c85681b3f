#pragma once
// The clock every latency in rhot is measured on: std::chrono::steady_clock, as seconds since its
// epoch. Capture times from camera nodes and video devices, the runtime's stage times and the
// renderer's completion times are all on it (docs/latency.md).

#include <chrono>

namespace rhot {

inline double steady_now_s() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

}  // namespace rhot
