#include "engine/sim/ColourCameras.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <numbers>

#include <glm/gtc/matrix_transform.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "engine/core/Transform.h"
#include "engine/math/EigenGlm.h"
#include "engine/mesh/MeshData.h"
#include "engine/render/StereoCamera.h"
#include "engine/scene/SceneLoader.h"
#include "tracking/core/MarkerColour.h"
#include "tracking/sim/SyntheticImages.h"

namespace rhot {

namespace {

double linear_from_srgb(double c) { return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4); }
double srgb_from_linear(double l) { return l <= 0.0031308 ? 12.92 * l : 1.055 * std::pow(l, 1.0 / 2.4) - 0.055; }

glm::vec4 linear_colour(const std::array<double, 3>& srgb) {
  return {static_cast<float>(linear_from_srgb(srgb[0])), static_cast<float>(linear_from_srgb(srgb[1])),
          static_cast<float>(linear_from_srgb(srgb[2])), 1.0f};
}

constexpr int kEncodeSteps = 16384;  // linear light to sRGB by table: under 0.2 levels apart anywhere

const std::array<double, 3> kSkinSrgb{0.86, 0.66, 0.54};
const std::array<double, 3> kWallSrgb{0.72, 0.70, 0.66};

// The identity colour of marker i: red 0, green 4 (i mod 63 + 1), blue 4 (i / 63), as sRGB codes.
glm::vec4 id_colour(std::size_t i) {
  const auto code = [](double c) { return static_cast<float>(linear_from_srgb(c / 255.0)); };
  return {0.0f, code(4.0 * static_cast<double>(i % 63 + 1)), code(4.0 * static_cast<double>(i / 63)), 1.0f};
}

glm::mat4 glm_from(const Eigen::Matrix4d& m) {
  glm::mat4 g(1.0f);
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) g[c][r] = static_cast<float>(m(r, c));
  }
  return g;
}

}  // namespace

std::expected<void, std::string> ColourCameraSettings::check() const {
  const auto bad = [](const char* field, const char* expected, double value) {
    return std::unexpected(std::string(field) + ": expected " + expected + ", got " + std::to_string(value));
  };
  if (!std::isfinite(noise_sigma) || noise_sigma < 0.0 || noise_sigma > 50.0) return bad("noise_sigma", "0 to 50 levels", noise_sigma);
  if (!std::isfinite(kelvin) || kelvin < 1500.0 || kelvin > 15000.0) return bad("kelvin", "1500 to 15000 K", kelvin);
  if (!std::isfinite(exposure) || exposure < 0.05 || exposure > 4.0) return bad("exposure", "0.05 to 4", exposure);
  if (!std::isfinite(blur_sigma_px) || blur_sigma_px < 0.0 || blur_sigma_px > 5.0)
    return bad("blur_sigma_px", "0 to 5 pixels", blur_sigma_px);
  return {};
}

ColourCameras::~ColourCameras() = default;

const RendererInfo& ColourCameras::renderer_info() const { return renderer_->info(); }

std::expected<std::unique_ptr<ColourCameras>, std::string> ColourCameras::create(const CameraRig& rig, const SceneDesc& scene,
                                                                                 ColourCameraSettings settings) {
  if (auto ok = settings.check(); !ok) return std::unexpected("colour cameras: " + ok.error());
  if (rig.cameras.empty()) return std::unexpected(std::string("colour cameras: the rig has no cameras"));
  const int width = rig.cameras[0].intrinsics.width_px, height = rig.cameras[0].intrinsics.height_px;
  for (const Camera& c : rig.cameras) {
    if (c.intrinsics.width_px != width || c.intrinsics.height_px != height) {
      return std::unexpected("colour cameras: every camera must have one image size; \"" + c.name + "\" is " +
                             std::to_string(c.intrinsics.width_px) + "x" + std::to_string(c.intrinsics.height_px) + ", \"" +
                             rig.cameras[0].name + "\" " + std::to_string(width) + "x" + std::to_string(height));
    }
  }
  std::unique_ptr<ColourCameras> out(new ColourCameras());
  out->rig_ = rig;
  out->settings_ = settings;
  RendererSettings rs;
  rs.eye_width_px = width;
  rs.eye_height_px = height;
  rs.device = settings.device;
  rs.stereo = StereoMode::kTwoPass;
  rs.clear_color = linear_colour(kWallSrgb);
  auto renderer = Renderer::create(rs);
  if (!renderer) return std::unexpected("colour cameras: " + renderer.error());
  out->renderer_ = std::move(*renderer);
  SceneRenderSettings srs;
  srs.draw_grid = false;
  out->scene_renderer_ = std::make_unique<SceneRenderer>(*out->renderer_, srs);
  out->sphere_ = out->renderer_->upload_mesh(make_sphere(1.0f, 16, 8));
  out->box_ = out->renderer_->upload_mesh(make_box({1.0f, 1.0f, 1.0f}));
  // The scene's entities, where the scene puts them (without clutter: its floor and table only).
  SceneDesc props = scene;
  props.interactions.clear();
  if (!settings.clutter) {
    std::erase_if(props.entities, [](const EntityDesc& e) { return e.name.rfind("table", 0) != 0 && e.name != "floor"; });
  }
  for (EntityDesc& e : props.entities) {
    e.body.reset();
    e.parent.clear();
  }
  instantiate(props, out->world_);
  update_world_transforms(out->world_);
  // Per camera, where each distorted pixel's ray falls in the pinhole image.
  const double s = out->render_f_scale_;
  for (const Camera& c : rig.cameras) {
    cv::Mat mx(height, width, CV_32FC1), my(height, width, CV_32FC1);
    const double fx = s * c.intrinsics.fx, fy = s * c.intrinsics.fy, cx = (width - 1) / 2.0, cy = (height - 1) / 2.0;
    for (int v = 0; v < height; ++v) {
      for (int u = 0; u < width; ++u) {
        const Eigen::Vector2d n = c.undistort(Eigen::Vector2d(u, v));
        mx.at<float>(v, u) = static_cast<float>(fx * n.x() + cx);
        my.at<float>(v, u) = static_cast<float>(fy * n.y() + cy);
      }
    }
    out->map_x_.push_back(mx);
    out->map_y_.push_back(my);
  }
  return out;
}

