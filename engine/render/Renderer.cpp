#include "engine/render/Renderer.h"

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <thread>

#define GLFW_INCLUDE_NONE
#include <vulkan/vulkan.h>
#include <GLFW/glfw3.h>
#include <spdlog/spdlog.h>

#include "engine/render/Window.h"
#include "engine/render/XrHeadset.h"
#include "engine/render/vk/StereoPass.h"
#include "engine/render/vk/Overlay.h"
#include "engine/render/vk/Swapchain.h"
#include "engine/render/vk/VulkanContext.h"
#include "engine/render/vk/XrBinding.h"

namespace rhot {

const char* to_string(StereoMode mode) {
  switch (mode) {
    case StereoMode::kAuto:
      return "auto";
    case StereoMode::kMultiview:
      return "multiview";
    case StereoMode::kTwoPass:
      return "two-pass";
  }
  return "?";
}

const char* to_string(Shading shading) {
  switch (shading) {
    case Shading::kAuto:
      return "auto";
    case Shading::kPerPixel:
      return "pixel";
    case Shading::kPerVertex:
      return "vertex";
  }
  return "?";
}

std::optional<Shading> shading_from_string(std::string_view name) {
  for (const Shading s : {Shading::kAuto, Shading::kPerPixel, Shading::kPerVertex}) {
    if (name == to_string(s)) return s;
  }
  return std::nullopt;
}

std::expected<void, std::string> RendererSettings::check() const {
  if (eye_width_px < 16 || eye_width_px > 8192 || eye_height_px < 16 || eye_height_px > 8192) {
    return std::unexpected("eye size must be 16 to 8192 pixels each way, got " + std::to_string(eye_width_px) + "x" +
                           std::to_string(eye_height_px));
  }
  for (int c = 0; c < 4; ++c) {
    if (!std::isfinite(clear_color[c]) || clear_color[c] < 0.0f || clear_color[c] > 1.0f) {
      return std::unexpected(std::string("clear colour components must be in [0, 1]"));
    }
  }
  return {};
}

struct Renderer::Impl {
  std::unique_ptr<vk::Context> context;
  std::vector<vk::GpuMesh> meshes;
  std::unique_ptr<vk::StereoPass> pass;
  std::unique_ptr<vk::Swapchain> swapchain;
  std::unique_ptr<vk::Overlay> overlay;
  Window* window = nullptr;
  XrHeadset* headset = nullptr;
  bool capture_window = false;
  vk::Buffer window_buffer;
  Image window_image;
  RendererInfo info;
  double last_render_ms = 0.0;
  bool warned_non_finite = false;

