#include "tracking/calib/WandCalibration.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numeric>
#include <set>

#include <Eigen/Dense>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "tracking/calib/BundleAdjustment.h"
#include "tracking/calib/Similarity.h"
#include "tracking/core/Solvers.h"

namespace rhot {

namespace {

std::string camera_label(const CameraRig& rig, int c) {
  return "camera " + std::to_string(c) + " (\"" + rig.cameras[static_cast<std::size_t>(c)].name + "\")";
}

std::string fmt(double v, int digits = 2) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const auto i = static_cast<std::size_t>(std::clamp(q, 0.0, 1.0) * static_cast<double>(v.size() - 1) + 0.5);
  return v[std::min(i, v.size() - 1)];
}

struct Track {
  long frame = 0;
  int marker = -1;
  std::vector<int> cameras;
  std::vector<Eigen::Vector2d> pixels;      // distorted
  std::vector<Eigen::Vector2d> normalised;  // undistorted with the view's own camera
  std::vector<bool> rejected;               // outliers
  std::optional<Eigen::Vector3d> point;

  int live_views(const std::vector<bool>& placed) const {
    int n = 0;
    for (std::size_t k = 0; k < cameras.size(); ++k) n += (!rejected[k] && placed[static_cast<std::size_t>(cameras[k])]) ? 1 : 0;
    return n;
  }
};

// Everything one attempt at the calibration works on.
struct State {
  std::vector<Camera> cameras;  // every rig camera; poses valid where placed
  std::vector<bool> placed;
  std::vector<int> order;  // placement order
  std::vector<Track> tracks;
};

// Linear (DLT) triangulation from the placed, unrejected views, in normalised coordinates; then
// checked: in front of every camera and within `max_px` of every observation.
std::optional<Eigen::Vector3d> triangulate(const State& s, const Track& t, double max_px) {
  // The homogeneous point minimising |A h| with |h| = 1: the eigenvector of A^T A with the smallest
  // eigenvalue (A's rows: two per view). In normalised coordinates A is well conditioned, and the
  // bundle adjustment refines the point anyway.
  Eigen::Matrix4d normal = Eigen::Matrix4d::Zero();
  int rows = 0;
  for (std::size_t k = 0; k < t.cameras.size(); ++k) {
    const auto c = static_cast<std::size_t>(t.cameras[k]);
    if (t.rejected[k] || !s.placed[c]) continue;
    Eigen::Matrix<double, 3, 4> p;
    p.leftCols<3>() = s.cameras[c].cam_from_world.rotation.toRotationMatrix();
    p.col(3) = s.cameras[c].cam_from_world.translation;
    const Eigen::RowVector4d rx = t.normalised[k].x() * p.row(2) - p.row(0);
    const Eigen::RowVector4d ry = t.normalised[k].y() * p.row(2) - p.row(1);
    normal += rx.transpose() * rx + ry.transpose() * ry;
    rows += 2;
  }
  if (rows < 4) return std::nullopt;
  const Eigen::Vector4d h = symmetric_eigen(normal).vectors.col(0);
  if (std::abs(h[3]) < 1e-12) return std::nullopt;
  const Eigen::Vector3d x = h.head<3>() / h[3];
  if (!x.allFinite()) return std::nullopt;
  for (std::size_t k = 0; k < t.cameras.size(); ++k) {
    const auto c = static_cast<std::size_t>(t.cameras[k]);
    if (t.rejected[k] || !s.placed[c]) continue;
    const auto p = s.cameras[c].project(x);
    if (!p || (*p - t.pixels[k]).norm() > max_px) return std::nullopt;
  }
  return x;
}

void triangulate_new(State& s, double max_px) {
  for (Track& t : s.tracks) {
    if (t.point || t.live_views(s.placed) < 2) continue;
    t.point = triangulate(s, t, max_px);
  }
}

struct Adjusted {
  BundleSummary summary;
};

// Bundle-adjusts the placed cameras (in placement order, so the first two fix the gauge) and the
// tracks with points.
std::expected<BundleSummary, std::string> adjust(State& s, BundleSettings settings) {
  std::vector<int> position(s.cameras.size(), -1);
  std::vector<Camera> cameras;
  for (const int c : s.order) {
    position[static_cast<std::size_t>(c)] = static_cast<int>(cameras.size());
    cameras.push_back(s.cameras[static_cast<std::size_t>(c)]);
  }
  std::vector<Eigen::Vector3d> points;
  std::vector<int> point_track;
  std::vector<BundleObservation> observations;
  for (std::size_t i = 0; i < s.tracks.size(); ++i) {
    const Track& t = s.tracks[i];
    if (!t.point || t.live_views(s.placed) < 2) continue;
    const int p = static_cast<int>(points.size());
    points.push_back(*t.point);
    point_track.push_back(static_cast<int>(i));
    for (std::size_t k = 0; k < t.cameras.size(); ++k) {
      const int pos = position[static_cast<std::size_t>(t.cameras[k])];
      if (t.rejected[k] || pos < 0) continue;
      observations.push_back({pos, p, t.pixels[k]});
    }
  }
  const auto summary = bundle_adjust(cameras, points, observations, settings);
  if (!summary) return std::unexpected(summary.error());
  for (std::size_t k = 0; k < s.order.size(); ++k) s.cameras[static_cast<std::size_t>(s.order[k])] = cameras[k];
  for (std::size_t p = 0; p < points.size(); ++p) s.tracks[static_cast<std::size_t>(point_track[p])].point = points[p];
  // Normalised coordinates follow refined intrinsics.
  if (settings.refine_focal || settings.refine_principal_point || settings.refine_k1) {
    for (Track& t : s.tracks) {
      for (std::size_t k = 0; k < t.cameras.size(); ++k)
        t.normalised[k] = s.cameras[static_cast<std::size_t>(t.cameras[k])].undistort(t.pixels[k]);
    }
  }
  return *summary;
}

// The residual of every placed, unrejected view of a track with a point.
template <typename F>
void for_each_residual(const State& s, F&& f) {
  for (std::size_t i = 0; i < s.tracks.size(); ++i) {
    const Track& t = s.tracks[i];
    if (!t.point) continue;
    for (std::size_t k = 0; k < t.cameras.size(); ++k) {
      const auto c = static_cast<std::size_t>(t.cameras[k]);
      if (!s.placed[c]) continue;
      const auto p = s.cameras[c].project(*t.point);
      const Eigen::Vector2d r = p ? Eigen::Vector2d(t.pixels[k] - *p) : Eigen::Vector2d::Constant(1e6);
      f(i, k, r);
    }
  }
}

// Marks views further off than the threshold as outliers and drops points left with fewer than
// two views. Returns how many views it newly rejected.
int reject_outliers(State& s, double outlier_px, double& threshold_used) {
  std::vector<double> norms;
  for_each_residual(s, [&](std::size_t i, std::size_t k, const Eigen::Vector2d& r) {
    if (!s.tracks[i].rejected[k]) norms.push_back(r.norm());
  });
  // The median norm of a 2D Gaussian residual is 1.1774 sigma.
  const double sigma = quantile(norms, 0.5) / 1.1774;
  threshold_used = outlier_px > 0 ? outlier_px : std::max(1.0, 5.0 * sigma);
  int rejected = 0;
  for_each_residual(s, [&](std::size_t i, std::size_t k, const Eigen::Vector2d& r) {
    Track& t = s.tracks[i];
    if (!t.rejected[k] && !(r.norm() <= threshold_used)) {
      t.rejected[k] = true;
      ++rejected;
    }
  });
  for (Track& t : s.tracks) {
    if (t.point && t.live_views(s.placed) < 2) t.point.reset();
  }
  return rejected;
}

cv::Mat identity() { return cv::Mat::eye(3, 3, CV_64F); }

// The first pair: the best-connected edge whose essential matrix gives a well-conditioned
// reconstruction (enough inliers, rays meeting at more than a degree).
std::expected<void, std::string> place_first_pair(State& s, const std::vector<GraphEdge>& edges, int min_shared, double tolerance_px,
                                                  const CameraRig& rig) {
  std::vector<GraphEdge> sorted = edges;
  std::sort(sorted.begin(), sorted.end(), [](const GraphEdge& x, const GraphEdge& y) { return x.shared_points > y.shared_points; });
  std::string last_reason = "no pair of cameras shares enough points";
  for (const GraphEdge& e : sorted) {
    if (e.shared_points < min_shared) break;
    std::vector<cv::Point2d> p1, p2;
    std::vector<std::size_t> which;
    for (std::size_t i = 0; i < s.tracks.size(); ++i) {
      const Track& t = s.tracks[i];
      int ka = -1, kb = -1;
      for (std::size_t k = 0; k < t.cameras.size(); ++k) {
        if (t.cameras[k] == e.a) ka = static_cast<int>(k);
        if (t.cameras[k] == e.b) kb = static_cast<int>(k);
      }
      if (ka < 0 || kb < 0) continue;
      p1.emplace_back(t.normalised[static_cast<std::size_t>(ka)].x(), t.normalised[static_cast<std::size_t>(ka)].y());
      p2.emplace_back(t.normalised[static_cast<std::size_t>(kb)].x(), t.normalised[static_cast<std::size_t>(kb)].y());
      which.push_back(i);
    }
    const double f =
        0.5 * (s.cameras[static_cast<std::size_t>(e.a)].intrinsics.fx + s.cameras[static_cast<std::size_t>(e.b)].intrinsics.fx);
    cv::Mat mask;
    cv::Mat essential;
    try {
      essential = cv::findEssentialMat(p1, p2, identity(), cv::RANSAC, 0.999, tolerance_px / f, 2000, mask);
    } catch (const cv::Exception&) {
      essential = cv::Mat();
    }
    if (essential.rows != 3 || essential.cols != 3) {
      last_reason = "no essential matrix fits " + camera_label(rig, e.a) + " and " + camera_label(rig, e.b);
      continue;
    }
    cv::Mat r, t;
    const int good = cv::recoverPose(essential, p1, p2, identity(), r, t, mask);
    if (good < std::max(min_shared, static_cast<int>(0.5 * static_cast<double>(p1.size())))) {
      last_reason = camera_label(rig, e.a) + " and " + camera_label(rig, e.b) + ": only " + std::to_string(good) + " of " +
                    std::to_string(p1.size()) + " shared points fit one relative pose";
      continue;
    }
    State trial = s;
    Camera& ca = trial.cameras[static_cast<std::size_t>(e.a)];
    Camera& cb = trial.cameras[static_cast<std::size_t>(e.b)];
    ca.cam_from_world = Rigid3d{};
    Eigen::Matrix3d rb;
    Eigen::Vector3d tb;
    for (int i = 0; i < 3; ++i) {
      tb[i] = t.at<double>(i);
      for (int j = 0; j < 3; ++j) rb(i, j) = r.at<double>(i, j);
    }
    cb.cam_from_world.rotation = Eigen::Quaterniond(rb).normalized();
    cb.cam_from_world.translation = tb;
    trial.placed[static_cast<std::size_t>(e.a)] = trial.placed[static_cast<std::size_t>(e.b)] = true;
    trial.order = {e.a, e.b};
    triangulate_new(trial, 2.5 * tolerance_px);
    // The rays' angle at each point: a reconstruction from nearly parallel rays is unreliable.
    std::vector<double> angles;
    const Eigen::Vector3d oa = ca.centre_world(), ob = cb.centre_world();
    for (const std::size_t i : which) {
      const auto& x = trial.tracks[i].point;
      if (!x) continue;
      const double cosine = (*x - oa).normalized().dot((*x - ob).normalized());
      angles.push_back(std::acos(std::clamp(cosine, -1.0, 1.0)) * 180.0 / M_PI);
    }
    if (static_cast<int>(angles.size()) < min_shared || quantile(angles, 0.5) < 1.0) {
      last_reason = camera_label(rig, e.a) + " and " + camera_label(rig, e.b) + ": their rays meet at " + fmt(quantile(angles, 0.5)) +
                    " degrees (median), too little to reconstruct from";
      for (Track& tr : trial.tracks) tr.point.reset();
      continue;
    }
    s = std::move(trial);
    return {};
  }
  return std::unexpected("cannot start the reconstruction: " + last_reason);
}

// Places one more camera against the reconstructed points (PnP with RANSAC in normalised
// coordinates). Returns false when the points it sees do not fit one pose.
bool place_camera(State& s, int c, double tolerance_px) {
  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> image;
  for (const Track& t : s.tracks) {
    if (!t.point) continue;
    for (std::size_t k = 0; k < t.cameras.size(); ++k) {
      if (t.cameras[k] != c || t.rejected[k]) continue;
      object.emplace_back(t.point->x(), t.point->y(), t.point->z());
      image.emplace_back(t.normalised[k].x(), t.normalised[k].y());
    }
  }
  if (object.size() < 12) return false;
  cv::Mat rvec, tvec;
  std::vector<int> inliers;
  const double f = s.cameras[static_cast<std::size_t>(c)].intrinsics.fx;
  bool ok = false;
  try {
    ok = cv::solvePnPRansac(object, image, identity(), cv::noArray(), rvec, tvec, false, 500, static_cast<float>(tolerance_px / f), 0.999,
                            inliers, cv::SOLVEPNP_EPNP);
    if (ok && inliers.size() >= 6) {
      std::vector<cv::Point3d> o2;
      std::vector<cv::Point2d> i2;
      for (const int i : inliers) {
        o2.push_back(object[static_cast<std::size_t>(i)]);
        i2.push_back(image[static_cast<std::size_t>(i)]);
      }
      ok = cv::solvePnP(o2, i2, identity(), cv::noArray(), rvec, tvec, true, cv::SOLVEPNP_ITERATIVE);
    }
  } catch (const cv::Exception&) {
    ok = false;
  }
  if (!ok || static_cast<double>(inliers.size()) < std::max(12.0, 0.5 * static_cast<double>(object.size()))) return false;
  cv::Mat r;
  cv::Rodrigues(rvec, r);
  Eigen::Matrix3d rotation;
  Eigen::Vector3d translation;
  for (int i = 0; i < 3; ++i) {
    translation[i] = tvec.at<double>(i);
    for (int j = 0; j < 3; ++j) rotation(i, j) = r.at<double>(i, j);
  }
  if (!rotation.allFinite() || !translation.allFinite()) return false;
  Camera& cam = s.cameras[static_cast<std::size_t>(c)];
  cam.cam_from_world.rotation = Eigen::Quaterniond(rotation).normalized();
  cam.cam_from_world.translation = translation;
  s.placed[static_cast<std::size_t>(c)] = true;
  s.order.push_back(c);
  return true;
}

// The wave's thinnest direction over its widest (standard deviations): near 0 for a planar wave,
// which pins neither the cameras' depth nor their focal lengths.
double thinness(const State& s) {
  std::vector<Eigen::Vector3d> points;
  for (const Track& t : s.tracks) {
    if (t.point) points.push_back(*t.point);
  }
  if (points.size() < 3) return 0.0;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : points) cov += (p - mean) * (p - mean).transpose();
  const Eigen::Vector3d values = symmetric_eigenvalues(cov);
  return std::sqrt(std::max(values[0], 0.0) / std::max(values[2], 1e-300));
}