std::vector<Image> ColourCameras::draw(const ColourShot& shot, bool ids) {
  const int width = rig_.cameras[0].intrinsics.width_px, height = rig_.cameras[0].intrinsics.height_px;
  std::vector<HandDrawInput> hands;
  std::vector<MeshInstance> palms, markers;
  const glm::vec4 skin = ids ? glm::vec4(0, 0, 0, 1) : linear_colour(kSkinSrgb);
  for (const ColourHand& h : shot.hands) {
    HandDrawInput d;
    for (std::size_t j = 0; j < kHandJointCount; ++j) {
      d.joint_world[j] = to_glm(h.world_from_hand * h.pose.position_m[j]);
      d.radius_m[j] = static_cast<float>(h.pose.radius_m[j]);
    }
    d.color = skin;
    hands.push_back(d);
    // The palm: a slab between the metacarpals, which joints and bones alone leave open.
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    m.topLeftCorner<3, 3>() = h.world_from_hand.rotation.toRotationMatrix() * Eigen::Vector3d(0.072, 0.022, 0.08).asDiagonal();
    m.topRightCorner<3, 1>() = h.world_from_hand * h.pose.position_m[static_cast<std::size_t>(HandJoint::kPalm)];
    palms.push_back({glm_from(m), skin});
  }
  for (std::size_t i = 0; i < shot.markers.size(); ++i) {
    const ColourMarker& mk = shot.markers[i];
    const auto r = static_cast<float>(mk.radius_m);
    const glm::mat4 t = glm::scale(glm::translate(glm::mat4(1.0f), to_glm(mk.centre_m)), glm::vec3(r));
    markers.push_back(
        {t, ids ? id_colour(i)
                : linear_colour(kMarkerColours[static_cast<std::size_t>(std::clamp(mk.colour, 0, kMarkerColourCount - 1))].display_srgb)});
  }
  // The cameras' pinhole views, two per pass.
  const double s = render_f_scale_;
  std::vector<Image> out(rig_.cameras.size());
  for (std::size_t first = 0; first < rig_.cameras.size(); first += 2) {
    StereoViews views;
    for (int eye = 0; eye < 2; ++eye) {
      const Camera& c = rig_.cameras[std::min(first + static_cast<std::size_t>(eye), rig_.cameras.size() - 1)];
      Eigen::Matrix4d cam = Eigen::Matrix4d::Identity();
      cam.topLeftCorner<3, 3>() = c.cam_from_world.rotation.toRotationMatrix();
      cam.topRightCorner<3, 1>() = c.cam_from_world.translation;
      const Eigen::Matrix4d flip = Eigen::Vector4d(1.0, -1.0, -1.0, 1.0).asDiagonal();
      views.eye_from_world[static_cast<std::size_t>(eye)] = glm_from(flip * cam);
      const double fx = s * c.intrinsics.fx, fy = s * c.intrinsics.fy, cx = (width - 1) / 2.0, cy = (height - 1) / 2.0;
      constexpr double kDeg = 180.0 / std::numbers::pi;
      EyeFovDeg fov;
      fov.left = std::atan((cx + 0.5) / fx) * kDeg;
      fov.right = std::atan((width - 0.5 - cx) / fx) * kDeg;
      fov.up = std::atan((cy + 0.5) / fy) * kDeg;
      fov.down = std::atan((height - 0.5 - cy) / fy) * kDeg;
      views.clip_from_eye[static_cast<std::size_t>(eye)] = projection_from_fov(fov, 0.02, 20.0);
    }
    FrameInput frame = scene_renderer_->build(world_, views, hands);
    if (ids) {  // everything that can hide a marker, black
      for (MeshBatch& batch : frame.batches) {
        for (MeshInstance& instance : batch.instances) instance.color = glm::vec4(0.0f, 0.0f, 0.0f, 1.0f);
      }
    }
    if (!palms.empty()) frame.batches.push_back({box_, palms});
    if (!markers.empty()) frame.batches.push_back({sphere_, markers});
    if (ids) {
      frame.ambient = 1.0f;
      frame.light_color = glm::vec3(0.0f);
    } else {
      frame.light_dir_world = glm::normalize(glm::vec3(0.3f, -1.0f, -0.4f));
      frame.light_color = glm::vec3(0.75f);
      frame.ambient = 0.35f;
    }
    renderer_->render(frame);
    auto eyes = renderer_->read_eyes();
    out[first] = std::move(eyes[0]);
    if (first + 1 < rig_.cameras.size()) out[first + 1] = std::move(eyes[1]);
  }
  return out;
}

