#include "engine/render/XrHeadset.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <utility>

#include <glm/gtc/quaternion.hpp>
#include <spdlog/spdlog.h>

#include "base/SteadyClock.h"
#include "engine/render/vk/XrBinding.h"

namespace rhot {

namespace {

constexpr const char* kCoreValidation = "XR_APILAYER_LUNARG_core_validation";

std::string xr_result(XrInstance instance, XrResult r) {
  char text[XR_MAX_RESULT_STRING_SIZE] = {};
  if (instance != XR_NULL_HANDLE && xrResultToString(instance, r, text) == XR_SUCCESS) return text;
  switch (r) {  // what the loader answers before there is an instance to name them
    case XR_ERROR_RUNTIME_UNAVAILABLE:
      return "XR_ERROR_RUNTIME_UNAVAILABLE";
    case XR_ERROR_RUNTIME_FAILURE:
      return "XR_ERROR_RUNTIME_FAILURE";
    case XR_ERROR_INITIALIZATION_FAILED:
      return "XR_ERROR_INITIALIZATION_FAILED";
    case XR_ERROR_API_VERSION_UNSUPPORTED:
      return "XR_ERROR_API_VERSION_UNSUPPORTED";
    case XR_ERROR_EXTENSION_NOT_PRESENT:
      return "XR_ERROR_EXTENSION_NOT_PRESENT";
    case XR_ERROR_API_LAYER_NOT_PRESENT:
      return "XR_ERROR_API_LAYER_NOT_PRESENT";
    default:
      return "XrResult " + std::to_string(static_cast<int>(r));
  }
}

// Where no runtime answers: how to install or select one.
std::string xr_no_runtime(XrResult r) {
  std::string why = "no OpenXR runtime (" + xr_result(XR_NULL_HANDLE, r) + ")";
  if (const char* json = std::getenv("XR_RUNTIME_JSON"); json != nullptr && *json != '\0') {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(json, ec)) return why + ": XR_RUNTIME_JSON names " + json + ", which is not a file";
    return why + ": the runtime XR_RUNTIME_JSON names (" + json + ") did not start";
  }
  return why +
         ": install one (Monado: Debian package monado-service; SteamVR) and make it the active runtime, or point "
         "XR_RUNTIME_JSON at its manifest (docs/openxr.md)";
}

bool xr_has_extension(const std::vector<XrExtensionProperties>& all, const char* name) {
  return std::any_of(all.begin(), all.end(), [&](const XrExtensionProperties& e) { return std::strcmp(e.extensionName, name) == 0; });
}

XRAPI_ATTR XrBool32 XRAPI_CALL on_xr_message(XrDebugUtilsMessageSeverityFlagsEXT severity, XrDebugUtilsMessageTypeFlagsEXT,
                                             const XrDebugUtilsMessengerCallbackDataEXT* data, void* user) {
  auto* impl = static_cast<XrHeadset::Impl*>(user);
  impl->validation_messages.fetch_add(1);
  const char* text = data != nullptr && data->message != nullptr ? data->message : "";
  if ((severity & XR_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT) != 0) {
    spdlog::error("openxr validation: {}", text);
  } else {
    spdlog::warn("openxr validation: {}", text);
  }
  return XR_FALSE;
}

template <typename Fn>
Fn xr_proc(XrInstance instance, const char* name) {
  PFN_xrVoidFunction f = nullptr;
  if (xrGetInstanceProcAddr(instance, name, &f) != XR_SUCCESS) return nullptr;
  return reinterpret_cast<Fn>(f);
}

// The instance's extensions: what rhot needs, and what it uses where the runtime has it.
std::expected<std::vector<const char*>, std::string> choose_xr_extensions(bool validation, bool& debug_utils) {
  std::uint32_t count = 0;
  if (const XrResult r = xrEnumerateInstanceExtensionProperties(nullptr, 0, &count, nullptr); XR_FAILED(r)) {
    return std::unexpected(xr_no_runtime(r));
  }
  std::vector<XrExtensionProperties> all(count, XrExtensionProperties{XR_TYPE_EXTENSION_PROPERTIES});
  if (const XrResult r = xrEnumerateInstanceExtensionProperties(nullptr, count, &count, all.data()); XR_FAILED(r)) {
    return std::unexpected(xr_no_runtime(r));
  }
  std::vector<const char*> names;
  for (const char* needed : {XR_KHR_VULKAN_ENABLE2_EXTENSION_NAME, XR_KHR_CONVERT_TIMESPEC_TIME_EXTENSION_NAME}) {
    if (!xr_has_extension(all, needed)) return std::unexpected(std::string("the OpenXR runtime lacks ") + needed + ", which rhot needs");
    names.push_back(needed);
  }
  debug_utils = validation && xr_has_extension(all, XR_EXT_DEBUG_UTILS_EXTENSION_NAME);
  if (debug_utils) names.push_back(XR_EXT_DEBUG_UTILS_EXTENSION_NAME);
  return names;
}

bool xr_layer_available(const char* name) {
  std::uint32_t count = 0;
  if (XR_FAILED(xrEnumerateApiLayerProperties(0, &count, nullptr))) return false;
  std::vector<XrApiLayerProperties> layers(count, XrApiLayerProperties{XR_TYPE_API_LAYER_PROPERTIES});
  if (XR_FAILED(xrEnumerateApiLayerProperties(count, &count, layers.data()))) return false;
  return std::any_of(layers.begin(), layers.end(), [&](const XrApiLayerProperties& l) { return std::strcmp(l.layerName, name) == 0; });
}

bool xr_pose_usable(const XrPosef& p) {
  const float values[] = {p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w, p.position.x, p.position.y, p.position.z};
  const float q = p.orientation.x * p.orientation.x + p.orientation.y * p.orientation.y + p.orientation.z * p.orientation.z +
                  p.orientation.w * p.orientation.w;
  // Finite, a rotation (not a zero quaternion), and within a kilometre of the space's origin.
  return std::all_of(std::begin(values), std::end(values), [](float x) { return std::isfinite(x) && std::abs(x) < 1000.0f; }) && q > 0.5f &&
         q < 2.0f;
}

// A view the renderer can draw: a usable pose and a field of view with its left edge left of its
// right and its lower edge below its upper, every edge less than 89 degrees from the view axis.
bool xr_view_usable(const XrView& v) {
  const float limit = 89.0f * static_cast<float>(M_PI) / 180.0f;
  const XrFovf& f = v.fov;
  const float angles[] = {f.angleLeft, f.angleRight, f.angleUp, f.angleDown};
  return xr_pose_usable(v.pose) &&
         std::all_of(std::begin(angles), std::end(angles), [&](float a) { return std::isfinite(a) && std::abs(a) < limit; }) &&
         f.angleLeft < f.angleRight && f.angleDown < f.angleUp;
}

bool finite(const glm::mat4& m) {
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) {
      if (!std::isfinite(m[c][r])) return false;
    }
  }
  return true;
}

