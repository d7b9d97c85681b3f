#include "engine/render/vk/StereoPass.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "base/SteadyClock.h"
#include "rhot_shaders/shaders.h"

namespace rhot::vk {

namespace {

constexpr VkFormat kColourFormat = VK_FORMAT_R8G8B8A8_SRGB;
constexpr VkFormat kColourFormatUnorm = VK_FORMAT_R8G8B8A8_UNORM;  // the same bytes, not encoded on store
constexpr VkFormat kDepthFormat = VK_FORMAT_D32_SFLOAT;

// Per-instance data, matching mesh.vert's locations 2 to 9.
struct GpuInstance {
  glm::mat4 world_from_local;
  glm::vec4 normal_matrix[3];  // columns of the inverse transpose of the upper 3x3
  glm::vec4 color;
};
static_assert(sizeof(GpuInstance) == 128);

// The Frame uniform block of the shaders (std140).
struct FrameUniforms {
  glm::mat4 clip_from_world[2];
  glm::vec4 light_dir_world;
  glm::vec4 light_color;  // a: ambient
};

bool finite(const glm::mat4& m) {
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) {
      if (!std::isfinite(m[c][r])) return false;
    }
  }
  return true;
}
bool finite(const glm::vec4& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z) && std::isfinite(v.w); }

// shaders/srgb.glsl on the CPU, for the clear colour.
float srgb_from_linear(float linear) {
  const float c = std::clamp(linear, 0.0f, 1.0f);
  return c < 0.0031308f ? c * 12.92f : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

// The Frame uniform block of a frame. Precondition: its views and light are finite.
FrameUniforms frame_uniforms(const FrameInput& frame) {
  FrameUniforms u{};
  for (int eye = 0; eye < 2; ++eye) u.clip_from_world[eye] = frame.views.clip_from_world(eye);
  u.light_dir_world = glm::vec4(glm::normalize(frame.light_dir_world), 0.0f);
  u.light_color = glm::vec4(frame.light_color, frame.ambient);
  RHOT_PRECONDITION(finite(u.clip_from_world[0]) && finite(u.clip_from_world[1]) && finite(u.light_dir_world) && finite(u.light_color),
                    "StereoPass::render: the views and light must be finite");
  return u;
}

// One instanced draw of a mesh: instances [first_instance, first_instance + instance_count) of
// the instance buffer.
struct Draw {
  const GpuMesh* mesh;
  std::uint32_t first_instance;
  std::uint32_t instance_count;
};

// The batches' finite instances into `out` (room for all of them), batch after batch, and the
// draws that show them; `skipped` counts the instances left out. Precondition: every batch's mesh
// is one of `meshes`.
std::vector<Draw> write_instances(const std::vector<MeshBatch>& batches, std::span<const GpuMesh> meshes, GpuInstance* out,
                                  std::size_t& skipped) {
  std::vector<Draw> draws;
  std::uint32_t written = 0;
  for (const MeshBatch& b : batches) {
    RHOT_PRECONDITION(b.mesh.index < meshes.size(), "StereoPass::render: unknown mesh handle");
    const std::uint32_t first = written;
    for (const MeshInstance& inst : b.instances) {
      if (!finite(inst.world_from_local) || !finite(inst.color)) {
        ++skipped;
        continue;
      }
      const glm::mat3 normal = glm::transpose(glm::inverse(glm::mat3(inst.world_from_local)));
      GpuInstance& g = out[written++];
      g.world_from_local = inst.world_from_local;
      for (int c = 0; c < 3; ++c) g.normal_matrix[c] = glm::vec4(normal[c], 0.0f);
      g.color = inst.color;
    }
    if (written > first) draws.push_back({&meshes[b.mesh.index], first, written - first});
  }
  return draws;
}

// The line list's finite lines into `out` (room for all of them): the vertices written;
// `skipped` counts the lines left out.
std::uint32_t write_lines(const std::vector<LineVertex>& lines, LineVertex* out, std::size_t& skipped) {
  std::uint32_t line_vertices = 0;
  for (std::size_t i = 0; i + 1 < lines.size(); i += 2) {
    const LineVertex& a = lines[i];
    const LineVertex& b = lines[i + 1];
    if (!finite(glm::vec4(a.position, 1.0f)) || !finite(glm::vec4(b.position, 1.0f)) || !finite(a.color) || !finite(b.color)) {
      ++skipped;
      continue;
    }
    out[line_vertices++] = a;
    out[line_vertices++] = b;
  }
  return line_vertices;
}

void draw_meshes(VkCommandBuffer cmd, VkPipeline pipeline, VkBuffer instances, const std::vector<Draw>& draws) {
  if (draws.empty()) return;
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline);
  for (const Draw& draw : draws) {
    const std::array<VkBuffer, 2> buffers{draw.mesh->vertices.buffer, instances};
    const std::array<VkDeviceSize, 2> offsets{0, VkDeviceSize{draw.first_instance} * sizeof(GpuInstance)};
    vkCmdBindVertexBuffers(cmd, 0, 2, buffers.data(), offsets.data());
    vkCmdBindIndexBuffer(cmd, draw.mesh->indices.buffer, 0, VK_INDEX_TYPE_UINT32);
    vkCmdDrawIndexed(cmd, draw.mesh->index_count, draw.instance_count, 0, 0, 0);
  }
}

