#include "engine/render/vk/Swapchain.h"

#include <algorithm>

#include <spdlog/spdlog.h>

namespace rhot::vk {

Swapchain::Swapchain(const Context& context) : ctx_(context) {
  const VkPhysicalDevice gpu = ctx_.physical_device();
  const VkSurfaceKHR surface = ctx_.surface();
  std::uint32_t count = 0;
  vkGetPhysicalDeviceSurfaceFormatsKHR(gpu, surface, &count, nullptr);
  std::vector<VkSurfaceFormatKHR> formats(count);
  vkGetPhysicalDeviceSurfaceFormatsKHR(gpu, surface, &count, formats.data());
  RHOT_ASSERT(!formats.empty(), "the window surface offers no formats");
  // An sRGB format that can be a blit destination keeps colours as rendered.
  const auto blit_dst = [&](VkFormat f) {
    VkFormatProperties p;
    vkGetPhysicalDeviceFormatProperties(gpu, f, &p);
    return (p.optimalTilingFeatures & VK_FORMAT_FEATURE_BLIT_DST_BIT) != 0;
  };
  VkSurfaceFormatKHR chosen = formats[0];
  for (const VkSurfaceFormatKHR& f : formats) {
    if ((f.format == VK_FORMAT_B8G8R8A8_SRGB || f.format == VK_FORMAT_R8G8B8A8_SRGB) && blit_dst(f.format)) {
      chosen = f;
      break;
    }
  }
  RHOT_ASSERT(blit_dst(chosen.format), "the window's swapchain format cannot be a blit destination");
  surface_format_ = chosen;
  format_ = chosen.format;
  VkSemaphoreCreateInfo sci{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
  RHOT_VK_CHECK(vkCreateSemaphore(ctx_.device(), &sci, nullptr, &acquired_));
  RHOT_VK_CHECK(vkCreateSemaphore(ctx_.device(), &sci, nullptr, &ready_));
}

Swapchain::~Swapchain() {
  vkDeviceWaitIdle(ctx_.device());
  destroy_swapchain();
  vkDestroySemaphore(ctx_.device(), acquired_, nullptr);
  vkDestroySemaphore(ctx_.device(), ready_, nullptr);
}

void Swapchain::destroy_swapchain() {
  if (swapchain_ != VK_NULL_HANDLE) vkDestroySwapchainKHR(ctx_.device(), swapchain_, nullptr);
  swapchain_ = VK_NULL_HANDLE;
  images_.clear();
}

void Swapchain::create(VkExtent2D wanted) {
  vkDeviceWaitIdle(ctx_.device());
  const VkPhysicalDevice gpu = ctx_.physical_device();
  const VkSurfaceKHR surface = ctx_.surface();
  VkSurfaceCapabilitiesKHR caps;
  RHOT_VK_CHECK(vkGetPhysicalDeviceSurfaceCapabilitiesKHR(gpu, surface, &caps));

  VkExtent2D extent = caps.currentExtent;
  if (extent.width == 0xffffffffu) extent = wanted;
  extent.width = std::clamp(extent.width, caps.minImageExtent.width, caps.maxImageExtent.width);
  extent.height = std::clamp(extent.height, caps.minImageExtent.height, caps.maxImageExtent.height);

  VkSwapchainCreateInfoKHR sci{VK_STRUCTURE_TYPE_SWAPCHAIN_CREATE_INFO_KHR};
  sci.surface = surface;
  sci.minImageCount = caps.maxImageCount == 0 ? caps.minImageCount + 1 : std::min(caps.minImageCount + 1, caps.maxImageCount);
  sci.imageFormat = surface_format_.format;
  sci.imageColorSpace = surface_format_.colorSpace;
  sci.imageExtent = extent;
  sci.imageArrayLayers = 1;
  // Blitted into; the overlay draws into it as a colour attachment (which every surface supports).
  sci.imageUsage = VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT;
  // Read back for window captures where the surface allows it.
  copy_supported_ = (caps.supportedUsageFlags & VK_IMAGE_USAGE_TRANSFER_SRC_BIT) != 0;
  if (copy_supported_) sci.imageUsage |= VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
  sci.imageSharingMode = VK_SHARING_MODE_EXCLUSIVE;
  sci.preTransform = caps.currentTransform;
  sci.compositeAlpha = VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR;
  sci.presentMode = VK_PRESENT_MODE_FIFO_KHR;  // always available; paced to the display
  sci.clipped = VK_TRUE;
  sci.oldSwapchain = swapchain_;
  VkSwapchainKHR next = VK_NULL_HANDLE;
  RHOT_VK_CHECK(vkCreateSwapchainKHR(ctx_.device(), &sci, nullptr, &next));
  destroy_swapchain();
  swapchain_ = next;
  extent_ = extent;
  std::uint32_t count = 0;
  vkGetSwapchainImagesKHR(ctx_.device(), swapchain_, &count, nullptr);
  images_.resize(count);
  vkGetSwapchainImagesKHR(ctx_.device(), swapchain_, &count, images_.data());
  out_of_date_ = false;
  ++recreations_;
  spdlog::debug("swapchain {}x{}, {} images", extent_.width, extent_.height, count);
}

bool Swapchain::prepare(std::pair<int, int> framebuffer_size) {
  const auto [w, h] = framebuffer_size;
  if (w <= 0 || h <= 0) return false;
  const VkExtent2D wanted{static_cast<std::uint32_t>(w), static_cast<std::uint32_t>(h)};
  if (out_of_date_ || swapchain_ == VK_NULL_HANDLE || wanted.width != extent_.width || wanted.height != extent_.height) {
    create(wanted);
  }
  return true;
}

bool Swapchain::acquire() {
  const VkResult r = vkAcquireNextImageKHR(ctx_.device(), swapchain_, UINT64_MAX, acquired_, VK_NULL_HANDLE, &image_index_);
  if (r == VK_ERROR_OUT_OF_DATE_KHR) {
    out_of_date_ = true;
    return false;
  }
  if (r == VK_SUBOPTIMAL_KHR)
    out_of_date_ = true;  // still usable this frame; recreate next frame
  else
    RHOT_VK_CHECK(r);
  return true;
}

namespace {

// One layout transition of a swapchain image's colour, with its access and stage masks.
struct Transition {
  VkImageLayout from;
  VkImageLayout to;
  VkAccessFlags src_access;
  VkAccessFlags dst_access;
  VkPipelineStageFlags src_stage;
  VkPipelineStageFlags dst_stage;
};

void transition(VkCommandBuffer cmd, VkImage image, const Transition& t) {
  VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
  b.srcAccessMask = t.src_access;
  b.dstAccessMask = t.dst_access;
  b.oldLayout = t.from;
  b.newLayout = t.to;
  b.srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = image;
  b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  vkCmdPipelineBarrier(cmd, t.src_stage, t.dst_stage, 0, 0, nullptr, 0, nullptr, 1, &b);
}

}  // namespace

void Swapchain::record_blit(VkCommandBuffer cmd, VkImage eyes, int eye_width_px, int eye_height_px, bool overlay_follows) const {
  const VkImage target = images_[image_index_];
  transition(cmd, target,
             {VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 0, VK_ACCESS_TRANSFER_WRITE_BIT,
              VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT});
  const auto half = static_cast<std::int32_t>(extent_.width / 2);
  const auto height = static_cast<std::int32_t>(extent_.height);
  for (std::uint32_t eye = 0; eye < 2; ++eye) {
    VkImageBlit blit{};
    blit.srcSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, eye, 1};
    blit.srcOffsets[1] = {eye_width_px, eye_height_px, 1};
    blit.dstSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    blit.dstOffsets[0] = {eye == 0 ? 0 : half, 0, 0};
    blit.dstOffsets[1] = {eye == 0 ? half : 2 * half, height, 1};
    vkCmdBlitImage(cmd, eyes, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, target, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &blit,
                   VK_FILTER_LINEAR);
  }
  if (overlay_follows) {
    transition(cmd, target,
               {VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_ACCESS_TRANSFER_WRITE_BIT,
                VK_ACCESS_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
                VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT});
  } else {
    transition(cmd, target,
               {VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_PRESENT_SRC_KHR, VK_ACCESS_TRANSFER_WRITE_BIT, 0,
                VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT});
  }
}

bool Swapchain::record_copy(VkCommandBuffer cmd, const Buffer& buffer) const {
  if (!copy_supported_) return false;
  const VkImage image = images_[image_index_];
  transition(cmd, image,
             {VK_IMAGE_LAYOUT_PRESENT_SRC_KHR, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
              VK_ACCESS_TRANSFER_WRITE_BIT | VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT, VK_ACCESS_TRANSFER_READ_BIT,
              VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT});
  VkBufferImageCopy region{};
  region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  region.imageExtent = {extent_.width, extent_.height, 1};
  vkCmdCopyImageToBuffer(cmd, image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, buffer.buffer, 1, &region);
  transition(cmd, image,
             {VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_IMAGE_LAYOUT_PRESENT_SRC_KHR, VK_ACCESS_TRANSFER_READ_BIT, 0,
              VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT});
  VkBufferMemoryBarrier host{VK_STRUCTURE_TYPE_BUFFER_MEMORY_BARRIER};
  host.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  host.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
  host.srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  host.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  host.buffer = buffer.buffer;
  host.size = VK_WHOLE_SIZE;
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 0, nullptr, 1, &host, 0, nullptr);
  return true;
}