std::vector<cv::Mat> ColourCameras::render(const ColourShot& shot, std::uint64_t frame) {
  const auto images = draw(shot, false);
  static const auto tables = [] {
    std::pair<std::array<float, 256>, std::vector<float>> t;
    for (int i = 0; i < 256; ++i) t.first[static_cast<std::size_t>(i)] = static_cast<float>(linear_from_srgb(i / 255.0));
    t.second.resize(kEncodeSteps + 1);  // linear 0-1 in kEncodeSteps steps -> sRGB 0-255
    for (int i = 0; i <= kEncodeSteps; ++i)
      t.second[static_cast<std::size_t>(i)] = static_cast<float>(255.0 * srgb_from_linear(i / static_cast<double>(kEncodeSteps)));
    return t;
  }();
  const auto& to_linear = tables.first;
  const auto& to_srgb = tables.second;
  const auto gain = white_balance_gains(settings_.kelvin);
  std::vector<cv::Mat> out;
  for (std::size_t c = 0; c < images.size(); ++c) {
    const Image& img = images[c];
    cv::Mat rgba(img.height, img.width, CV_8UC4, const_cast<std::uint8_t*>(img.rgba.data()));
    cv::remap(rgba, distorted_, map_x_[c], map_y_[c], cv::INTER_LINEAR, cv::BORDER_REPLICATE);
    // Linear light, the light's colour and the exposure, the blur, then back to sRGB with noise.
    light_.create(img.height, img.width, CV_32FC3);
    for (int y = 0; y < img.height; ++y) {
      const auto* p = distorted_.ptr<cv::Vec4b>(y);
      auto* l = light_.ptr<cv::Vec3f>(y);
      for (int x = 0; x < img.width; ++x) {
        for (int ch = 0; ch < 3; ++ch) {
          l[x][ch] = to_linear[p[x][ch]] * static_cast<float>(gain[static_cast<std::size_t>(ch)] * settings_.exposure);
        }
      }
    }
    if (settings_.blur_sigma_px > 0.0) cv::GaussianBlur(light_, light_, cv::Size(0, 0), settings_.blur_sigma_px);
    noise_.create(img.height, img.width, CV_32FC3);
    cv::RNG rng(settings_.seed * 1000003ULL + frame * 131ULL + c);
    rng.fill(noise_, cv::RNG::NORMAL, 0.0, settings_.noise_sigma);
    cv::Mat bgr(img.height, img.width, CV_8UC3);
    for (int y = 0; y < img.height; ++y) {
      const auto* l = light_.ptr<cv::Vec3f>(y);
      const auto* n = noise_.ptr<cv::Vec3f>(y);
      auto* o = bgr.ptr<cv::Vec3b>(y);
      for (int x = 0; x < img.width; ++x) {
        for (int ch = 0; ch < 3; ++ch) {
          const auto step = static_cast<std::size_t>(std::clamp(l[x][ch], 0.0f, 1.0f) * static_cast<float>(kEncodeSteps) + 0.5f);
          const float v = to_srgb[step] + n[x][ch];
          o[x][2 - ch] = static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
        }
      }
    }
    out.push_back(bgr);
  }
  return out;
}