void draw_lines(VkCommandBuffer cmd, VkPipeline pipeline, const VkBuffer& lines, std::uint32_t line_vertices) {
  if (line_vertices == 0) return;
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline);
  const VkDeviceSize offset = 0;
  vkCmdBindVertexBuffers(cmd, 0, 1, &lines, &offset);
  vkCmdDraw(cmd, line_vertices, 1, 0, 0);
}

// A submission of `cmd` (kept alive by the caller, as is `sync`) waiting on and signalling what
// `sync` names.
VkSubmitInfo submit_info(const VkCommandBuffer& cmd, const SubmitSync& sync) {
  VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  submit.commandBufferCount = 1;
  submit.pCommandBuffers = &cmd;
  if (sync.wait != VK_NULL_HANDLE) {
    submit.waitSemaphoreCount = 1;
    submit.pWaitSemaphores = &sync.wait;
    submit.pWaitDstStageMask = &sync.wait_stage;
  }
  if (sync.signal != VK_NULL_HANDLE) {
    submit.signalSemaphoreCount = 1;
    submit.pSignalSemaphores = &sync.signal;
  }
  return submit;
}

}  // namespace

StereoPass::StereoPass(const Context& context, int eye_width_px, int eye_height_px, bool multiview, bool vertex_lit, glm::vec4 clear_color)
    : ctx_(context),
      width_(eye_width_px),
      height_(eye_height_px),
      multiview_(multiview),
      vertex_lit_(vertex_lit),
      attachment_format_(vertex_lit ? kColourFormatUnorm : kColourFormat),
      clear_color_(vertex_lit ? glm::vec4(srgb_from_linear(clear_color.r), srgb_from_linear(clear_color.g), srgb_from_linear(clear_color.b),
                                          clear_color.a)
                              : clear_color),
      watch_(context.device()) {
  RHOT_PRECONDITION(!multiview || context.multiview_supported(), "StereoPass: the device has no multiview");
  create_targets();
  create_render_pass();
  create_pipelines();

  VkCommandBufferAllocateInfo cai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  cai.commandPool = ctx_.command_pool();
  cai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  cai.commandBufferCount = 1;
  RHOT_VK_CHECK(vkAllocateCommandBuffers(ctx_.device(), &cai, &cmd_));
  VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  RHOT_VK_CHECK(vkCreateFence(ctx_.device(), &fci, nullptr, &fence_));
  readback_ = ctx_.create_buffer(VkDeviceSize{2} * static_cast<VkDeviceSize>(width_) * static_cast<VkDeviceSize>(height_) * 4,
                                 VK_BUFFER_USAGE_TRANSFER_DST_BIT, true);
}

