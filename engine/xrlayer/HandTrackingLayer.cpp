// rhot's OpenXR API layer: XR_EXT_hand_tracking for any OpenXR application, from the hands a
// running rhot publishes (engine/stream/HandShare.h). docs/openxr.md says how to enable it.
//
// The loader puts the layer between the application and the runtime. Where the application
// enables XR_EXT_hand_tracking, the layer answers the extension's calls itself and passes
// everything else down untouched:
//
//   xrCreateApiLayerInstance   the extension taken out of the list the runtime sees (the loader
//                              passes it down unfiltered), XR_KHR_convert_timespec_time added
//                              where the runtime has it (the layer needs the runtime's clock)
//   xrGetSystemProperties      supportsHandTracking true
//   xrCreateHandTrackerEXT     a tracker of the layer's own; the session's STAGE space made once
//   xrLocateHandJointsEXT      the newest published hands moved on to the time asked for at their
//                              velocities, from rhot's world through the registration into the
//                              STAGE space, then into the base space the application asks for
//   xrDestroyHandTrackerEXT    forgotten
//
// Never blocks (the hands are read from shared memory with a seqlock), and never hands the
// application a value that is not finite: such a hand is reported untracked.

#include <time.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>
#define XR_USE_TIMESPEC
#include <openxr/openxr.h>
#include <openxr/openxr_platform.h>

#include "engine/stream/HandShare.h"

// The loader's interface to API layers (the OpenXR loader's negotiation ABI, version 1; Debian
// 12's OpenXR headers do not ship openxr_loader_negotiation.h).
extern "C" {
enum XrLoaderInterfaceStructs {
  XR_LOADER_INTERFACE_STRUCT_UNINTIALIZED = 0,
  XR_LOADER_INTERFACE_STRUCT_LOADER_INFO,
  XR_LOADER_INTERFACE_STRUCT_API_LAYER_REQUEST,
  XR_LOADER_INTERFACE_STRUCT_RUNTIME_REQUEST,
  XR_LOADER_INTERFACE_STRUCT_API_LAYER_CREATE_INFO,
  XR_LOADER_INTERFACE_STRUCT_API_LAYER_NEXT_INFO,
};
struct XrApiLayerCreateInfo;
typedef XrResult(XRAPI_PTR* PFN_xrCreateApiLayerInstance)(const XrInstanceCreateInfo* info, const XrApiLayerCreateInfo* layer_info,
                                                          XrInstance* instance);
struct XrApiLayerNextInfo {
  XrLoaderInterfaceStructs structType;
  uint32_t structVersion;
  size_t structSize;
  char layerName[XR_MAX_API_LAYER_NAME_SIZE];
  PFN_xrGetInstanceProcAddr nextGetInstanceProcAddr;
  PFN_xrCreateApiLayerInstance nextCreateApiLayerInstance;
  XrApiLayerNextInfo* next;
};
struct XrApiLayerCreateInfo {
  XrLoaderInterfaceStructs structType;
  uint32_t structVersion;
  size_t structSize;
  void* loaderInstance;
  char settings_file_location[512];
  XrApiLayerNextInfo* nextInfo;
};
struct XrNegotiateLoaderInfo {
  XrLoaderInterfaceStructs structType;
  uint32_t structVersion;
  size_t structSize;
  uint32_t minInterfaceVersion;
  uint32_t maxInterfaceVersion;
  XrVersion minApiVersion;
  XrVersion maxApiVersion;
};
struct XrNegotiateApiLayerRequest {
  XrLoaderInterfaceStructs structType;
  uint32_t structVersion;
  size_t structSize;
  uint32_t layerInterfaceVersion;
  XrVersion layerApiVersion;
  PFN_xrGetInstanceProcAddr getInstanceProcAddr;
  PFN_xrCreateApiLayerInstance createApiLayerInstance;
};
__attribute__((visibility("default"))) XrResult XRAPI_CALL xrNegotiateLoaderApiLayerInterface(const XrNegotiateLoaderInfo* loader_info,
                                                                                              const char* layer_name,
                                                                                              XrNegotiateApiLayerRequest* request);
}

