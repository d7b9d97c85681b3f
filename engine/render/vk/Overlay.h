#pragma once
// Dear ImGui over the desktop window: GLFW feeds it the window's mouse and keyboard, and its draw
// lists are drawn onto the swapchain image after the eyes are blitted there, in a render pass of
// its own. The eyes themselves (and any PNG capture) never contain the overlay.

#include <cstdint>
#include <expected>
#include <memory>
#include <string>
#include <vector>

#include "engine/render/vk/Swapchain.h"
#include "engine/render/vk/VulkanContext.h"

struct GLFWwindow;

namespace rhot::vk {

class Overlay {
 public:
  // Starts Dear ImGui (one context per process) for `window`, drawing into images of `format`.
  [[nodiscard]] static std::expected<std::unique_ptr<Overlay>, std::string> create(const Context& context, GLFWwindow* window,
                                                                                   VkFormat format);
  ~Overlay();
  Overlay(const Overlay&) = delete;
  Overlay& operator=(const Overlay&) = delete;

  // Starts a frame of Dear ImGui calls.
  void begin_frame();
  // Ends the frame begun (ImGui::Render); its draw data waits for record().
  void end_frame();
  bool frame_begun() const { return begun_; }

  // Records the last ended frame's draw data onto the swapchain's acquired image, which must be
  // in COLOR_ATTACHMENT_OPTIMAL; leaves it in PRESENT_SRC_KHR.
  void record(VkCommandBuffer cmd, const Swapchain& swapchain);

  // Vertices drawn by the last record() (0 when nothing was drawn).
  std::uint64_t last_vertex_count() const { return last_vertices_; }

 private:
  Overlay(const Context& context, VkFormat format) : ctx_(context), format_(format) {}
  void rebuild_framebuffers(const Swapchain& swapchain);
  void destroy_framebuffers();

  const Context& ctx_;
  VkFormat format_;
  VkRenderPass render_pass_ = VK_NULL_HANDLE;
  VkDescriptorPool descriptor_pool_ = VK_NULL_HANDLE;
  std::vector<VkImageView> views_;
  std::vector<VkFramebuffer> framebuffers_;
  std::uint64_t built_for_ = 0;  // the swapchain recreation the framebuffers belong to
  bool imgui_vulkan_ = false;
  bool imgui_glfw_ = false;
  bool begun_ = false;
  bool ended_ = false;
  std::uint64_t last_vertices_ = 0;
};

}  // namespace rhot::vk