struct Solved {
  State state;
  BundleSummary summary;
  double threshold_px = 0.0;
  int outliers = 0;
};

// One whole attempt from the given intrinsics: graph initialisation, adjustment, outliers.
std::expected<Solved, std::string> solve(State s, const std::vector<GraphEdge>& edges, const WandSettings& settings, const CameraRig& rig,
                                         const std::function<void(const std::string&)>& progress) {
  // Before the adjustment, intrinsics that are to be refined may be off by several pixels.
  const bool refining = settings.refine_focal || settings.refine_principal_point || settings.refine_k1 || settings.search_focal;
  const double tolerance_px = settings.initial_tolerance_px > 0 ? settings.initial_tolerance_px : (refining ? 10.0 : 3.0);
  if (const auto ok = place_first_pair(s, edges, settings.min_shared_points, tolerance_px, rig); !ok) return std::unexpected(ok.error());
  if (const double thin = thinness(s); thin < 0.02) {
    return std::unexpected("the wave is nearly planar (its thinnest direction spans " + fmt(100.0 * thin, 1) +
                           " % of its widest): wave up and down and in depth too, through the whole volume");
  }
  BundleSettings quick;
  quick.max_iterations = 15;
  quick.threads = settings.threads;
  quick.huber_px = 2.0;
  if (const auto b = adjust(s, quick); !b) return std::unexpected(b.error());
  if (progress)
    progress("placed " + camera_label(rig, s.order[0]) + " and " + camera_label(rig, s.order[1]) + " from their essential matrix");
  const int n = static_cast<int>(s.cameras.size());
  while (static_cast<int>(s.order.size()) < n) {
    // The unplaced camera that sees the most reconstructed points.
    int best = -1, best_count = 0;
    for (int c = 0; c < n; ++c) {
      if (s.placed[static_cast<std::size_t>(c)]) continue;
      int count = 0;
      for (const Track& t : s.tracks) {
        if (!t.point) continue;
        for (const int tc : t.cameras) count += tc == c ? 1 : 0;
      }
      if (count > best_count) {
        best = c;
        best_count = count;
      }
    }
    if (best < 0) break;
    if (!place_camera(s, best, tolerance_px)) {
      return std::unexpected(
          "cannot place " + camera_label(rig, best) + ": the " + std::to_string(best_count) +
          " reconstructed points it saw do not fit one camera pose; are the detections' camera streams in the rig's order, "
          "and are its intrinsics its own?");
    }
    triangulate_new(s, 2.5 * tolerance_px);
    if (const auto b = adjust(s, quick); !b) return std::unexpected(b.error());
    triangulate_new(s, 2.5 * tolerance_px);
    if (progress) progress("placed " + camera_label(rig, best) + " against " + std::to_string(best_count) + " points");
  }
  for (int c = 0; c < n; ++c) {
    if (!s.placed[static_cast<std::size_t>(c)]) {
      return std::unexpected("cannot place " + camera_label(rig, c) + ": it sees no reconstructed point");
    }
  }
  BundleSettings full;
  full.refine_focal = settings.refine_focal || settings.search_focal;
  full.refine_principal_point = settings.refine_principal_point;
  full.refine_k1 = settings.refine_k1;
  full.threads = settings.threads;
  full.huber_px = 1.0;
  Solved out;
  auto summary = adjust(s, full);
  if (!summary) return std::unexpected(summary.error());
  for (int round = 0; round < 4; ++round) {
    const int rejected = reject_outliers(s, settings.outlier_px, out.threshold_px);
    out.outliers += rejected;
    triangulate_new(s, out.threshold_px);
    summary = adjust(s, full);
    if (!summary) return std::unexpected(summary.error());
    if (progress) {
      progress("bundle adjustment round " + std::to_string(round + 1) + ": " + fmt(summary->final_rms_px, 3) + " px RMS, " +
               std::to_string(rejected) + " outliers beyond " + fmt(out.threshold_px) + " px dropped");
    }
    if (rejected == 0) break;
  }
  out.summary = *summary;
  out.state = std::move(s);
  return out;
}

