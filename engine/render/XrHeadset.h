#pragma once
// A headset through OpenXR: the runtime's instance, system and session, its frame pacing and the
// eyes' poses. The renderer draws into the runtime's swapchains once it is created with a headset
// (Renderer::create(settings, window, headset)): the Vulkan instance and device are then made
// through XR_KHR_vulkan_enable2, so that the runtime's Vulkan requirements and device extensions
// are met.
//
// One frame, as the runtime (engine/runtime/Runtime.h) drives it:
//
//   poll_events()   the runtime's events: the session state machine (begin on READY, end on
//                   STOPPING; EXITING, LOSS_PENDING and instance loss end the run)
//   begin_frame()   xrWaitFrame (the runtime paces the loop) and xrBeginFrame; the frame's
//                   predicted display time
//   locate_views()  both eyes at that display time, in rhot's world
//   Renderer::render()  draws both eyes, copies them into the swapchains and ends the frame
//                   (xrEndFrame) with a projection layer of the located views
//
// No OpenXR or Vulkan type crosses this header (the binding lives in engine/render/vk/XrBinding.h).

#include <cstdint>
#include <expected>
#include <memory>
#include <optional>
#include <string>

#include <glm/glm.hpp>

#include "engine/render/StereoCamera.h"

namespace rhot {

struct XrHeadsetSettings {
  std::string application = "rhot";
  // Enable the OpenXR core validation layer (XR_APILAYER_LUNARG_core_validation) and count its
  // messages (validation_messages()). Also switched on by RHOT_XR_VALIDATION=1.
  bool validation = false;
};

// The session's state (XrSessionState), as the runtime last reported it.
enum class XrState { kUnknown, kIdle, kReady, kSynchronized, kVisible, kFocused, kStopping, kLossPending, kExiting };
const char* to_string(XrState state);

struct XrHeadsetInfo {
  std::string runtime;  // name and version
  std::string system;   // the headset's name
  int recommended_width_px = 0;
  int recommended_height_px = 0;
  double refresh_hz = 0.0;          // 1 / the predicted display period of the last frame begun (0 before the first)
  bool validation_enabled = false;  // the core validation layer is on and its messages are counted
};

// A frame the runtime asked for (xrWaitFrame) and that has begun (xrBeginFrame).
struct XrFrameTiming {
  std::uint64_t index = 0;        // frames begun before it
  bool should_render = false;     // false: the frame ends with no layer (the runtime shows nothing new)
  std::int64_t display_time = 0;  // the runtime's predicted display time (XrTime, ns on its clock)
  double display_s = 0.0;         // the same moment on the steady clock (seconds)
  double period_s = 0.0;          // predicted display period
  double begun_s = 0.0;           // when xrWaitFrame returned (steady clock)
};

class XrHeadset {
 public:
  // Creates the instance (with XR_KHR_vulkan_enable2 and XR_KHR_convert_timespec_time) and finds
  // the head-mounted display. Fails with one line where no runtime is installed or selected
  // (saying how: XR_RUNTIME_JSON), where the runtime lacks an extension rhot needs, or where no
  // headset is connected.
  [[nodiscard]] static std::expected<std::unique_ptr<XrHeadset>, std::string> create(const XrHeadsetSettings& settings);
  ~XrHeadset();
  XrHeadset(const XrHeadset&) = delete;
  XrHeadset& operator=(const XrHeadset&) = delete;

  const XrHeadsetInfo& info() const;

  // Handles the events waiting (without blocking): the session begins when READY and ends when
  // STOPPING. Only once a renderer made the session.
  void poll_events();
  XrState state() const;
  // Between xrBeginSession and xrEndSession: frames are to be waited for, begun and ended.
  bool session_running() const;
  // The application has the input focus (FOCUSED): while it is not, rhot's simulation pauses.
  bool focused() const;
  // The run is over: the runtime asked the session to exit (EXITING), the session or the instance
  // is being lost, or request_exit() has taken its course. Why, for the log: exit_reason().
  bool should_exit() const;
  const std::string& exit_reason() const;
  // The run ended because the session or the instance was being lost (not asked for).
  bool lost() const;
  // Asks the runtime to end the session (xrRequestExitSession); it goes through STOPPING to
  // EXITING, polled as usual.
  void request_exit();

  // With the session running: waits for the runtime's next frame and begins it. The previous
  // frame, if the renderer did not end it, is ended first with no layer. nullopt where the
  // session is not running (nothing to wait for) or a call failed (logged).
  std::optional<XrFrameTiming> begin_frame();
  // The frame begun and not yet ended, if any.
  const std::optional<XrFrameTiming>& current_frame() const;
  // Both eyes at the current frame's display time, in rhot's world (through world_from_stage()),
  // with clip distances near_m and far_m. nullopt where there is no frame or the runtime does not
  // know where the eyes are (their poses are not valid).
  std::optional<StereoViews> locate_views(double near_m, double far_m);

  // The head (the runtime's VIEW space: between the eyes, +Y up, looking down -Z) in its STAGE
  // space at a moment on the steady clock, such as when a camera exposed (the runtime keeps a
  // short history and predicts a little ahead). nullopt with no session, or where the runtime does
  // not know where the head is (its pose is not valid or not finite).
  std::optional<glm::mat4> stage_from_head(double steady_s);

  // rhot's world from the runtime's STAGE space (the rig's registration to the headset; identity
  // until one is set: both have +Y up and the floor at y = 0).
  // Refused (and nothing changed) where it is not a rigid transform.
  [[nodiscard]] std::expected<void, std::string> set_world_from_stage(const glm::mat4& world_from_stage);
  const glm::mat4& world_from_stage() const;

  // Converts between the steady clock (seconds) and the runtime's XrTime
  // (XR_KHR_convert_timespec_time: both are CLOCK_MONOTONIC on Linux). NaN, or 0, where the
  // runtime cannot convert.
  double steady_s_from_xr_time(std::int64_t time) const;
  std::int64_t xr_time_from_steady_s(double steady_s) const;

  // Counts: frames ended with a layer; those ended after their predicted display time; and of
  // those, the ones late through rhot's own work (the runtime's wait returned before the display
  // time, and the frame still missed it; the others were late before rhot began them).
  std::uint64_t frames_submitted() const;
  std::uint64_t frames_late() const;
  std::uint64_t frames_late_own() const;
  // Messages of the core validation layer (0 without it).
  std::uint64_t validation_messages() const;

  // The OpenXR binding the renderer uses (engine/render/vk/XrBinding.h).
  struct Impl;
  Impl& impl() { return *impl_; }

 private:
  explicit XrHeadset(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace rhot