namespace rhot::xrlayer {
namespace {

constexpr const char* kLayerName = "XR_APILAYER_RHOT_hand_tracking";
constexpr double kStale_s = 0.075;      // hands published longer ago than this are not tracked (rhot stopped or stuck)
constexpr double kMaxHorizon_s = 0.05;  // hands are moved on at most this far in time, either way
constexpr float kMaxCoordinate_m = 1000.0f;

double steady_now_s() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

struct Instance {
  XrInstance handle = XR_NULL_HANDLE;
  bool hand_tracking = false;  // the application enabled XR_EXT_hand_tracking
  PFN_xrGetInstanceProcAddr next = nullptr;
  PFN_xrDestroyInstance destroy_instance = nullptr;
  PFN_xrGetSystemProperties get_system_properties = nullptr;
  PFN_xrCreateReferenceSpace create_reference_space = nullptr;
  PFN_xrLocateSpace locate_space = nullptr;
  PFN_xrDestroySession destroy_session = nullptr;
  PFN_xrConvertTimeToTimespecTimeKHR to_timespec = nullptr;  // null where the runtime lacks it
  std::unique_ptr<HandShareReader> reader;                   // the block named when the instance was made
  std::mutex reader_mutex;                                   // the reader keeps state: one call at a time
  bool timespec_added = false;  // the layer enabled XR_KHR_convert_timespec_time: its functions are not the application's
};

struct Tracker {
  XrSession session = XR_NULL_HANDLE;
  XrHandEXT hand = XR_HAND_LEFT_EXT;
};

struct Session {
  std::shared_ptr<Instance> instance;
  XrSpace stage = XR_NULL_HANDLE;  // the layer's own: rhot's hands come registered to it
  std::vector<std::unique_ptr<Tracker>> trackers;
};

// Everything the layer knows, behind one lock: calls come from any of the application's threads.
struct State {
  std::mutex mutex;
  std::map<XrInstance, std::shared_ptr<Instance>> instances;
  std::map<XrSession, Session> sessions;
};

State& state() {
  static State s;
  return s;
}

template <typename Fn>
Fn next_proc(const Instance& instance, const char* name) {
  PFN_xrVoidFunction f = nullptr;
  if (XR_FAILED(instance.next(instance.handle, name, &f))) return nullptr;
  return reinterpret_cast<Fn>(f);
}

Tracker* tracker_of(XrHandTrackerEXT handle) { return reinterpret_cast<Tracker*>(handle); }

// The tracker's session, if both are still known (under the lock).
Session* session_of(State& s, const Tracker* tracker) {
  for (auto& [handle, session] : s.sessions) {
    for (const auto& t : session.trackers) {
      if (t.get() == tracker) return &session;
    }
  }
  return nullptr;
}

// The layer's record of an instance (null for one it does not know), taken under the lock.
std::shared_ptr<Instance> find_instance(XrInstance instance) {
  State& s = state();
  const std::lock_guard lock(s.mutex);
  const auto it = s.instances.find(instance);
  return it != s.instances.end() ? it->second : nullptr;
}

XRAPI_ATTR XrResult XRAPI_CALL get_system_properties(XrInstance instance, XrSystemId system, XrSystemProperties* properties) {
  const std::shared_ptr<Instance> in = find_instance(instance);
  if (in == nullptr) return XR_ERROR_HANDLE_INVALID;
  if (properties == nullptr) return in->get_system_properties(instance, system, properties);
  // The runtime is not to see the extension's structure (it may not know the extension): taken
  // out of the chain for the call down, put back and filled after.
  XrBaseOutStructure* before = reinterpret_cast<XrBaseOutStructure*>(properties);
  XrSystemHandTrackingPropertiesEXT* ours = nullptr;
  while (before->next != nullptr) {
    if (before->next->type == XR_TYPE_SYSTEM_HAND_TRACKING_PROPERTIES_EXT) {
      ours = reinterpret_cast<XrSystemHandTrackingPropertiesEXT*>(before->next);
      before->next = before->next->next;
      break;
    }
    before = before->next;
  }
  const XrResult r = in->get_system_properties(instance, system, properties);
  if (ours != nullptr) {
    ours->next = before->next;
    before->next = reinterpret_cast<XrBaseOutStructure*>(ours);
    if (XR_SUCCEEDED(r)) ours->supportsHandTracking = in->hand_tracking ? XR_TRUE : XR_FALSE;
  }
  return r;
}

XrResult create_hand_tracker_unguarded(XrSession session, const XrHandTrackerCreateInfoEXT* info, XrHandTrackerEXT* tracker) {
  if (info == nullptr || tracker == nullptr || info->type != XR_TYPE_HAND_TRACKER_CREATE_INFO_EXT) return XR_ERROR_VALIDATION_FAILURE;
  if (info->hand != XR_HAND_LEFT_EXT && info->hand != XR_HAND_RIGHT_EXT) return XR_ERROR_VALIDATION_FAILURE;
  if (info->handJointSet != XR_HAND_JOINT_SET_DEFAULT_EXT) return XR_ERROR_FEATURE_UNSUPPORTED;
  State& s = state();
  const std::lock_guard lock(s.mutex);
  auto it = s.sessions.find(session);
  bool no_stage = false;
  if (it == s.sessions.end()) {
    // The session's instance: the one the session's calls go to. A session is only ever made by
    // the one instance there is, nearly always; with several, the first that can locate in it.
    for (const auto& [handle, instance] : s.instances) {
      if (!instance->hand_tracking) continue;
      XrReferenceSpaceCreateInfo rci{XR_TYPE_REFERENCE_SPACE_CREATE_INFO};
      rci.poseInReferenceSpace.orientation.w = 1.0f;
      // STAGE only: the registration is to it (another space would put the hands elsewhere).
      rci.referenceSpaceType = XR_REFERENCE_SPACE_TYPE_STAGE;
      XrSpace space = XR_NULL_HANDLE;
      if (XR_FAILED(instance->create_reference_space(session, &rci, &space))) {
        no_stage = true;
        continue;
      }
      it = s.sessions.emplace(session, Session{instance, space, {}}).first;
      break;
    }
    if (it == s.sessions.end()) return no_stage ? XR_ERROR_FEATURE_UNSUPPORTED : XR_ERROR_HANDLE_INVALID;
  }
  auto made = std::make_unique<Tracker>();
  made->session = session;
  made->hand = info->hand;
  *tracker = reinterpret_cast<XrHandTrackerEXT>(made.get());
  it->second.trackers.push_back(std::move(made));
  return XR_SUCCESS;
}

// The application's calls that allocate: nothing is thrown across the C interface.
XRAPI_ATTR XrResult XRAPI_CALL create_hand_tracker(XrSession session, const XrHandTrackerCreateInfoEXT* info, XrHandTrackerEXT* tracker) {
  try {
    return create_hand_tracker_unguarded(session, info, tracker);
  } catch (...) {
    return XR_ERROR_RUNTIME_FAILURE;
  }
}

XRAPI_ATTR XrResult XRAPI_CALL destroy_hand_tracker(XrHandTrackerEXT handle) {
  State& s = state();
  const std::lock_guard lock(s.mutex);
  Session* session = session_of(s, tracker_of(handle));
  if (session == nullptr) return XR_ERROR_HANDLE_INVALID;
  std::erase_if(session->trackers, [&](const std::unique_ptr<Tracker>& t) { return t.get() == tracker_of(handle); });
  return XR_SUCCESS;
}

double d(float x) { return static_cast<double>(x); }

glm::dmat4 pose_matrix(const XrPosef& p) {
  glm::dmat4 m = glm::mat4_cast(glm::normalize(glm::dquat(d(p.orientation.w), d(p.orientation.x), d(p.orientation.y), d(p.orientation.z))));
  m[3] = glm::dvec4(d(p.position.x), d(p.position.y), d(p.position.z), 1.0);
  return m;
}

// Marks every joint unknown (the hand is not tracked).
void untracked(XrHandJointLocationsEXT* locations, XrHandJointVelocitiesEXT* velocities) {
  locations->isActive = XR_FALSE;
  for (uint32_t j = 0; j < locations->jointCount; ++j) {
    locations->jointLocations[j].locationFlags = 0;
    locations->jointLocations[j].pose = XrPosef{{0, 0, 0, 1}, {0, 0, 0}};
    locations->jointLocations[j].radius = 0.0f;
  }
  if (velocities == nullptr) return;
  for (uint32_t j = 0; j < velocities->jointCount; ++j) velocities->jointVelocities[j] = XrHandJointVelocityEXT{0, {0, 0, 0}, {0, 0, 0}};
}

bool usable(float x) { return std::isfinite(x) && std::abs(x) < kMaxCoordinate_m; }

XRAPI_ATTR XrResult XRAPI_CALL locate_hand_joints(XrHandTrackerEXT handle, const XrHandJointsLocateInfoEXT* info,
                                                  XrHandJointLocationsEXT* locations) {
  if (info == nullptr || locations == nullptr || info->type != XR_TYPE_HAND_JOINTS_LOCATE_INFO_EXT ||
      locations->type != XR_TYPE_HAND_JOINT_LOCATIONS_EXT || locations->jointLocations == nullptr ||
      locations->jointCount != XR_HAND_JOINT_COUNT_EXT || info->baseSpace == XR_NULL_HANDLE) {
    return XR_ERROR_VALIDATION_FAILURE;
  }
  XrHandJointVelocitiesEXT* velocities = nullptr;
  for (auto* next = reinterpret_cast<XrBaseOutStructure*>(locations->next); next != nullptr; next = next->next) {
    if (next->type == XR_TYPE_HAND_JOINT_VELOCITIES_EXT) velocities = reinterpret_cast<XrHandJointVelocitiesEXT*>(next);
  }
  if (velocities != nullptr && (velocities->jointCount != XR_HAND_JOINT_COUNT_EXT || velocities->jointVelocities == nullptr)) {
    return XR_ERROR_VALIDATION_FAILURE;
  }
  // What the call needs, copied under the lock; the runtime's calls are made without it.
  std::shared_ptr<Instance> in;
  XrSpace stage = XR_NULL_HANDLE;
  XrHandEXT hand = XR_HAND_LEFT_EXT;
  {
    State& s = state();
    const std::lock_guard lock(s.mutex);
    Tracker* tracker = tracker_of(handle);
    Session* session = session_of(s, tracker);
    if (session == nullptr) return XR_ERROR_HANDLE_INVALID;
    in = session->instance;
    stage = session->stage;
    hand = tracker->hand;
  }
  untracked(locations, velocities);
  const double now = steady_now_s();
  std::optional<HandShareSnapshot> snapshot;
  {
    const std::lock_guard lock(in->reader_mutex);
    snapshot = in->reader->read(now);
  }
  const std::size_t h = hand == XR_HAND_LEFT_EXT ? 0 : 1;
  // Stale, or stamped in the future or with nothing: not tracked.
  if (!snapshot || snapshot->hands[h].tracked == 0 || !(std::abs(now - snapshot->published_s) <= kStale_s)) return XR_SUCCESS;
  // The time asked for on the steady clock (where the runtime cannot say, now), and how far the
  // hands are to be moved on from their capture.
  double asked_s = now;
  timespec ts{};
  if (in->to_timespec != nullptr && XR_SUCCEEDED(in->to_timespec(in->handle, info->time, &ts))) {
    asked_s = static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
  }
  const double horizon = std::clamp(asked_s - snapshot->capture_s, -kMaxHorizon_s, kMaxHorizon_s);
  if (!std::isfinite(horizon)) return XR_SUCCESS;
  // The STAGE space in the base space, with its motion there (a base space that moves, such as
  // VIEW, moves the joints' velocities too).
  XrSpaceVelocity stage_motion{XR_TYPE_SPACE_VELOCITY};
  XrSpaceLocation base_from_stage{XR_TYPE_SPACE_LOCATION};
  base_from_stage.next = &stage_motion;
  if (XR_FAILED(in->locate_space(stage, info->baseSpace, info->time, &base_from_stage))) return XR_SUCCESS;
  const XrSpaceLocationFlags valid = XR_SPACE_LOCATION_ORIENTATION_VALID_BIT | XR_SPACE_LOCATION_POSITION_VALID_BIT;
  if ((base_from_stage.locationFlags & valid) != valid) return XR_SUCCESS;
  const bool stage_motion_known =
      (stage_motion.velocityFlags & (XR_SPACE_VELOCITY_LINEAR_VALID_BIT | XR_SPACE_VELOCITY_ANGULAR_VALID_BIT)) ==
      (XR_SPACE_VELOCITY_LINEAR_VALID_BIT | XR_SPACE_VELOCITY_ANGULAR_VALID_BIT);
  const glm::dvec3 stage_linear(d(stage_motion.linearVelocity.x), d(stage_motion.linearVelocity.y), d(stage_motion.linearVelocity.z));
  const glm::dvec3 stage_angular(d(stage_motion.angularVelocity.x), d(stage_motion.angularVelocity.y), d(stage_motion.angularVelocity.z));
  const glm::dvec3 stage_origin(d(base_from_stage.pose.position.x), d(base_from_stage.pose.position.y), d(base_from_stage.pose.position.z));
  glm::dmat4 world_from_stage;
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) world_from_stage[c][r] = d(snapshot->world_from_stage[4 * c + r]);
  }
  const glm::dmat4 base_from_world = pose_matrix(base_from_stage.pose) * glm::inverse(world_from_stage);
  const glm::dquat base_from_world_q = glm::normalize(glm::quat_cast(glm::dmat3(base_from_world)));
  std::array<XrHandJointLocationEXT, XR_HAND_JOINT_COUNT_EXT> out{};
  std::array<XrHandJointVelocityEXT, XR_HAND_JOINT_COUNT_EXT> vout{};
  for (int j = 0; j < XR_HAND_JOINT_COUNT_EXT; ++j) {
    const HandShareJoint& joint = snapshot->hands[h].joints[j];
    const glm::dvec3 v(d(joint.velocity[0]), d(joint.velocity[1]), d(joint.velocity[2]));
    const glm::dvec3 p = glm::dvec3(d(joint.position[0]), d(joint.position[1]), d(joint.position[2])) + v * horizon;
    const glm::dvec3 pb(base_from_world * glm::dvec4(p, 1.0));
    const glm::dquat q = glm::normalize(
        base_from_world_q * glm::dquat(d(joint.orientation[3]), d(joint.orientation[0]), d(joint.orientation[1]), d(joint.orientation[2])));
    // Relative to the base space: the joint's own velocity, plus the stage's motion there.
    const glm::dvec3 vb = glm::dmat3(base_from_world) * v +
                          (stage_motion_known ? stage_linear + glm::cross(stage_angular, pb - stage_origin) : glm::dvec3(0.0));
    out[j].pose = XrPosef{{static_cast<float>(q.x), static_cast<float>(q.y), static_cast<float>(q.z), static_cast<float>(q.w)},
                          {static_cast<float>(pb.x), static_cast<float>(pb.y), static_cast<float>(pb.z)}};
    out[j].radius = joint.radius;
    out[j].locationFlags = XR_SPACE_LOCATION_ORIENTATION_VALID_BIT | XR_SPACE_LOCATION_POSITION_VALID_BIT |
                           XR_SPACE_LOCATION_ORIENTATION_TRACKED_BIT | XR_SPACE_LOCATION_POSITION_TRACKED_BIT;
    // rhot measures no angular velocity per joint; the linear one only where the base space's motion is known.
    vout[j].velocityFlags = stage_motion_known ? XR_SPACE_VELOCITY_LINEAR_VALID_BIT : 0;
    vout[j].linearVelocity = {static_cast<float>(vb.x), static_cast<float>(vb.y), static_cast<float>(vb.z)};
    const float values[] = {out[j].pose.orientation.x, out[j].pose.orientation.y, out[j].pose.orientation.z, out[j].pose.orientation.w,
                            out[j].pose.position.x,    out[j].pose.position.y,    out[j].pose.position.z,    out[j].radius,
                            vout[j].linearVelocity.x,  vout[j].linearVelocity.y,  vout[j].linearVelocity.z};
    if (!std::all_of(std::begin(values), std::end(values), usable) || !(out[j].radius >= 0.0f)) return XR_SUCCESS;  // untracked
  }
  std::copy(out.begin(), out.end(), locations->jointLocations);
  if (velocities != nullptr) std::copy(vout.begin(), vout.end(), velocities->jointVelocities);
  locations->isActive = XR_TRUE;
  return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL destroy_session(XrSession session) {
  std::shared_ptr<Instance> in;
  {
    State& s = state();
    const std::lock_guard lock(s.mutex);
    const auto it = s.sessions.find(session);
    if (it != s.sessions.end()) {
      in = it->second.instance;
      s.sessions.erase(it);  // its space and trackers go with the session
    } else {
      for (const auto& [handle, instance] : s.instances) {
        if (instance->destroy_session != nullptr) in = instance;
      }
    }
  }
  return in != nullptr ? in->destroy_session(session) : XR_ERROR_HANDLE_INVALID;
}

XRAPI_ATTR XrResult XRAPI_CALL destroy_instance(XrInstance instance) {
  std::shared_ptr<Instance> in;
  {
    State& s = state();
    const std::lock_guard lock(s.mutex);
    const auto it = s.instances.find(instance);
    if (it == s.instances.end()) return XR_ERROR_HANDLE_INVALID;
    in = it->second;
    s.instances.erase(it);
    std::erase_if(s.sessions, [&](const auto& entry) { return entry.second.instance == in; });
  }
  return in->destroy_instance(instance);
}

XRAPI_ATTR XrResult XRAPI_CALL get_instance_proc_addr(XrInstance instance, const char* name, PFN_xrVoidFunction* function);

XrResult create_api_layer_instance_unguarded(const XrInstanceCreateInfo* info, const XrApiLayerCreateInfo* layer_info,
                                             XrInstance* instance) {
  if (info == nullptr || layer_info == nullptr || layer_info->nextInfo == nullptr || instance == nullptr) {
    return XR_ERROR_INITIALIZATION_FAILED;
  }
  const XrApiLayerNextInfo& next = *layer_info->nextInfo;
  bool hand_tracking = false;
  bool has_timespec = false;
  std::vector<const char*> down;
  for (uint32_t i = 0; i < info->enabledExtensionCount; ++i) {
    const char* e = info->enabledExtensionNames[i];
    if (std::strcmp(e, XR_EXT_HAND_TRACKING_EXTENSION_NAME) == 0) {
      hand_tracking = true;  // answered here: the runtime is not to see it
      continue;
    }
    has_timespec = has_timespec || std::strcmp(e, XR_KHR_CONVERT_TIMESPEC_TIME_EXTENSION_NAME) == 0;
    down.push_back(e);
  }
  XrApiLayerCreateInfo next_layer = *layer_info;
  next_layer.nextInfo = next.next;
  XrInstanceCreateInfo down_info = *info;
  XrResult r = XR_ERROR_EXTENSION_NOT_PRESENT;
  bool added_timespec = false;
  if (hand_tracking && !has_timespec) {
    // The runtime's clock, for the time the application asks joints for: asked for where the
    // runtime has it, else the layer takes "now".
    std::vector<const char*> with = down;
    with.push_back(XR_KHR_CONVERT_TIMESPEC_TIME_EXTENSION_NAME);
    down_info.enabledExtensionCount = static_cast<uint32_t>(with.size());
    down_info.enabledExtensionNames = with.data();
    r = next.nextCreateApiLayerInstance(&down_info, &next_layer, instance);
    added_timespec = XR_SUCCEEDED(r);
    if (XR_FAILED(r) && r != XR_ERROR_EXTENSION_NOT_PRESENT) return r;  // not the added extension's fault
  }
  if (!added_timespec) {
    down_info.enabledExtensionCount = static_cast<uint32_t>(down.size());
    down_info.enabledExtensionNames = down.data();
    r = next.nextCreateApiLayerInstance(&down_info, &next_layer, instance);
  }
  if (XR_FAILED(r)) return r;
  auto in = std::make_shared<Instance>();
  in->handle = *instance;
  in->hand_tracking = hand_tracking;
  in->next = next.nextGetInstanceProcAddr;
  in->destroy_instance = next_proc<PFN_xrDestroyInstance>(*in, "xrDestroyInstance");
  in->get_system_properties = next_proc<PFN_xrGetSystemProperties>(*in, "xrGetSystemProperties");
  in->create_reference_space = next_proc<PFN_xrCreateReferenceSpace>(*in, "xrCreateReferenceSpace");
  in->locate_space = next_proc<PFN_xrLocateSpace>(*in, "xrLocateSpace");
  in->destroy_session = next_proc<PFN_xrDestroySession>(*in, "xrDestroySession");
  if (has_timespec || added_timespec)
    in->to_timespec = next_proc<PFN_xrConvertTimeToTimespecTimeKHR>(*in, "xrConvertTimeToTimespecTimeKHR");
  in->reader = std::make_unique<HandShareReader>(hand_share_name());
  in->timespec_added = added_timespec;
  State& s = state();
  const std::lock_guard lock(s.mutex);
  s.instances[*instance] = std::move(in);
  return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL create_api_layer_instance(const XrInstanceCreateInfo* info, const XrApiLayerCreateInfo* layer_info,
                                                         XrInstance* instance) {
  try {
    return create_api_layer_instance_unguarded(info, layer_info, instance);
  } catch (...) {
    return XR_ERROR_RUNTIME_FAILURE;
  }
}

XRAPI_ATTR XrResult XRAPI_CALL get_instance_proc_addr(XrInstance instance, const char* name, PFN_xrVoidFunction* function) {
  if (name == nullptr || function == nullptr) return XR_ERROR_VALIDATION_FAILURE;
  *function = nullptr;
  const std::shared_ptr<Instance> in = find_instance(instance);
  if (in == nullptr) return XR_ERROR_HANDLE_INVALID;  // the loader asks for functions of an instance only
  const std::string n(name);
  const auto give = [&](auto fn) {
    *function = reinterpret_cast<PFN_xrVoidFunction>(fn);
    return XR_SUCCESS;
  };
  if (n == "xrGetInstanceProcAddr") return give(&get_instance_proc_addr);
  if (in->timespec_added && (n == "xrConvertTimeToTimespecTimeKHR" || n == "xrConvertTimespecTimeToTimeKHR")) {
    return XR_ERROR_FUNCTION_UNSUPPORTED;  // enabled by the layer for itself, not by the application
  }
  if (n == "xrDestroyInstance") return give(&destroy_instance);
  if (in->hand_tracking) {
    if (n == "xrGetSystemProperties") return give(&get_system_properties);
    if (n == "xrDestroySession") return give(&destroy_session);
    if (n == "xrCreateHandTrackerEXT") return give(&create_hand_tracker);
    if (n == "xrDestroyHandTrackerEXT") return give(&destroy_hand_tracker);
    if (n == "xrLocateHandJointsEXT") return give(&locate_hand_joints);
  } else if (n == "xrCreateHandTrackerEXT" || n == "xrDestroyHandTrackerEXT" || n == "xrLocateHandJointsEXT") {
    return XR_ERROR_FUNCTION_UNSUPPORTED;  // the application did not enable the extension
  }
  return in->next(instance, name, function);
}

}  // namespace
}  // namespace rhot::xrlayer

extern "C" XrResult XRAPI_CALL xrNegotiateLoaderApiLayerInterface(const XrNegotiateLoaderInfo* loader_info, const char* layer_name,
                                                                  XrNegotiateApiLayerRequest* request) {
  if (loader_info == nullptr || request == nullptr || layer_name == nullptr || std::strcmp(layer_name, rhot::xrlayer::kLayerName) != 0 ||
      loader_info->structType != XR_LOADER_INTERFACE_STRUCT_LOADER_INFO || loader_info->minInterfaceVersion > 1 ||
      loader_info->maxInterfaceVersion < 1 || request->structType != XR_LOADER_INTERFACE_STRUCT_API_LAYER_REQUEST) {
    return XR_ERROR_INITIALIZATION_FAILED;
  }
  request->layerInterfaceVersion = 1;
  request->layerApiVersion = XR_CURRENT_API_VERSION;
  request->getInstanceProcAddr = &rhot::xrlayer::get_instance_proc_addr;
  request->createApiLayerInstance = &rhot::xrlayer::create_api_layer_instance;
  return XR_SUCCESS;
}
