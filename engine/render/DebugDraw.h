#pragma once
// A per-frame list of debug shapes in world coordinates: lines (rays, camera frusta, axes, the
// ground grid) and points drawn as small spheres (markers). Fill it during a frame, hand it to
// SceneRenderer::build, clear it for the next.

#include <vector>

#include <glm/glm.hpp>

#include "engine/render/Renderer.h"

namespace rhot {

struct DebugPoint {
  glm::vec3 position{0.0f};
  float radius_m = 0.005f;
  glm::vec4 color{1.0f};
};

class DebugDraw {
 public:
  void line(const glm::vec3& a, const glm::vec3& b, const glm::vec4& color);
  void ray(const glm::vec3& origin, const glm::vec3& direction, float length_m, const glm::vec4& color);
  void point(const glm::vec3& p, float radius_m, const glm::vec4& color);
  // A capsule's outline: its axis from a to b, a ring of its radius at each end and four lines
  // joining the rings.
  void capsule(const glm::vec3& a, const glm::vec3& b, float radius_m, const glm::vec4& color);
  // The frame's axes from its origin: x red, y green, z blue.
  void axes(const glm::mat4& world_from_frame, float length_m);
  // A pinhole camera's viewing pyramid out to depth_m. The camera frame is OpenCV's (x right,
  // y down, z forward); fx, fy, cx, cy in pixels for an image of width x height pixels.
  void camera_frustum(const glm::mat4& world_from_cam, int width_px, int height_px, float fx, float fy, float cx, float cy, float depth_m,
                      const glm::vec4& color);
  // Lines on the plane y = height_m every spacing_m out to +-half_extent_m, with the x axis red
  // and the z axis blue.
  void grid(float half_extent_m, float spacing_m, float height_m, const glm::vec4& color);

  void clear();
  const std::vector<LineVertex>& lines() const { return lines_; }
  const std::vector<DebugPoint>& points() const { return points_; }

 private:
  std::vector<LineVertex> lines_;
  std::vector<DebugPoint> points_;
};

}  // namespace rhot
