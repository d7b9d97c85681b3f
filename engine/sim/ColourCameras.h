#pragma once
// Simulated colour cameras that look like the real thing: each camera of a rig sees the scene
// drawn by rhot's own Vulkan renderer (engine/render/Renderer.h) from its calibrated pose and
// intrinsics: the scene's table and objects (clutter of every colour, some of them the markers'
// own), the hands in skin colour (a sphere per joint, a cylinder per bone, a slab for the palm),
// and the coloured marker spheres, lit by one light and ambient. Then what a cheap sensor adds:
// the lens's distortion (OpenCV's model, by remapping the pinhole image), a little blur, the
// light's colour against a camera balanced for daylight (white_balance_gains), exposure and noise.
//
// For evaluation the same cameras also draw an identity image: every marker in a colour of its
// own, everything else black, distorted the same way, so each marker's visible pixels are known
// with the hands and objects hiding it (render_ids, marker_visibility).
//
// Every camera must have the same image size (the renderer's two eyes are two cameras: a frame of
// N cameras is ceil(N / 2) render passes). Precondition everywhere: finite inputs.

#include <cstdint>
#include <expected>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "engine/core/World.h"
#include "engine/render/Renderer.h"
#include "engine/render/SceneRenderer.h"
#include "engine/scene/SceneDesc.h"
#include "tracking/camera/Camera.h"
#include "tracking/core/Rigid3.h"
#include "tracking/detect/ColourDetector.h"
#include "tracking/hand/HandJoints.h"
#include "tracking/source/FrameSource.h"

namespace rhot {

struct ColourCameraSettings {
  double noise_sigma = 2.0;     // per channel, levels
  double kelvin = 6500.0;       // the light; the cameras stay balanced for 6500 K
  double exposure = 1.0;        // every pixel scaled by this
  double blur_sigma_px = 0.6;   // the lens and the sensor's demosaicing
  bool clutter = true;          // the scene's objects; off: only its table and floor
  std::string device = "auto";  // the Vulkan device (RendererSettings::device)
  std::uint64_t seed = 1;       // for the noise

  // Every value usable: "<field>: <what was expected>, got <value>" for the first that is not.
  [[nodiscard]] std::expected<void, std::string> check() const;
};

struct ColourMarker {
  Eigen::Vector3d centre_m{0, 0, 0};
  double radius_m = 0.007;
  int colour = 0;  // tracking/core/MarkerColour.h
};

struct ColourHand {
  Rigid3d world_from_hand;
  HandPose pose;  // hand frame
};

// What the cameras photograph at one moment.
struct ColourShot {
  std::vector<ColourMarker> markers;
  std::vector<ColourHand> hands;
};

// A marker as one camera sees it: its visible pixels in the identity image and where its centre
// projects (distorted pixel), with the pixels its whole disc would cover unhidden.
struct MarkerView {
  int visible_px = 0;
  double disc_px = 0.0;         // pi r^2 of its projected radius: what it covers when nothing hides it
  Eigen::Vector2d pixel{0, 0};  // its centre projected (valid when in_front)
  bool in_front = false;
};

class ColourCameras {
 public:
  // Fails naming the problem: bad settings, cameras of different sizes, no Vulkan device.
  [[nodiscard]] static std::expected<std::unique_ptr<ColourCameras>, std::string> create(const CameraRig& rig, const SceneDesc& scene,
                                                                                         ColourCameraSettings settings = {});
  ~ColourCameras();

  // One 8-bit BGR image (CV_8UC3) per camera, in rig order; `frame` picks the noise.
  std::vector<cv::Mat> render(const ColourShot& shot, std::uint64_t frame);
  // Per camera an identity image (CV_32SC1): 1 + the marker's index where a marker is seen, else 0.
  std::vector<cv::Mat> render_ids(const ColourShot& shot);
  // Per camera, per marker: what render_ids shows of it.
  std::vector<std::vector<MarkerView>> marker_visibility(const ColourShot& shot);

  const CameraRig& rig() const { return rig_; }
  const RendererInfo& renderer_info() const;

 private:
  ColourCameras() = default;
  std::vector<Image> draw(const ColourShot& shot, bool ids);

  CameraRig rig_;
  ColourCameraSettings settings_;
  std::unique_ptr<Renderer> renderer_;
  std::unique_ptr<SceneRenderer> scene_renderer_;
  World world_;  // the scene's table, floor and (with clutter) objects, where the scene puts them
  MeshHandle sphere_, box_;
  double render_f_scale_ = 0.9;         // the pinhole image's focal length over the camera's, for a margin to distort into
  std::vector<cv::Mat> map_x_, map_y_;  // per camera: distorted pixel -> pinhole image pixel
  // render's working images, kept from frame to frame (about 9 MB a camera at 640 x 480, which
  // allocated anew each frame cost a page fault per page).
  cv::Mat distorted_, light_, noise_;
};

// A frame source of simulated colour cameras: at each moment the shot the world gives is rendered
// (ColourCameras::render) and each camera's image goes through its own ColourDetector, which
// follows its markers from image to image, as a real colour camera's frames would. The frames
// carry the markers' true positions (the shot's order) for evaluation; detections carry no truth.
class ColourCameraSource final : public FrameSource {
 public:
  // `shoot` gives what the cameras see at a moment. Precondition: model.check() and detector.check() pass.
  ColourCameraSource(std::unique_ptr<ColourCameras> cameras, std::function<ColourShot(double t_s)> shoot, const ColourModel& model,
                     ColourDetectorSettings detector = {});
  std::optional<RigFrame> next(double t_s) override;
  const CameraRig& rig() const override { return cameras_->rig(); }
  std::vector<std::string> summary() const override;

  ColourCameras& cameras() { return *cameras_; }
  const std::vector<cv::Mat>& last_images() const { return images_; }
  const ColourShot& last_shot() const { return shot_; }
  double last_render_ms() const { return render_ms_; }
  double last_detect_ms() const { return detect_ms_; }  // all cameras

 private:
  std::unique_ptr<ColourCameras> cameras_;
  std::function<ColourShot(double)> shoot_;
  std::vector<ColourDetector> detectors_;
  std::vector<cv::Mat> images_;
  ColourShot shot_;
  std::uint64_t index_ = 0;
  double render_ms_ = 0.0, detect_ms_ = 0.0, render_total_ms_ = 0.0, detect_total_ms_ = 0.0;
};

}  // namespace rhot
