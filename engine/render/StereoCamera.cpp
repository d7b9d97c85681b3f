#include "engine/render/StereoCamera.h"

#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

namespace rhot {

glm::mat4 projection_from_fov(const EyeFovDeg& fov, double near_m, double far_m) {
  // Frustum edges on the near plane.
  const double l = -near_m * std::tan(fov.left * M_PI / 180.0);
  const double r = near_m * std::tan(fov.right * M_PI / 180.0);
  const double t = near_m * std::tan(fov.up * M_PI / 180.0);
  const double b = -near_m * std::tan(fov.down * M_PI / 180.0);
  const double n = near_m;
  const double f = far_m;
  // Eye space looks down -Z, so w_clip = -z. x maps [l, r] on the near plane to [-1, 1]; y maps
  // [t, b] to [-1, 1] (Vulkan's y points down); z maps [-n, -f] to [0, 1].
  glm::dmat4 m(0.0);
  m[0][0] = 2.0 * n / (r - l);
  m[2][0] = (r + l) / (r - l);
  m[1][1] = -2.0 * n / (t - b);
  m[2][1] = -(t + b) / (t - b);
  m[2][2] = f / (n - f);
  m[3][2] = n * f / (n - f);
  m[2][3] = -1.0;
  return glm::mat4(m);
}

StereoViews stereo_views(const glm::mat4& world_from_head, const HeadsetSettings& headset) {
  StereoViews v;
  const float half_ipd = static_cast<float>(headset.ipd_m / 2.0);
  const std::array<const EyeFovDeg*, 2> fov{&headset.left_eye, &headset.right_eye};
  for (int eye = 0; eye < 2; ++eye) {
    const float offset = eye == kLeftEye ? -half_ipd : half_ipd;
    const glm::mat4 world_from_eye = world_from_head * glm::translate(glm::mat4(1.0f), glm::vec3(offset, 0.0f, 0.0f));
    v.eye_from_world[eye] = glm::inverse(world_from_eye);
    v.clip_from_eye[eye] = projection_from_fov(*fov[eye], headset.near_m, headset.far_m);
  }
  return v;
}

glm::vec2 project_to_pixel(const StereoViews& views, int eye, const glm::vec3& p_world, int width_px, int height_px) {
  const glm::vec4 clip = views.clip_from_world(eye) * glm::vec4(p_world, 1.0f);
  const glm::vec2 ndc(clip.x / clip.w, clip.y / clip.w);
  // Vulkan's viewport maps ndc -1 to the left/top edge of the first pixel, +1 to the far edge.
  return {(ndc.x + 1.0f) * 0.5f * static_cast<float>(width_px), (ndc.y + 1.0f) * 0.5f * static_cast<float>(height_px)};
}

glm::mat4 default_world_from_head(float pitch_deg) {
  const glm::mat4 translate = glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, 1.2f, 0.0f));
  return glm::rotate(translate, glm::radians(-pitch_deg), glm::vec3(1.0f, 0.0f, 0.0f));
}

}  // namespace rhot