void Swapchain::read_copy(const Buffer& buffer, std::vector<std::uint8_t>& rgba) const {
  const std::size_t bytes = static_cast<std::size_t>(extent_.width) * extent_.height * 4;
  rgba.resize(bytes);
  const auto* src = static_cast<const std::uint8_t*>(buffer.mapped);
  const bool bgra = format_ == VK_FORMAT_B8G8R8A8_SRGB || format_ == VK_FORMAT_B8G8R8A8_UNORM;
  for (std::size_t i = 0; i < bytes; i += 4) {
    rgba[i + 0] = src[i + (bgra ? 2 : 0)];
    rgba[i + 1] = src[i + 1];
    rgba[i + 2] = src[i + (bgra ? 0 : 2)];
    rgba[i + 3] = 255;  // the window is opaque
  }
}

void Swapchain::present() {
  VkPresentInfoKHR pi{VK_STRUCTURE_TYPE_PRESENT_INFO_KHR};
  pi.waitSemaphoreCount = 1;
  pi.pWaitSemaphores = &ready_;
  pi.swapchainCount = 1;
  pi.pSwapchains = &swapchain_;
  pi.pImageIndices = &image_index_;
  const VkResult r = vkQueuePresentKHR(ctx_.queue(), &pi);
  if (r == VK_ERROR_OUT_OF_DATE_KHR || r == VK_SUBOPTIMAL_KHR) {
    out_of_date_ = true;
  } else {
    RHOT_VK_CHECK(r);
  }
}

}  // namespace rhot::vk