double inlier_rms(const State& s) {
  double sum = 0;
  std::size_t n = 0;
  for_each_residual(s, [&](std::size_t i, std::size_t k, const Eigen::Vector2d& r) {
    if (s.tracks[i].rejected[k]) return;
    sum += r.squaredNorm();
    ++n;
  });
  return n > 0 ? std::sqrt(sum / static_cast<double>(n)) : 1e9;
}

std::expected<void, std::string> check_inputs(const CameraRig& rig, const Detections& d) {
  const int n = static_cast<int>(rig.cameras.size());
  if (n < 2 || n > 32) return std::unexpected("the rig has " + std::to_string(n) + " cameras; a wand calibration needs 2 to 32");
  if (d.camera_count > n) {
    return std::unexpected("the detections name camera " + std::to_string(d.camera_count - 1) + " but the rig has only " +
                           std::to_string(n) + " cameras (0 to " + std::to_string(n - 1) + ")");
  }
  for (std::size_t c = 0; c < d.image_sizes_px.size() && c < rig.cameras.size(); ++c) {
    const CameraIntrinsics& k = rig.cameras[c].intrinsics;
    if (d.image_sizes_px[c] != Eigen::Vector2i(k.width_px, k.height_px)) {
      return std::unexpected(camera_label(rig, static_cast<int>(c)) + ": the detections' images are " +
                             std::to_string(d.image_sizes_px[c].x()) + "x" + std::to_string(d.image_sizes_px[c].y()) +
                             " but its intrinsics are for " + std::to_string(k.width_px) + "x" + std::to_string(k.height_px));
    }
  }
  for (const DetectionFrame& f : d.frames) {
    for (const MarkerObservation& o : f.observations) {
      if (o.camera < 0 || o.camera >= n) {
        return std::unexpected("frame " + std::to_string(f.frame) + ": a detection names camera " + std::to_string(o.camera) +
                               " but the rig has cameras 0 to " + std::to_string(n - 1));
      }
      if (!o.pixel.allFinite()) return std::unexpected("frame " + std::to_string(f.frame) + ": a detection's pixel is not finite");
    }
  }
  std::vector<int> outside(static_cast<std::size_t>(n), 0);
  std::vector<std::string> example(static_cast<std::size_t>(n));
  for (const DetectionFrame& f : d.frames) {
    for (const MarkerObservation& o : f.observations) {
      const CameraIntrinsics& k = rig.cameras[static_cast<std::size_t>(o.camera)].intrinsics;
      // A detector's centroids lie within the image; noise of a simulated or interpolated one may
      // carry them a little past the edge, so only 2 px past it counts as off the image.
      if (o.pixel.x() < -2.0 || o.pixel.y() < -2.0 || o.pixel.x() > k.width_px + 1.5 || o.pixel.y() > k.height_px + 1.5) {
        if (outside[static_cast<std::size_t>(o.camera)]++ == 0) {
          example[static_cast<std::size_t>(o.camera)] =
              "frame " + std::to_string(f.frame) + " at (" + fmt(o.pixel.x(), 1) + ", " + fmt(o.pixel.y(), 1) + ")";
        }
      }
    }
  }
  for (int c = 0; c < n; ++c) {
    if (outside[static_cast<std::size_t>(c)] > 0) {
      const CameraIntrinsics& k = rig.cameras[static_cast<std::size_t>(c)].intrinsics;
      return std::unexpected(camera_label(rig, c) + ": " + std::to_string(outside[static_cast<std::size_t>(c)]) +
                             " detections lie outside its " + std::to_string(k.width_px) + "x" + std::to_string(k.height_px) +
                             " image (first: " + example[static_cast<std::size_t>(c)] +
                             "); are the detections' cameras in the rig's order?");
    }
  }
  return {};
}

