#include "engine/render/StereoCamera.h"

#include <cmath>

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

namespace rhot {
namespace {

glm::vec3 ndc(const glm::mat4& clip_from_eye, const glm::vec3& p_eye) {
  const glm::vec4 c = clip_from_eye * glm::vec4(p_eye, 1.0f);
  return glm::vec3(c) / c.w;
}

TEST(Projection, FrustumEdgesMapToClipEdges) {
  const EyeFovDeg fov{52.0, 44.0, 50.0, 40.0};
  const glm::mat4 p = projection_from_fov(fov, 0.05, 100.0);
  const float d = 2.0f;  // any depth in front of the eye
  const auto rad = [](double deg) { return static_cast<float>(deg * M_PI / 180.0); };
  // The left edge of the frustum at depth d is at x = -d tan(left).
  EXPECT_NEAR(ndc(p, {-d * std::tan(rad(fov.left)), 0, -d}).x, -1.0f, 1e-5f);
  EXPECT_NEAR(ndc(p, {d * std::tan(rad(fov.right)), 0, -d}).x, 1.0f, 1e-5f);
  // Vulkan's y points down: the top edge maps to -1.
  EXPECT_NEAR(ndc(p, {0, d * std::tan(rad(fov.up)), -d}).y, -1.0f, 1e-5f);
  EXPECT_NEAR(ndc(p, {0, -d * std::tan(rad(fov.down)), -d}).y, 1.0f, 1e-5f);
  // Depth: 0 at the near plane, 1 at the far plane.
  EXPECT_NEAR(ndc(p, {0, 0, -0.05f}).z, 0.0f, 1e-5f);
  EXPECT_NEAR(ndc(p, {0, 0, -100.0f}).z, 1.0f, 1e-4f);
}

TEST(StereoViews, EyesSitHalfTheIpdEitherSideOfTheHead) {
  HeadsetSettings h;
  h.ipd_m = 0.064;
  const glm::mat4 world_from_head = glm::translate(glm::mat4(1.0f), glm::vec3(1, 1.5f, 2));
  const StereoViews v = stereo_views(world_from_head, h);
  const glm::vec3 left_eye_world(glm::inverse(v.eye_from_world[kLeftEye])[3]);
  const glm::vec3 right_eye_world(glm::inverse(v.eye_from_world[kRightEye])[3]);
  EXPECT_NEAR(left_eye_world.x, 1.0f - 0.032f, 1e-6f);
  EXPECT_NEAR(right_eye_world.x, 1.0f + 0.032f, 1e-6f);
  EXPECT_NEAR(left_eye_world.y, 1.5f, 1e-6f);
  EXPECT_NEAR(right_eye_world.z, 2.0f, 1e-6f);
}

TEST(StereoViews, DisparityOfAPointAheadIsFocalLengthTimesIpdOverDepth) {
  HeadsetSettings h;
  h.ipd_m = 0.063;
  h.left_eye = h.right_eye = EyeFovDeg{45, 45, 45, 45};
  const StereoViews v = stereo_views(glm::mat4(1.0f), h);
  const int w = 400;
  const double fx = (w / 2.0) / std::tan(M_PI / 4.0);
  for (const float depth : {0.5f, 1.0f, 3.0f}) {
    const glm::vec2 l = project_to_pixel(v, kLeftEye, {0, 0, -depth}, w, w);
    const glm::vec2 r = project_to_pixel(v, kRightEye, {0, 0, -depth}, w, w);
    EXPECT_NEAR(static_cast<double>(l.x - r.x), fx * 0.063 / static_cast<double>(depth), 1e-3) << "depth " << depth;
    EXPECT_NEAR(l.y, 200.0f, 1e-3f);
  }
}

TEST(StereoViews, DefaultHeadLooksDownTowardTheTable) {
  const glm::mat4 head = default_world_from_head(20.0f);
  const glm::vec3 forward = -glm::vec3(head[2]);
  EXPECT_NEAR(forward.y, -std::sin(glm::radians(20.0f)), 1e-6f);
  EXPECT_LT(forward.z, 0.0f);
  EXPECT_NEAR(head[3].y, 1.2f, 1e-6f);
}

}  // namespace
}  // namespace rhot
