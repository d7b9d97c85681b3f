#include "tracking/sim/CalibrationSessions.h"

#include <array>
#include <map>
#include <optional>
#include <random>

#include <Eigen/Dense>

#include "tracking/geometry/Triangulation.h"

namespace rhot {

namespace {

// The frames of a simulated rig as detections, with strays and outliers added.
Detections to_detections(SimulatedRig& sim, const CameraRig& rig, int frames, bool labelled, const SessionNoise& noise) {
  std::mt19937_64 rng(noise.rig.seed * 7919ULL + 17ULL);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Detections d;
  d.camera_count = static_cast<int>(rig.cameras.size());
  for (int f = 0; f < frames; ++f) {
    const RigFrame frame = sim.next();
    DetectionFrame df;
    df.frame = f;
    for (const CameraFrame& cf : frame.cameras) {
      const CameraIntrinsics& k = rig.cameras[static_cast<std::size_t>(cf.camera)].intrinsics;
      for (const Detection& det : cf.detections) {
        Eigen::Vector2d pixel = det.pixel;
        if (noise.outliers > 0 && unit(rng) < noise.outliers) {
          const double angle = 2 * M_PI * unit(rng);
          const double distance = 3.0 + 27.0 * unit(rng);
          pixel += distance * Eigen::Vector2d(std::cos(angle), std::sin(angle));
          pixel = pixel.cwiseMax(Eigen::Vector2d(0, 0)).cwiseMin(Eigen::Vector2d(k.width_px - 1, k.height_px - 1));
        }
        df.observations.push_back({cf.camera, pixel, labelled ? det.truth_marker : -1});
      }
      if (noise.strays > 0 && unit(rng) < noise.strays) {
        df.observations.push_back({cf.camera, {unit(rng) * (k.width_px - 1), unit(rng) * (k.height_px - 1)}, -1});
      }
    }
    if (!df.observations.empty()) d.frames.push_back(std::move(df));
  }
  return d;
}

Trajectory still(const Eigen::Vector3d& p) {
  Trajectory t;
  t.centre_m = p;
  return t;
}

}  // namespace

double wand_length_rms_mm(const CameraRig& rig, const Detections& detections, double wand_length_m) {
  std::map<long, std::array<std::optional<Eigen::Vector3d>, 2>> ends;
  for (const PointTrack& t : split_tracks(detections).tracks) {
    if (t.marker < 0 || t.marker > 1) continue;
    std::vector<Observation> observations;
    for (const auto& [camera, pixel] : t.views) observations.push_back({camera, pixel});
    const auto x = triangulate(rig, observations);
    if (x) ends[t.frame][static_cast<std::size_t>(t.marker)] = x->position_world;
  }
  double sq = 0;
  int n = 0;
  for (const auto& [frame, e] : ends) {
    if (!e[0] || !e[1]) continue;
    const double error = ((*e[0] - *e[1]).norm() - wand_length_m) * 1000.0;
    sq += error * error;
    ++n;
  }
  return n > 0 ? std::sqrt(sq / n) : 0.0;
}

TrackingVolume session_box(const CameraRig& rig) {
  if (rig.volume) return *rig.volume;
  return TrackingVolume{axes_meeting_point(rig), Eigen::Vector3d::Ones()};
}

Detections simulate_wand_session(const CameraRig& rig, const WandSession& session, const SessionNoise& noise) {
  const Eigen::Vector3d half = session.box_size_m / 2;
  const auto ends = wand_trajectories(session.wand_length_m, session.box_centre_m - half, session.box_centre_m + half);
  std::vector<Trajectory> markers{ends[0]};
  if (session.markers >= 2) markers.push_back(ends[1]);
  SimulatedRig sim(rig, markers, noise.rig);
  return to_detections(sim, rig, session.frames, session.markers >= 2, noise);
}

Detections simulate_lframe_session(const CameraRig& rig, const LFrame& frame, const Rigid3d& world_from_frame, int frames,
                                   const SessionNoise& noise) {
  std::vector<Trajectory> markers;
  for (const Eigen::Vector3d& m : frame.markers_world()) markers.push_back(still(world_from_frame * m));
  SimulatedRig sim(rig, markers, noise.rig);
  return to_detections(sim, rig, frames, false, noise);
}

Detections simulate_floor_session(const CameraRig& rig, const std::vector<Eigen::Vector3d>& places_on_floor, double height_m,
                                  int frames_per_place, const SessionNoise& noise) {
  // Between places the marker is carried over in kMoving frames, lifted up to 10 cm, starting and
  // stopping gently (a smoothstep), as a hand would.
  constexpr int kMoving = 30;
  const int period = frames_per_place + kMoving;
  const int frames = period * static_cast<int>(places_on_floor.size()) - kMoving;
  SimulatedRig sim(rig, {}, noise.rig);
  const double rate = noise.rig.rate_hz;
  const std::vector<Eigen::Vector3d> places = places_on_floor;
  sim.set_scripted_markers([places, height_m, period, frames_per_place, rate](double t_s) {
    const auto f = static_cast<int>(std::lround(t_s * rate));
    const auto i = std::min(places.size() - 1, static_cast<std::size_t>(f / period));
    const int into = f % period;
    Eigen::Vector3d p = places[i];
    if (into >= frames_per_place && i + 1 < places.size()) {
      const double t = static_cast<double>(into - frames_per_place + 1) / (period - frames_per_place + 1);
      const double eased = t * t * (3 - 2 * t);
      p = places[i] + eased * (places[i + 1] - places[i]) + Eigen::Vector3d(0, 0.1 * std::sin(M_PI * t), 0);
    }
    return std::vector<Eigen::Vector3d>{p + Eigen::Vector3d(0, height_m, 0)};
  });
  return to_detections(sim, rig, frames, false, noise);
}

}  // namespace rhot
