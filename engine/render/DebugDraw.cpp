#include "engine/render/DebugDraw.h"

#include <array>
#include <cmath>

namespace rhot {

void DebugDraw::line(const glm::vec3& a, const glm::vec3& b, const glm::vec4& color) {
  lines_.push_back({a, color});
  lines_.push_back({b, color});
}

void DebugDraw::ray(const glm::vec3& origin, const glm::vec3& direction, float length_m, const glm::vec4& color) {
  const float n = glm::length(direction);
  if (!(n > 0.0f)) return;
  line(origin, origin + direction * (length_m / n), color);
}

void DebugDraw::capsule(const glm::vec3& a, const glm::vec3& b, float radius_m, const glm::vec4& color) {
  line(a, b, color);
  const glm::vec3 axis = b - a;
  const float length = glm::length(axis);
  if (!(length > 0.0f) || !(radius_m > 0.0f)) return;
  const glm::vec3 z = axis / length;
  // Any unit vector across the axis, then the third by the cross product.
  const glm::vec3 helper = std::abs(z.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
  const glm::vec3 x = glm::normalize(glm::cross(helper, z));
  const glm::vec3 y = glm::cross(z, x);
  constexpr int kSegments = 12;
  for (int i = 0; i < kSegments; ++i) {
    const float t0 = 6.2831853f * static_cast<float>(i) / kSegments;
    const float t1 = 6.2831853f * static_cast<float>(i + 1) / kSegments;
    const glm::vec3 r0 = radius_m * (std::cos(t0) * x + std::sin(t0) * y);
    const glm::vec3 r1 = radius_m * (std::cos(t1) * x + std::sin(t1) * y);
    line(a + r0, a + r1, color);
    line(b + r0, b + r1, color);
    if (i % (kSegments / 4) == 0) line(a + r0, b + r0, color);
  }
}

void DebugDraw::point(const glm::vec3& p, float radius_m, const glm::vec4& color) { points_.push_back({p, radius_m, color}); }

void DebugDraw::axes(const glm::mat4& world_from_frame, float length_m) {
  const glm::vec3 o(world_from_frame[3]);
  const std::array<glm::vec4, 3> colors{glm::vec4(1, 0, 0, 1), glm::vec4(0, 1, 0, 1), glm::vec4(0, 0, 1, 1)};
  for (int a = 0; a < 3; ++a) line(o, o + glm::vec3(world_from_frame[a]) * length_m, colors[static_cast<std::size_t>(a)]);
}

void DebugDraw::camera_frustum(const glm::mat4& world_from_cam, int width_px, int height_px, float fx, float fy, float cx, float cy,
                               float depth_m, const glm::vec4& color) {
  const glm::vec3 o(world_from_cam[3]);
  const std::array<glm::vec2, 4> corners{glm::vec2(0, 0), glm::vec2(static_cast<float>(width_px), 0),
                                         glm::vec2(static_cast<float>(width_px), static_cast<float>(height_px)),
                                         glm::vec2(0, static_cast<float>(height_px))};
  std::array<glm::vec3, 4> far{};
  for (std::size_t i = 0; i < 4; ++i) {
    const glm::vec3 p_cam((corners[i].x - cx) / fx * depth_m, (corners[i].y - cy) / fy * depth_m, depth_m);
    far[i] = glm::vec3(world_from_cam * glm::vec4(p_cam, 1.0f));
    line(o, far[i], color);
  }
  for (std::size_t i = 0; i < 4; ++i) line(far[i], far[(i + 1) % 4], color);
}

void DebugDraw::grid(float half_extent_m, float spacing_m, float height_m, const glm::vec4& color) {
  if (!(spacing_m > 0.0f) || !(half_extent_m > 0.0f)) return;
  const int n = static_cast<int>(std::floor(half_extent_m / spacing_m));
  for (int i = -n; i <= n; ++i) {
    const float t = static_cast<float>(i) * spacing_m;
    const glm::vec4 x_color = i == 0 ? glm::vec4(0.8f, 0.15f, 0.15f, 1.0f) : color;  // the line z = 0 is the x axis
    const glm::vec4 z_color = i == 0 ? glm::vec4(0.15f, 0.25f, 0.85f, 1.0f) : color;
    line({-half_extent_m, height_m, t}, {half_extent_m, height_m, t}, x_color);
    line({t, height_m, -half_extent_m}, {t, height_m, half_extent_m}, z_color);
  }
}

void DebugDraw::clear() {
  lines_.clear();
  points_.clear();
}

}  // namespace rhot
