#pragma once
// A window's swapchain. Each frame both eye layers are blitted side by side into the acquired
// image (left eye on the left half), which is then presented. The swapchain is recreated when the
// window's size changes or the driver reports it out of date; while the window is minimised
// nothing is presented.

#include <cstdint>
#include <utility>
#include <vector>

#include "engine/render/vk/VulkanContext.h"

namespace rhot::vk {

class Swapchain {
 public:
  explicit Swapchain(const Context& context);
  ~Swapchain();
  Swapchain(const Swapchain&) = delete;
  Swapchain& operator=(const Swapchain&) = delete;

  // Makes the swapchain match the window's framebuffer size (recreating it if it changed).
  // Returns false while the size is 0 x 0 (minimised): skip presenting.
  bool prepare(std::pair<int, int> framebuffer_size);

  // Acquires the next image; returns false when the swapchain must be recreated first.
  bool acquire();
  VkSemaphore acquired_semaphore() const { return acquired_; }
  VkSemaphore ready_semaphore() const { return ready_; }

  // Records the blit of both layers of `eyes` (in TRANSFER_SRC_OPTIMAL, eye_w x eye_h) into the
  // acquired image, side by side, and its transition for presenting (or, where the overlay
  // draws next, to COLOR_ATTACHMENT_OPTIMAL).
  void record_blit(VkCommandBuffer cmd, VkImage eyes, int eye_width_px, int eye_height_px, bool overlay_follows = false) const;

  // Records a copy of the acquired image (in PRESENT_SRC_KHR, as left by the blit or the overlay)
  // into `buffer` (host-visible, at least width * height * 4 bytes), leaving the image ready to
  // present. False (nothing recorded) where the surface cannot be a copy source.
  bool record_copy(VkCommandBuffer cmd, const Buffer& buffer) const;
  bool copy_supported() const { return copy_supported_; }
  // Reads a buffer filled by record_copy (after its submit finished) as RGBA.
  void read_copy(const Buffer& buffer, std::vector<std::uint8_t>& rgba) const;

  // Presents the acquired image once `ready_semaphore` signals.
  void present();

  std::uint64_t recreations() const { return recreations_; }
  VkFormat format() const { return format_; }  // chosen from the surface's formats when constructed
  const std::vector<VkImage>& images() const { return images_; }
  std::uint32_t image_index() const { return image_index_; }  // the acquired image
  VkExtent2D vk_extent() const { return extent_; }
  std::pair<int, int> extent() const { return {static_cast<int>(extent_.width), static_cast<int>(extent_.height)}; }

 private:
  void create(VkExtent2D wanted);
  void destroy_swapchain();

  const Context& ctx_;
  VkSwapchainKHR swapchain_ = VK_NULL_HANDLE;
  VkSurfaceFormatKHR surface_format_{};
  VkFormat format_ = VK_FORMAT_UNDEFINED;
  VkExtent2D extent_{0, 0};
  std::vector<VkImage> images_;
  std::uint32_t image_index_ = 0;
  bool out_of_date_ = true;
  VkSemaphore acquired_ = VK_NULL_HANDLE;
  VkSemaphore ready_ = VK_NULL_HANDLE;
  std::uint64_t recreations_ = 0;
  bool copy_supported_ = false;
};

}  // namespace rhot::vk