StereoPass::~StereoPass() {
  // The fence watch lets go of the fence (whatever became of the frame: no checks while tearing down).
  if (in_flight_) (void)watch_.wait();
  const VkDevice d = ctx_.device();
  vkDeviceWaitIdle(d);
  if (timestamps_ != VK_NULL_HANDLE) vkDestroyQueryPool(d, timestamps_, nullptr);
  vkDestroyFence(d, fence_, nullptr);
  vkFreeCommandBuffers(d, ctx_.command_pool(), 1, &cmd_);
  for (Buffer* b : {&frame_uniforms_, &instances_, &lines_, &readback_}) ctx_.destroy(*b);
  vkDestroyPipeline(d, mesh_pipeline_, nullptr);
  vkDestroyPipeline(d, line_pipeline_, nullptr);
  vkDestroyPipelineLayout(d, pipeline_layout_, nullptr);
  vkDestroyDescriptorPool(d, descriptor_pool_, nullptr);
  vkDestroyDescriptorSetLayout(d, set_layout_, nullptr);
  for (VkFramebuffer f : framebuffers_) vkDestroyFramebuffer(d, f, nullptr);
  vkDestroyRenderPass(d, render_pass_, nullptr);
  for (VkImageView v : colour_views_) vkDestroyImageView(d, v, nullptr);
  for (VkImageView v : depth_views_) vkDestroyImageView(d, v, nullptr);
  ctx_.destroy(colour_);
  ctx_.destroy(depth_);
}

