#pragma once
// The headset's two eyes: where they are and what each sees. Eye frames follow OpenXR: +X right,
// +Y up, looking down -Z. Projections map to Vulkan clip space (y down, depth 0 at near_m to 1
// at far_m) with each eye's own asymmetric frustum.

#include <array>

#include <glm/glm.hpp>

#include "engine/scene/SceneDesc.h"

namespace rhot {

enum Eye : int { kLeftEye = 0, kRightEye = 1 };

struct StereoViews {
  std::array<glm::mat4, 2> eye_from_world{glm::mat4(1.0f), glm::mat4(1.0f)};
  std::array<glm::mat4, 2> clip_from_eye{glm::mat4(1.0f), glm::mat4(1.0f)};
  glm::mat4 clip_from_world(int eye) const { return clip_from_eye[eye] * eye_from_world[eye]; }
};

// An asymmetric perspective projection from half-angles (degrees, positive outward) and clip
// distances, for Vulkan's clip space.
glm::mat4 projection_from_fov(const EyeFovDeg& fov, double near_m, double far_m);

// Both eyes for a head pose: each eye sits ipd_m / 2 left or right of the head origin along the
// head's +X axis.
StereoViews stereo_views(const glm::mat4& world_from_head, const HeadsetSettings& headset);

// Pixel coordinates (x right, y down, origin at the top-left corner of the image) of a world point
// in one eye's image of width x height pixels; the point must be in front of the eye.
glm::vec2 project_to_pixel(const StereoViews& views, int eye, const glm::vec3& p_world, int width_px, int height_px);

// A seated user's default head pose: eyes 1.2 m above the floor at the origin, looking down -Z
// and pitched down by pitch_deg toward the table.
glm::mat4 default_world_from_head(float pitch_deg = 20.0f);

}  // namespace rhot