// The session or the instance is gone: nothing more can be done with it.
bool xr_lost(XrResult r) { return r == XR_ERROR_SESSION_LOST || r == XR_ERROR_INSTANCE_LOST || r == XR_ERROR_RUNTIME_FAILURE; }

glm::mat4 xr_pose_matrix(const XrPosef& pose) {
  const glm::quat q(pose.orientation.w, pose.orientation.x, pose.orientation.y, pose.orientation.z);
  glm::mat4 m = glm::mat4_cast(glm::normalize(q));
  m[3] = glm::vec4(pose.position.x, pose.position.y, pose.position.z, 1.0f);
  return m;
}

}  // namespace

const char* to_string(XrState state) {
  switch (state) {
    case XrState::kUnknown:
      return "unknown";
    case XrState::kIdle:
      return "idle";
    case XrState::kReady:
      return "ready";
    case XrState::kSynchronized:
      return "synchronized";
    case XrState::kVisible:
      return "visible";
    case XrState::kFocused:
      return "focused";
    case XrState::kStopping:
      return "stopping";
    case XrState::kLossPending:
      return "loss pending";
    case XrState::kExiting:
      return "exiting";
  }
  return "?";
}

std::expected<std::unique_ptr<XrHeadset>, std::string> XrHeadset::create(const XrHeadsetSettings& settings) {
  // The loader prints its own errors (several lines where no runtime is found) unless told not to;
  // rhot says what went wrong in one. XR_LOADER_DEBUG set by the user wins.
  setenv("XR_LOADER_DEBUG", "none", 0);
  auto impl = std::make_unique<Impl>();
  impl->settings = settings;
  const char* env_validation = std::getenv("RHOT_XR_VALIDATION");
  const bool want_validation = settings.validation || (env_validation != nullptr && std::strcmp(env_validation, "1") == 0);
  bool debug_utils = false;
  auto extensions = choose_xr_extensions(want_validation, debug_utils);
  if (!extensions) return std::unexpected(extensions.error());
  std::vector<const char*> layers;
  if (want_validation) {
    if (xr_layer_available(kCoreValidation)) {
      layers.push_back(kCoreValidation);
      impl->info.validation_enabled = true;
    } else {
      spdlog::warn("OpenXR validation requested but {} is not installed (Debian package openxr-layer-corevalidation)", kCoreValidation);
    }
  }
  XrInstanceCreateInfo ici{XR_TYPE_INSTANCE_CREATE_INFO};
  std::snprintf(ici.applicationInfo.applicationName, XR_MAX_APPLICATION_NAME_SIZE, "%s", settings.application.c_str());
  std::snprintf(ici.applicationInfo.engineName, XR_MAX_ENGINE_NAME_SIZE, "%s", "rhot");
  ici.applicationInfo.apiVersion = XR_MAKE_VERSION(1, 0, 0);
  ici.enabledExtensionCount = static_cast<std::uint32_t>(extensions->size());
  ici.enabledExtensionNames = extensions->data();
  ici.enabledApiLayerCount = static_cast<std::uint32_t>(layers.size());
  ici.enabledApiLayerNames = layers.data();
  if (const XrResult r = xrCreateInstance(&ici, &impl->instance); XR_FAILED(r)) return std::unexpected(xr_no_runtime(r));
  XrInstance instance = impl->instance;

  if (impl->info.validation_enabled && !debug_utils) {
    spdlog::warn("OpenXR validation: the runtime lacks XR_EXT_debug_utils; the layer's messages go to its own output, uncounted");
    impl->info.validation_enabled = false;
  }
  if (debug_utils && impl->info.validation_enabled) {
    auto create_messenger = xr_proc<PFN_xrCreateDebugUtilsMessengerEXT>(instance, "xrCreateDebugUtilsMessengerEXT");
    XrDebugUtilsMessengerCreateInfoEXT mci{XR_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
    mci.messageSeverities = XR_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | XR_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
    mci.messageTypes = XR_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | XR_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                       XR_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT | XR_DEBUG_UTILS_MESSAGE_TYPE_CONFORMANCE_BIT_EXT;
    mci.userCallback = &on_xr_message;
    mci.userData = impl.get();
    if (create_messenger == nullptr || XR_FAILED(create_messenger(instance, &mci, &impl->messenger))) {
      spdlog::warn("OpenXR validation: cannot create a debug messenger; the layer's messages go to its own output, uncounted");
      impl->info.validation_enabled = false;
    }
  }

  XrInstanceProperties props{XR_TYPE_INSTANCE_PROPERTIES};
  if (XR_SUCCEEDED(xrGetInstanceProperties(instance, &props))) {
    impl->info.runtime = std::string(props.runtimeName) + " " + std::to_string(XR_VERSION_MAJOR(props.runtimeVersion)) + "." +
                         std::to_string(XR_VERSION_MINOR(props.runtimeVersion)) + "." +
                         std::to_string(XR_VERSION_PATCH(props.runtimeVersion));
  }
  XrSystemGetInfo sgi{XR_TYPE_SYSTEM_GET_INFO};
  sgi.formFactor = XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY;
  if (const XrResult r = xrGetSystem(instance, &sgi, &impl->system); XR_FAILED(r)) {
    return std::unexpected("the OpenXR runtime " + impl->info.runtime + " has no headset (" + xr_result(instance, r) +
                           "): connect one and start its runtime");
  }
  XrSystemProperties sys{XR_TYPE_SYSTEM_PROPERTIES};
  if (XR_SUCCEEDED(xrGetSystemProperties(instance, impl->system, &sys))) impl->info.system = sys.systemName;

  std::uint32_t view_count = 0;
  xrEnumerateViewConfigurationViews(instance, impl->system, XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO, 0, &view_count, nullptr);
  std::vector<XrViewConfigurationView> views(view_count, XrViewConfigurationView{XR_TYPE_VIEW_CONFIGURATION_VIEW});
  if (view_count != 2 || XR_FAILED(xrEnumerateViewConfigurationViews(instance, impl->system, XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO,
                                                                     view_count, &view_count, views.data()))) {
    return std::unexpected("the headset " + impl->info.system + " has no stereo view configuration of two views");
  }
  impl->info.recommended_width_px = static_cast<int>(views[0].recommendedImageRectWidth);
  impl->info.recommended_height_px = static_cast<int>(views[0].recommendedImageRectHeight);

  impl->get_requirements = xr_proc<PFN_xrGetVulkanGraphicsRequirements2KHR>(instance, "xrGetVulkanGraphicsRequirements2KHR");
  impl->create_vk_instance = xr_proc<PFN_xrCreateVulkanInstanceKHR>(instance, "xrCreateVulkanInstanceKHR");
  impl->get_vk_device = xr_proc<PFN_xrGetVulkanGraphicsDevice2KHR>(instance, "xrGetVulkanGraphicsDevice2KHR");
  impl->create_vk_device = xr_proc<PFN_xrCreateVulkanDeviceKHR>(instance, "xrCreateVulkanDeviceKHR");
  impl->to_timespec = xr_proc<PFN_xrConvertTimeToTimespecTimeKHR>(instance, "xrConvertTimeToTimespecTimeKHR");
  impl->from_timespec = xr_proc<PFN_xrConvertTimespecTimeToTimeKHR>(instance, "xrConvertTimespecTimeToTimeKHR");
  if (!impl->get_requirements || !impl->create_vk_instance || !impl->get_vk_device || !impl->create_vk_device || !impl->to_timespec ||
      !impl->from_timespec) {
    return std::unexpected("the OpenXR runtime " + impl->info.runtime + " advertises but does not give the functions of " +
                           XR_KHR_VULKAN_ENABLE2_EXTENSION_NAME + " and " + XR_KHR_CONVERT_TIMESPEC_TIME_EXTENSION_NAME);
  }
  std::uint32_t blend_count = 0;
  xrEnumerateEnvironmentBlendModes(instance, impl->system, XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO, 0, &blend_count, nullptr);
  std::vector<XrEnvironmentBlendMode> blends(blend_count);
  xrEnumerateEnvironmentBlendModes(instance, impl->system, XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO, blend_count, &blend_count,
                                   blends.data());
  if (!blends.empty()) impl->blend = blends.front();  // the runtime's preferred one
  spdlog::info("OpenXR: {} on {}, {} x {} per eye recommended{}", impl->info.runtime, impl->info.system, impl->info.recommended_width_px,
               impl->info.recommended_height_px, impl->info.validation_enabled ? ", core validation on" : "");
  return std::unique_ptr<XrHeadset>(new XrHeadset(std::move(impl)));
}

XrHeadset::XrHeadset(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
XrHeadset::~XrHeadset() = default;

XrHeadset::Impl::~Impl() {
  stop();
  if (messenger != XR_NULL_HANDLE) {
    if (auto destroy = xr_proc<PFN_xrDestroyDebugUtilsMessengerEXT>(instance, "xrDestroyDebugUtilsMessengerEXT")) destroy(messenger);
  }
  if (instance != XR_NULL_HANDLE) xrDestroyInstance(instance);
}

const XrHeadsetInfo& XrHeadset::info() const { return impl_->info; }

std::expected<VkInstance, std::string> XrHeadset::Impl::make_instance(const VkInstanceCreateInfo& create_info) {
  // The runtime's Vulkan requirements must be asked for before the session (the spec says so).
  XrGraphicsRequirementsVulkan2KHR req{XR_TYPE_GRAPHICS_REQUIREMENTS_VULKAN2_KHR};
  if (const XrResult r = get_requirements(instance, system, &req); XR_FAILED(r)) {
    return std::unexpected("the OpenXR runtime does not say what Vulkan it needs: " + xr_result(instance, r));
  }
  const std::uint32_t wanted = create_info.pApplicationInfo != nullptr ? create_info.pApplicationInfo->apiVersion : VK_API_VERSION_1_0;
  const XrVersion as_xr = XR_MAKE_VERSION(VK_API_VERSION_MAJOR(wanted), VK_API_VERSION_MINOR(wanted), 0);
  const XrVersion min = XR_MAKE_VERSION(XR_VERSION_MAJOR(req.minApiVersionSupported), XR_VERSION_MINOR(req.minApiVersionSupported), 0);
  const XrVersion max = XR_MAKE_VERSION(XR_VERSION_MAJOR(req.maxApiVersionSupported), XR_VERSION_MINOR(req.maxApiVersionSupported), 0);
  const std::string range = std::to_string(XR_VERSION_MAJOR(min)) + "." + std::to_string(XR_VERSION_MINOR(min)) + " to " +
                            std::to_string(XR_VERSION_MAJOR(max)) + "." + std::to_string(XR_VERSION_MINOR(max));
  const std::string ours = std::to_string(VK_API_VERSION_MAJOR(wanted)) + "." + std::to_string(VK_API_VERSION_MINOR(wanted));
  if (as_xr < min) return std::unexpected("the OpenXR runtime needs Vulkan " + range + ", rhot's renderer uses " + ours);
  // Newer than the runtime has tested "might work" (the extension's words): said, not refused.
  if (as_xr > max) spdlog::warn("OpenXR: the runtime has tested Vulkan {}; rhot's renderer uses {}", range, ours);
  XrVulkanInstanceCreateInfoKHR ci{XR_TYPE_VULKAN_INSTANCE_CREATE_INFO_KHR};
  ci.systemId = system;
  ci.pfnGetInstanceProcAddr = &vkGetInstanceProcAddr;
  ci.vulkanCreateInfo = &create_info;
  VkInstance vk_instance = VK_NULL_HANDLE;
  VkResult vk_result = VK_SUCCESS;
  const XrResult r = create_vk_instance(instance, &ci, &vk_instance, &vk_result);
  if (XR_FAILED(r) || vk_result != VK_SUCCESS) {
    return std::unexpected("the OpenXR runtime cannot create rhot's Vulkan instance: " + xr_result(instance, r) + ", " +
                           vk::result_string(vk_result));
  }
  return vk_instance;
}

std::expected<VkPhysicalDevice, std::string> XrHeadset::Impl::physical_device(VkInstance vk_instance) {
  XrVulkanGraphicsDeviceGetInfoKHR gi{XR_TYPE_VULKAN_GRAPHICS_DEVICE_GET_INFO_KHR};
  gi.systemId = system;
  gi.vulkanInstance = vk_instance;
  VkPhysicalDevice device = VK_NULL_HANDLE;
  if (const XrResult r = get_vk_device(instance, &gi, &device); XR_FAILED(r) || device == VK_NULL_HANDLE) {
    return std::unexpected("the OpenXR runtime names no Vulkan device for the headset: " + xr_result(instance, r));
  }
  return device;
}

std::expected<VkDevice, std::string> XrHeadset::Impl::make_device(VkPhysicalDevice physical, const VkDeviceCreateInfo& create_info) {
  XrVulkanDeviceCreateInfoKHR ci{XR_TYPE_VULKAN_DEVICE_CREATE_INFO_KHR};
  ci.systemId = system;
  ci.pfnGetInstanceProcAddr = &vkGetInstanceProcAddr;
  ci.vulkanPhysicalDevice = physical;
  ci.vulkanCreateInfo = &create_info;
  VkDevice device = VK_NULL_HANDLE;
  VkResult vk_result = VK_SUCCESS;
  const XrResult r = create_vk_device(instance, &ci, &device, &vk_result);
  if (XR_FAILED(r) || vk_result != VK_SUCCESS) {
    return std::unexpected("the OpenXR runtime cannot create rhot's Vulkan device: " + xr_result(instance, r) + ", " +
                           vk::result_string(vk_result));
  }
  return device;
}

std::expected<void, std::string> XrHeadset::Impl::start(const vk::Context& context, bool array_swapchain) {
  XrGraphicsBindingVulkan2KHR binding{XR_TYPE_GRAPHICS_BINDING_VULKAN2_KHR};
  binding.instance = context.instance();
  binding.physicalDevice = context.physical_device();
  binding.device = context.device();
  binding.queueFamilyIndex = context.queue_family();
  binding.queueIndex = 0;
  XrSessionCreateInfo sci{XR_TYPE_SESSION_CREATE_INFO};
  sci.next = &binding;
  sci.systemId = system;
  if (const XrResult r = xrCreateSession(instance, &sci, &session); XR_FAILED(r)) {
    return std::unexpected("cannot start an OpenXR session: " + xr_result(instance, r));
  }
  // STAGE: the floor at y = 0, like rhot's world; LOCAL where the runtime has no stage.
  std::uint32_t count = 0;
  xrEnumerateReferenceSpaces(session, 0, &count, nullptr);
  std::vector<XrReferenceSpaceType> spaces(count);
  xrEnumerateReferenceSpaces(session, count, &count, spaces.data());
  XrReferenceSpaceCreateInfo rci{XR_TYPE_REFERENCE_SPACE_CREATE_INFO};
  rci.referenceSpaceType = std::find(spaces.begin(), spaces.end(), XR_REFERENCE_SPACE_TYPE_STAGE) != spaces.end()
                               ? XR_REFERENCE_SPACE_TYPE_STAGE
                               : XR_REFERENCE_SPACE_TYPE_LOCAL;
  if (rci.referenceSpaceType != XR_REFERENCE_SPACE_TYPE_STAGE) spdlog::warn("OpenXR: the runtime has no STAGE space; using LOCAL");
  rci.poseInReferenceSpace.orientation.w = 1.0f;
  if (const XrResult r = xrCreateReferenceSpace(session, &rci, &stage); XR_FAILED(r)) {
    return std::unexpected("cannot create the OpenXR reference space: " + xr_result(instance, r));
  }
  rci.referenceSpaceType = XR_REFERENCE_SPACE_TYPE_VIEW;
  if (const XrResult r = xrCreateReferenceSpace(session, &rci, &view); XR_FAILED(r)) {
    return std::unexpected("cannot create the OpenXR view space: " + xr_result(instance, r));
  }
  // The swapchain format: the renderer's own (a copy), else BGRA (a blit converts).
  xrEnumerateSwapchainFormats(session, 0, &count, nullptr);
  std::vector<std::int64_t> formats(count);
  xrEnumerateSwapchainFormats(session, count, &count, formats.data());
  for (const VkFormat f : {VK_FORMAT_R8G8B8A8_SRGB, VK_FORMAT_B8G8R8A8_SRGB}) {
    if (format == VK_FORMAT_UNDEFINED && std::find(formats.begin(), formats.end(), static_cast<std::int64_t>(f)) != formats.end())
      format = f;
  }
  if (format == VK_FORMAT_UNDEFINED) return std::unexpected(std::string("the OpenXR runtime offers no 8-bit sRGB swapchain format"));
  width = info.recommended_width_px;
  height = info.recommended_height_px;
  const std::uint32_t chain_count = array_swapchain ? 1 : 2;
  for (std::uint32_t c = 0; c < chain_count; ++c) {
    Chain chain;
    chain.layers = array_swapchain ? 2 : 1;
    XrSwapchainCreateInfo ci{XR_TYPE_SWAPCHAIN_CREATE_INFO};
    ci.usageFlags = XR_SWAPCHAIN_USAGE_COLOR_ATTACHMENT_BIT | XR_SWAPCHAIN_USAGE_TRANSFER_DST_BIT;
    ci.format = format;
    ci.sampleCount = 1;
    ci.width = static_cast<std::uint32_t>(width);
    ci.height = static_cast<std::uint32_t>(height);
    ci.faceCount = 1;
    ci.arraySize = chain.layers;
    ci.mipCount = 1;
    if (const XrResult r = xrCreateSwapchain(session, &ci, &chain.handle); XR_FAILED(r)) {
      return std::unexpected("cannot create an OpenXR swapchain: " + xr_result(instance, r));
    }
    std::uint32_t images = 0;
    xrEnumerateSwapchainImages(chain.handle, 0, &images, nullptr);
    std::vector<XrSwapchainImageVulkan2KHR> vk_images(images, XrSwapchainImageVulkan2KHR{XR_TYPE_SWAPCHAIN_IMAGE_VULKAN2_KHR});
    xrEnumerateSwapchainImages(chain.handle, images, &images, reinterpret_cast<XrSwapchainImageBaseHeader*>(vk_images.data()));
    for (const auto& image : vk_images) chain.images.push_back(image.image);
    chains.push_back(std::move(chain));
  }
  spdlog::info("OpenXR session: {} swapchain(s) of {} x {}{}, {}", chains.size(), width, height, array_swapchain ? " x 2 layers" : "",
               format == VK_FORMAT_R8G8B8A8_SRGB ? "R8G8B8A8_SRGB" : "B8G8R8A8_SRGB");
  return {};
}

void XrHeadset::Impl::stop() {
  if (frame) end_frame();
  for (Chain& c : chains) {
    if (c.handle != XR_NULL_HANDLE) xrDestroySwapchain(c.handle);
  }
  chains.clear();
  if (view != XR_NULL_HANDLE) xrDestroySpace(view);
  view = XR_NULL_HANDLE;
  if (stage != XR_NULL_HANDLE) xrDestroySpace(stage);
  stage = XR_NULL_HANDLE;
  if (session != XR_NULL_HANDLE) {
    // Ended only where the runtime is stopping it; destroying a running session is allowed.
    if (running && state == XR_SESSION_STATE_STOPPING) xrEndSession(session);
    running = false;
    xrDestroySession(session);
  }
  session = XR_NULL_HANDLE;
}

void XrHeadset::Impl::handle_state(XrSessionState next) {
  state = next;
  spdlog::info("OpenXR session: {}", to_string(static_cast<XrState>(std::clamp<int>(next, 0, 8))));
  switch (next) {
    case XR_SESSION_STATE_READY: {
      XrSessionBeginInfo bi{XR_TYPE_SESSION_BEGIN_INFO};
      bi.primaryViewConfigurationType = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
      if (const XrResult r = xrBeginSession(session, &bi); XR_FAILED(r)) {
        exit = true;
        exit_reason = "cannot begin the OpenXR session: " + xr_result(instance, r);
      } else {
        running = true;
      }
      break;
    }
    case XR_SESSION_STATE_STOPPING:
      if (frame) end_frame();
      xrEndSession(session);
      running = false;
      break;
    case XR_SESSION_STATE_EXITING:
      exit = true;
      if (exit_reason.empty()) exit_reason = exit_requested ? "the session ended as asked" : "the OpenXR runtime ended the session";
      break;
    case XR_SESSION_STATE_LOSS_PENDING:
      exit = true;
      lost = true;
      exit_reason = "the OpenXR runtime is losing the session (the headset went away)";
      break;
    default:
      break;
  }
}

void XrHeadset::poll_events() {
  Impl& m = *impl_;
  for (;;) {
    XrEventDataBuffer event{XR_TYPE_EVENT_DATA_BUFFER};
    const XrResult r = xrPollEvent(m.instance, &event);
    if (XR_FAILED(r)) m.fail("xrPollEvent", r);
    if (r != XR_SUCCESS) break;  // XR_EVENT_UNAVAILABLE, or a failure
    switch (event.type) {
      case XR_TYPE_EVENT_DATA_SESSION_STATE_CHANGED: {
        const auto& changed = *reinterpret_cast<const XrEventDataSessionStateChanged*>(&event);
        if (changed.session == m.session) m.handle_state(changed.state);
        break;
      }
      case XR_TYPE_EVENT_DATA_INSTANCE_LOSS_PENDING:
        m.exit = true;
        m.lost = true;
        m.exit_reason = "the OpenXR runtime is going away (instance loss pending)";
        break;
      case XR_TYPE_EVENT_DATA_EVENTS_LOST:
        spdlog::warn("OpenXR: the runtime lost {} event(s)", reinterpret_cast<const XrEventDataEventsLost*>(&event)->lostEventCount);
        break;
      default:
        break;
    }
  }
}

XrState XrHeadset::state() const { return static_cast<XrState>(std::clamp<int>(impl_->state, 0, 8)); }
bool XrHeadset::session_running() const { return impl_->running; }
bool XrHeadset::focused() const { return impl_->state == XR_SESSION_STATE_FOCUSED; }
bool XrHeadset::should_exit() const { return impl_->exit; }
const std::string& XrHeadset::exit_reason() const { return impl_->exit_reason; }
bool XrHeadset::lost() const { return impl_->lost; }

void XrHeadset::request_exit() {
  Impl& m = *impl_;
  if (m.exit_requested) return;
  m.exit_requested = true;
  if (m.session == XR_NULL_HANDLE || !m.running) {
    m.exit = true;
    m.exit_reason = "the session ended as asked";
    return;
  }
  if (const XrResult r = xrRequestExitSession(m.session); XR_FAILED(r)) {
    m.exit = true;
    m.exit_reason = "xrRequestExitSession failed: " + xr_result(m.instance, r);
  }
}

std::optional<XrFrameTiming> XrHeadset::begin_frame() {
  Impl& m = *impl_;
  if (!m.running || m.exit) return std::nullopt;
  if (m.frame) m.end_frame();  // the renderer did not draw it: nothing new to show
  XrFrameState fs{XR_TYPE_FRAME_STATE};
  if (const XrResult r = xrWaitFrame(m.session, nullptr, &fs); XR_FAILED(r)) {
    m.fail("xrWaitFrame", r);
    return std::nullopt;
  }
  const double begun = steady_now_s();
  if (const XrResult r = xrBeginFrame(m.session, nullptr); XR_FAILED(r)) {
    m.fail("xrBeginFrame", r);
    return std::nullopt;
  }
  XrFrameTiming t;
  t.index = m.frames_begun++;
  t.should_render = fs.shouldRender == XR_TRUE;
  t.display_time = fs.predictedDisplayTime;
  t.period_s = static_cast<double>(fs.predictedDisplayPeriod) * 1e-9;
  t.display_s = steady_s_from_xr_time(fs.predictedDisplayTime);
  if (!std::isfinite(t.display_s)) t.display_s = begun + t.period_s;  // the conversion failed: a period after the wait
  // The refresh from the period (XR_FB_display_refresh_rate would say it too, but Monado's null
  // compositor advertises it and then calls a function it lacks).
  if (t.period_s > 1e-3 && t.period_s < 1.0) m.info.refresh_hz = 1.0 / t.period_s;
  t.begun_s = begun;
  m.frame = t;
  m.views_located = false;
  return t;
}

const std::optional<XrFrameTiming>& XrHeadset::current_frame() const { return impl_->frame; }

std::optional<StereoViews> XrHeadset::locate_views(double near_m, double far_m) {
  Impl& m = *impl_;
  if (!m.frame) return std::nullopt;
  XrViewLocateInfo li{XR_TYPE_VIEW_LOCATE_INFO};
  li.viewConfigurationType = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
  li.displayTime = m.frame->display_time;
  li.space = m.stage;
  XrViewState vs{XR_TYPE_VIEW_STATE};
  std::uint32_t count = 0;
  std::array<XrView, 2> views{XrView{XR_TYPE_VIEW}, XrView{XR_TYPE_VIEW}};
  if (const XrResult r = xrLocateViews(m.session, &li, &vs, 2, &count, views.data()); XR_FAILED(r) || count != 2) return std::nullopt;
  const XrViewStateFlags needed = XR_VIEW_STATE_ORIENTATION_VALID_BIT | XR_VIEW_STATE_POSITION_VALID_BIT;
  if ((vs.viewStateFlags & needed) != needed || !xr_view_usable(views[0]) || !xr_view_usable(views[1])) return std::nullopt;
  StereoViews out;
  for (int eye = 0; eye < 2; ++eye) {
    const XrView& v = views[static_cast<std::size_t>(eye)];
    const glm::mat4 world_from_eye = m.world_from_stage * xr_pose_matrix(v.pose);
    out.eye_from_world[eye] = glm::inverse(world_from_eye);
    constexpr double kDeg = 180.0 / M_PI;
    const EyeFovDeg fov{-static_cast<double>(v.fov.angleLeft) * kDeg, static_cast<double>(v.fov.angleRight) * kDeg,
                        static_cast<double>(v.fov.angleUp) * kDeg, -static_cast<double>(v.fov.angleDown) * kDeg};
    out.clip_from_eye[eye] = projection_from_fov(fov, near_m, far_m);
    if (!finite(out.eye_from_world[eye]) || !finite(out.clip_from_eye[eye])) return std::nullopt;
  }
  m.views = views;
  m.views_located = true;
  return out;
}

std::optional<glm::mat4> XrHeadset::stage_from_head(double steady_s) {
  Impl& m = *impl_;
  if (m.view == XR_NULL_HANDLE || m.stage == XR_NULL_HANDLE) return std::nullopt;
  XrSpaceLocation location{XR_TYPE_SPACE_LOCATION};
  if (XR_FAILED(xrLocateSpace(m.view, m.stage, xr_time_from_steady_s(steady_s), &location))) return std::nullopt;
  const XrSpaceLocationFlags needed = XR_SPACE_LOCATION_ORIENTATION_VALID_BIT | XR_SPACE_LOCATION_POSITION_VALID_BIT;
  if ((location.locationFlags & needed) != needed) return std::nullopt;
  if (!xr_pose_usable(location.pose)) return std::nullopt;
  return xr_pose_matrix(location.pose);
}

std::expected<void, std::string> XrHeadset::set_world_from_stage(const glm::mat4& world_from_stage) {
  const glm::mat3 r(world_from_stage);
  const glm::mat3 off = glm::transpose(r) * r - glm::mat3(1.0f);
  float error = std::abs(glm::determinant(r) - 1.0f) + std::abs(world_from_stage[0][3]) + std::abs(world_from_stage[1][3]) +
                std::abs(world_from_stage[2][3]) + std::abs(world_from_stage[3][3] - 1.0f);
  for (int c = 0; c < 3; ++c) error += std::abs(off[c][0]) + std::abs(off[c][1]) + std::abs(off[c][2]);
  if (!finite(world_from_stage) || !(error < 1e-4f)) {
    return std::unexpected(std::string("world_from_stage is not a rigid transform (finite, a rotation and a translation)"));
  }
  impl_->world_from_stage = world_from_stage;
  return {};
}

const glm::mat4& XrHeadset::world_from_stage() const { return impl_->world_from_stage; }

double XrHeadset::steady_s_from_xr_time(std::int64_t time) const {
  timespec ts{};
  if (XR_FAILED(impl_->to_timespec(impl_->instance, time, &ts))) return std::nan("");
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

std::int64_t XrHeadset::xr_time_from_steady_s(double steady_s) const {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(std::floor(steady_s));
  ts.tv_nsec = static_cast<long>((steady_s - std::floor(steady_s)) * 1e9);
  XrTime time = 0;
  if (XR_FAILED(impl_->from_timespec(impl_->instance, &ts, &time))) return 0;
  return time;
}

std::uint64_t XrHeadset::frames_submitted() const { return impl_->submitted; }
std::uint64_t XrHeadset::frames_late() const { return impl_->late; }
std::uint64_t XrHeadset::frames_late_own() const { return impl_->late_own; }
std::uint64_t XrHeadset::validation_messages() const { return impl_->validation_messages.load(); }

bool XrHeadset::Impl::acquire() {
  if (!frame || !frame->should_render || !views_located || chains.empty()) return false;
  for (Chain& c : chains) {
    XrSwapchainImageAcquireInfo ai{XR_TYPE_SWAPCHAIN_IMAGE_ACQUIRE_INFO};
    if (const XrResult r = xrAcquireSwapchainImage(c.handle, &ai, &c.acquired); XR_FAILED(r) || c.acquired >= c.images.size()) {
      // Nothing acquired from this one; those before it are waited for and released unwritten.
      fail("xrAcquireSwapchainImage", XR_FAILED(r) ? r : XR_ERROR_RUNTIME_FAILURE);
      release();
      return false;
    }
    // An acquired image may be released only once waited for: a timeout is waited out again (the
    // runtime still has the image in use), up to a second.
    XrSwapchainImageWaitInfo wi{XR_TYPE_SWAPCHAIN_IMAGE_WAIT_INFO};
    wi.timeout = 100'000'000;  // 100 ms
    XrResult r = XR_TIMEOUT_EXPIRED;
    for (int tries = 0; tries < 10 && r == XR_TIMEOUT_EXPIRED; ++tries) r = xrWaitSwapchainImage(c.handle, &wi);
    if (r != XR_SUCCESS) {
      // Stuck: this image can be neither written nor released, and the session cannot go on.
      fail("xrWaitSwapchainImage", r == XR_TIMEOUT_EXPIRED ? XR_ERROR_RUNTIME_FAILURE : r);
      release();
      return false;
    }
    c.held = true;
  }
  return true;
}

void XrHeadset::Impl::release() {
  for (Chain& c : chains) {
    if (!c.held) continue;
    XrSwapchainImageReleaseInfo ri{XR_TYPE_SWAPCHAIN_IMAGE_RELEASE_INFO};
    xrReleaseSwapchainImage(c.handle, &ri);
    c.held = false;
  }
}

void XrHeadset::Impl::fail(const char* call, XrResult r) {
  spdlog::error("OpenXR: {} failed: {}", call, xr_result(instance, r));
  if (xr_lost(r) || ++failures >= 10) {
    exit = true;
    lost = true;
    if (exit_reason.empty()) exit_reason = std::string("the OpenXR session failed (") + call + ": " + xr_result(instance, r) + ")";
  }
}

void XrHeadset::Impl::record_copy(VkCommandBuffer cmd, VkImage eyes, int eye_width, int eye_height) const {
  for (std::size_t c = 0; c < chains.size(); ++c) {
    const Chain& chain = chains[c];
    if (!chain.held) continue;
    const VkImage target = chain.images[chain.acquired];
    VkImageMemoryBarrier to_dst{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
    to_dst.srcAccessMask = 0;
    to_dst.dstAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    to_dst.oldLayout = VK_IMAGE_LAYOUT_UNDEFINED;  // all of it is overwritten
    to_dst.newLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
    to_dst.srcQueueFamilyIndex = to_dst.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    to_dst.image = target;
    to_dst.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, chain.layers};
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0, nullptr, 0, nullptr, 1, &to_dst);
    // One array swapchain takes both layers at once; one per eye takes its own layer.
    const std::uint32_t first_layer = chains.size() == 1 ? 0 : static_cast<std::uint32_t>(c);
    const VkImageSubresourceLayers src{VK_IMAGE_ASPECT_COLOR_BIT, 0, first_layer, chain.layers};
    const VkImageSubresourceLayers dst{VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, chain.layers};
    const int w = std::min(eye_width, width);
    const int h = std::min(eye_height, height);
    if (format == VK_FORMAT_R8G8B8A8_SRGB) {
      VkImageCopy region{};
      region.srcSubresource = src;
      region.dstSubresource = dst;
      region.extent = {static_cast<std::uint32_t>(w), static_cast<std::uint32_t>(h), 1};
      vkCmdCopyImage(cmd, eyes, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, target, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &region);
    } else {
      VkImageBlit region{};
      region.srcSubresource = src;
      region.dstSubresource = dst;
      region.srcOffsets[1] = {w, h, 1};
      region.dstOffsets[1] = {w, h, 1};
      vkCmdBlitImage(cmd, eyes, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, target, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &region,
                     VK_FILTER_NEAREST);
    }
    // Released as the runtime takes colour swapchain images: COLOR_ATTACHMENT_OPTIMAL.
    VkImageMemoryBarrier to_runtime = to_dst;
    to_runtime.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    to_runtime.dstAccessMask = 0;
    to_runtime.oldLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
    to_runtime.newLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, 0, 0, nullptr, 0, nullptr, 1,
                         &to_runtime);
  }
}

void XrHeadset::Impl::end_frame() {
  if (!frame) return;
  const bool drawn = std::any_of(chains.begin(), chains.end(), [](const Chain& c) { return c.held; });
  release();
  std::array<XrCompositionLayerProjectionView, 2> pv{};
  XrCompositionLayerProjection layer{XR_TYPE_COMPOSITION_LAYER_PROJECTION};
  const XrCompositionLayerBaseHeader* layers[] = {reinterpret_cast<const XrCompositionLayerBaseHeader*>(&layer)};
  for (std::size_t e = 0; e < 2; ++e) {
    pv[e] = XrCompositionLayerProjectionView{XR_TYPE_COMPOSITION_LAYER_PROJECTION_VIEW};
    pv[e].pose = views[e].pose;
    pv[e].fov = views[e].fov;
    pv[e].subImage.swapchain = chains.size() == 1 ? chains[0].handle : chains[e].handle;
    pv[e].subImage.imageRect = {{0, 0}, {width, height}};
    pv[e].subImage.imageArrayIndex = chains.size() == 1 ? static_cast<std::uint32_t>(e) : 0;
  }
  layer.space = stage;
  layer.viewCount = 2;
  layer.views = pv.data();
  XrFrameEndInfo ei{XR_TYPE_FRAME_END_INFO};
  ei.displayTime = frame->display_time;
  ei.environmentBlendMode = blend;
  ei.layerCount = drawn ? 1 : 0;
  ei.layers = drawn ? layers : nullptr;
  const double ended_s = steady_now_s();
  if (const XrResult r = xrEndFrame(session, &ei); XR_FAILED(r)) {
    fail("xrEndFrame", r);
  } else if (drawn) {
    failures = 0;
    ++submitted;
    if (ended_s > frame->display_s) {
      ++late;
      if (frame->begun_s < frame->display_s) ++late_own;
      spdlog::debug("OpenXR: frame {} ended {:.1f} ms after its predicted display time ({:.1f} ms after its wait returned)", frame->index,
                    (ended_s - frame->display_s) * 1e3, (ended_s - frame->begun_s) * 1e3);
    }
  }
  frame.reset();
  views_located = false;
}

}  // namespace rhot
