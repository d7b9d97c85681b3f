#pragma once
// Conversions between Bullet's vectors and rhot's (GLM in engine/, Eigen in tracking/).

#include <btBulletDynamicsCommon.h>
#include <Eigen/Geometry>
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "tracking/core/Rigid3.h"

namespace rhot {

inline btVector3 to_bt(const glm::vec3& v) { return {v.x, v.y, v.z}; }
inline btQuaternion to_bt(const glm::quat& q) { return {q.x, q.y, q.z, q.w}; }
inline btVector3 to_bt(const Eigen::Vector3d& v) {
  return {static_cast<btScalar>(v.x()), static_cast<btScalar>(v.y()), static_cast<btScalar>(v.z())};
}
inline btQuaternion to_bt(const Eigen::Quaterniond& q) {
  return {static_cast<btScalar>(q.x()), static_cast<btScalar>(q.y()), static_cast<btScalar>(q.z()), static_cast<btScalar>(q.w())};
}
inline btTransform to_bt(const Rigid3d& r) { return btTransform(to_bt(r.rotation), to_bt(r.translation)); }

inline glm::vec3 to_glm(const btVector3& v) { return {v.x(), v.y(), v.z()}; }
inline glm::quat to_glm(const btQuaternion& q) { return {q.w(), q.x(), q.y(), q.z()}; }
inline Eigen::Vector3d to_eigen(const btVector3& v) { return Eigen::Matrix<btScalar, 3, 1>{v.x(), v.y(), v.z()}.cast<double>(); }
inline Eigen::Quaterniond to_eigen(const btQuaternion& q) { return Eigen::Quaternion<btScalar>{q.w(), q.x(), q.y(), q.z()}.cast<double>(); }
inline Rigid3d to_rigid(const btTransform& t) { return Rigid3d{to_eigen(t.getRotation()), to_eigen(t.getOrigin())}; }

inline bool finite(const btVector3& v) { return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z()); }

// The angular velocity that turns `from` into `to` in `dt` seconds (the short way round).
inline btVector3 angular_velocity(const btQuaternion& from, const btQuaternion& to, btScalar dt) {
  btQuaternion d = to * from.inverse();
  if (d.w() < 0) d = -d;
  const btScalar angle = d.getAngle();
  if (angle < btScalar(1e-7)) return {0, 0, 0};
  return d.getAxis() * (angle / dt);
}

}  // namespace rhot
