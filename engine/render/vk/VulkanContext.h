#pragma once
// Vulkan instance, device and memory for the renderer. Private to engine/render.

#include <vulkan/vulkan.h>

#include <atomic>
#include <expected>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "base/Check.h"

namespace rhot::vk {

const char* result_string(VkResult result);

// For Vulkan calls that can only fail through device loss, out-of-memory or a bug in rhot.
#define RHOT_VK_CHECK(call)                                                                                                \
  do {                                                                                                                     \
    const VkResult rhot_vk_result = (call);                                                                                \
    RHOT_ASSERT(rhot_vk_result == VK_SUCCESS, std::string(#call " failed: ") + ::rhot::vk::result_string(rhot_vk_result)); \
  } while (false)

struct Buffer {
  VkBuffer buffer = VK_NULL_HANDLE;
  VkDeviceMemory memory = VK_NULL_HANDLE;
  VkDeviceSize size = 0;
  void* mapped = nullptr;  // host-visible buffers stay mapped
};

struct ImageMemory {
  VkImage image = VK_NULL_HANDLE;
  VkDeviceMemory memory = VK_NULL_HANDLE;
};

// A mesh on the GPU.
struct GpuMesh {
  Buffer vertices;
  Buffer indices;
  std::uint32_t index_count = 0;
};

class Context {
 public:
  struct Options {
    std::string device = "auto";
    bool validation = false;
    std::vector<std::string> instance_extensions;  // e.g. what GLFW needs for a surface
    // Creates the window surface once the instance exists; absent for offscreen rendering.
    std::function<std::expected<VkSurfaceKHR, std::string>(VkInstance)> make_surface;
    // A headset's OpenXR runtime (XR_KHR_vulkan_enable2): it creates the instance and the device
    // from rhot's create-infos, adding what it needs, and names the physical device. All three or
    // none.
    std::function<std::expected<VkInstance, std::string>(const VkInstanceCreateInfo&)> make_instance;
    std::function<std::expected<VkPhysicalDevice, std::string>(VkInstance)> physical_device;
    std::function<std::expected<VkDevice, std::string>(VkPhysicalDevice, const VkDeviceCreateInfo&)> make_device;
  };

  [[nodiscard]] static std::expected<std::unique_ptr<Context>, std::string> create(const Options& options);
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  VkInstance instance() const { return instance_; }
  VkPhysicalDevice physical_device() const { return physical_; }
  VkDevice device() const { return device_; }
  VkQueue queue() const { return queue_; }
  std::uint32_t queue_family() const { return queue_family_; }
  VkCommandPool command_pool() const { return command_pool_; }
  VkSurfaceKHR surface() const { return surface_; }

  const std::string& device_name() const { return device_name_; }
  bool cpu_device() const { return cpu_device_; }
  bool multiview_supported() const { return multiview_; }
  bool validation_enabled() const { return validation_enabled_; }
  std::uint64_t validation_messages() const { return validation_messages_.load(); }

  Buffer create_buffer(VkDeviceSize size, VkBufferUsageFlags usage, bool host_visible) const;
  void destroy(Buffer& buffer) const;
  ImageMemory create_image(const VkImageCreateInfo& info) const;
  void destroy(ImageMemory& image) const;
  // Device-local buffer filled through a staging buffer (one submit, waited for).
  Buffer upload(const void* data, VkDeviceSize size, VkBufferUsageFlags usage) const;
  GpuMesh upload_mesh(const void* vertices, VkDeviceSize vertex_bytes, const std::uint32_t* indices, std::uint32_t index_count) const;
  void destroy(GpuMesh& mesh) const;

  // Records with `record` into a fresh command buffer, submits and waits.
  void run_once(const std::function<void(VkCommandBuffer)>& record) const;

 private:
  Context() = default;
  // create()'s steps, in order.
  [[nodiscard]] std::expected<void, std::string> create_instance(const Options& options);
  [[nodiscard]] std::expected<void, std::string> choose_device(const Options& options);
  [[nodiscard]] std::expected<void, std::string> create_device(const Options& options);
  std::uint32_t memory_type(std::uint32_t type_bits, VkMemoryPropertyFlags properties) const;
  static VKAPI_ATTR VkBool32 VKAPI_CALL on_debug_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                         VkDebugUtilsMessageTypeFlagsEXT types,
                                                         const VkDebugUtilsMessengerCallbackDataEXT* data, void* self);

  VkInstance instance_ = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
  VkSurfaceKHR surface_ = VK_NULL_HANDLE;
  VkPhysicalDevice physical_ = VK_NULL_HANDLE;
  VkDevice device_ = VK_NULL_HANDLE;
  VkQueue queue_ = VK_NULL_HANDLE;
  std::uint32_t queue_family_ = 0;
  VkCommandPool command_pool_ = VK_NULL_HANDLE;
  VkPhysicalDeviceMemoryProperties memory_properties_{};
  std::string device_name_;
  VkPhysicalDeviceType device_type_ = VK_PHYSICAL_DEVICE_TYPE_OTHER;
  bool fill_mode_non_solid_ = false;  // the device can draw wireframes
  bool cpu_device_ = false;
  bool multiview_ = false;
  bool validation_enabled_ = false;
  std::atomic<std::uint64_t> validation_messages_{0};
};

}  // namespace rhot::vk