// Connected groups of the camera graph (edges with at least `min_shared` shared points).
std::vector<std::vector<int>> graph_groups(int n, const std::vector<GraphEdge>& edges, int min_shared) {
  std::vector<int> group(static_cast<std::size_t>(n));
  std::iota(group.begin(), group.end(), 0);
  const std::function<int(int)> root = [&](int c) {
    return group[static_cast<std::size_t>(c)] == c ? c : root(group[static_cast<std::size_t>(c)]);
  };
  for (const GraphEdge& e : edges) {
    if (e.shared_points >= min_shared) group[static_cast<std::size_t>(root(e.a))] = root(e.b);
  }
  std::map<int, std::vector<int>> groups;
  for (int c = 0; c < n; ++c) groups[root(c)].push_back(c);
  std::vector<std::vector<int>> out;
  for (auto& [r, members] : groups) out.push_back(members);
  return out;
}

// The point tracks of the detections, each pixel undistorted with its own camera; refuses too few
// tracks, and a camera that sees too few of them (saying when its blobs were ambiguous).
std::expected<State, std::string> start_state(const CameraRig& intrinsics, const Detections& detections, const TrackSplit& split,
                                              const WandSettings& settings) {
  const int n = static_cast<int>(intrinsics.cameras.size());
  State start;
  start.cameras = intrinsics.cameras;
  start.placed.assign(static_cast<std::size_t>(n), false);
  std::vector<int> points_per_camera(static_cast<std::size_t>(n), 0);
  for (const PointTrack& pt : split.tracks) {
    Track t;
    t.frame = pt.frame;
    t.marker = pt.marker;
    for (const auto& [camera, pixel] : pt.views) {
      t.cameras.push_back(camera);
      t.pixels.push_back(pixel);
      t.normalised.push_back(start.cameras[static_cast<std::size_t>(camera)].undistort(pixel));
      t.rejected.push_back(false);
      ++points_per_camera[static_cast<std::size_t>(camera)];
    }
    start.tracks.push_back(std::move(t));
  }
  if (static_cast<int>(start.tracks.size()) < settings.min_points) {
    return std::unexpected("too few frames: " + std::to_string(start.tracks.size()) +
                           " marker positions were seen by two cameras or more (need " + std::to_string(settings.min_points) + ")");
  }
  for (int c = 0; c < n; ++c) {
    if (points_per_camera[static_cast<std::size_t>(c)] < settings.min_points) {
      // Blobs it could not tell apart: a fixed reflection or a second light in its view.
      int ambiguous = 0;
      for (const DetectionFrame& f : detections.frames) {
        int blobs = 0;
        for (const MarkerObservation& o : f.observations) blobs += (o.camera == c && o.marker < 0) ? 1 : 0;
        ambiguous += blobs > 1 ? 1 : 0;
      }
      std::string why = "wave where it can see";
      if (ambiguous > 0) {
        why = "in " + std::to_string(ambiguous) +
              " frames it saw several unlabelled blobs that cannot be told apart (a reflection or a second light in its view?)";
      }
      return std::unexpected(camera_label(intrinsics, c) + " saw only " + std::to_string(points_per_camera[static_cast<std::size_t>(c)]) +
                             " marker positions that another camera saw too (need " + std::to_string(settings.min_points) +
                             "): it cannot be connected to the rig; " + why);
    }
  }
  return start;
}

