#include "tracking/calib/RigMerge.h"

#include <cmath>
#include <cstdio>
#include <map>

#include <Eigen/Dense>

#include "tracking/calib/BundleAdjustment.h"
#include "tracking/geometry/Triangulation.h"
#include "tracking/core/Solvers.h"

namespace rhot {

namespace {

// The rotation nearest (Frobenius) to the mean of the given ones.
Eigen::Matrix3d mean_rotation(const std::vector<Eigen::Matrix3d>& rotations) {
  Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
  for (const auto& r : rotations) sum += r;
  const Svd3 decomposed = svd(sum);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (decomposed.u * decomposed.v.transpose()).determinant() < 0 ? -1.0 : 1.0;
  return decomposed.u * d * decomposed.v.transpose();
}

bool same_intrinsics(const CameraIntrinsics& x, const CameraIntrinsics& y) {
  if (x.width_px != y.width_px || x.height_px != y.height_px) return false;
  const double tol = 0.01 * std::max(x.fx, y.fx);
  return std::abs(x.fx - y.fx) < tol && std::abs(x.fy - y.fy) < tol && std::abs(x.cx - y.cx) < tol && std::abs(x.cy - y.cy) < tol;
}

// Every (frame, marker) both rigs' sessions reconstructed, each with its own rig: (in A, in B).
std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> shared_points(const CameraRig& a, const Detections& da, const CameraRig& b,
                                                                       const Detections& db) {
  const auto reconstruct = [](const CameraRig& rig, const Detections& d) {
    std::map<std::pair<long, int>, Eigen::Vector3d> out;
    for (const PointTrack& t : split_tracks(d).tracks) {
      std::vector<Observation> views;
      for (const auto& [camera, pixel] : t.views) {
        if (camera >= 0 && camera < static_cast<int>(rig.cameras.size())) views.push_back({camera, pixel});
      }
      if (views.size() < 2) continue;
      const auto x = triangulate(rig, views);
      if (x && x->position_world.allFinite() && x->reprojection_rms_px < 2.0) out[{t.frame, t.marker}] = x->position_world;
    }
    return out;
  };
  const auto in_a = reconstruct(a, da);
  const auto in_b = reconstruct(b, db);
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> pairs;
  for (const auto& [key, p] : in_a) {
    const auto it = in_b.find(key);
    if (it != in_b.end()) pairs.emplace_back(p, it->second);
  }
  return pairs;
}

// The merged rig from the alignment: A's cameras, shared ones averaged, B's others moved into A's
// world; then, with both sessions' detections, one bundle adjustment over them all.
std::expected<MergeResult, std::string> finish(const CameraRig& a, const CameraRig& b,
                                               const std::vector<std::pair<std::size_t, std::size_t>>& shared, const Similarity3& a_from_b,
                                               const Detections* detections_a, const Detections* detections_b, MergeResult out) {
  MergeReport& r = out.report;
  // Residuals of the shared cameras, and their poses averaged.
  out.rig.name = a.name.empty() ? b.name : a.name;
  out.rig.volume = a.volume;
  out.rig.cameras = a.cameras;
  double centre_sq = 0, angle_sq = 0;
  for (const auto& [i, j] : shared) {
    const Camera moved = transform_camera(b.cameras[j], a_from_b);
    const Eigen::Vector3d ca = a.cameras[i].centre_world(), cb = moved.centre_world();
    centre_sq += (ca - cb).squaredNorm();
    const double angle = a.cameras[i].cam_from_world.rotation.angularDistance(moved.cam_from_world.rotation);
    angle_sq += angle * angle;
    Camera& merged = out.rig.cameras[i];
    merged.cam_from_world.rotation = a.cameras[i].cam_from_world.rotation.slerp(0.5, moved.cam_from_world.rotation).normalized();
    const Eigen::Vector3d centre = 0.5 * (ca + cb);
    merged.cam_from_world.translation = -(merged.cam_from_world.rotation * centre);
  }
  if (!shared.empty()) {
    r.centre_rms_mm = std::sqrt(centre_sq / static_cast<double>(shared.size())) * 1000.0;
    r.rotation_rms_deg = std::sqrt(angle_sq / static_cast<double>(shared.size())) * 180.0 / M_PI;
  }
  std::vector<int> b_index(b.cameras.size(), -1);
  for (const auto& [i, j] : shared) b_index[j] = static_cast<int>(i);
  for (std::size_t j = 0; j < b.cameras.size(); ++j) {
    if (b_index[j] >= 0) continue;
    b_index[j] = static_cast<int>(out.rig.cameras.size());
    out.rig.cameras.push_back(transform_camera(b.cameras[j], a_from_b));
  }
  if (b.volume && !out.rig.volume) out.rig.volume = transform_volume(*b.volume, a_from_b);

  if (detections_a != nullptr) {
    // One adjustment over both sessions: each single-view-per-camera track triangulated with the
    // merged rig, then everything refined together (camera 0 and the scale held).
    std::vector<Eigen::Vector3d> points;
    std::vector<BundleObservation> observations;
    const auto add_session = [&](const Detections& d, const std::vector<int>& to_merged) {
      for (const PointTrack& t : split_tracks(d).tracks) {
        std::vector<Observation> views;
        std::vector<BundleObservation> obs;
        for (const auto& [camera, pixel] : t.views) {
          if (camera < 0 || camera >= static_cast<int>(to_merged.size())) continue;
          const int merged = to_merged[static_cast<std::size_t>(camera)];
          views.push_back({merged, pixel});
          obs.push_back({merged, static_cast<int>(points.size()), pixel});
        }
        if (views.size() < 2) continue;
        const auto x = triangulate(out.rig, views);
        if (!x || !x->position_world.allFinite() || x->reprojection_rms_px > 3.0) continue;
        points.push_back(x->position_world);
        observations.insert(observations.end(), obs.begin(), obs.end());
      }
    };
    std::vector<int> a_index(a.cameras.size());
    for (std::size_t i = 0; i < a.cameras.size(); ++i) a_index[i] = static_cast<int>(i);
    add_session(*detections_a, a_index);
    add_session(*detections_b, b_index);
    if (points.size() < 20)
      return std::unexpected("merge: only " + std::to_string(points.size()) + " points of the two sessions fit the merged rig within 3 px");
    BundleSettings bs;
    bs.huber_px = 1.0;
    // The gauge: A's first two cameras as the similarity left them (A's frame and metric scale).
    bs.held_cameras = {0, 1};
    std::vector<Camera> cameras = out.rig.cameras;
    const auto summary = bundle_adjust(cameras, points, observations, bs);
    if (!summary) return std::unexpected("merge: " + summary.error());
    out.rig.cameras = cameras;
    r.adjusted = true;
    r.rms_px = summary->final_rms_px;
    r.points = static_cast<int>(points.size());
  }
  return out;
}

}  // namespace

std::expected<MergeResult, std::string> merge_rigs(const CameraRig& a, const CameraRig& b, const MergeSettings& settings,
                                                   const Detections* detections_a, const Detections* detections_b) {
  if ((detections_a == nullptr) != (detections_b == nullptr)) {
    return std::unexpected("merge: give both sessions' detections, or neither");
  }
  std::map<std::string, std::size_t> in_a;
  for (std::size_t i = 0; i < a.cameras.size(); ++i) in_a[a.cameras[i].name] = i;
  std::vector<std::pair<std::size_t, std::size_t>> shared;  // (index in a, index in b)
  for (std::size_t j = 0; j < b.cameras.size(); ++j) {
    const auto it = in_a.find(b.cameras[j].name);
    if (it == in_a.end()) continue;
    if (!same_intrinsics(a.cameras[it->second].intrinsics, b.cameras[j].intrinsics)) {
      return std::unexpected(
          "merge: camera \"" + b.cameras[j].name +
          "\" is in both rigs with different intrinsics (image size, focal length or principal point differ by more than 1 %)");
    }
    shared.emplace_back(it->second, j);
  }
  MergeResult out;
  MergeReport& r = out.report;
  if (shared.empty()) {
    if (detections_a == nullptr) {
      return std::unexpected(
          "merge: the rigs share no camera (cameras are matched by name); calibrate so that at least one camera is in both waves, or give "
          "both sessions' detections of one wave both rigs saw (the same frame numbers)");
    }
    // Shared points: a marker in one frame triangulated by each rig on its own.
    const std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> pairs = shared_points(a, *detections_a, b, *detections_b);
    std::vector<Eigen::Vector3d> points_a, points_b;
    for (const auto& [pa, pb] : pairs) {
      points_a.push_back(pa);
      points_b.push_back(pb);
    }
    const auto fit = points_a.size() >= 10 ? fit_similarity(points_b, points_a, settings.allow_scale) : std::nullopt;
    if (!fit) {
      return std::unexpected(
          "merge: the rigs share no camera, and only " + std::to_string(pairs.size()) +
          " marker positions (the same frame and marker) were seen by two cameras of each (need 10, not all on one line)");
    }
    r.a_from_b = *fit;
    r.shared_points = static_cast<int>(pairs.size());
    double sq = 0;
    for (std::size_t i = 0; i < pairs.size(); ++i) sq += (fit->apply(points_b[i]) - points_a[i]).squaredNorm();
    r.point_rms_mm = std::sqrt(sq / static_cast<double>(pairs.size())) * 1000.0;
    return finish(a, b, {}, *fit, detections_a, detections_b, std::move(out));
  }
  // Rotation: each shared camera gives a_from_b = R_a^T R_b.
  std::vector<Eigen::Matrix3d> rotations;
  for (const auto& [i, j] : shared) {
    r.shared_cameras.push_back(a.cameras[i].name);
    rotations.push_back(a.cameras[i].cam_from_world.rotation.toRotationMatrix().transpose() *
                        b.cameras[j].cam_from_world.rotation.toRotationMatrix());
  }
  Similarity3 a_from_b;
  a_from_b.rotation = mean_rotation(rotations);
  Eigen::Vector3d mean_a = Eigen::Vector3d::Zero(), mean_b = Eigen::Vector3d::Zero();
  for (const auto& [i, j] : shared) {
    mean_a += a.cameras[i].centre_world();
    mean_b += b.cameras[j].centre_world();
  }
  mean_a /= static_cast<double>(shared.size());
  mean_b /= static_cast<double>(shared.size());
  if (settings.allow_scale && shared.size() >= 2) {
    double num = 0, den = 0;
    for (const auto& [i, j] : shared) {
      const Eigen::Vector3d db = a_from_b.rotation * (b.cameras[j].centre_world() - mean_b);
      num += (a.cameras[i].centre_world() - mean_a).dot(db);
      den += db.squaredNorm();
    }
    if (!(den > 1e-12) || !(num > 0)) return std::unexpected("merge: the shared cameras' centres cannot fix the scale between the rigs");
    a_from_b.scale = num / den;
  }
  a_from_b.translation = mean_a - a_from_b.scale * (a_from_b.rotation * mean_b);
  r.a_from_b = a_from_b;
  return finish(a, b, shared, a_from_b, detections_a, detections_b, std::move(out));
}

}  // namespace rhot
