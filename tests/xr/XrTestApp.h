#pragma once
// A small OpenXR application for the layer's tests: an instance with XR_EXT_hand_tracking (and
// the core validation layer counting its messages), a headless session (XR_MND_headless: no
// graphics), its frames, and hand trackers. Run against the runtime of tests/support/XrRuntime.h
// with rhot's layer enabled through the loader's environment (enable_layers()).

#include <time.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>

#define XR_USE_TIMESPEC
#include <openxr/openxr.h>
#include <openxr/openxr_platform.h>

// OpenXR structs are written as `XrFoo info{XR_TYPE_FOO};` (the rest zeroed), as in the renderer.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"

namespace rhot::test {

// The loader's environment: rhot's layer (from the build) under the core validation layer, the
// hands read from shared memory `hands_shm`.
inline void enable_layers(const std::string& hands_shm) {
  const std::string path = std::string(RHOT_BINARY_DIR) + "/xrlayer:/usr/share/openxr/1/api_layers/explicit.d";
  setenv("XR_API_LAYER_PATH", path.c_str(), 1);
  setenv("XR_ENABLE_API_LAYERS", "XR_APILAYER_LUNARG_core_validation:XR_APILAYER_RHOT_hand_tracking", 1);
  setenv("RHOT_HANDS_SHM", hands_shm.c_str(), 1);
  setenv("XR_LOADER_DEBUG", "none", 0);
}

class XrTestApp {
 public:
  XrTestApp() = default;
  XrTestApp(const XrTestApp&) = delete;
  XrTestApp& operator=(const XrTestApp&) = delete;
  ~XrTestApp() {
    for (XrHandTrackerEXT t : trackers) {
      if (t != XR_NULL_HANDLE) destroy_tracker(t);
    }
    if (session != XR_NULL_HANDLE) xrDestroySession(session);
    if (messenger != XR_NULL_HANDLE) destroy_messenger(messenger);
    if (instance != XR_NULL_HANDLE) xrDestroyInstance(instance);
  }