// Every camera pair that shares points; refuses a graph in pieces, naming its groups.
std::expected<std::vector<GraphEdge>, std::string> camera_graph(const State& start, const CameraRig& intrinsics,
                                                                const WandSettings& settings) {
  const int n = static_cast<int>(intrinsics.cameras.size());
  std::vector<std::vector<int>> shared(static_cast<std::size_t>(n), std::vector<int>(static_cast<std::size_t>(n), 0));
  for (const Track& t : start.tracks) {
    for (std::size_t i = 0; i < t.cameras.size(); ++i) {
      for (std::size_t j = i + 1; j < t.cameras.size(); ++j) {
        const auto a = static_cast<std::size_t>(std::min(t.cameras[i], t.cameras[j]));
        const auto b = static_cast<std::size_t>(std::max(t.cameras[i], t.cameras[j]));
        ++shared[a][b];
      }
    }
  }
  std::vector<GraphEdge> edges;
  for (int a = 0; a < n; ++a) {
    for (int b = a + 1; b < n; ++b) {
      if (shared[static_cast<std::size_t>(a)][static_cast<std::size_t>(b)] > 0) {
        edges.push_back({a, b, shared[static_cast<std::size_t>(a)][static_cast<std::size_t>(b)]});
      }
    }
  }
  const auto groups = graph_groups(n, edges, settings.min_shared_points);
  if (groups.size() > 1) {
    std::string message = "the cameras do not form one connected graph (an edge needs " + std::to_string(settings.min_shared_points) +
                          " shared points): groups";
    for (const auto& g : groups) {
      message += " {";
      for (std::size_t i = 0; i < g.size(); ++i) message += (i ? ", " : "") + intrinsics.cameras[static_cast<std::size_t>(g[i])].name;
      message += "}";
    }
    message += "; wave where cameras of different groups see the marker at once, or calibrate the groups apart and merge them";
    return std::unexpected(message);
  }
  return edges;
}