std::vector<cv::Mat> ColourCameras::render_ids(const ColourShot& shot) {
  const auto images = draw(shot, true);
  std::vector<cv::Mat> out;
  for (std::size_t c = 0; c < images.size(); ++c) {
    const Image& img = images[c];
    cv::Mat rgba(img.height, img.width, CV_8UC4, const_cast<std::uint8_t*>(img.rgba.data()));
    cv::Mat distorted;
    cv::remap(rgba, distorted, map_x_[c], map_y_[c], cv::INTER_NEAREST, cv::BORDER_REPLICATE);
    cv::Mat ids(img.height, img.width, CV_32SC1, cv::Scalar(0));
    for (int y = 0; y < img.height; ++y) {
      const auto* p = distorted.ptr<cv::Vec4b>(y);
      auto* o = ids.ptr<int>(y);
      for (int x = 0; x < img.width; ++x) {
        if (p[x][0] > 1 || p[x][1] < 2) continue;  // the wall (red in it) or black
        const int g = (p[x][1] + 2) / 4, b = (p[x][2] + 2) / 4;
        o[x] = g + 63 * b;  // 1 + the marker's index
      }
    }
    out.push_back(ids);
  }
  return out;
}

std::vector<std::vector<MarkerView>> ColourCameras::marker_visibility(const ColourShot& shot) {
  const auto ids = render_ids(shot);
  std::vector<std::vector<MarkerView>> out(rig_.cameras.size(), std::vector<MarkerView>(shot.markers.size()));
  for (std::size_t c = 0; c < rig_.cameras.size(); ++c) {
    for (int y = 0; y < ids[c].rows; ++y) {
      const auto* p = ids[c].ptr<int>(y);
      for (int x = 0; x < ids[c].cols; ++x) {
        if (p[x] > 0 && static_cast<std::size_t>(p[x]) <= shot.markers.size()) ++out[c][static_cast<std::size_t>(p[x] - 1)].visible_px;
      }
    }
    const Camera& cam = rig_.cameras[c];
    for (std::size_t m = 0; m < shot.markers.size(); ++m) {
      MarkerView& v = out[c][m];
      const Eigen::Vector3d pc = cam.cam_from_world * shot.markers[m].centre_m;
      const auto px = cam.project(shot.markers[m].centre_m);
      v.in_front = px.has_value();
      if (!px) continue;
      v.pixel = *px;
      const double r = cam.intrinsics.fx * shot.markers[m].radius_m / pc.z();
      v.disc_px = std::numbers::pi * r * r;
    }
  }
  return out;
}

ColourCameraSource::ColourCameraSource(std::unique_ptr<ColourCameras> cameras, std::function<ColourShot(double)> shoot,
                                       const ColourModel& model, ColourDetectorSettings detector)
    : cameras_(std::move(cameras)), shoot_(std::move(shoot)) {
  detectors_.assign(cameras_->rig().cameras.size(), ColourDetector(model, detector));
}

std::optional<RigFrame> ColourCameraSource::next(double t_s) {
  using Clock = std::chrono::steady_clock;
  shot_ = shoot_(t_s);
  const auto start = Clock::now();
  images_ = cameras_->render(shot_, index_);
  const auto rendered = Clock::now();
  RigFrame frame;
  frame.index = index_++;
  frame.time_s = t_s;
  for (std::size_t c = 0; c < images_.size(); ++c) {
    CameraFrame cf;
    cf.camera = static_cast<int>(c);
    cf.timestamp_s = t_s;
    if (auto d = detectors_[c].track(images_[c])) cf.detections = std::move(*d);
    frame.cameras.push_back(std::move(cf));
  }
  const auto detected = Clock::now();
  render_ms_ = std::chrono::duration<double, std::milli>(rendered - start).count();
  detect_ms_ = std::chrono::duration<double, std::milli>(detected - rendered).count();
  render_total_ms_ += render_ms_;
  detect_total_ms_ += detect_ms_;
  for (const ColourMarker& m : shot_.markers) frame.truth_position_m.push_back(m.centre_m);
  frame.truth_marker_body.assign(shot_.markers.size(), -1);
  return frame;
}

std::vector<std::string> ColourCameraSource::summary() const {
  if (index_ == 0) return {};
  char line[160];
  std::snprintf(line, sizeof(line), "colour cameras (%s): %llu frames, render %.2f ms and detection %.2f ms a frame on average",
                cameras_->renderer_info().device_name.c_str(), static_cast<unsigned long long>(index_),
                render_total_ms_ / static_cast<double>(index_), detect_total_ms_ / static_cast<double>(index_));
  return {line};
}

}  // namespace rhot
