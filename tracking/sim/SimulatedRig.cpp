#include "tracking/sim/SimulatedRig.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <Eigen/Geometry>

#include "base/Check.h"

namespace rhot {

namespace {

// In scalars: a simulated frame tests every marker's line of sight to every camera against every
// occluder, and at the sanitized build's -O1 Eigen's expressions were calls (15 % of the render
// soak's time, before the libraries inlined them). The results are bit for bit Eigen's on x86-64
// (SSE2, no FMA): each sum in Eigen's order, the quaternion's rotation as its _transformVector.
struct V3 {
  double x, y, z;
};
V3 v3(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }
V3 sub(const V3& a, const V3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
double dot(const V3& a, const V3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

// Smallest distance between segments [p0, p1] and [q0, q1].
double segment_distance(const V3& p0, const V3& p1, const V3& q0, const V3& q1) {
  const V3 d1 = sub(p1, p0);
  const V3 d2 = sub(q1, q0);
  const V3 r = sub(p0, q0);
  const double a = dot(d1, d1);
  const double e = dot(d2, d2);
  const double f = dot(d2, r);
  double s = 0.0;
  double t = 0.0;
  if (a <= 1e-18 && e <= 1e-18) return std::sqrt(dot(r, r));
  if (a <= 1e-18) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = dot(d1, r);
    if (e <= 1e-18) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = dot(d1, d2);
      const double denom = a * e - b * b;
      s = denom > 1e-18 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0.0) {
        t = 0.0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1.0) {
        t = 1.0;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  const V3 gap{(p0.x + d1.x * s) - (q0.x + d2.x * t), (p0.y + d1.y * s) - (q0.y + d2.y * t), (p0.z + d1.z * s) - (q0.z + d2.z * t)};
  return std::sqrt(dot(gap, gap));
}

// v turned by the conjugate of the unit quaternion (w, x, y, z): v + w t + u x t with
// t = 2 (u x v), u = -(x, y, z), as Eigen's quaternion-vector product.
V3 turn_back(const Eigen::Quaterniond& q, const V3& v) {
  const V3 u{-q.x(), -q.y(), -q.z()};
  const V3 t{2.0 * (u.y * v.z - u.z * v.y), 2.0 * (u.z * v.x - u.x * v.z), 2.0 * (u.x * v.y - u.y * v.x)};
  const double w = q.w();
  return {v.x + w * t.x + (u.y * t.z - u.z * t.y), v.y + w * t.y + (u.z * t.x - u.x * t.z), v.z + w * t.z + (u.x * t.y - u.y * t.x)};
}

}  // namespace

bool Occluder::blocks(const Eigen::Vector3d& p, const Eigen::Vector3d& q) const {
  const V3 p3 = v3(p), q3 = v3(q), a3 = v3(a_m);  // a_m: a capsule's one end, or the box's centre
  if (!is_box()) return segment_distance(p3, q3, a3, v3(b_m)) < radius_m;
  // Slabs: the segment in the box's frame, clipped by each pair of faces.
  const V3 a = turn_back(box_rotation, sub(p3, a3));
  const V3 d = sub(turn_back(box_rotation, sub(q3, a3)), a);
  const double half[3] = {box_half_m.x(), box_half_m.y(), box_half_m.z()};
  const double start[3] = {a.x, a.y, a.z};
  const double along[3] = {d.x, d.y, d.z};
  double t0 = 0.0, t1 = 1.0;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(along[i]) < 1e-15) {
      if (std::abs(start[i]) > half[i]) return false;
      continue;
    }
    double u = (-half[i] - start[i]) / along[i];
    double v = (half[i] - start[i]) / along[i];
    if (u > v) std::swap(u, v);
    t0 = std::max(t0, u);
    t1 = std::min(t1, v);
    if (t0 > t1) return false;
  }
  return true;
}

std::expected<void, std::string> SimulatedRigSettings::check() const {
  const auto bad = [](const char* field, const char* expected, double value) {
    return std::unexpected(std::string(field) + ": expected " + expected + ", got " + std::to_string(value));
  };
  if (!std::isfinite(sigma_px) || sigma_px < 0.0) return bad("sigma_px", "a pixel noise of 0 or more", sigma_px);
  if (!std::isfinite(dropout) || dropout < 0.0 || dropout > 1.0) return bad("dropout", "a probability from 0 to 1", dropout);
  if (!std::isfinite(rate_hz) || !(rate_hz > 0.0)) return bad("rate_hz", "a positive frame rate", rate_hz);
  if (!std::isfinite(camera_skew_s) || std::abs(camera_skew_s) > 1.0) return bad("camera_skew_s", "at most 1 s either way", camera_skew_s);
  if (!std::isfinite(merge_distance_px) || merge_distance_px < 0.0) return bad("merge_distance_px", "0 or more pixels", merge_distance_px);
  if (!std::isfinite(marker_diameter_m) || marker_diameter_m < 0.0 || marker_diameter_m > 0.1)
    return bad("marker_diameter_m", "0 to 0.1 m", marker_diameter_m);
  if (strays < 0 || strays > 1000) return bad("strays", "0 to 1000 stray detections per camera", strays);
  if (!std::isfinite(stray_fixed_fraction) || stray_fixed_fraction < 0.0 || stray_fixed_fraction > 1.0)
    return bad("stray_fixed_fraction", "a fraction from 0 to 1", stray_fixed_fraction);
  return {};
}

Eigen::Vector3d Trajectory::at(double t_s) const {
  Eigen::Vector3d p = centre_m;
  for (int i = 0; i < 3; ++i) {
    p(i) += amplitude_m(i) * std::sin(2.0 * std::numbers::pi * frequency_hz(i) * t_s + phase_rad(i)) +
            drift_amplitude_m(i) * std::sin(2.0 * std::numbers::pi * drift_frequency_hz(i) * t_s + drift_phase_rad(i));
  }
  return p;
}

SimulatedRig::SimulatedRig(CameraRig rig, std::vector<Trajectory> markers, SimulatedRigSettings settings)
    : rig_(std::move(rig)), markers_(std::move(markers)), settings_(settings), rng_(settings.seed), stray_lamps_(rig_.cameras.size()) {
  RHOT_PRECONDITION(settings.check().has_value(), "SimulatedRig: " + settings.check().error());
}

bool SimulatedRig::visible(int camera, const Eigen::Vector3d& p_world) const {
  if (!p_world.allFinite()) return false;  // a scripted marker in a gap of its take
  const Camera& c = rig_.cameras[static_cast<std::size_t>(camera)];
  const auto pixel = c.project(p_world);
  if (!pixel || !c.in_image(*pixel)) return false;
  // The line of sight stops 1 mm short of the marker, so the surface a marker sits on does not
  // hide it from cameras on its own side.
  const Eigen::Vector3d from = c.centre_world();
  const Eigen::Vector3d to = p_world + (from - p_world).normalized() * 1e-3;
  for (const Occluder& o : occluders_) {
    if (o.blocks(from, to)) return false;
  }
  return true;
}

Rigid3d RigidMotion::world_from_body(double t_s) const {
  Eigen::Vector3d turn;
  for (int a = 0; a < 3; ++a)
    turn(a) = turn_amplitude_rad(a) * std::sin(2.0 * std::numbers::pi * turn_frequency_hz(a) * t_s + turn_phase_rad(a));
  Rigid3d out;
  out.rotation = base_orientation;
  if (turn.norm() > 0.0)
    out.rotation = (Eigen::Quaterniond(Eigen::AngleAxisd(turn.norm(), turn.normalized())) * base_orientation).normalized();
  out.translation = position.at(t_s);
  return out;
}

void SimulatedRig::set_bodies(std::vector<SimulatedBody> bodies) {
  bodies_ = std::move(bodies);
  body_markers_.clear();
  for (std::size_t b = 0; b < bodies_.size(); ++b) {
    for (std::size_t m = 0; m < bodies_[b].markers_body_m.size(); ++m) body_markers_.emplace_back(static_cast<int>(b), static_cast<int>(m));
  }
}

Eigen::Vector3d SimulatedRig::marker_at(std::size_t marker, double t_s) const {
  if (marker < markers_.size()) return markers_[marker].at(t_s);
  const auto [b, m] = body_markers_[marker - markers_.size()];
  const SimulatedBody& body = bodies_[static_cast<std::size_t>(b)];
  return body.motion.world_from_body(t_s) * body.markers_body_m[static_cast<std::size_t>(m)];
}

void SimulatedRig::merge_blobs(int camera, const std::vector<Eigen::Vector3d>& positions, std::vector<Detection>& detections) const {
  const Rigid3d& cam_from_world = rig_.cameras[static_cast<std::size_t>(camera)].cam_from_world;
  auto depth = [&](const Detection& d) {
    return d.truth_marker < 0 ? 1e9 : (cam_from_world * positions[static_cast<std::size_t>(d.truth_marker)]).z();
  };
  std::sort(detections.begin(), detections.end(), [&](const Detection& a, const Detection& b) { return depth(a) < depth(b); });
  // A marker's image is a disc of radius f (d / 2) / depth; two discs that overlap are one blob.
  const Camera& cam = rig_.cameras[static_cast<std::size_t>(camera)];
  const double focal = 0.5 * (cam.intrinsics.fx + cam.intrinsics.fy);
  auto radius = [&](const Detection& d) {
    return d.truth_marker < 0 ? 0.0 : focal * 0.5 * settings_.marker_diameter_m / std::max(depth(d), 1e-3);
  };
  struct Blob {
    Eigen::Vector2d sum;
    double weight;
    double radius;
    int marker;
  };
  std::vector<Blob> blobs;
  for (const Detection& d : detections) {
    const double r = radius(d);
    auto into = std::find_if(blobs.begin(), blobs.end(), [&](const Blob& b) {
      const double reach = std::max(settings_.merge_distance_px, b.radius + r);
      return (b.sum / b.weight - d.pixel).squaredNorm() < reach * reach;
    });
    // The merged blob's centroid weighs each disc by its area (equal discs: the mean).
    const double w = r > 0.0 ? r * r : 1.0;
    if (into == blobs.end()) {
      blobs.push_back({w * d.pixel, w, r, d.truth_marker});
    } else {
      into->sum += w * d.pixel;
      into->weight += w;
      into->radius = std::max(into->radius, r);
    }
  }
  detections.clear();
  for (const Blob& b : blobs) detections.push_back({b.sum / b.weight, b.marker});
}

void SimulatedRig::add_strays(int camera, std::vector<Detection>& detections) {
  if (settings_.strays == 0) return;
  const Camera& cam = rig_.cameras[static_cast<std::size_t>(camera)];
  const auto fixed = static_cast<int>(std::lround(settings_.stray_fixed_fraction * settings_.strays));
  std::uniform_real_distribution<double> x(0.0, static_cast<double>(cam.intrinsics.width_px));
  std::uniform_real_distribution<double> y(0.0, static_cast<double>(cam.intrinsics.height_px));
  std::normal_distribution<double> noise(0.0, settings_.sigma_px);
  auto& lamps = stray_lamps_[static_cast<std::size_t>(camera)];
  // Lamps: drawn once per camera from their own generator, so they stay put whatever else happens.
  if (lamps.empty()) {
    std::mt19937_64 lamp_rng(settings_.seed * 7919u + static_cast<unsigned>(camera) + 1u);
    for (int k = 0; k < fixed; ++k) lamps.emplace_back(x(lamp_rng), y(lamp_rng));
  }
  for (const Eigen::Vector2d& lamp : lamps) detections.push_back({lamp + Eigen::Vector2d{noise(rng_), noise(rng_)}, -1});
  for (int k = fixed; k < settings_.strays; ++k) detections.push_back({Eigen::Vector2d{x(rng_), y(rng_)}, -1});
}

RigFrame SimulatedRig::next() { return frame_at(static_cast<double>(frame_) / settings_.rate_hz); }

RigFrame SimulatedRig::frame_at(double t_s) {
  RigFrame frame;
  frame.index = frame_++;
  frame.time_s = t_s;
  std::normal_distribution<double> noise(0.0, settings_.sigma_px);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const std::size_t own_count = markers_.size() + body_markers_.size();
  for (std::size_t m = 0; m < own_count; ++m) {
    frame.truth_position_m.push_back(marker_at(m, frame.time_s));
    frame.truth_marker_body.push_back(m < markers_.size() ? -1 : body_markers_[m - markers_.size()].first);
  }
  // Scripted markers and the world's follow the rig's own, with no body.
  const auto scripted_at = [this](double t) {
    std::vector<Eigen::Vector3d> out;
    if (script_) out = script_(t);
    if (world_) {
      const std::vector<Eigen::Vector3d> w = world_->at(t).markers_m;
      out.insert(out.end(), w.begin(), w.end());
    }
    return out;
  };
  if (script_) {
    for (const Eigen::Vector3d& p : script_(frame.time_s)) {
      frame.truth_position_m.push_back(p);
      frame.truth_marker_body.push_back(-1);
    }
  }
  if (world_) {
    WorldSnapshot now = world_->at(frame.time_s);
    occluders_ = std::move(now.occluders);
    for (const Eigen::Vector3d& p : now.markers_m) {
      frame.truth_position_m.push_back(p);
      frame.truth_marker_body.push_back(-1);
    }
  }
  const std::size_t marker_count = frame.truth_position_m.size();
  for (const SimulatedBody& b : bodies_) frame.truth_world_from_body.push_back(b.motion.world_from_body(frame.time_s));
  for (std::size_t c = 0; c < rig_.cameras.size(); ++c) {
    CameraFrame cf;
    cf.camera = static_cast<int>(c);
    cf.timestamp_s = frame.time_s + static_cast<double>(c) * settings_.camera_skew_s;
    std::vector<Eigen::Vector3d> scripted_at_camera;
    if ((script_ || world_) && settings_.camera_skew_s != 0.0) scripted_at_camera = scripted_at(cf.timestamp_s);
    for (std::size_t m = 0; m < marker_count; ++m) {
      // Unsynchronised cameras see the marker where it is at their own exposure time.
      const Eigen::Vector3d p = settings_.camera_skew_s == 0.0              ? frame.truth_position_m[m]
                                : m < own_count                             ? marker_at(m, cf.timestamp_s)
                                : m - own_count < scripted_at_camera.size() ? scripted_at_camera[m - own_count]
                                                                            : frame.truth_position_m[m];
      // Draw the random numbers whatever happens, so one marker's visibility does not shift the
      // noise of every other: frames stay comparable across settings.
      const double drop = uniform(rng_);
      const Eigen::Vector2d n{noise(rng_), noise(rng_)};
      if (!visible(static_cast<int>(c), p) || drop < settings_.dropout) continue;
      cf.detections.push_back({*rig_.cameras[c].project(p) + n, static_cast<int>(m)});
    }
    add_strays(static_cast<int>(c), cf.detections);
    if (settings_.merge_distance_px > 0.0 || settings_.marker_diameter_m > 0.0)
      merge_blobs(static_cast<int>(c), frame.truth_position_m, cf.detections);
    std::shuffle(cf.detections.begin(), cf.detections.end(), rng_);
    frame.cameras.push_back(std::move(cf));
  }
  return frame;
}

std::array<Trajectory, 2> wand_trajectories(double length_m, const Eigen::Vector3d& box_min_m, const Eigen::Vector3d& box_max_m) {
  // Half the wand along the horizontal circle (x, z) = r (sin, cos) of one frequency: the two ends
  // are opposite points of that circle, so their distance is exactly 2 r. The middle drifts on
  // independent frequencies through the box, keeping the ends inside it.
  const double r = 0.5 * length_m;
  const Eigen::Vector3d centre = 0.5 * (box_min_m + box_max_m);
  const Eigen::Vector3d room = (0.5 * (box_max_m - box_min_m)).array() - r;
  std::array<Trajectory, 2> ends;
  for (int e = 0; e < 2; ++e) {
    Trajectory& t = ends[static_cast<std::size_t>(e)];
    const double phase = e == 0 ? 0.0 : std::numbers::pi;
    t.centre_m = centre;
    t.amplitude_m = {r, 0.0, r};
    t.frequency_hz = {0.23, 0.0, 0.23};
    t.phase_rad = {phase, 0.0, phase + 0.5 * std::numbers::pi};
    t.drift_amplitude_m = room.cwiseMax(0.0);
    t.drift_frequency_hz = {0.071, 0.113, 0.089};
    t.drift_phase_rad = {0.0, 1.0, 2.0};
  }
  return ends;
}

std::vector<RigidMotion> random_motions(int count, const Eigen::Vector3d& box_min_m, const Eigen::Vector3d& box_max_m, unsigned seed) {
  std::vector<RigidMotion> out;
  const std::vector<Trajectory> paths = random_trajectories(count, box_min_m, box_max_m, seed);
  std::mt19937_64 rng(seed ^ 0x9e3779b97f4a7c15ULL);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (const Trajectory& path : paths) {
    RigidMotion m;
    m.position = path;
    // Uniform over rotations: a normalised 4D Gaussian (Eigen's UnitRandom would draw from std::rand).
    std::normal_distribution<double> gauss(0.0, 1.0);
    const double w = gauss(rng), x = gauss(rng), y = gauss(rng), z = gauss(rng);
    m.base_orientation = Eigen::Quaterniond(w, x, y, z).normalized();
    for (int a = 0; a < 3; ++a) {
      m.turn_amplitude_rad(a) = 0.5 * std::numbers::pi * unit(rng);
      m.turn_frequency_hz(a) = 0.1 + 0.3 * unit(rng);
      m.turn_phase_rad(a) = 2.0 * std::numbers::pi * unit(rng);
    }
    out.push_back(m);
  }
  return out;
}

std::vector<Trajectory> random_trajectories(int count, const Eigen::Vector3d& box_min_m, const Eigen::Vector3d& box_max_m, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Trajectory> out;
  const Eigen::Vector3d size = box_max_m - box_min_m;
  for (int i = 0; i < count; ++i) {
    Trajectory t;
    for (int a = 0; a < 3; ++a) {
      t.amplitude_m(a) = 0.25 * size(a) * unit(rng);
      // Keep the whole path inside the box.
      t.centre_m(a) = box_min_m(a) + t.amplitude_m(a) + (size(a) - 2.0 * t.amplitude_m(a)) * unit(rng);
      t.frequency_hz(a) = 0.1 + 0.4 * unit(rng);
      t.phase_rad(a) = 2.0 * std::numbers::pi * unit(rng);
    }
    out.push_back(t);
  }
  return out;
}

std::vector<Trajectory> scattered_markers(int count, const Eigen::Vector3d& box_min_m, const Eigen::Vector3d& box_max_m, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Trajectory> out;
  for (int i = 0; i < count; ++i) {
    Trajectory t;
    for (int a = 0; a < 3; ++a) t.centre_m(a) = box_min_m(a) + (box_max_m(a) - box_min_m(a)) * unit(rng);
    t.amplitude_m.setZero();
    out.push_back(t);
  }
  return out;
}

std::vector<Trajectory> wandering_markers(const CameraRig& rig, int count, unsigned seed) {
  Eigen::Vector3d centre = axes_meeting_point(rig), size = Eigen::Vector3d::Ones();
  if (rig.volume) {
    centre = rig.volume->centre_m;
    size = rig.volume->size_m;
  }
  return random_trajectories(count, centre - size / 2, centre + size / 2, seed);
}

}  // namespace rhot