// With rough intrinsics: a whole solve per candidate focal length (0.5 to 2 image widths), keeping
// the one that explains the detections best. `factor` receives the chosen one.
std::expected<Solved, std::string> solve_searching_focal(const State& start, const std::vector<GraphEdge>& edges,
                                                         const WandSettings& settings, const CameraRig& intrinsics,
                                                         const std::function<void(const std::string&)>& progress, double& searched_factor) {
  std::optional<Solved> best;
  double best_rms = 1e300;
  std::string last_error;
  for (const double factor : {0.5, 0.63, 0.8, 1.0, 1.26, 1.59, 2.0}) {
    State trial = start;
    for (Camera& c : trial.cameras) {
      const double aspect = c.intrinsics.fy / c.intrinsics.fx;
      c.intrinsics.fx = factor * c.intrinsics.width_px;
      c.intrinsics.fy = c.intrinsics.fx * aspect;
    }
    for (Track& t : trial.tracks) {
      for (std::size_t k = 0; k < t.cameras.size(); ++k)
        t.normalised[k] = trial.cameras[static_cast<std::size_t>(t.cameras[k])].undistort(t.pixels[k]);
    }
    auto solved = solve(trial, edges, settings, intrinsics, {});
    const double r = solved ? inlier_rms(solved->state) : 1e300;
    if (progress) progress("focal length " + fmt(factor, 2) + " image widths: " + (solved ? fmt(r, 3) + " px RMS" : solved.error()));
    if (!solved) {
      last_error = solved.error();
    } else if (r < best_rms) {
      best_rms = r;
      best = std::move(*solved);
      searched_factor = factor;
    }
  }
  if (!best) return std::unexpected("no focal length from 0.5 to 2 image widths explains the detections: " + last_error);
  return std::move(*best);
}

