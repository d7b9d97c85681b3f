#pragma once
// The one place where tracking's maths (Eigen, double) meets the engine's (GLM, float). Every
// conversion rounds to the nearest float; quaternions keep their components (GLM's and Eigen's
// constructors both take w first; the calls below name each component).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "tracking/core/Rigid3.h"

namespace rhot {

inline glm::vec3 to_glm(const Eigen::Vector3d& v) {
  return {static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z())};
}

// Not normalised: a caller that needs a unit quaternion in float normalises it.
inline glm::quat to_glm(const Eigen::Quaterniond& q) {
  return glm::quat(static_cast<float>(q.w()), static_cast<float>(q.x()), static_cast<float>(q.y()), static_cast<float>(q.z()));
}

// The rigid transform as a 4x4 matrix (column-major, as GLM stores it).
inline glm::mat4 to_glm(const Rigid3d& b_from_a) {
  const Eigen::Matrix3d r = b_from_a.rotation.toRotationMatrix();
  glm::mat4 m(1.0f);
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 3; ++col) m[col][row] = static_cast<float>(r(row, col));
    m[3][row] = static_cast<float>(b_from_a.translation(row));
  }
  return m;
}

inline Eigen::Vector3d to_eigen(const glm::vec3& v) { return Eigen::Vector3f{v.x, v.y, v.z}.cast<double>(); }

inline Eigen::Quaterniond to_eigen(const glm::quat& q) { return Eigen::Quaternionf{q.w, q.x, q.y, q.z}.cast<double>(); }

}  // namespace rhot
