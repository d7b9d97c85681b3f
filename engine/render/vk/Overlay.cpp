#include "engine/render/vk/Overlay.h"

#include <array>

#include <imgui.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_vulkan.h>
#include <spdlog/spdlog.h>

namespace rhot::vk {

namespace {

void check_imgui_vk(VkResult r) { RHOT_VK_CHECK(r); }

}  // namespace

std::expected<std::unique_ptr<Overlay>, std::string> Overlay::create(const Context& context, GLFWwindow* window, VkFormat format) {
  if (ImGui::GetCurrentContext() != nullptr) return std::unexpected(std::string("the overlay is already running (one per process)"));
  std::unique_ptr<Overlay> o(new Overlay(context, format));
  const VkDevice device = context.device();

  // Load the image the blit left, draw over it, hand it to the presentation engine.
  VkAttachmentDescription colour{};
  colour.format = format;
  colour.samples = VK_SAMPLE_COUNT_1_BIT;
  colour.loadOp = VK_ATTACHMENT_LOAD_OP_LOAD;
  colour.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
  colour.stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
  colour.stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
  colour.initialLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
  colour.finalLayout = VK_IMAGE_LAYOUT_PRESENT_SRC_KHR;
  VkAttachmentReference ref{0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
  VkSubpassDescription subpass{};
  subpass.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
  subpass.colorAttachmentCount = 1;
  subpass.pColorAttachments = &ref;
  VkRenderPassCreateInfo rpci{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
  rpci.attachmentCount = 1;
  rpci.pAttachments = &colour;
  rpci.subpassCount = 1;
  rpci.pSubpasses = &subpass;
  RHOT_VK_CHECK(vkCreateRenderPass(device, &rpci, nullptr, &o->render_pass_));

  // The font atlas is the one texture the overlay samples.
  const VkDescriptorPoolSize sizes{VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 4};
  VkDescriptorPoolCreateInfo dpci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  dpci.flags = VK_DESCRIPTOR_POOL_CREATE_FREE_DESCRIPTOR_SET_BIT;
  dpci.maxSets = 4;
  dpci.poolSizeCount = 1;
  dpci.pPoolSizes = &sizes;
  RHOT_VK_CHECK(vkCreateDescriptorPool(device, &dpci, nullptr, &o->descriptor_pool_));

  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGuiIO& io = ImGui::GetIO();
  io.IniFilename = nullptr;  // no imgui.ini files next to wherever the demo was started
  ImGui::StyleColorsDark();
  ImGui::GetStyle().Alpha = 0.92f;
  if (!ImGui_ImplGlfw_InitForVulkan(window, /*install_callbacks=*/true)) {
    return std::unexpected(std::string("Dear ImGui cannot take the window's input (ImGui_ImplGlfw_InitForVulkan failed)"));
  }
  o->imgui_glfw_ = true;
  ImGui_ImplVulkan_InitInfo info{};
  info.Instance = context.instance();
  info.PhysicalDevice = context.physical_device();
  info.Device = device;
  info.QueueFamily = context.queue_family();
  info.Queue = context.queue();
  info.DescriptorPool = o->descriptor_pool_;
  info.Subpass = 0;
  // Each frame waits for its fence before the next is recorded, so two vertex buffers suffice.
  info.MinImageCount = 2;
  info.ImageCount = 2;
  info.MSAASamples = VK_SAMPLE_COUNT_1_BIT;
  info.CheckVkResultFn = check_imgui_vk;
  if (!ImGui_ImplVulkan_Init(&info, o->render_pass_)) {
    return std::unexpected(std::string("Dear ImGui cannot draw with this Vulkan device (ImGui_ImplVulkan_Init failed)"));
  }
  o->imgui_vulkan_ = true;
  bool fonts = false;
  context.run_once([&](VkCommandBuffer cmd) { fonts = ImGui_ImplVulkan_CreateFontsTexture(cmd); });
  ImGui_ImplVulkan_DestroyFontUploadObjects();
  if (!fonts) return std::unexpected(std::string("Dear ImGui cannot upload its font atlas"));
  spdlog::debug("overlay: Dear ImGui {} on the window", IMGUI_VERSION);
  return o;
}

Overlay::~Overlay() {
  vkDeviceWaitIdle(ctx_.device());
  if (begun_ && !ended_) ImGui::EndFrame();
  if (imgui_vulkan_) ImGui_ImplVulkan_Shutdown();
  if (imgui_glfw_) ImGui_ImplGlfw_Shutdown();
  if (ImGui::GetCurrentContext() != nullptr) ImGui::DestroyContext();
  destroy_framebuffers();
  if (descriptor_pool_ != VK_NULL_HANDLE) vkDestroyDescriptorPool(ctx_.device(), descriptor_pool_, nullptr);
  if (render_pass_ != VK_NULL_HANDLE) vkDestroyRenderPass(ctx_.device(), render_pass_, nullptr);
}

void Overlay::begin_frame() {
  if (begun_ && !ended_) ImGui::EndFrame();  // a frame begun and never drawn (window minimised)
  ImGui_ImplVulkan_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
  begun_ = true;
  ended_ = false;
}

void Overlay::end_frame() {
  if (!begun_ || ended_) return;
  ImGui::Render();
  ended_ = true;
}

void Overlay::destroy_framebuffers() {
  for (VkFramebuffer f : framebuffers_) vkDestroyFramebuffer(ctx_.device(), f, nullptr);
  for (VkImageView v : views_) vkDestroyImageView(ctx_.device(), v, nullptr);
  framebuffers_.clear();
  views_.clear();
}

void Overlay::rebuild_framebuffers(const Swapchain& swapchain) {
  destroy_framebuffers();
  const VkExtent2D extent = swapchain.vk_extent();
  for (const VkImage image : swapchain.images()) {
    VkImageViewCreateInfo vci{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    vci.image = image;
    vci.viewType = VK_IMAGE_VIEW_TYPE_2D;
    vci.format = format_;
    vci.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    VkImageView view = VK_NULL_HANDLE;
    RHOT_VK_CHECK(vkCreateImageView(ctx_.device(), &vci, nullptr, &view));
    views_.push_back(view);
    VkFramebufferCreateInfo fci{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
    fci.renderPass = render_pass_;
    fci.attachmentCount = 1;
    fci.pAttachments = &view;
    fci.width = extent.width;
    fci.height = extent.height;
    fci.layers = 1;
    VkFramebuffer framebuffer = VK_NULL_HANDLE;
    RHOT_VK_CHECK(vkCreateFramebuffer(ctx_.device(), &fci, nullptr, &framebuffer));
    framebuffers_.push_back(framebuffer);
  }
  built_for_ = swapchain.recreations();
}

void Overlay::record(VkCommandBuffer cmd, const Swapchain& swapchain) {
  RHOT_ASSERT(swapchain.format() == format_, "the overlay was made for another swapchain format");
  if (built_for_ != swapchain.recreations() || framebuffers_.size() != swapchain.images().size()) rebuild_framebuffers(swapchain);
  VkRenderPassBeginInfo rpbi{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
  rpbi.renderPass = render_pass_;
  rpbi.framebuffer = framebuffers_[swapchain.image_index()];
  rpbi.renderArea.extent = swapchain.vk_extent();
  vkCmdBeginRenderPass(cmd, &rpbi, VK_SUBPASS_CONTENTS_INLINE);
  ImDrawData* draw = ended_ ? ImGui::GetDrawData() : nullptr;
  last_vertices_ = 0;
  if (draw != nullptr && draw->TotalVtxCount > 0) {
    ImGui_ImplVulkan_RenderDrawData(draw, cmd);
    last_vertices_ = static_cast<std::uint64_t>(draw->TotalVtxCount);
  }
  vkCmdEndRenderPass(cmd);
}

}  // namespace rhot::vk
