#include "engine/render/vk/VulkanContext.h"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <cstring>

#include <spdlog/spdlog.h>

namespace rhot::vk {

const char* result_string(VkResult result) {
  switch (result) {
    case VK_SUCCESS:
      return "VK_SUCCESS";
    case VK_NOT_READY:
      return "VK_NOT_READY";
    case VK_TIMEOUT:
      return "VK_TIMEOUT";
    case VK_SUBOPTIMAL_KHR:
      return "VK_SUBOPTIMAL_KHR";
    case VK_ERROR_OUT_OF_HOST_MEMORY:
      return "VK_ERROR_OUT_OF_HOST_MEMORY";
    case VK_ERROR_OUT_OF_DEVICE_MEMORY:
      return "VK_ERROR_OUT_OF_DEVICE_MEMORY";
    case VK_ERROR_INITIALIZATION_FAILED:
      return "VK_ERROR_INITIALIZATION_FAILED";
    case VK_ERROR_DEVICE_LOST:
      return "VK_ERROR_DEVICE_LOST";
    case VK_ERROR_LAYER_NOT_PRESENT:
      return "VK_ERROR_LAYER_NOT_PRESENT";
    case VK_ERROR_EXTENSION_NOT_PRESENT:
      return "VK_ERROR_EXTENSION_NOT_PRESENT";
    case VK_ERROR_FEATURE_NOT_PRESENT:
      return "VK_ERROR_FEATURE_NOT_PRESENT";
    case VK_ERROR_INCOMPATIBLE_DRIVER:
      return "VK_ERROR_INCOMPATIBLE_DRIVER (no Vulkan driver installed?)";
    case VK_ERROR_SURFACE_LOST_KHR:
      return "VK_ERROR_SURFACE_LOST_KHR";
    case VK_ERROR_OUT_OF_DATE_KHR:
      return "VK_ERROR_OUT_OF_DATE_KHR";
    default:
      return "VkResult (unlisted)";
  }
}

namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

const char* type_name(VkPhysicalDeviceType type) {
  switch (type) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU:
      return "discrete GPU";
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU:
      return "integrated GPU";
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU:
      return "virtual GPU";
    case VK_PHYSICAL_DEVICE_TYPE_CPU:
      return "CPU";
    default:
      return "other";
  }
}

int preference(VkPhysicalDeviceType type) {
  switch (type) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU:
      return 4;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU:
      return 3;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU:
      return 2;
    case VK_PHYSICAL_DEVICE_TYPE_CPU:
      return 1;
    default:
      return 0;
  }
}

bool layer_available(const char* name) {
  std::uint32_t count = 0;
  vkEnumerateInstanceLayerProperties(&count, nullptr);
  std::vector<VkLayerProperties> layers(count);
  vkEnumerateInstanceLayerProperties(&count, layers.data());
  return std::any_of(layers.begin(), layers.end(), [&](const VkLayerProperties& l) { return std::strcmp(l.layerName, name) == 0; });
}

}  // namespace

VKAPI_ATTR VkBool32 VKAPI_CALL Context::on_debug_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                         VkDebugUtilsMessageTypeFlagsEXT types,
                                                         const VkDebugUtilsMessengerCallbackDataEXT* data, void* self) {
  auto* context = static_cast<Context*>(self);
  const bool error = (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT) != 0;
  if ((types & (VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT)) != 0) {
    context->validation_messages_.fetch_add(1);
  }
  if (error) {
    spdlog::error("vulkan validation: {}", data->pMessage);
  } else {
    spdlog::warn("vulkan validation: {}", data->pMessage);
  }
  return VK_FALSE;
}

std::expected<std::unique_ptr<Context>, std::string> Context::create(const Options& options) {
  std::unique_ptr<Context> c(new Context());
  if (auto made = c->create_instance(options); !made) return std::unexpected(made.error());
  if (auto chosen = c->choose_device(options); !chosen) return std::unexpected(chosen.error());
  if (auto made = c->create_device(options); !made) return std::unexpected(made.error());
  spdlog::info("Vulkan device: {} ({}){}", c->device_name_, type_name(c->device_type_), c->validation_enabled_ ? ", validation on" : "");
  return c;
}

