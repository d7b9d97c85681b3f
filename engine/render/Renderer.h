#pragma once
// The stereo renderer: both eyes of a headset drawn into a two-layer colour target (layer 0 the
// left eye, layer 1 the right), either in one multiview pass or in one pass per eye; read back to
// the CPU for PNG capture, or shown side by side in a desktop window.
//
// This header is the whole interface to the GPU: no Vulkan or GLFW type crosses it (the backend
// lives in engine/render/vk/). Errors at start-up (no Vulkan, no device, no display) come back as
// messages; the frame loop never sees a failed frame except through a device loss, which stops
// the program with a message.

#include <array>
#include <cstdint>
#include <expected>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "engine/render/Image.h"
#include "engine/mesh/MeshData.h"
#include "engine/render/StereoCamera.h"

namespace rhot {

class Window;
class XrHeadset;

enum class StereoMode {
  kAuto,       // multiview where the start-up self-test shows the driver gets it right, else two passes
  kMultiview,  // one pass with VK_KHR_multiview, even if the self-test fails (for measurements)
  kTwoPass,    // one render pass per eye
};

// Where the Lambert lighting is evaluated. On a CPU driver (lavapipe) the per-pixel work is most
// of a frame: lighting per vertex, and encoding sRGB in the shader rather than in the target,
// halves a 1080 x 1200 frame there (docs/PERFORMANCE.md). Flat faces (the table, the floor,
// boxes) come out the same either way, within one level of rounding; curved ones get the diffuse
// term interpolated across each triangle (Gouraud shading) rather than evaluated per pixel.
enum class Shading {
  kAuto,       // per vertex on a CPU driver, per pixel on a GPU
  kPerPixel,   // lit per pixel; the _SRGB render target encodes
  kPerVertex,  // lit and sRGB-encoded per vertex, drawn through a _UNORM view of the same target
};

struct RendererSettings {
  int eye_width_px = 1080;
  int eye_height_px = 1200;
  // Which Vulkan device: "auto" (a discrete GPU if there is one, then integrated, virtual, and
  // last the CPU driver), "gpu" (any non-CPU device, or fail), "cpu" (the CPU driver, lavapipe),
  // a device index from the log, or part of a device name. Where this is "auto", the environment
  // variable RHOT_VK_DEVICE, if set, chooses instead.
  std::string device = "auto";
  StereoMode stereo = StereoMode::kAuto;
  Shading shading = Shading::kAuto;
  // Enable VK_LAYER_KHRONOS_validation and count its messages (validation_messages()). Also
  // switched on by the environment variable RHOT_VK_VALIDATION=1.
  bool validation = false;
  glm::vec4 clear_color{0.55f, 0.62f, 0.70f, 1.0f};  // linear RGBA
  // GPU timestamps around each eye's pass (FrameCompletion::gpu_eye_ms), where the device has
  // them; info().gpu_timings says whether it did.
  bool gpu_timings = false;

  [[nodiscard]] std::expected<void, std::string> check() const;
};

// A mesh uploaded to the GPU. Valid for the renderer's lifetime.
struct MeshHandle {
  std::uint32_t index = ~0u;
};

struct MeshInstance {
  glm::mat4 world_from_local{1.0f};
  glm::vec4 color{0.8f, 0.8f, 0.8f, 1.0f};  // linear RGBA
};

struct MeshBatch {
  MeshHandle mesh;
  std::vector<MeshInstance> instances;  // drawn with one instanced call
};

struct LineVertex {
  glm::vec3 position{0.0f};  // world, metres
  glm::vec4 color{1.0f};     // linear RGBA
};

// Everything one frame draws. Matrices and positions must be finite (the renderer checks, and
// skips an instance or line that is not, logging once).
struct FrameInput {
  StereoViews views;
  std::vector<MeshBatch> batches;
  std::vector<LineVertex> lines;                                               // pairs: a line list (ground grid, debug draw)
  glm::vec3 light_dir_world = glm::normalize(glm::vec3(-0.4f, -1.0f, -0.3f));  // direction light travels
  glm::vec3 light_color{0.85f, 0.85f, 0.8f};
  float ambient = 0.3f;
};

struct RendererInfo {
  std::string device_name;
  bool cpu_device = false;  // lavapipe or another CPU implementation
  bool validation_enabled = false;
  bool multiview_supported = false;
  bool multiview_self_test_passed = false;  // meaningful where multiview_supported
  StereoMode mode = StereoMode::kTwoPass;   // what is actually used: kMultiview or kTwoPass
  Shading shading = Shading::kPerPixel;     // what is actually used: kPerPixel or kPerVertex
  bool gpu_timings = false;                 // asked for, and the device has timestamps
  bool headset = false;                     // drawing into an OpenXR runtime's swapchains
};

// A frame the GPU has finished drawing: when it was submitted and when it was done, on the steady
// clock (seconds), measured by a thread that waits for its fence (vk/FenceWatch.h).
struct FrameCompletion {
  std::uint64_t frame = 0;  // render() calls before it
  double submitted_s = 0.0;
  double done_s = 0.0;
  // With RendererSettings::gpu_timings: the GPU's own time per eye from timestamps around each
  // eye's pass (multiview draws both in one pass: all of it in eye 0). 0 otherwise.
  std::array<double, 2> gpu_eye_ms{};
};

class Renderer {
 public:
  // Creates the renderer for offscreen rendering, or (with a window) also for presenting into
  // it, or (with a headset) for drawing into its OpenXR runtime's swapchains, the window (if any)
  // then a desktop mirror. With a headset, its runtime makes the Vulkan instance and device
  // (XR_KHR_vulkan_enable2), the eyes take the runtime's recommended size, and the session starts;
  // the headset must outlive the renderer. Fails with a message where there is no Vulkan, no
  // suitable device, the window cannot get a swapchain or the runtime refuses the session.
  [[nodiscard]] static std::expected<std::unique_ptr<Renderer>, std::string> create(const RendererSettings& settings,
                                                                                    Window* window = nullptr, XrHeadset* headset = nullptr);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  const RendererInfo& info() const;
  int eye_width_px() const;
  int eye_height_px() const;

