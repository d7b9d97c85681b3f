#include "engine/render/vk/Swapchain.h"

#include <algorithm>

#include <spdlog/spdlog.h>

namespace rhot::vk {

Swapchain::Swapchain(const Context& context) : ctx_(context) {
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
  format_ = chosen.format;

  VkExtent2D extent = caps.currentExtent;
  if (extent.width == 0xffffffffu) extent = wanted;
  extent.width = std::clamp(extent.width, caps.minImageExtent.width, caps.maxImageExtent.width);
  extent.height = std::clamp(extent.height, caps.minImageExtent.height, caps.maxImageExtent.height);

  VkSwapchainCreateInfoKHR sci{VK_STRUCTURE_TYPE_SWAPCHAIN_CREATE_INFO_KHR};
  sci.surface = surface;
  sci.minImageCount = caps.maxImageCount == 0 ? caps.minImageCount + 1 : std::min(caps.minImageCount + 1, caps.maxImageCount);
  sci.imageFormat = chosen.format;
  sci.imageColorSpace = chosen.colorSpace;
  sci.imageExtent = extent;
  sci.imageArrayLayers = 1;
  sci.imageUsage = VK_IMAGE_USAGE_TRANSFER_DST_BIT;
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
  if (r == VK_SUBOPTIMAL_KHR) out_of_date_ = true;  // still usable this frame; recreate next frame
  else RHOT_VK_CHECK(r);
  return true;
}

void Swapchain::record_blit(VkCommandBuffer cmd, VkImage eyes, int eye_width_px, int eye_height_px) const {
  const VkImage target = images_[image_index_];
  VkImageMemoryBarrier to_dst{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
  to_dst.srcAccessMask = 0;
  to_dst.dstAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  to_dst.oldLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  to_dst.newLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
  to_dst.srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  to_dst.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  to_dst.image = target;
  to_dst.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0, nullptr, 0, nullptr, 1, &to_dst);

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

  VkImageMemoryBarrier to_present = to_dst;
  to_present.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  to_present.dstAccessMask = 0;
  to_present.oldLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
  to_present.newLayout = VK_IMAGE_LAYOUT_PRESENT_SRC_KHR;
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, 0, 0, nullptr, 0, nullptr, 1,
                       &to_present);
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
