#pragma once
// Running the frame loop on a headset (engine/render/XrHeadset.h): its runtime paces the frames,
// and a run ends by asking the runtime to end the session and following it there, not by
// leaving the loop in the middle of a session.

#include <cstdint>
#include <functional>

#include "engine/app/FrameLoop.h"
#include "engine/runtime/Runtime.h"

namespace rhot {

// The frame loop's settings for the runtime's headset: paced by its runtime (the wait is outside
// each frame's timing: FrameLoopSettings::pace), not by the wall clock. Unchanged without one.
FrameLoopSettings headset_loop_settings(Runtime& runtime, FrameLoopSettings settings);

struct HeadsetRunLimits {
  double start_timeout_s = 15.0;  // for the session to show its first frame
  double stop_timeout_s = 5.0;    // for the runtime to end the session once asked
};

// Runs `loop` until `frames` have been shown on the runtime's headset (0: until its runtime ends
// the session) or `stop_asked` says so; then asks the runtime to end the session and runs on
// through its states until it has. Gives up, logging why, when the session shows no frame or does
// not end within the limits. Without a headset: loop.run(frames) until stop_asked. Returns the
// frames run.
std::uint64_t run_on_headset(Runtime& runtime, FrameLoop& loop, std::uint64_t frames, const std::function<bool()>& stop_asked,
                             const HeadsetRunLimits& limits = {});

}  // namespace rhot
