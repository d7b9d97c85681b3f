#pragma once
// OpenXR on Vulkan (XR_KHR_vulkan_enable2): the state behind engine/render/XrHeadset.h and what
// the renderer calls to make its Vulkan objects through the runtime and to hand it both eyes.
// Private to engine/render.

#include <time.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <expected>
#include <optional>
#include <string>
#include <vector>

#include <vulkan/vulkan.h>
#define XR_USE_GRAPHICS_API_VULKAN
#define XR_USE_TIMESPEC
#include <openxr/openxr.h>
#include <openxr/openxr_platform.h>

#include "engine/render/XrHeadset.h"
#include "engine/render/vk/VulkanContext.h"

namespace rhot {

struct XrHeadset::Impl {
  // One swapchain: both eyes as its two array layers, or one eye.
  struct Chain {
    XrSwapchain handle = XR_NULL_HANDLE;
    std::uint32_t layers = 1;
    std::vector<VkImage> images;
    std::uint32_t acquired = 0;
    bool held = false;  // acquired and waited for, not yet released
  };

  XrHeadsetSettings settings;
  XrHeadsetInfo info;
  XrInstance instance = XR_NULL_HANDLE;
  XrSystemId system = XR_NULL_SYSTEM_ID;
  XrEnvironmentBlendMode blend = XR_ENVIRONMENT_BLEND_MODE_OPAQUE;
  XrDebugUtilsMessengerEXT messenger = XR_NULL_HANDLE;
  std::atomic<std::uint64_t> validation_messages{0};

  PFN_xrGetVulkanGraphicsRequirements2KHR get_requirements = nullptr;
  PFN_xrCreateVulkanInstanceKHR create_vk_instance = nullptr;
  PFN_xrGetVulkanGraphicsDevice2KHR get_vk_device = nullptr;
  PFN_xrCreateVulkanDeviceKHR create_vk_device = nullptr;
  PFN_xrConvertTimeToTimespecTimeKHR to_timespec = nullptr;
  PFN_xrConvertTimespecTimeToTimeKHR from_timespec = nullptr;

  XrSession session = XR_NULL_HANDLE;
  XrSpace stage = XR_NULL_HANDLE;
  XrSpace view = XR_NULL_HANDLE;  // the head
  XrSessionState state = XR_SESSION_STATE_UNKNOWN;
  bool running = false;
  bool exit = false;
  std::string exit_reason;
  bool exit_requested = false;
  bool lost = false;

  std::vector<Chain> chains;  // one (two layers) or two (one eye each)
  VkFormat format = VK_FORMAT_UNDEFINED;
  int width = 0;
  int height = 0;
  std::optional<XrFrameTiming> frame;
  std::uint64_t frames_begun = 0;
  std::array<XrView, 2> views{};
  bool views_located = false;
  glm::mat4 world_from_stage{1.0f};
  std::uint64_t submitted = 0;
  std::uint64_t late = 0;
  std::uint64_t late_own = 0;
  int failures = 0;  // calls failed since the last frame shown

  ~Impl();

  // The renderer's Vulkan objects, made through the runtime (they meet its requirements).
  [[nodiscard]] std::expected<VkInstance, std::string> make_instance(const VkInstanceCreateInfo& info);
  [[nodiscard]] std::expected<VkPhysicalDevice, std::string> physical_device(VkInstance vk_instance);
  [[nodiscard]] std::expected<VkDevice, std::string> make_device(VkPhysicalDevice physical, const VkDeviceCreateInfo& info);
  // The session on the renderer's device and queue, the STAGE space and the swapchains
  // (array_swapchain: one two-layer swapchain, else one per eye) of the recommended size.
  [[nodiscard]] std::expected<void, std::string> start(const vk::Context& context, bool array_swapchain);
  // Ends the frame, the session and the swapchains (before the renderer's device goes).
  void stop();

  // For the current frame, where it is to be rendered: acquires and waits for each swapchain's
  // image. False (nothing held) where the frame is not to be rendered or a call failed.
  bool acquire();
  // Copies both eyes (layer 0 left, 1 right of `eyes`, TRANSFER_SRC_OPTIMAL, width x height in
  // R8G8B8A8_SRGB) into the acquired images, leaving them as the runtime expects them.
  void record_copy(VkCommandBuffer cmd, VkImage eyes, int eye_width, int eye_height) const;
  // Releases the images and ends the frame: with the projection layer where images were
  // acquired, else with none.
  void end_frame();
  // Releases the images held (acquired and waited for).
  void release();
  // Logs a failed call; a lost session or instance, or ten failures without a frame shown between
  // them, ends the run as lost.
  void fail(const char* call, XrResult r);

  void handle_state(XrSessionState next);
};

}  // namespace rhot
