#include "tracking/calib/WorldFrame.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numeric>

#include <Eigen/Dense>

#include "tracking/geometry/Matching.h"
#include "tracking/core/Solvers.h"

namespace rhot {

namespace {

std::string to_fixed(double v, int digits = 1) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

WorldFrameResult apply(const CameraRig& rig, const Similarity3& new_from_old) {
  WorldFrameResult out;
  out.new_from_old = new_from_old;
  out.rig = rig;
  out.rig.cameras.clear();
  for (const Camera& c : rig.cameras) out.rig.cameras.push_back(transform_camera(c, new_from_old));
  if (rig.volume) out.rig.volume = transform_volume(*rig.volume, new_from_old);
  return out;
}

}  // namespace

std::vector<Eigen::Vector3d> LFrame::markers_world() const {
  std::vector<Eigen::Vector3d> m{{0, height_m, 0}, {0, height_m, -long_m}, {short_m, height_m, 0}};
  if (middle_m) m.emplace_back(0, height_m, -*middle_m);
  return m;
}

std::expected<void, std::string> LFrame::check() const {
  if (!(std::isfinite(long_m) && std::isfinite(short_m) && short_m >= 0.05 && long_m > short_m * 1.05 && long_m <= 5.0)) {
    return std::unexpected("L-frame: expected arms of 5 cm to 5 m with the long arm at least 5 % longer than the short one, got " +
                           to_fixed(long_m * 1000) + " mm and " + to_fixed(short_m * 1000) + " mm");
  }
  if (middle_m && !(std::isfinite(*middle_m) && *middle_m > 0.02 && *middle_m < long_m - 0.02 && std::abs(*middle_m - short_m) > 0.02)) {
    return std::unexpected(
        "L-frame: the middle marker must lie on the long arm, 2 cm or more from either end, and 2 cm or more from the short arm's length");
  }
  if (!(std::isfinite(height_m) && std::abs(height_m) <= 3.0))
    return std::unexpected("L-frame: marker height expected within 3 m of the floor");
  return {};
}

std::vector<StillPoint> still_points(const CameraRig& rig, const Detections& detections, double radius_m, int min_frames) {
  // A run of points near one another in frames close in time; a moving marker leaves runs too,
  // spread along its path, which the spread test below refuses.
  constexpr long kMaxGapFrames = 10;
  constexpr double kStill_m = 0.005;
  struct Cluster {
    std::vector<Eigen::Vector3d> points;
    Eigen::Vector3d mean{0, 0, 0};
    long first_frame = 0;
    long last_frame = 0;
  };
  std::vector<Cluster> clusters;
  const RigMatcher matcher(rig);
  for (const DetectionFrame& f : detections.frames) {
    RigFrame frame;
    frame.index = static_cast<std::uint64_t>(f.frame);
    frame.cameras.resize(rig.cameras.size());
    for (std::size_t c = 0; c < rig.cameras.size(); ++c) frame.cameras[c].camera = static_cast<int>(c);
    for (const MarkerObservation& o : f.observations) {
      if (o.camera < 0 || o.camera >= static_cast<int>(rig.cameras.size()) || !o.pixel.allFinite()) continue;
      frame.cameras[static_cast<std::size_t>(o.camera)].detections.push_back({o.pixel, -1});
    }
    for (const MatchedPoint& m : matcher.match(frame)) {
      const Eigen::Vector3d p = m.point.position_world;
      if (!p.allFinite()) continue;
      Cluster* nearest = nullptr;
      double nearest_m = radius_m;
      for (Cluster& c : clusters) {
        const double d = (c.mean - p).norm();
        if (f.frame - c.last_frame <= kMaxGapFrames && d < nearest_m) {
          nearest = &c;
          nearest_m = d;
        }
      }
      if (!nearest) {
        clusters.push_back({{}, p, f.frame, f.frame});
        nearest = &clusters.back();
      }
      nearest->points.push_back(p);
      nearest->mean += (p - nearest->mean) / static_cast<double>(nearest->points.size());
      nearest->last_frame = f.frame;
    }
  }
  std::vector<StillPoint> out;
  for (const Cluster& c : clusters) {
    if (static_cast<int>(c.points.size()) < min_frames) continue;
    // The still part: the points within kStill_m of the median. A group gathered from a marker
    // moving (even slowly, as it sets off or arrives) keeps too few of them.
    Eigen::Vector3d centre;
    for (int axis = 0; axis < 3; ++axis) {
      std::vector<double> v;
      for (const auto& p : c.points) v.push_back(p[axis]);
      centre[axis] = median(v);
    }
    std::vector<Eigen::Vector3d> still;
    for (const auto& p : c.points) {
      if ((p - centre).norm() <= kStill_m) still.push_back(p);
    }
    if (static_cast<int>(still.size()) < min_frames) continue;
    StillPoint s;
    for (int axis = 0; axis < 3; ++axis) {
      std::vector<double> v;
      for (const auto& p : still) v.push_back(p[axis]);
      s.position[axis] = median(v);
    }
    s.frames = static_cast<int>(still.size());
    s.first_frame = c.first_frame;
    // The same place again after a gap: one point.
    StillPoint* same = nullptr;
    for (StillPoint& o : out) {
      if ((o.position - s.position).norm() < radius_m) same = &o;
    }
    if (same) {
      const double w = static_cast<double>(s.frames) / (s.frames + same->frames);
      same->position += w * (s.position - same->position);
      same->frames += s.frames;
      same->first_frame = std::min(same->first_frame, s.first_frame);
    } else {
      out.push_back(s);
    }
  }
  std::sort(out.begin(), out.end(), [](const StillPoint& a, const StillPoint& b) { return a.first_frame < b.first_frame; });
  return out;
}

std::expected<WorldFrameResult, std::string> world_from_lframe(const CameraRig& rig, const Detections& detections, const LFrame& frame,
                                                               bool rescale, double tolerance_m) {
  if (const auto ok = frame.check(); !ok) return std::unexpected(ok.error());
  const std::vector<Eigen::Vector3d> model = frame.markers_world();
  const int min_frames = std::max(3, static_cast<int>(detections.frames.size() / 2));
  const std::vector<StillPoint> found = still_points(rig, detections, 0.02, min_frames);
  if (found.size() != model.size()) {
    return std::unexpected("the L-frame has " + std::to_string(model.size()) + " markers, but " + std::to_string(found.size()) +
                           " points stayed still in at least half of the " + std::to_string(detections.frames.size()) +
                           " frames; is the frame in view of two cameras or more, and nothing else still in view?");
  }
  // The markers carry no labels: try every assignment and keep the one that fits best.
  std::vector<int> perm(model.size());
  std::iota(perm.begin(), perm.end(), 0);
  double best = 1e300;
  Similarity3 best_fit;
  std::vector<int> best_perm;
  do {
    std::vector<Eigen::Vector3d> measured;
    for (const int i : perm) measured.push_back(found[static_cast<std::size_t>(i)].position);
    const auto fit = fit_similarity(model, measured, rescale);  // measured = fit(model)
    if (!fit) continue;
    double sq = 0;
    for (std::size_t i = 0; i < model.size(); ++i) sq += (fit->apply(model[i]) - measured[i]).squaredNorm();
    if (sq < best) {
      best = sq;
      best_fit = *fit;
      best_perm = perm;
    }
  } while (std::next_permutation(perm.begin(), perm.end()));
  if (best_perm.empty()) return std::unexpected("the L-frame's markers found lie on one line");
  // Reflections are impossible (umeyama returns a proper rotation), so a frame seen from below or
  // a mislabelled one fits badly and is refused here.
  WorldFrameResult out = apply(rig, best_fit.inverse());
  WorldFrameReport& r = out.report;
  double sq = 0;
  r.frames = 1 << 30;
  for (std::size_t i = 0; i < model.size(); ++i) {
    const StillPoint& p = found[static_cast<std::size_t>(best_perm[i])];
    const Eigen::Vector3d in_world = out.new_from_old.apply(p.position);
    r.measured_world.push_back(in_world);
    const double e = (in_world - model[i]).norm();
    r.marker_residual_mm.push_back(e * 1000.0);
    sq += e * e;
    r.max_mm = std::max(r.max_mm, e * 1000.0);
    r.frames = std::min(r.frames, p.frames);
  }
  r.rms_mm = std::sqrt(sq / static_cast<double>(model.size())) * 1000.0;
  r.scale = out.new_from_old.scale;
  const Eigen::Vector3d long_arm = r.measured_world[1] - r.measured_world[0];
  const Eigen::Vector3d short_arm = r.measured_world[2] - r.measured_world[0];
  r.angle_error_deg = std::acos(std::clamp(long_arm.normalized().dot(short_arm.normalized()), -1.0, 1.0)) * 180.0 / M_PI - 90.0;
  if (!(r.max_mm <= tolerance_m * 1000.0)) {
    static const char* const kNames[] = {"the corner", "the long arm's end", "the short arm's end", "the middle marker"};
    const auto worst =
        static_cast<std::size_t>(std::max_element(r.marker_residual_mm.begin(), r.marker_residual_mm.end()) - r.marker_residual_mm.begin());
    return std::unexpected("the points found do not fit the L-frame: " + std::string(kNames[worst]) + " lies " + to_fixed(r.max_mm) +
                           " mm from its place (tolerance " + to_fixed(tolerance_m * 1000.0) + " mm); check the frame's dimensions" +
                           (rescale ? "" : ", or whether the rig is metric"));
  }
  // Three or four markers in one plane fit their mirror image as well as themselves: a frame laid
  // mirrored (the short arm to the left) or seen from below fits, with the world upside down.
  Eigen::Vector3d cameras_mean = Eigen::Vector3d::Zero();
  for (const Camera& c : out.rig.cameras) cameras_mean += c.centre_world();
  cameras_mean /= static_cast<double>(out.rig.cameras.size());
  if (!(cameras_mean.y() > frame.height_m)) {
    return std::unexpected(
        "the L-frame reads as mirrored: with it, the cameras would be below the floor; lay it with the short arm to the right of the long "
        "arm (seen from above, the long arm pointing away from you)");
  }
  return out;
}

std::expected<WorldFrameResult, std::string> world_from_floor_points(const CameraRig& rig, const Detections& detections,
                                                                     double marker_height_m, int min_frames) {
  if (!(std::isfinite(marker_height_m) && std::abs(marker_height_m) <= 3.0)) {
    return std::unexpected("marker height: expected within 3 m of the floor");
  }
  const std::vector<StillPoint> found = still_points(rig, detections, 0.02, min_frames);
  if (found.size() < 3) {
    return std::unexpected("floor points: found " + std::to_string(found.size()) + " places where the marker stayed still for " +
                           std::to_string(min_frames) + " frames or more; need 3 or more");
  }
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : found) mean += p.position;
  mean /= static_cast<double>(found.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : found) cov += (p.position - mean) * (p.position - mean).transpose();
  const SymmetricEigen3 eig = symmetric_eigen(cov);
  if (!(eig.values[1] > 1e-4))
    return std::unexpected("floor points: the places lie on one line; touch the floor at three corners of a wide triangle");
  Eigen::Vector3d up = eig.vectors.col(0).normalized();
  // Up is the side the cameras are on.
  Eigen::Vector3d cameras_mean = Eigen::Vector3d::Zero();
  for (const Camera& c : rig.cameras) cameras_mean += c.centre_world();
  cameras_mean /= static_cast<double>(rig.cameras.size());
  if ((cameras_mean - mean).dot(up) < 0) up = -up;
  // Origin: the first place, dropped onto the floor; +X towards the second, within the floor.
  const Eigen::Vector3d origin = found[0].position - up * ((found[0].position - mean).dot(up) + marker_height_m);
  Eigen::Vector3d x = found[1].position - found[0].position;
  x -= up * x.dot(up);
  if (x.norm() < 0.05) return std::unexpected("floor points: the second place is within 5 cm of the first; it sets the direction of +X");
  x.normalize();
  const Eigen::Vector3d z = x.cross(up);
  Eigen::Matrix3d old_from_new;  // columns: the new axes in the old world
  old_from_new.col(0) = x;
  old_from_new.col(1) = up;
  old_from_new.col(2) = z;
  Similarity3 new_from_old;
  new_from_old.rotation = old_from_new.transpose();
  new_from_old.translation = -(old_from_new.transpose() * origin);
  WorldFrameResult out = apply(rig, new_from_old);
  WorldFrameReport& r = out.report;
  double sq = 0;
  r.frames = 1 << 30;
  double spread = 0;
  for (const auto& p : found) {
    const Eigen::Vector3d w = new_from_old.apply(p.position);
    r.measured_world.push_back(w);
    const double e = std::abs(w.y() - marker_height_m);
    r.marker_residual_mm.push_back(e * 1000.0);
    sq += e * e;
    r.max_mm = std::max(r.max_mm, e * 1000.0);
    r.frames = std::min(r.frames, p.frames);
    spread = std::max(spread, std::hypot(w.x(), w.z()));
  }
  r.rms_mm = std::sqrt(sq / static_cast<double>(found.size())) * 1000.0;
  r.angle_error_deg = std::atan2(r.rms_mm / 1000.0, std::max(spread, 1e-3)) * 180.0 / M_PI;
  return out;
}

}  // namespace rhot
