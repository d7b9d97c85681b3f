#include "engine/runtime/HeadsetLoop.h"

#include <spdlog/spdlog.h>

#include "base/SteadyClock.h"
#include "engine/render/XrHeadset.h"

namespace rhot {

namespace {
XrHeadset* headset_of(Runtime& runtime) { return runtime.renderer() != nullptr ? runtime.renderer()->headset() : nullptr; }
}  // namespace

FrameLoopSettings headset_loop_settings(Runtime& runtime, FrameLoopSettings settings) {
  if (headset_of(runtime) == nullptr) return settings;
  settings.real_time = false;
  settings.pace = [&runtime] { runtime.wait_for_headset(); };
  return settings;
}

std::uint64_t run_on_headset(Runtime& runtime, FrameLoop& loop, std::uint64_t frames, const std::function<bool()>& stop_asked,
                             const HeadsetRunLimits& limits) {
  XrHeadset* headset = headset_of(runtime);
  if (headset == nullptr) return loop.run(frames, [&] { return !stop_asked(); });
  const double started_s = steady_now_s();
  double stop_asked_s = 0.0;
  return loop.run(0, [&] {
    const double now = steady_now_s();
    if (stop_asked_s == 0.0 && (stop_asked() || (frames > 0 && headset->frames_submitted() >= frames))) {
      headset->request_exit();
      stop_asked_s = now;
    }
    if (headset->frames_submitted() == 0 && stop_asked_s == 0.0 && now - started_s > limits.start_timeout_s) {
      spdlog::error("the OpenXR session showed no frame within {:.0f} s (its state: {})", limits.start_timeout_s,
                    to_string(headset->state()));
      return false;
    }
    if (stop_asked_s > 0.0 && now - stop_asked_s > limits.stop_timeout_s) {
      spdlog::warn("the OpenXR runtime did not end the session within {:.0f} s of being asked (its state: {})", limits.stop_timeout_s,
                   to_string(headset->state()));
      return false;
    }
    return !headset->should_exit();
  });
}

}  // namespace rhot