// Per camera: residuals (kept for the pictures), RMS, median, p95, inliers, outliers, frames, coverage.
void report_cameras(const State& s, WandCalibration& out) {
  const int n = static_cast<int>(s.cameras.size());
  WandReport& report = out.report;
  out.residuals.assign(static_cast<std::size_t>(n), {});
  std::vector<std::vector<double>> norms(static_cast<std::size_t>(n));
  std::vector<std::set<long>> frames(static_cast<std::size_t>(n));
  std::vector<std::vector<Eigen::Vector2d>> seen(static_cast<std::size_t>(n));
  std::vector<int> outliers(static_cast<std::size_t>(n), 0);
  for_each_residual(s, [&](std::size_t i, std::size_t k, const Eigen::Vector2d& r) {
    const Track& t = s.tracks[i];
    const auto c = static_cast<std::size_t>(t.cameras[k]);
    out.residuals[c].push_back({t.pixels[k], r, !t.rejected[k]});
    if (t.rejected[k]) {
      ++outliers[c];
      return;
    }
    norms[c].push_back(r.norm());
    frames[c].insert(t.frame);
    seen[c].push_back(t.pixels[k]);
  });
  for (const Track& t : s.tracks) {
    if (t.point) continue;
    for (std::size_t k = 0; k < t.cameras.size(); ++k) outliers[static_cast<std::size_t>(t.cameras[k])] += t.rejected[k] ? 1 : 0;
  }
  for (int c = 0; c < n; ++c) {
    const auto ci = static_cast<std::size_t>(c);
    CameraCalibrationReport cr;
    cr.name = s.cameras[ci].name;
    double sq = 0;
    for (const double v : norms[ci]) sq += v * v;
    cr.rms_px = norms[ci].empty() ? 0.0 : std::sqrt(sq / static_cast<double>(norms[ci].size()));
    cr.median_px = quantile(norms[ci], 0.5);
    cr.p95_px = quantile(norms[ci], 0.95);
    cr.inliers = static_cast<int>(norms[ci].size());
    cr.outliers = outliers[ci];
    cr.frames_seen = static_cast<int>(frames[ci].size());
    cr.coverage = image_coverage(s.cameras[ci].intrinsics.width_px, s.cameras[ci].intrinsics.height_px, seen[ci]);
    report.cameras.push_back(cr);
  }
}

// A camera far worse than the others (swapped streams, wrong intrinsics) or a wave too small to
// pin the cameras is refused; a camera the wave covered poorly is a warning.
std::expected<void, std::string> check_result(const CameraRig& intrinsics, WandReport& report) {
  const int n = static_cast<int>(intrinsics.cameras.size());
  {
    std::vector<double> camera_rms;
    for (const auto& cr : report.cameras) camera_rms.push_back(cr.rms_px);
    const double median_rms = quantile(camera_rms, 0.5);
    for (int c = 0; c < n; ++c) {
      const auto& cr = report.cameras[static_cast<std::size_t>(c)];
      if (cr.rms_px > std::max(1.0, 3.0 * median_rms)) {
        return std::unexpected(camera_label(intrinsics, c) + " does not fit the others: " + fmt(cr.rms_px) +
                               " px RMS against a median of " + fmt(median_rms) +
                               " px; are the detections' camera streams in the rig's order, and are its intrinsics its own?");
      }
    }
  }
  {
    double best_coverage = 0;
    for (const auto& cr : report.cameras) best_coverage = std::max(best_coverage, cr.coverage);
    if (best_coverage < 0.05) {
      return std::unexpected("the wave is too small: it covers at most " + fmt(100.0 * best_coverage, 1) +
                             " % of any camera's image; wave through the whole volume");
    }
    for (const auto& cr : report.cameras) {
      if (cr.coverage < 0.25) {
        report.warnings.push_back("camera \"" + cr.name + "\": the wave covered only " + fmt(100.0 * cr.coverage, 0) +
                                  " % of its image; its calibration is less certain near the edges");
      }
    }
  }

  return {};
}

// The scale: from the wand's ends (least squares over every frame with both), reported as the
// wand's length errors; without a wand, the distance between the first two cameras placed.
std::expected<double, std::string> rig_scale(const State& s, const WandSettings& settings, WandReport& report) {
  double scale = 1.0;
  std::vector<double> lengths;
  if (settings.wand_length_m) {
    std::map<long, std::pair<const Track*, const Track*>> ends;
    for (const Track& t : s.tracks) {
      if (!t.point) continue;
      if (t.marker == settings.marker_a) ends[t.frame].first = &t;
      if (t.marker == settings.marker_b) ends[t.frame].second = &t;
    }
    for (const auto& [frame, pair] : ends) {
      if (pair.first && pair.second) lengths.push_back((*pair.first->point - *pair.second->point).norm());
    }
    if (lengths.size() < 10) {
      return std::unexpected("the wand's markers " + std::to_string(settings.marker_a) + " and " + std::to_string(settings.marker_b) +
                             " were reconstructed together in only " + std::to_string(lengths.size()) +
                             " frames (need 10); are they labelled in the detections' marker column?");
    }
    double sd = 0, sdd = 0;
    for (const double d : lengths) {
      sd += d;
      sdd += d * d;
    }
    scale = *settings.wand_length_m * sd / sdd;
    double sum = 0, sum_sq = 0, max_abs = 0;
    for (const double d : lengths) {
      const double e = (scale * d - *settings.wand_length_m) * 1000.0;
      sum += e;
      sum_sq += e * e;
      max_abs = std::max(max_abs, std::abs(e));
    }
    report.metric = true;
    report.wand_frames = static_cast<int>(lengths.size());
    report.wand_mean_mm = sum / static_cast<double>(lengths.size());
    report.wand_rms_mm = std::sqrt(sum_sq / static_cast<double>(lengths.size()));
    report.wand_max_mm = max_abs;
  } else {
    // The unit: the distance between the first two cameras placed.
    scale = 1.0 / std::max(1e-12, (s.cameras[static_cast<std::size_t>(s.order[0])].centre_world() -
                                   s.cameras[static_cast<std::size_t>(s.order[1])].centre_world())
                                      .norm());
    report.warnings.push_back(
        "no wand length given: the rig is not metric (its unit is the distance between the first two cameras placed)");
  }
  return scale;
}

}  // namespace

