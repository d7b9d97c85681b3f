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

void DebugDraw::point(const glm::vec3& p, float radius_m, const glm::vec4& color) { points_.push_back({p, radius_m, color}); }

void DebugDraw::axes(const glm::mat4& world_from_frame, float length_m) {
  const glm::vec3 o(world_from_frame[3]);
  const std::array<glm::vec4, 3> colors{glm::vec4(1, 0, 0, 1), glm::vec4(0, 1, 0, 1), glm::vec4(0, 0, 1, 1)};
  for (int a = 0; a < 3; ++a) line(o, o + glm::vec3(world_from_frame[a]) * length_m, colors[static_cast<std::size_t>(a)]);
}

void DebugDraw::camera_frustum(const glm::mat4& world_from_cam, int width_px, int height_px, float fx, float fy, float cx,
                               float cy, float depth_m, const glm::vec4& color) {
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