// The instance (with the validation layer and its messenger when asked for), and the window's
// surface when there is a window.
std::expected<void, std::string> Context::create_instance(const Options& options) {
  std::vector<const char*> extensions;
  for (const std::string& e : options.instance_extensions) extensions.push_back(e.c_str());
  std::vector<const char*> layers;
  const char* env_validation = std::getenv("RHOT_VK_VALIDATION");
  const bool want_validation = options.validation || (env_validation != nullptr && std::strcmp(env_validation, "1") == 0);
  if (want_validation) {
    if (layer_available("VK_LAYER_KHRONOS_validation")) {
      layers.push_back("VK_LAYER_KHRONOS_validation");
      extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
      validation_enabled_ = true;
    } else {
      spdlog::warn(
          "validation requested but VK_LAYER_KHRONOS_validation is not installed "
          "(Debian package vulkan-validationlayers); running without it");
    }
  }
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = "rhot";
  app.pEngineName = "rhot";
  app.apiVersion = VK_API_VERSION_1_1;
  VkInstanceCreateInfo ici{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  ici.pApplicationInfo = &app;
  ici.enabledExtensionCount = static_cast<std::uint32_t>(extensions.size());
  ici.ppEnabledExtensionNames = extensions.data();
  ici.enabledLayerCount = static_cast<std::uint32_t>(layers.size());
  ici.ppEnabledLayerNames = layers.data();
  VkDebugUtilsMessengerCreateInfoEXT dci{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
  dci.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
  dci.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                    VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
  dci.pfnUserCallback = &Context::on_debug_message;
  dci.pUserData = this;
  if (validation_enabled_) ici.pNext = &dci;  // also catches messages from instance creation itself
  if (options.make_instance) {
    auto made = options.make_instance(ici);
    if (!made) return std::unexpected(made.error());
    instance_ = *made;
  } else if (const VkResult r = vkCreateInstance(&ici, nullptr, &instance_); r != VK_SUCCESS) {
    return std::unexpected(std::string("cannot create a Vulkan 1.1 instance: ") + result_string(r));
  }
  if (validation_enabled_) {
    auto create_messenger =
        reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(vkGetInstanceProcAddr(instance_, "vkCreateDebugUtilsMessengerEXT"));
    if (create_messenger != nullptr) create_messenger(instance_, &dci, nullptr, &messenger_);
  }
  if (options.make_surface) {
    auto surface = options.make_surface(instance_);
    if (!surface) return std::unexpected(surface.error());
    surface_ = *surface;
  }

  return {};
}

// The device the options select (auto: a discrete GPU before an integrated one before the CPU
// driver) among those with Vulkan 1.1 graphics (and presentation to the surface, if any).
std::expected<void, std::string> Context::choose_device(const Options& options) {
  std::uint32_t count = 0;
  vkEnumeratePhysicalDevices(instance_, &count, nullptr);
  std::vector<VkPhysicalDevice> devices(count);
  vkEnumeratePhysicalDevices(instance_, &count, devices.data());
  if (devices.empty()) {
    return std::unexpected(
        std::string("no Vulkan device found; install a driver (on machines without a GPU, Mesa's "
                    "CPU driver: Debian package mesa-vulkan-drivers)"));
  }
  std::string selector = options.device;
  if (selector == "auto") {
    if (const char* env = std::getenv("RHOT_VK_DEVICE"); env != nullptr && *env != '\0') selector = env;
  }
  VkPhysicalDevice required = VK_NULL_HANDLE;  // the headset's, where its runtime names one
  if (options.physical_device) {
    auto named = options.physical_device(instance_);
    if (!named) return std::unexpected(named.error());
    required = *named;
    if (options.device != "auto") spdlog::warn("--device {} ignored: the headset's runtime chooses the Vulkan device", options.device);
    selector = "auto";
  }
  struct Candidate {
    VkPhysicalDevice device;
    VkPhysicalDeviceProperties props;
    std::uint32_t family;
  };
  std::vector<Candidate> usable;
  std::string listing;
  for (std::uint32_t i = 0; i < count; ++i) {
    VkPhysicalDeviceProperties props;
    vkGetPhysicalDeviceProperties(devices[i], &props);
    listing += "\n  [" + std::to_string(i) + "] " + props.deviceName + " (" + type_name(props.deviceType) + ")";
    if (props.apiVersion < VK_API_VERSION_1_1 || (required != VK_NULL_HANDLE && devices[i] != required)) continue;
    std::uint32_t nfam = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(devices[i], &nfam, nullptr);
    std::vector<VkQueueFamilyProperties> families(nfam);
    vkGetPhysicalDeviceQueueFamilyProperties(devices[i], &nfam, families.data());
    for (std::uint32_t f = 0; f < nfam; ++f) {
      VkBool32 present = VK_TRUE;
      if (surface_ != VK_NULL_HANDLE) vkGetPhysicalDeviceSurfaceSupportKHR(devices[i], f, surface_, &present);
      if ((families[f].queueFlags & VK_QUEUE_GRAPHICS_BIT) != 0 && present == VK_TRUE) {
        usable.push_back({devices[i], props, f});
        break;
      }
    }
  }
  spdlog::debug("Vulkan devices:{}", listing);
  const Candidate* chosen = nullptr;
  const bool by_index =
      !selector.empty() && std::all_of(selector.begin(), selector.end(), [](unsigned char ch) { return std::isdigit(ch); });
  for (const Candidate& cand : usable) {
    const bool is_cpu = cand.props.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU;
    bool match = false;
    if (selector == "auto") {
      match = chosen == nullptr || preference(cand.props.deviceType) > preference(chosen->props.deviceType);
    } else if (selector == "gpu") {
      match = !is_cpu && (chosen == nullptr || preference(cand.props.deviceType) > preference(chosen->props.deviceType));
    } else if (selector == "cpu") {
      match = is_cpu && chosen == nullptr;
    } else if (by_index) {
      match = selector.size() < 4 && std::stoul(selector) < count && cand.device == devices[std::stoul(selector)];
    } else {
      match = chosen == nullptr && lower(cand.props.deviceName).find(lower(selector)) != std::string::npos;
    }
    if (match) chosen = &cand;
  }
  if (chosen == nullptr && required != VK_NULL_HANDLE) {
    return std::unexpected(std::string("the Vulkan device the headset's runtime names offers no Vulkan 1.1 graphics; devices found:") +
                           listing);
  }
  if (chosen == nullptr) {
    return std::unexpected("no Vulkan device matches \"" + selector +
                           "\" (choose auto, gpu, cpu, an index or part of a "
                           "name); devices found:" +
                           listing +
                           (usable.empty() ? "\n  none of them offers Vulkan 1.1 graphics" +
                                                 std::string(surface_ != VK_NULL_HANDLE ? " and presentation to the window" : "")
                                           : ""));
  }
  physical_ = chosen->device;
  queue_family_ = chosen->family;
  device_name_ = chosen->props.deviceName;
  cpu_device_ = chosen->props.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU;
  device_type_ = chosen->props.deviceType;
  vkGetPhysicalDeviceMemoryProperties(physical_, &memory_properties_);

  VkPhysicalDeviceMultiviewFeatures multiview{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MULTIVIEW_FEATURES};
  VkPhysicalDeviceFeatures2 features{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
  features.pNext = &multiview;
  vkGetPhysicalDeviceFeatures2(physical_, &features);
  multiview_ = multiview.multiview == VK_TRUE;
  fill_mode_non_solid_ = features.features.fillModeNonSolid == VK_TRUE;

  return {};
}

// The logical device with one graphics queue (multiview enabled where supported) and the
// command pool.
std::expected<void, std::string> Context::create_device(const Options& options) {
  const float priority = 1.0f;
  VkDeviceQueueCreateInfo qci{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  qci.queueFamilyIndex = queue_family_;
  qci.queueCount = 1;
  qci.pQueuePriorities = &priority;
  VkPhysicalDeviceMultiviewFeatures enable_multiview{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MULTIVIEW_FEATURES};
  enable_multiview.multiview = multiview_ ? VK_TRUE : VK_FALSE;
  VkPhysicalDeviceFeatures2 enable{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
  enable.pNext = &enable_multiview;
  enable.features.fillModeNonSolid = fill_mode_non_solid_ ? VK_TRUE : VK_FALSE;
  std::vector<const char*> device_extensions;
  if (surface_ != VK_NULL_HANDLE) device_extensions.push_back(VK_KHR_SWAPCHAIN_EXTENSION_NAME);
  VkDeviceCreateInfo dci2{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  dci2.pNext = &enable;
  dci2.queueCreateInfoCount = 1;
  dci2.pQueueCreateInfos = &qci;
  dci2.enabledExtensionCount = static_cast<std::uint32_t>(device_extensions.size());
  dci2.ppEnabledExtensionNames = device_extensions.data();
  if (options.make_device) {
    auto made = options.make_device(physical_, dci2);
    if (!made) return std::unexpected(made.error());
    device_ = *made;
  } else if (const VkResult r = vkCreateDevice(physical_, &dci2, nullptr, &device_); r != VK_SUCCESS) {
    return std::unexpected("cannot create a Vulkan device on " + device_name_ + ": " + result_string(r));
  }
  vkGetDeviceQueue(device_, queue_family_, 0, &queue_);
  VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pci.queueFamilyIndex = queue_family_;
  RHOT_VK_CHECK(vkCreateCommandPool(device_, &pci, nullptr, &command_pool_));
  return {};
}

Context::~Context() {
  if (device_ != VK_NULL_HANDLE) {
    vkDeviceWaitIdle(device_);
    vkDestroyCommandPool(device_, command_pool_, nullptr);
    vkDestroyDevice(device_, nullptr);
  }
  if (surface_ != VK_NULL_HANDLE) vkDestroySurfaceKHR(instance_, surface_, nullptr);
  if (messenger_ != VK_NULL_HANDLE) {
    auto destroy =
        reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(vkGetInstanceProcAddr(instance_, "vkDestroyDebugUtilsMessengerEXT"));
    if (destroy != nullptr) destroy(instance_, messenger_, nullptr);
  }
  if (instance_ != VK_NULL_HANDLE) vkDestroyInstance(instance_, nullptr);
}

std::uint32_t Context::memory_type(std::uint32_t type_bits, VkMemoryPropertyFlags properties) const {
  for (std::uint32_t i = 0; i < memory_properties_.memoryTypeCount; ++i) {
    if ((type_bits & (1u << i)) != 0 && (memory_properties_.memoryTypes[i].propertyFlags & properties) == properties) return i;
  }
  RHOT_ASSERT(false, "no Vulkan memory type with the required properties");
  return 0;
}

Buffer Context::create_buffer(VkDeviceSize size, VkBufferUsageFlags usage, bool host_visible) const {
  Buffer b;
  b.size = size;
  VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  bci.size = size;
  bci.usage = usage;
  bci.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  RHOT_VK_CHECK(vkCreateBuffer(device_, &bci, nullptr, &b.buffer));
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(device_, b.buffer, &req);
  VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  mai.allocationSize = req.size;
  mai.memoryTypeIndex =
      memory_type(req.memoryTypeBits, host_visible ? VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT
                                                   : VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
  RHOT_VK_CHECK(vkAllocateMemory(device_, &mai, nullptr, &b.memory));
  RHOT_VK_CHECK(vkBindBufferMemory(device_, b.buffer, b.memory, 0));
  if (host_visible) RHOT_VK_CHECK(vkMapMemory(device_, b.memory, 0, VK_WHOLE_SIZE, 0, &b.mapped));
  return b;
}

void Context::destroy(Buffer& b) const {
  if (b.buffer != VK_NULL_HANDLE) vkDestroyBuffer(device_, b.buffer, nullptr);
  if (b.memory != VK_NULL_HANDLE) vkFreeMemory(device_, b.memory, nullptr);  // unmaps implicitly
  b = Buffer{};
}

ImageMemory Context::create_image(const VkImageCreateInfo& info) const {
  ImageMemory im;
  RHOT_VK_CHECK(vkCreateImage(device_, &info, nullptr, &im.image));
  VkMemoryRequirements req;
  vkGetImageMemoryRequirements(device_, im.image, &req);
  VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  mai.allocationSize = req.size;
  mai.memoryTypeIndex = memory_type(req.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
  RHOT_VK_CHECK(vkAllocateMemory(device_, &mai, nullptr, &im.memory));
  RHOT_VK_CHECK(vkBindImageMemory(device_, im.image, im.memory, 0));
  return im;
}

void Context::destroy(ImageMemory& im) const {
  if (im.image != VK_NULL_HANDLE) vkDestroyImage(device_, im.image, nullptr);
  if (im.memory != VK_NULL_HANDLE) vkFreeMemory(device_, im.memory, nullptr);
  im = ImageMemory{};
}

void Context::run_once(const std::function<void(VkCommandBuffer)>& record) const {
  VkCommandBufferAllocateInfo cai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  cai.commandPool = command_pool_;
  cai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  cai.commandBufferCount = 1;
  VkCommandBuffer cmd = VK_NULL_HANDLE;
  RHOT_VK_CHECK(vkAllocateCommandBuffers(device_, &cai, &cmd));
  VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  RHOT_VK_CHECK(vkBeginCommandBuffer(cmd, &begin));
  record(cmd);
  RHOT_VK_CHECK(vkEndCommandBuffer(cmd));
  VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  submit.commandBufferCount = 1;
  submit.pCommandBuffers = &cmd;
  RHOT_VK_CHECK(vkQueueSubmit(queue_, 1, &submit, VK_NULL_HANDLE));
  RHOT_VK_CHECK(vkQueueWaitIdle(queue_));
  vkFreeCommandBuffers(device_, command_pool_, 1, &cmd);
}

Buffer Context::upload(const void* data, VkDeviceSize size, VkBufferUsageFlags usage) const {
  Buffer staging = create_buffer(size, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, true);
  std::memcpy(staging.mapped, data, static_cast<std::size_t>(size));
  Buffer target = create_buffer(size, usage | VK_BUFFER_USAGE_TRANSFER_DST_BIT, false);
  run_once([&](VkCommandBuffer cmd) {
    const VkBufferCopy region{0, 0, size};
    vkCmdCopyBuffer(cmd, staging.buffer, target.buffer, 1, &region);
  });
  destroy(staging);
  return target;
}

GpuMesh Context::upload_mesh(const void* vertices, VkDeviceSize vertex_bytes, const std::uint32_t* indices,
                             std::uint32_t index_count) const {
  GpuMesh m;
  m.vertices = upload(vertices, vertex_bytes, VK_BUFFER_USAGE_VERTEX_BUFFER_BIT);
  m.indices = upload(indices, VkDeviceSize{index_count} * sizeof(std::uint32_t), VK_BUFFER_USAGE_INDEX_BUFFER_BIT);
  m.index_count = index_count;
  return m;
}

void Context::destroy(GpuMesh& mesh) const {
  destroy(mesh.vertices);
  destroy(mesh.indices);
  mesh.index_count = 0;
}

}  // namespace rhot::vk