void StereoPass::create_targets() {
  VkImageCreateInfo ici{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
  ici.imageType = VK_IMAGE_TYPE_2D;
  ici.extent = {static_cast<std::uint32_t>(width_), static_cast<std::uint32_t>(height_), 1};
  ici.mipLevels = 1;
  ici.arrayLayers = 2;
  ici.samples = VK_SAMPLE_COUNT_1_BIT;
  ici.tiling = VK_IMAGE_TILING_OPTIMAL;
  ici.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  ici.format = kColourFormat;
  ici.usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
  if (vertex_lit_) ici.flags = VK_IMAGE_CREATE_MUTABLE_FORMAT_BIT;  // drawn through a _UNORM view
  colour_ = ctx_.create_image(ici);
  ici.flags = 0;
  ici.format = kDepthFormat;
  ici.usage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT;
  depth_ = ctx_.create_image(ici);

  const auto make_view = [&](VkImage image, VkFormat format, VkImageAspectFlags aspect, std::uint32_t first_layer, std::uint32_t layers) {
    VkImageViewCreateInfo vci{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    vci.image = image;
    vci.viewType = layers > 1 ? VK_IMAGE_VIEW_TYPE_2D_ARRAY : VK_IMAGE_VIEW_TYPE_2D;
    vci.format = format;
    vci.subresourceRange = {aspect, 0, 1, first_layer, layers};
    VkImageView view = VK_NULL_HANDLE;
    RHOT_VK_CHECK(vkCreateImageView(ctx_.device(), &vci, nullptr, &view));
    return view;
  };
  if (multiview_) {
    colour_views_[0] = make_view(colour_.image, attachment_format_, VK_IMAGE_ASPECT_COLOR_BIT, 0, 2);
    depth_views_[0] = make_view(depth_.image, kDepthFormat, VK_IMAGE_ASPECT_DEPTH_BIT, 0, 2);
  } else {
    for (std::uint32_t eye = 0; eye < 2; ++eye) {
      colour_views_[eye] = make_view(colour_.image, attachment_format_, VK_IMAGE_ASPECT_COLOR_BIT, eye, 1);
      depth_views_[eye] = make_view(depth_.image, kDepthFormat, VK_IMAGE_ASPECT_DEPTH_BIT, eye, 1);
    }
  }
}

void StereoPass::create_render_pass() {
  std::array<VkAttachmentDescription, 2> attachments{};
  attachments[0].format = attachment_format_;
  attachments[0].samples = VK_SAMPLE_COUNT_1_BIT;
  attachments[0].loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
  attachments[0].storeOp = VK_ATTACHMENT_STORE_OP_STORE;
  attachments[0].stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
  attachments[0].stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
  attachments[0].initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  attachments[0].finalLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
  attachments[1] = attachments[0];
  attachments[1].format = kDepthFormat;
  attachments[1].storeOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
  attachments[1].finalLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
  const VkAttachmentReference colour_ref{0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
  const VkAttachmentReference depth_ref{1, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
  VkSubpassDescription subpass{};
  subpass.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
  subpass.colorAttachmentCount = 1;
  subpass.pColorAttachments = &colour_ref;
  subpass.pDepthStencilAttachment = &depth_ref;
  // Before: the previous frame's read-back or blit must finish before the clear overwrites the
  // image. After: attachment writes must land before the read-back or blit reads them.
  std::array<VkSubpassDependency, 2> deps{};
  deps[0].srcSubpass = VK_SUBPASS_EXTERNAL;
  deps[0].dstSubpass = 0;
  deps[0].srcStageMask = VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT;
  deps[0].srcAccessMask = VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;
  deps[0].dstStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT;
  deps[0].dstAccessMask =
      VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT;
  deps[1].srcSubpass = 0;
  deps[1].dstSubpass = VK_SUBPASS_EXTERNAL;
  deps[1].srcStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
  deps[1].srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
  deps[1].dstStageMask = VK_PIPELINE_STAGE_TRANSFER_BIT;
  deps[1].dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
  VkRenderPassCreateInfo rpci{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
  rpci.attachmentCount = static_cast<std::uint32_t>(attachments.size());
  rpci.pAttachments = attachments.data();
  rpci.subpassCount = 1;
  rpci.pSubpasses = &subpass;
  rpci.dependencyCount = static_cast<std::uint32_t>(deps.size());
  rpci.pDependencies = deps.data();
  const std::uint32_t view_mask = 0b11;
  VkRenderPassMultiviewCreateInfo mv{VK_STRUCTURE_TYPE_RENDER_PASS_MULTIVIEW_CREATE_INFO};
  mv.subpassCount = 1;
  mv.pViewMasks = &view_mask;
  mv.correlationMaskCount = 1;
  mv.pCorrelationMasks = &view_mask;  // both views are nearly the same: a hint for the driver
  if (multiview_) rpci.pNext = &mv;
  RHOT_VK_CHECK(vkCreateRenderPass(ctx_.device(), &rpci, nullptr, &render_pass_));

  for (int i = 0; i < (multiview_ ? 1 : 2); ++i) {
    const std::array<VkImageView, 2> views{colour_views_[i], depth_views_[i]};
    VkFramebufferCreateInfo fci{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
    fci.renderPass = render_pass_;
    fci.attachmentCount = 2;
    fci.pAttachments = views.data();
    fci.width = static_cast<std::uint32_t>(width_);
    fci.height = static_cast<std::uint32_t>(height_);
    fci.layers = 1;  // with multiview the view mask, not the layer count, selects the layers
    RHOT_VK_CHECK(vkCreateFramebuffer(ctx_.device(), &fci, nullptr, &framebuffers_[i]));
  }
}

VkPipeline StereoPass::create_pipeline(std::span<const std::uint32_t> vert, std::span<const std::uint32_t> frag, bool lines) {
  const VkDevice d = ctx_.device();
  const auto module = [&](std::span<const std::uint32_t> code) {
    VkShaderModuleCreateInfo smci{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    smci.codeSize = code.size_bytes();
    smci.pCode = code.data();
    VkShaderModule m = VK_NULL_HANDLE;
    RHOT_VK_CHECK(vkCreateShaderModule(d, &smci, nullptr, &m));
    return m;
  };
  const VkShaderModule vs = module(vert);
  const VkShaderModule fs = module(frag);
  std::array<VkPipelineShaderStageCreateInfo, 2> stages{};
  stages[0] = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, nullptr, 0, VK_SHADER_STAGE_VERTEX_BIT, vs, "main", nullptr};
  stages[1] = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, nullptr, 0, VK_SHADER_STAGE_FRAGMENT_BIT, fs, "main", nullptr};

  std::vector<VkVertexInputBindingDescription> bindings;
  std::vector<VkVertexInputAttributeDescription> attributes;
  if (lines) {
    bindings.push_back({0, sizeof(LineVertex), VK_VERTEX_INPUT_RATE_VERTEX});
    attributes.push_back({0, 0, VK_FORMAT_R32G32B32_SFLOAT, offsetof(LineVertex, position)});
    attributes.push_back({1, 0, VK_FORMAT_R32G32B32A32_SFLOAT, offsetof(LineVertex, color)});
  } else {
    bindings.push_back({0, sizeof(Vertex), VK_VERTEX_INPUT_RATE_VERTEX});
    bindings.push_back({1, sizeof(GpuInstance), VK_VERTEX_INPUT_RATE_INSTANCE});
    attributes.push_back({0, 0, VK_FORMAT_R32G32B32_SFLOAT, offsetof(Vertex, position)});
    attributes.push_back({1, 0, VK_FORMAT_R32G32B32_SFLOAT, offsetof(Vertex, normal)});
    for (std::uint32_t i = 0; i < 8; ++i) {
      attributes.push_back({2 + i, 1, VK_FORMAT_R32G32B32A32_SFLOAT, i * 16});
    }
  }
  VkPipelineVertexInputStateCreateInfo vi{VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
  vi.vertexBindingDescriptionCount = static_cast<std::uint32_t>(bindings.size());
  vi.pVertexBindingDescriptions = bindings.data();
  vi.vertexAttributeDescriptionCount = static_cast<std::uint32_t>(attributes.size());
  vi.pVertexAttributeDescriptions = attributes.data();
  VkPipelineInputAssemblyStateCreateInfo ia{VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
  ia.topology = lines ? VK_PRIMITIVE_TOPOLOGY_LINE_LIST : VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
  VkPipelineViewportStateCreateInfo vp{VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
  vp.viewportCount = 1;
  vp.scissorCount = 1;
  VkPipelineRasterizationStateCreateInfo rs{VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
  rs.polygonMode = VK_POLYGON_MODE_FILL;
  // The projection flips y for Vulkan, so a triangle counter-clockwise in the world as seen by
  // the eye is counter-clockwise on screen too.
  rs.cullMode = lines ? VK_CULL_MODE_NONE : VK_CULL_MODE_BACK_BIT;
  rs.frontFace = VK_FRONT_FACE_COUNTER_CLOCKWISE;
  rs.lineWidth = 1.0f;
  VkPipelineMultisampleStateCreateInfo ms{VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
  ms.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT;
  VkPipelineDepthStencilStateCreateInfo ds{VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO};
  ds.depthTestEnable = VK_TRUE;
  ds.depthWriteEnable = VK_TRUE;
  ds.depthCompareOp = VK_COMPARE_OP_LESS_OR_EQUAL;
  VkPipelineColorBlendAttachmentState blend{};
  blend.colorWriteMask = VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT | VK_COLOR_COMPONENT_B_BIT | VK_COLOR_COMPONENT_A_BIT;
  VkPipelineColorBlendStateCreateInfo cb{VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
  cb.attachmentCount = 1;
  cb.pAttachments = &blend;
  const std::array<VkDynamicState, 2> dynamic{VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR};
  VkPipelineDynamicStateCreateInfo dyn{VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO};
  dyn.dynamicStateCount = static_cast<std::uint32_t>(dynamic.size());
  dyn.pDynamicStates = dynamic.data();

  VkGraphicsPipelineCreateInfo gci{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO};
  gci.stageCount = 2;
  gci.pStages = stages.data();
  gci.pVertexInputState = &vi;
  gci.pInputAssemblyState = &ia;
  gci.pViewportState = &vp;
  gci.pRasterizationState = &rs;
  gci.pMultisampleState = &ms;
  gci.pDepthStencilState = &ds;
  gci.pColorBlendState = &cb;
  gci.pDynamicState = &dyn;
  gci.layout = pipeline_layout_;
  gci.renderPass = render_pass_;
  VkPipeline pipeline = VK_NULL_HANDLE;
  RHOT_VK_CHECK(vkCreateGraphicsPipelines(d, VK_NULL_HANDLE, 1, &gci, nullptr, &pipeline));
  vkDestroyShaderModule(d, vs, nullptr);
  vkDestroyShaderModule(d, fs, nullptr);
  return pipeline;
}

void StereoPass::create_pipelines() {
  const VkDevice d = ctx_.device();
  VkDescriptorSetLayoutBinding binding{0, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT,
                                       nullptr};
  VkDescriptorSetLayoutCreateInfo slci{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  slci.bindingCount = 1;
  slci.pBindings = &binding;
  RHOT_VK_CHECK(vkCreateDescriptorSetLayout(d, &slci, nullptr, &set_layout_));
  const VkPushConstantRange push{VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof(std::uint32_t)};
  VkPipelineLayoutCreateInfo plci{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  plci.setLayoutCount = 1;
  plci.pSetLayouts = &set_layout_;
  plci.pushConstantRangeCount = 1;
  plci.pPushConstantRanges = &push;
  RHOT_VK_CHECK(vkCreatePipelineLayout(d, &plci, nullptr, &pipeline_layout_));

  const VkDescriptorPoolSize pool_size{VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1};
  VkDescriptorPoolCreateInfo dpci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  dpci.maxSets = 1;
  dpci.poolSizeCount = 1;
  dpci.pPoolSizes = &pool_size;
  RHOT_VK_CHECK(vkCreateDescriptorPool(d, &dpci, nullptr, &descriptor_pool_));
  VkDescriptorSetAllocateInfo dsai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
  dsai.descriptorPool = descriptor_pool_;
  dsai.descriptorSetCount = 1;
  dsai.pSetLayouts = &set_layout_;
  RHOT_VK_CHECK(vkAllocateDescriptorSets(d, &dsai, &descriptor_set_));
  frame_uniforms_ = ctx_.create_buffer(sizeof(FrameUniforms), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, true);
  const VkDescriptorBufferInfo info{frame_uniforms_.buffer, 0, sizeof(FrameUniforms)};
  VkWriteDescriptorSet write{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
  write.dstSet = descriptor_set_;
  write.dstBinding = 0;
  write.descriptorCount = 1;
  write.descriptorType = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
  write.pBufferInfo = &info;
  vkUpdateDescriptorSets(d, 1, &write, 0, nullptr);

  using Spirv = std::span<const std::uint32_t>;
  const auto pick = [this](Spirv two_pass, Spirv multiview) { return multiview_ ? multiview : two_pass; };
  // Vertex-lit meshes need only the interpolated colour passed through: line.frag does that.
  mesh_pipeline_ = vertex_lit_ ? create_pipeline(pick(shaders::kMeshVertLit, shaders::kMeshVertLitMultiview), shaders::kLineFrag, false)
                               : create_pipeline(pick(shaders::kMeshVert, shaders::kMeshVertMultiview), shaders::kMeshFrag, false);
  line_pipeline_ = create_pipeline(
      vertex_lit_ ? pick(shaders::kLineVertSrgb, shaders::kLineVertSrgbMultiview) : pick(shaders::kLineVert, shaders::kLineVertMultiview),
      shaders::kLineFrag, true);
}

void StereoPass::ensure_capacity(Buffer& buffer, VkDeviceSize bytes, VkBufferUsageFlags usage) {
  if (buffer.size >= bytes) return;
  ctx_.destroy(buffer);
  VkDeviceSize size = 64 * 1024;
  while (size < bytes) size *= 2;
  buffer = ctx_.create_buffer(size, usage, true);
}

std::size_t StereoPass::render(const FrameInput& frame, std::span<const GpuMesh> meshes,
                               const std::function<void(VkCommandBuffer, VkImage)>& extra, const SubmitSync& sync) {
  std::size_t skipped = 0;
  // ---- frame data into host-visible buffers, once the previous frame no longer reads them.
  finish();
  const FrameUniforms u = frame_uniforms(frame);
  std::memcpy(frame_uniforms_.mapped, &u, sizeof(u));
  std::size_t total = 0;
  for (const MeshBatch& b : frame.batches) total += b.instances.size();
  ensure_capacity(instances_, std::max<VkDeviceSize>(total, 1) * sizeof(GpuInstance), VK_BUFFER_USAGE_VERTEX_BUFFER_BIT);
  const std::vector<Draw> draws = write_instances(frame.batches, meshes, static_cast<GpuInstance*>(instances_.mapped), skipped);
  ensure_capacity(lines_, std::max<VkDeviceSize>(frame.lines.size(), 1) * sizeof(LineVertex), VK_BUFFER_USAGE_VERTEX_BUFFER_BIT);
  const std::uint32_t line_vertices = write_lines(frame.lines, static_cast<LineVertex*>(lines_.mapped), skipped);

  // ---- record
  RHOT_VK_CHECK(vkResetCommandBuffer(cmd_, 0));
  VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  RHOT_VK_CHECK(vkBeginCommandBuffer(cmd_, &begin));
  std::array<VkClearValue, 2> clears{};
  clears[0].color = {{clear_color_.r, clear_color_.g, clear_color_.b, clear_color_.a}};
  clears[1].depthStencil = {1.0f, 0};
  const VkViewport viewport{0.0f, 0.0f, static_cast<float>(width_), static_cast<float>(height_), 0.0f, 1.0f};
  const VkRect2D scissor{{0, 0}, {static_cast<std::uint32_t>(width_), static_cast<std::uint32_t>(height_)}};
  const int passes = multiview_ ? 1 : 2;
  if (timestamps_ != VK_NULL_HANDLE) {
    vkCmdResetQueryPool(cmd_, timestamps_, 0, 3);
    vkCmdWriteTimestamp(cmd_, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, timestamps_, 0);
  }
  for (int pass = 0; pass < passes; ++pass) {
    VkRenderPassBeginInfo rbi{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
    rbi.renderPass = render_pass_;
    rbi.framebuffer = framebuffers_[pass];
    rbi.renderArea = scissor;
    rbi.clearValueCount = static_cast<std::uint32_t>(clears.size());
    rbi.pClearValues = clears.data();
    vkCmdBeginRenderPass(cmd_, &rbi, VK_SUBPASS_CONTENTS_INLINE);
    vkCmdSetViewport(cmd_, 0, 1, &viewport);
    vkCmdSetScissor(cmd_, 0, 1, &scissor);
    const std::uint32_t eye = static_cast<std::uint32_t>(pass);
    vkCmdBindDescriptorSets(cmd_, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline_layout_, 0, 1, &descriptor_set_, 0, nullptr);
    vkCmdPushConstants(cmd_, pipeline_layout_, VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof(eye), &eye);
    draw_meshes(cmd_, mesh_pipeline_, instances_.buffer, draws);
    draw_lines(cmd_, line_pipeline_, lines_.buffer, line_vertices);
    vkCmdEndRenderPass(cmd_);
    if (timestamps_ != VK_NULL_HANDLE) {
      // Multiview: both eyes in the first interval, the second empty.
      const auto query = static_cast<std::uint32_t>(pass + 1);
      vkCmdWriteTimestamp(cmd_, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, timestamps_, query);
      if (passes == 1) vkCmdWriteTimestamp(cmd_, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, timestamps_, 2);
    }
  }
  timed_in_flight_ = timestamps_ != VK_NULL_HANDLE;
  if (extra) extra(cmd_, colour_.image);
  RHOT_VK_CHECK(vkEndCommandBuffer(cmd_));

  const VkSubmitInfo submit = submit_info(cmd_, sync);
  RHOT_VK_CHECK(vkQueueSubmit(ctx_.queue(), 1, &submit, fence_));
  submitted_s_ = steady_now_s();
  watch_.watch(fence_);
  in_flight_ = true;
  ++submitted_frames_;
  return skipped;
}

void StereoPass::finish() {
  if (!in_flight_) return;
  FrameCompletion done;
  done.frame = submitted_frames_ - 1;
  done.submitted_s = submitted_s_;
  done.done_s = watch_.wait();
  // Whatever the watch saw (a lost device too), the fence's own status says what happened.
  RHOT_VK_CHECK(vkGetFenceStatus(ctx_.device(), fence_));
  RHOT_VK_CHECK(vkResetFences(ctx_.device(), 1, &fence_));
  in_flight_ = false;
  if (timed_in_flight_) {
    std::array<std::uint64_t, 3> ticks{};
    if (vkGetQueryPoolResults(ctx_.device(), timestamps_, 0, 3, sizeof(ticks), ticks.data(), sizeof(std::uint64_t),
                              VK_QUERY_RESULT_64_BIT) == VK_SUCCESS) {
      const auto ms = [&](std::uint64_t from, std::uint64_t to) {
        return to >= from ? static_cast<double>(to - from) * timestamp_period_ns_ * 1e-6 : 0.0;
      };
      done.gpu_eye_ms = {ms(ticks[0], ticks[1]), ms(ticks[1], ticks[2])};
    }
    timed_in_flight_ = false;
  }
  completed_ = done;
}

bool StereoPass::enable_gpu_timings() {
  if (timestamps_ != VK_NULL_HANDLE) return true;
  VkPhysicalDeviceProperties props{};
  vkGetPhysicalDeviceProperties(ctx_.physical_device(), &props);
  std::uint32_t families = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(ctx_.physical_device(), &families, nullptr);
  std::vector<VkQueueFamilyProperties> family(families);
  vkGetPhysicalDeviceQueueFamilyProperties(ctx_.physical_device(), &families, family.data());
  if (props.limits.timestampPeriod <= 0.0f || ctx_.queue_family() >= families || family[ctx_.queue_family()].timestampValidBits == 0) {
    return false;
  }
  VkQueryPoolCreateInfo qci{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
  qci.queryType = VK_QUERY_TYPE_TIMESTAMP;
  qci.queryCount = 3;
  if (vkCreateQueryPool(ctx_.device(), &qci, nullptr, &timestamps_) != VK_SUCCESS) return false;
  timestamp_period_ns_ = static_cast<double>(props.limits.timestampPeriod);
  return true;
}

std::array<Image, 2> StereoPass::read_back() {
  finish();
  const auto w = static_cast<std::uint32_t>(width_);
  const auto h = static_cast<std::uint32_t>(height_);
  ctx_.run_once([&](VkCommandBuffer cmd) {
    std::array<VkBufferImageCopy, 2> regions{};
    for (std::uint32_t layer = 0; layer < 2; ++layer) {
      regions[layer].bufferOffset = VkDeviceSize{layer} * w * h * 4;
      regions[layer].imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, layer, 1};
      regions[layer].imageExtent = {w, h, 1};
    }
    vkCmdCopyImageToBuffer(cmd, colour_.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, readback_.buffer, 2, regions.data());
    VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    barrier.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    barrier.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &barrier, 0, nullptr, 0, nullptr);
  });
  std::array<Image, 2> eyes{Image(width_, height_), Image(width_, height_)};
  const std::size_t bytes = std::size_t{w} * h * 4;
  for (std::size_t layer = 0; layer < 2; ++layer) {
    std::memcpy(eyes[layer].rgba.data(), static_cast<const std::uint8_t*>(readback_.mapped) + layer * bytes, bytes);
  }
  return eyes;
}

}  // namespace rhot::vk