std::expected<void, std::string> WandSettings::check() const {
  if (wand_length_m && !(std::isfinite(*wand_length_m) && *wand_length_m >= 0.001 && *wand_length_m <= 10.0)) {
    return std::unexpected("wand length: expected 1 mm to 10 m, got " + fmt(*wand_length_m * 1000.0, 3) + " mm");
  }
  if (marker_a < 0 || marker_b < 0 || marker_a == marker_b) return std::unexpected("wand markers: expected two different non-negative ids");
  if (!(outlier_px >= 0.0) || !std::isfinite(outlier_px))
    return std::unexpected("outlier threshold: expected 0 (automatic) or a positive number of pixels");
  if (!(initial_tolerance_px >= 0.0) || !std::isfinite(initial_tolerance_px)) {
    return std::unexpected("initial tolerance: expected 0 (automatic) or a positive number of pixels");
  }
  if (min_shared_points < 5) return std::unexpected("min_shared_points: expected at least 5");
  if (min_points < 6) return std::unexpected("min_points: expected at least 6");
  if (threads < 1) return std::unexpected("threads: expected at least 1");
  return {};
}

std::expected<WandCalibration, std::string> calibrate_wand(const CameraRig& intrinsics, const Detections& detections,
                                                           const WandSettings& settings,
                                                           const std::function<void(const std::string&)>& progress) {
  if (const auto ok = settings.check(); !ok) return std::unexpected(ok.error());
  if (const auto ok = check_inputs(intrinsics, detections); !ok) return std::unexpected(ok.error());
  const TrackSplit split = split_tracks(detections);
  const auto start = start_state(intrinsics, detections, split, settings);
  if (!start) return std::unexpected(start.error());
  const auto edges = camera_graph(*start, intrinsics, settings);
  if (!edges) return std::unexpected(edges.error());
  if (progress) {
    progress(std::to_string(start->tracks.size()) + " marker positions seen by two cameras or more, " + std::to_string(edges->size()) +
             " camera pairs sharing points");
  }
  double searched_factor = 0.0;
  auto solved = settings.search_focal ? solve_searching_focal(*start, *edges, settings, intrinsics, progress, searched_factor)
                                      : solve(*start, *edges, settings, intrinsics, progress);
  if (!solved) return std::unexpected(solved.error());
  const State& s = solved->state;

  WandCalibration out;
  WandReport& report = out.report;
  report.rms_px = inlier_rms(s);
  report.iterations = solved->summary.iterations;
  report.outliers = solved->outliers;
  report.ambiguous = static_cast<int>(split.ambiguous);
  report.placement_order = s.order;
  report.graph = *edges;
  report.focal_searched_px = searched_factor > 0 ? searched_factor * intrinsics.cameras[0].intrinsics.width_px : 0.0;
  report_cameras(s, out);
  if (const auto ok = check_result(intrinsics, report); !ok) return std::unexpected(ok.error());
  const auto scale = rig_scale(s, settings, report);
  if (!scale) return std::unexpected(scale.error());

  // Camera 0's frame in rhot's axes, at the wand's scale.
  std::vector<Eigen::Vector3d> points;
  for (const Track& t : s.tracks) {
    if (t.point) points.push_back(*t.point);
  }
  Similarity3 world_from_old;
  const Eigen::Matrix3d flip = Eigen::Vector3d(1, -1, -1).asDiagonal();
  world_from_old.scale = *scale;
  world_from_old.rotation = flip * s.cameras[0].cam_from_world.rotation.toRotationMatrix();
  world_from_old.translation = *scale * (flip * s.cameras[0].cam_from_world.translation);
  out.rig.name = intrinsics.name;
  for (const Camera& c : s.cameras) out.rig.cameras.push_back(transform_camera(c, world_from_old));
  for (const Eigen::Vector3d& p : points) out.points_world.push_back(world_from_old.apply(p));
  report.points = static_cast<int>(points.size());
  // The tracking volume: the box the wave filled.
  if (!out.points_world.empty()) {
    Eigen::Vector3d lo = out.points_world[0], hi = out.points_world[0];
    for (const auto& p : out.points_world) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    if ((hi - lo).minCoeff() > 0) out.rig.volume = TrackingVolume{(lo + hi) / 2, hi - lo};
  }
  return out;
}

}  // namespace rhot