  ~Impl() {
    if (pass) pass->finish();  // the frame in flight may use the overlay's and swapchain's objects
    overlay.reset();
    swapchain.reset();
    pass.reset();
    if (context) vkDeviceWaitIdle(context->device());
    if (headset) headset->impl().stop();  // the session and its swapchains go before the device
    if (context) {
      vkDeviceWaitIdle(context->device());
      context->destroy(window_buffer);
      for (vk::GpuMesh& m : meshes) context->destroy(m);
    }
  }
};

namespace {

// Renders, at 64 x 64 and with both eyes given the same view, one large triangle that crosses
// the sides of the frustum, in a multiview pass, and compares the two layers. Mesa's lavapipe in
// Debian 12 (22.3.6) drops such geometry from view 1; a correct driver gives identical layers.
bool multiview_self_test(const vk::Context& context) {
  vk::StereoPass probe(context, 64, 64, /*multiview=*/true, /*vertex_lit=*/false, glm::vec4(0.0f, 0.0f, 0.0f, 1.0f));
  MeshData triangle;
  triangle.vertices = {{{-50.0f, -1.0f, -2.0f}, {0, 0, 1}}, {{50.0f, -1.0f, -2.0f}, {0, 0, 1}}, {{0.0f, 1.0f, -2.0f}, {0, 0, 1}}};
  triangle.indices = {0, 1, 2};
  vk::GpuMesh mesh = context.upload_mesh(triangle.vertices.data(), triangle.vertices.size() * sizeof(Vertex), triangle.indices.data(), 3);
  FrameInput frame;
  HeadsetSettings symmetric;
  symmetric.ipd_m = 0.0;
  symmetric.left_eye = symmetric.right_eye = EyeFovDeg{45, 45, 45, 45};
  frame.views = stereo_views(glm::mat4(1.0f), symmetric);
  frame.batches.push_back({MeshHandle{0}, {MeshInstance{glm::mat4(1.0f), glm::vec4(1.0f)}}});
  frame.ambient = 1.0f;
  probe.render(frame, std::span<const vk::GpuMesh>(&mesh, 1));
  const auto eyes = probe.read_back();
  context.destroy(mesh);
  int covered[2] = {0, 0};
  int differing = 0;
  for (std::size_t i = 0; i < eyes[0].rgba.size(); i += 4) {
    const bool a = eyes[0].rgba[i] > 128;
    const bool b = eyes[1].rgba[i] > 128;
    covered[0] += a ? 1 : 0;
    covered[1] += b ? 1 : 0;
    differing += a != b ? 1 : 0;
  }
  spdlog::debug("multiview self-test: {} and {} pixels covered, {} differ", covered[0], covered[1], differing);
  return covered[0] > 500 && differing == 0;
}

}  // namespace

std::expected<std::unique_ptr<Renderer>, std::string> Renderer::create(const RendererSettings& requested, Window* window,
                                                                       XrHeadset* headset) {
  if (auto ok = requested.check(); !ok) return std::unexpected(ok.error());
  RendererSettings settings = requested;
  if (headset != nullptr) {
    const XrHeadsetInfo& xr = headset->info();
    if (xr.recommended_width_px < 16 || xr.recommended_width_px > 8192 || xr.recommended_height_px < 16 ||
        xr.recommended_height_px > 8192) {
      return std::unexpected("the headset's recommended eye size " + std::to_string(xr.recommended_width_px) + "x" +
                             std::to_string(xr.recommended_height_px) + " is outside 16 to 8192 pixels");
    }
    settings.eye_width_px = xr.recommended_width_px;
    settings.eye_height_px = xr.recommended_height_px;
  }
  // Mesa's CPU driver rasterises on worker threads and the frame waits for them. On two cores
  // those threads fight tracking and physics for the CPU, and the hand-off costs more than the
  // parallelism gains (measured: 540 x 600 per eye, the whole frame 11.9 ms p50 with workers,
  // 6.6 ms drawing on the frame's own thread; docs/PERFORMANCE.md). So on a machine with two
  // cores or fewer the driver draws on the calling thread, unless LP_NUM_THREADS says otherwise.
  // (It must be set before the driver loads; it changes nothing for GPU drivers.)
  if (std::getenv("LP_NUM_THREADS") == nullptr && std::thread::hardware_concurrency() <= 2) {
    setenv("LP_NUM_THREADS", "0", 0);
    spdlog::info("two CPU cores or fewer: a CPU Vulkan driver draws on the frame's thread (LP_NUM_THREADS=0)");
  }
  auto impl = std::make_unique<Impl>();
  vk::Context::Options options;
  options.device = settings.device;
  options.validation = settings.validation;
  if (window != nullptr) {
    std::uint32_t count = 0;
    const char** names = glfwGetRequiredInstanceExtensions(&count);
    if (names == nullptr) return std::unexpected(std::string("GLFW cannot present Vulkan images on this display"));
    for (std::uint32_t i = 0; i < count; ++i) options.instance_extensions.emplace_back(names[i]);
    options.make_surface = [window](VkInstance instance) -> std::expected<VkSurfaceKHR, std::string> {
      VkSurfaceKHR surface = VK_NULL_HANDLE;
      const VkResult r = glfwCreateWindowSurface(instance, static_cast<GLFWwindow*>(window->native_handle()), nullptr, &surface);
      if (r != VK_SUCCESS) return std::unexpected(std::string("cannot create a Vulkan surface for the window: ") + vk::result_string(r));
      return surface;
    };
  }
  if (headset != nullptr) {
    XrHeadset::Impl* xr = &headset->impl();
    options.make_instance = [xr](const VkInstanceCreateInfo& info) { return xr->make_instance(info); };
    options.physical_device = [xr](VkInstance instance) { return xr->physical_device(instance); };
    options.make_device = [xr](VkPhysicalDevice physical, const VkDeviceCreateInfo& info) { return xr->make_device(physical, info); };
  }
  auto context = vk::Context::create(options);
  if (!context) return std::unexpected(context.error());
  impl->context = std::move(*context);
  RendererInfo& info = impl->info;
  info.device_name = impl->context->device_name();
  info.cpu_device = impl->context->cpu_device();
  info.validation_enabled = impl->context->validation_enabled();
  info.multiview_supported = impl->context->multiview_supported();

  bool multiview = false;
  if (info.multiview_supported && settings.stereo != StereoMode::kTwoPass) {
    info.multiview_self_test_passed = multiview_self_test(*impl->context);
    if (settings.stereo == StereoMode::kMultiview) {
      multiview = true;
      if (!info.multiview_self_test_passed) {
        spdlog::warn("multiview forced although its self-test failed on {}: the right eye may miss geometry", info.device_name);
      }
    } else if (info.multiview_self_test_passed) {
      multiview = true;
    } else {
      spdlog::warn(
          "multiview self-test failed on {} (the second view drops geometry that crosses the frustum edge); "
          "drawing the eyes in two passes instead",
          info.device_name);
    }
  } else if (settings.stereo == StereoMode::kMultiview) {
    return std::unexpected(info.device_name + " has no multiview support (VK_KHR_multiview); use two-pass");
  }
  info.mode = multiview ? StereoMode::kMultiview : StereoMode::kTwoPass;
  info.shading = settings.shading != Shading::kAuto ? settings.shading : info.cpu_device ? Shading::kPerVertex : Shading::kPerPixel;
  impl->pass = std::make_unique<vk::StereoPass>(*impl->context, settings.eye_width_px, settings.eye_height_px, multiview,
                                                info.shading == Shading::kPerVertex, settings.clear_color);
  if (settings.gpu_timings) {
    info.gpu_timings = impl->pass->enable_gpu_timings();
    if (!info.gpu_timings) spdlog::warn("renderer: GPU timings asked for, but the device's queue has no timestamps");
  }
  if (window != nullptr) {
    impl->window = window;
    impl->swapchain = std::make_unique<vk::Swapchain>(*impl->context);
  }
  if (headset != nullptr) {
    // One two-layer swapchain where both eyes are drawn in one multiview pass, else one per eye.
    impl->headset = headset;  // from here on, a failure ends what start() made before the device goes
    if (auto started = headset->impl().start(*impl->context, multiview); !started) return std::unexpected(started.error());
    info.headset = true;
  }
  spdlog::info("renderer: {} x {} per eye, {}, lit per {}", settings.eye_width_px, settings.eye_height_px, to_string(info.mode),
               to_string(info.shading));
  return std::unique_ptr<Renderer>(new Renderer(std::move(impl)));
}

Renderer::Renderer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Renderer::~Renderer() = default;

const RendererInfo& Renderer::info() const { return impl_->info; }
XrHeadset* Renderer::headset() const { return impl_->headset; }
int Renderer::eye_width_px() const { return impl_->pass->width(); }
int Renderer::eye_height_px() const { return impl_->pass->height(); }
std::uint64_t Renderer::validation_messages() const { return impl_->context->validation_messages(); }
double Renderer::last_render_ms() const { return impl_->last_render_ms; }

MeshHandle Renderer::upload_mesh(const MeshData& mesh) {
  RHOT_PRECONDITION(!mesh.vertices.empty() && !mesh.indices.empty() && mesh.indices.size() % 3 == 0,
                    "Renderer::upload_mesh: a mesh needs vertices and whole triangles");
  for (const std::uint32_t i : mesh.indices) {
    RHOT_PRECONDITION(i < mesh.vertices.size(), "Renderer::upload_mesh: index out of range");
  }
  impl_->meshes.push_back(impl_->context->upload_mesh(mesh.vertices.data(), mesh.vertices.size() * sizeof(Vertex), mesh.indices.data(),
                                                      static_cast<std::uint32_t>(mesh.indices.size())));
  return MeshHandle{static_cast<std::uint32_t>(impl_->meshes.size() - 1)};
}

void Renderer::render(const FrameInput& frame) {
  const auto start = std::chrono::steady_clock::now();
  Impl& m = *impl_;
  std::size_t skipped = 0;
  bool presented = false;
  // The previous frame must be drawn before its swapchain semaphores, overlay buffers or
  // (after a resize) swapchain images are touched again.
  m.pass->finish();
  if (m.overlay) m.overlay->end_frame();
  XrHeadset::Impl* xr = m.headset ? &m.headset->impl() : nullptr;
  const bool to_headset = xr != nullptr && xr->acquire();
  const auto copy_to_headset = [&](VkCommandBuffer cmd, VkImage eyes) {
    if (to_headset) xr->record_copy(cmd, eyes, m.pass->width(), m.pass->height());
  };
  if (m.swapchain && m.swapchain->prepare(m.window->framebuffer_size())) {
    if (m.swapchain->acquire()) {
      // The blit (and the overlay) wait for the acquired image at the transfer stage; the
      // overlay's colour writes come after the blit in the same command buffer.
      const VkPipelineStageFlags wait =
          m.overlay ? VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT : VK_PIPELINE_STAGE_TRANSFER_BIT;
      vk::SubmitSync sync{m.swapchain->acquired_semaphore(), wait, m.swapchain->ready_semaphore()};
      const int w = m.pass->width();
      const int h = m.pass->height();
      const auto [sw, sh] = m.swapchain->extent();
      const bool capture = m.capture_window && m.swapchain->copy_supported();
      const auto capture_bytes = static_cast<VkDeviceSize>(sw) * static_cast<VkDeviceSize>(sh) * 4;
      if (capture && m.window_buffer.size < capture_bytes) {
        m.context->destroy(m.window_buffer);
        m.window_buffer = m.context->create_buffer(capture_bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT, /*host_visible=*/true);
      }
      skipped = m.pass->render(
          frame, m.meshes,
          [&](VkCommandBuffer cmd, VkImage eyes) {
            copy_to_headset(cmd, eyes);
            m.swapchain->record_blit(cmd, eyes, w, h, m.overlay != nullptr);
            if (m.overlay) m.overlay->record(cmd, *m.swapchain);
            if (capture) m.swapchain->record_copy(cmd, m.window_buffer);
          },
          sync);
      if (capture) {
        m.pass->finish();
        m.window_image = Image(sw, sh);
        m.swapchain->read_copy(m.window_buffer, m.window_image.rgba);
        m.capture_window = false;
      }
      m.swapchain->present();
      presented = true;
    }
  }
  if (!presented) {
    skipped = to_headset ? m.pass->render(frame, m.meshes, copy_to_headset) : m.pass->render(frame, m.meshes);
  }
  if (xr != nullptr) xr->end_frame();  // with the copies submitted; with no layer where nothing was acquired
  if (skipped > 0 && !m.warned_non_finite) {
    spdlog::warn("renderer: skipped {} instance(s) or line(s) with non-finite values (warned once)", skipped);
    m.warned_non_finite = true;
  }
  m.last_render_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

std::array<Image, 2> Renderer::read_eyes() { return impl_->pass->read_back(); }

void Renderer::finish() { impl_->pass->finish(); }

const std::optional<FrameCompletion>& Renderer::last_completed() const { return impl_->pass->last_completed(); }
std::uint64_t Renderer::frames_submitted() const { return impl_->pass->frames_submitted(); }

Image Renderer::read_eye(int eye) {
  RHOT_PRECONDITION(eye == kLeftEye || eye == kRightEye, "Renderer::read_eye: eye is 0 (left) or 1 (right)");
  return std::move(read_eyes()[static_cast<std::size_t>(eye)]);
}

std::expected<void, std::string> Renderer::enable_overlay() {
  Impl& m = *impl_;
  if (m.overlay) return {};
  if (!m.swapchain) return std::unexpected(std::string("the overlay needs a window (the renderer is offscreen)"));
  auto overlay = vk::Overlay::create(*m.context, static_cast<GLFWwindow*>(m.window->native_handle()), m.swapchain->format());
  if (!overlay) return std::unexpected(overlay.error());
  m.overlay = std::move(*overlay);
  return {};
}

std::expected<void, std::string> Renderer::capture_window() {
  Impl& m = *impl_;
  if (!m.swapchain) return std::unexpected(std::string("no window to capture (the renderer is offscreen)"));
  m.capture_window = true;
  return {};
}

const Image& Renderer::window_image() const { return impl_->window_image; }

bool Renderer::overlay_enabled() const { return impl_->overlay != nullptr; }

bool Renderer::begin_overlay() {
  if (!impl_->overlay) return false;
  impl_->overlay->begin_frame();
  return true;
}

std::uint64_t Renderer::overlay_vertices() const { return impl_->overlay ? impl_->overlay->last_vertex_count() : 0; }

std::uint64_t Renderer::swapchain_recreations() const { return impl_->swapchain ? impl_->swapchain->recreations() : 0; }

std::pair<int, int> Renderer::swapchain_extent() const { return impl_->swapchain ? impl_->swapchain->extent() : std::pair<int, int>{0, 0}; }

}  // namespace rhot