  // Uploads a mesh. Precondition: a valid MeshData (indices in range, three per triangle).
  MeshHandle upload_mesh(const MeshData& mesh);

  // The headset it draws for (null without).
  XrHeadset* headset() const;

  // Draws both eyes: waits for the previous frame to be drawn, then records and submits this one
  // and returns without waiting for it, so the caller's next frame (tracking, physics) runs while
  // the driver draws this one. One frame is in flight at most: the next render(), read_eyes(),
  // read_eye() or finish() waits for it. With a window, also shows both eyes side by side in it
  // (unless it is minimised). With a headset whose frame has begun (XrHeadset::begin_frame), also
  // copies both eyes into its swapchains and ends the frame with them (frame.views must be those
  // XrHeadset::locate_views gave for it), or ends it with nothing where the runtime said not to
  // render.
  void render(const FrameInput& frame);

  // Waits until the last rendered frame has been drawn (and presented, with a window).
  void finish();

  // The last frame known to be drawn (render() waits for the one before it; finish() for the
  // last); nothing before the first. Its frame number counts render() calls from 0.
  const std::optional<FrameCompletion>& last_completed() const;
  // render() calls so far.
  std::uint64_t frames_submitted() const;

  // Copies the last rendered frame of one eye (or both) to the CPU, waiting for it first.
  Image read_eye(int eye);
  std::array<Image, 2> read_eyes();

  // Validation-layer warnings and errors so far (0 when validation is off).
  std::uint64_t validation_messages() const;

  // Time of the last render(): waiting for the frame before it, recording and submitting (not
  // drawing it: that overlaps the caller's next frame).
  double last_render_ms() const;

  // With a window: Dear ImGui over the desktop window, taking the window's mouse and keyboard.
  // The eyes (and PNG captures) never contain it. Fails without a window or where Dear ImGui
  // cannot start (one overlay per process).
  [[nodiscard]] std::expected<void, std::string> enable_overlay();
  bool overlay_enabled() const;
  // Starts the overlay's next frame: Dear ImGui calls (imgui.h) may follow until render(), which
  // draws them over the window. Returns false, and starts nothing, without the overlay.
  bool begin_overlay();
  // Vertices the overlay drew into the last presented frame.
  std::uint64_t overlay_vertices() const;

  // With a window: the next presented frame is also copied to the CPU as the window shows it (both
  // eyes side by side and the overlay); window_image() holds it afterwards. Fails without a
  // window or where the window's surface cannot be read back.
  [[nodiscard]] std::expected<void, std::string> capture_window();
  const Image& window_image() const;

  // With a window: how often its swapchain was (re)created, and its current size in pixels.
  std::uint64_t swapchain_recreations() const;
  std::pair<int, int> swapchain_extent() const;

 private:
  struct Impl;
  explicit Renderer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

const char* to_string(StereoMode mode);
const char* to_string(Shading shading);  // "auto", "pixel" or "vertex"
// The inverse of to_string(Shading), for command lines; nullopt for anything else.
std::optional<Shading> shading_from_string(std::string_view name);

}  // namespace rhot
