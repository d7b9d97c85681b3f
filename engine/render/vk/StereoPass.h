#pragma once
// Both eyes' render targets and the passes that fill them. The colour target is one image with
// two array layers (0: left eye, 1: right eye) in R8G8B8A8_SRGB, plus a two-layer depth image.
// Lit per pixel, the passes draw into it as _SRGB and the target encodes; lit per vertex (see
// shaders/mesh.vert), they draw through an R8G8B8A8_UNORM view and the shaders encode. Either
// way reading back or blitting the image sees sRGB-encoded bytes.
// In multiview mode one render pass draws both layers (the shaders pick the eye by
// gl_ViewIndex); in two-pass mode the same draws run once per layer with the eye in a push
// constant. Either way, after a frame the colour image is in TRANSFER_SRC_OPTIMAL layout, ready to
// be read back or blitted to a window.

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>

#include "engine/render/Image.h"
#include "engine/render/Renderer.h"
#include "engine/render/vk/FenceWatch.h"
#include "engine/render/vk/VulkanContext.h"

namespace rhot::vk {

struct SubmitSync {
  VkSemaphore wait = VK_NULL_HANDLE;  // e.g. a swapchain image acquired
  VkPipelineStageFlags wait_stage = VK_PIPELINE_STAGE_TRANSFER_BIT;
  VkSemaphore signal = VK_NULL_HANDLE;  // e.g. ready to present
};

class StereoPass {
 public:
  // clear_color is linear RGBA.
  StereoPass(const Context& context, int eye_width_px, int eye_height_px, bool multiview, bool vertex_lit, glm::vec4 clear_color);
  ~StereoPass();
  StereoPass(const StereoPass&) = delete;
  StereoPass& operator=(const StereoPass&) = delete;

  // Records one frame (and then whatever `extra` records into the same command buffer, such as a
  // blit to a window) and submits it, first waiting for the previous frame (finish()). Returns
  // without waiting for this one: one frame is in flight until the next render(), read_back() or
  // finish(). Instances and lines that are not finite are skipped. Returns the number skipped.
  std::size_t render(const FrameInput& frame, std::span<const GpuMesh> meshes,
                     const std::function<void(VkCommandBuffer, VkImage)>& extra = {}, const SubmitSync& sync = {});

  // Waits until the frame last submitted has been drawn (and whatever `extra` recorded has run).
  void finish();

  // The last frame finish() waited for (docs/latency.md).
  const std::optional<FrameCompletion>& last_completed() const { return completed_; }
  std::uint64_t frames_submitted() const { return submitted_frames_; }
  // GPU timestamps around each eye's pass from the next frame on; false (and nothing changes)
  // where the queue has no timestamps.
  bool enable_gpu_timings();

  // Copies both layers to the CPU (finish, then submit and wait).
  std::array<Image, 2> read_back();

  VkImage colour_image() const { return colour_.image; }
  int width() const { return width_; }
  int height() const { return height_; }
  bool multiview() const { return multiview_; }
  bool vertex_lit() const { return vertex_lit_; }

 private:
  void create_targets();
  void create_render_pass();
  void create_pipelines();
  VkPipeline create_pipeline(std::span<const std::uint32_t> vert, std::span<const std::uint32_t> frag, bool lines);
  void ensure_capacity(Buffer& buffer, VkDeviceSize bytes, VkBufferUsageFlags usage);

  const Context& ctx_;
  int width_;
  int height_;
  bool multiview_;
  bool vertex_lit_;
  VkFormat attachment_format_;  // the format the passes draw through
  glm::vec4 clear_color_;       // as the attachment takes it: encoded when vertex-lit

  ImageMemory colour_;
  ImageMemory depth_;
  std::array<VkImageView, 2> colour_views_{};  // multiview: [0] is the two-layer view
  std::array<VkImageView, 2> depth_views_{};
  std::array<VkFramebuffer, 2> framebuffers_{};  // multiview: only [0]
  VkRenderPass render_pass_ = VK_NULL_HANDLE;

  VkDescriptorSetLayout set_layout_ = VK_NULL_HANDLE;
  VkDescriptorPool descriptor_pool_ = VK_NULL_HANDLE;
  VkDescriptorSet descriptor_set_ = VK_NULL_HANDLE;
  VkPipelineLayout pipeline_layout_ = VK_NULL_HANDLE;
  VkPipeline mesh_pipeline_ = VK_NULL_HANDLE;
  VkPipeline line_pipeline_ = VK_NULL_HANDLE;

  Buffer frame_uniforms_;
  Buffer instances_;
  Buffer lines_;
  Buffer readback_;
  VkCommandBuffer cmd_ = VK_NULL_HANDLE;
  VkFence fence_ = VK_NULL_HANDLE;
  bool in_flight_ = false;  // cmd_ submitted, fence_ not yet waited for
  FenceWatch watch_;
  std::uint64_t submitted_frames_ = 0;
  double submitted_s_ = 0.0;  // of the frame in flight
  std::optional<FrameCompletion> completed_;
  VkQueryPool timestamps_ = VK_NULL_HANDLE;  // three per frame: before eye 0, between the eyes, after eye 1
  double timestamp_period_ns_ = 0.0;
  bool timed_in_flight_ = false;  // the frame in flight wrote timestamps
};

}  // namespace rhot::vk