  // Everything up to a running session with a tracker per hand; "" on success, else what failed.
  std::string open() {
    const char* extensions[] = {XR_EXT_HAND_TRACKING_EXTENSION_NAME, XR_MND_HEADLESS_EXTENSION_NAME, XR_EXT_DEBUG_UTILS_EXTENSION_NAME,
                                XR_KHR_CONVERT_TIMESPEC_TIME_EXTENSION_NAME};
    XrInstanceCreateInfo ici{XR_TYPE_INSTANCE_CREATE_INFO};
    std::snprintf(ici.applicationInfo.applicationName, XR_MAX_APPLICATION_NAME_SIZE, "%s", "rhot-layer-test");
    ici.applicationInfo.apiVersion = XR_MAKE_VERSION(1, 0, 0);
    ici.enabledExtensionCount = 4;
    ici.enabledExtensionNames = extensions;
    if (XrResult r = xrCreateInstance(&ici, &instance); XR_FAILED(r)) return "xrCreateInstance: " + std::to_string(r);
    get("xrCreateDebugUtilsMessengerEXT", create_messenger);
    get("xrDestroyDebugUtilsMessengerEXT", destroy_messenger);
    get("xrCreateHandTrackerEXT", create_tracker);
    get("xrDestroyHandTrackerEXT", destroy_tracker);
    get("xrLocateHandJointsEXT", locate);
    get("xrConvertTimespecTimeToTimeKHR", from_timespec);
    if (!create_messenger || !create_tracker || !destroy_tracker || !locate || !from_timespec) return "a function is missing";
    XrDebugUtilsMessengerCreateInfoEXT mci{XR_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
    mci.messageSeverities = XR_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | XR_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
    mci.messageTypes = XR_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | XR_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                       XR_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT | XR_DEBUG_UTILS_MESSAGE_TYPE_CONFORMANCE_BIT_EXT;
    mci.userCallback = [](XrDebugUtilsMessageSeverityFlagsEXT, XrDebugUtilsMessageTypeFlagsEXT,
                          const XrDebugUtilsMessengerCallbackDataEXT* d, void* self) -> XrBool32 {
      auto* app = static_cast<XrTestApp*>(self);
      ++app->validation_messages;
      app->last_message = d != nullptr && d->message != nullptr ? d->message : "";
      return XR_FALSE;
    };
    mci.userData = this;
    if (XR_FAILED(create_messenger(instance, &mci, &messenger))) return "no debug messenger";
    XrSystemGetInfo sgi{XR_TYPE_SYSTEM_GET_INFO};
    sgi.formFactor = XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY;
    if (XR_FAILED(xrGetSystem(instance, &sgi, &system))) return "no headset";
    XrSystemHandTrackingPropertiesEXT hand{XR_TYPE_SYSTEM_HAND_TRACKING_PROPERTIES_EXT};
    XrSystemProperties props{XR_TYPE_SYSTEM_PROPERTIES};
    props.next = &hand;
    if (XR_FAILED(xrGetSystemProperties(instance, system, &props))) return "xrGetSystemProperties failed";
    supports_hand_tracking = hand.supportsHandTracking == XR_TRUE;
    XrSessionCreateInfo sci{XR_TYPE_SESSION_CREATE_INFO};
    sci.systemId = system;
    if (XrResult r = xrCreateSession(instance, &sci, &session); XR_FAILED(r)) return "xrCreateSession: " + std::to_string(r);
    XrReferenceSpaceCreateInfo rci{XR_TYPE_REFERENCE_SPACE_CREATE_INFO};
    rci.referenceSpaceType = XR_REFERENCE_SPACE_TYPE_STAGE;
    rci.poseInReferenceSpace.orientation.w = 1.0f;
    if (XR_FAILED(xrCreateReferenceSpace(session, &rci, &stage))) return "no STAGE space";
    // READY, then begin.
    for (int i = 0; i < 500 && !running; ++i) {
      poll();
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    if (!running) return "the session never became ready";
    for (XrHandEXT h : {XR_HAND_LEFT_EXT, XR_HAND_RIGHT_EXT}) {
      XrHandTrackerCreateInfoEXT hci{XR_TYPE_HAND_TRACKER_CREATE_INFO_EXT};
      hci.hand = h;
      hci.handJointSet = XR_HAND_JOINT_SET_DEFAULT_EXT;
      if (XrResult r = create_tracker(session, &hci, &trackers[h == XR_HAND_LEFT_EXT ? 0 : 1]); XR_FAILED(r)) {
        return "xrCreateHandTrackerEXT: " + std::to_string(r);
      }
    }
    return "";
  }

  void poll() {
    XrEventDataBuffer e{XR_TYPE_EVENT_DATA_BUFFER};
    while (xrPollEvent(instance, &e) == XR_SUCCESS) {
      if (e.type == XR_TYPE_EVENT_DATA_SESSION_STATE_CHANGED) {
        const auto* changed = reinterpret_cast<const XrEventDataSessionStateChanged*>(&e);
        if (changed->state == XR_SESSION_STATE_READY) {
          XrSessionBeginInfo bi{XR_TYPE_SESSION_BEGIN_INFO};
          bi.primaryViewConfigurationType = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
          running = XR_SUCCEEDED(xrBeginSession(session, &bi));
        }
      }
      e = XrEventDataBuffer{XR_TYPE_EVENT_DATA_BUFFER};
    }
  }

  // The runtime's time for a moment on the steady clock.
  XrTime xr_time(double steady_s) const {
    timespec ts{};
    ts.tv_sec = static_cast<time_t>(steady_s);
    ts.tv_nsec = static_cast<long>((steady_s - static_cast<double>(ts.tv_sec)) * 1e9);
    XrTime t = 0;
    from_timespec(instance, &ts, &t);
    return t;
  }

  // Both joints' locations (and velocities) of one hand at `time` in `space`.
  XrResult locate_hand(int hand, XrTime time, XrSpace space, XrHandJointLocationsEXT& locations, XrHandJointLocationEXT* joints,
                       XrHandJointVelocityEXT* velocities) {
    XrHandJointVelocitiesEXT v{XR_TYPE_HAND_JOINT_VELOCITIES_EXT};
    v.jointCount = XR_HAND_JOINT_COUNT_EXT;
    v.jointVelocities = velocities;
    locations = XrHandJointLocationsEXT{XR_TYPE_HAND_JOINT_LOCATIONS_EXT};
    locations.next = velocities != nullptr ? &v : nullptr;
    locations.jointCount = XR_HAND_JOINT_COUNT_EXT;
    locations.jointLocations = joints;
    XrHandJointsLocateInfoEXT li{XR_TYPE_HAND_JOINTS_LOCATE_INFO_EXT};
    li.baseSpace = space;
    li.time = time;
    const XrResult r = locate(trackers[static_cast<std::size_t>(hand)], &li, &locations);
    locations.next = nullptr;
    return r;
  }

  XrInstance instance = XR_NULL_HANDLE;
  XrSystemId system = XR_NULL_SYSTEM_ID;
  XrSession session = XR_NULL_HANDLE;
  XrSpace stage = XR_NULL_HANDLE;
  XrHandTrackerEXT trackers[2] = {XR_NULL_HANDLE, XR_NULL_HANDLE};
  XrDebugUtilsMessengerEXT messenger = XR_NULL_HANDLE;
  bool running = false;
  bool supports_hand_tracking = false;
  int validation_messages = 0;
  std::string last_message;

 private:
  template <typename Fn>
  void get(const char* name, Fn& fn) {
    PFN_xrVoidFunction f = nullptr;
    fn = XR_SUCCEEDED(xrGetInstanceProcAddr(instance, name, &f)) ? reinterpret_cast<Fn>(f) : nullptr;
  }
  PFN_xrCreateDebugUtilsMessengerEXT create_messenger = nullptr;
  PFN_xrDestroyDebugUtilsMessengerEXT destroy_messenger = nullptr;
  PFN_xrCreateHandTrackerEXT create_tracker = nullptr;
  PFN_xrDestroyHandTrackerEXT destroy_tracker = nullptr;
  PFN_xrLocateHandJointsEXT locate = nullptr;
  PFN_xrConvertTimespecTimeToTimeKHR from_timespec = nullptr;
};

}  // namespace rhot::test

#pragma GCC diagnostic pop
