// rhot-calib simulate: calibration sessions seen by the simulated rig, written as the detections a
// real session gives, so every step can be tried, and tested, against the truth.

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include <spdlog/spdlog.h>

#include "tools/calib/Calib.h"
#include "tracking/calib/Detections.h"
#include "tracking/camera/RigFile.h"
#include "tracking/media/Media.h"
#include "tracking/sim/CalibrationSessions.h"
#include "tracking/sim/SyntheticImages.h"

namespace rhot::calib_tool {

namespace {

struct NoiseOptions {
  double sigma = 0.3;
  double dropout = 0.0;
  double strays = 0.0;
  double outliers = 0.0;
  unsigned seed = 1;
  double rate_hz = 90.0;
};

struct SimulateOptions {
  std::string rig;
  std::string out;
  NoiseOptions noise;
  // wand
  int frames = 2000;
  double wand_mm = 500.0;
  int markers = 2;
  std::vector<double> volume;
  std::vector<double> volume_centre;
  std::string images;
  // lframe
  std::vector<double> lframe_mm{500, 300};
  double height_mm = 0.0;
  std::vector<double> at_m{0, 0, 0};
  double yaw_deg = 0.0;
  // floor
  std::vector<double> places;
  int frames_per_place = 30;
};

void add_noise_options(CLI::App* cmd, NoiseOptions& n) {
  cmd->add_option("--sigma", n.sigma, "pixel noise, standard deviation per axis")
      ->check(finite_number())
      ->capture_default_str()
      ->check(CLI::Range(0.0, 50.0));
  cmd->add_option("--dropout", n.dropout, "probability a camera misses a visible marker")
      ->check(finite_number())
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--strays", n.strays, "per camera and frame: probability of a stray blob")
      ->check(finite_number())
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--outliers", n.outliers, "per detection: probability it is displaced 3 to 30 px")
      ->check(finite_number())
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--seed", n.seed, "random seed")->capture_default_str();
  cmd->add_option("--rate-hz", n.rate_hz, "frames per second")
      ->check(finite_number())
      ->capture_default_str()
      ->check(CLI::Range(1.0, 10000.0));
}

std::expected<std::pair<CameraRig, SessionNoise>, std::string> prepare(const SimulateOptions& o) {
  auto rig = load_rig(o.rig);
  if (!rig) return std::unexpected(rig.error());
  SessionNoise noise;
  noise.rig.sigma_px = o.noise.sigma;
  noise.rig.dropout = o.noise.dropout;
  noise.rig.seed = o.noise.seed;
  noise.rig.rate_hz = o.noise.rate_hz;
  noise.strays = o.noise.strays;
  noise.outliers = o.noise.outliers;
  if (const auto ok = noise.rig.check(); !ok) return std::unexpected(ok.error());
  return std::make_pair(std::move(*rig), noise);
}

int write(const Detections& d, const SimulateOptions& o, const std::string& what) {
  if (d.frames.empty()) {
    spdlog::error("no camera saw anything: is {} inside the cameras' view?", what);
    return 1;
  }
  make_parent_folder(o.out);
  if (const auto ok = write_detections_csv(d, o.out); !ok) {
    spdlog::error("{}", ok.error());
    return 1;
  }
  spdlog::info("{}: {} detections in {} frames ({})", o.out, d.count(), d.frames.size(), what);
  return 0;
}

// Every frame of every camera as the image a camera would take (a blurred spot per detection),
// DIR/cam<i>_%04d.png, for `record` to find again.
int write_images(const Detections& d, const CameraRig& rig, int frames, const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  SyntheticImageSettings look;
  look.noise_sigma = 2.0;
  std::size_t next = 0;
  for (int f = 0; f < frames; ++f) {
    std::vector<CameraFrame> cameras(rig.cameras.size());
    for (std::size_t c = 0; c < cameras.size(); ++c) cameras[c].camera = static_cast<int>(c);
    if (next < d.frames.size() && d.frames[next].frame == f) {
      for (const MarkerObservation& o : d.frames[next].observations)
        cameras[static_cast<std::size_t>(o.camera)].detections.push_back({o.pixel, o.marker});
      ++next;
    }
    for (std::size_t c = 0; c < cameras.size(); ++c) {
      look.seed = static_cast<std::uint64_t>(f) * 131 + c;
      char name[64];
      std::snprintf(name, sizeof name, "/cam%zu_%04d.png", c, f);
      if (auto written = write_image(dir + name, draw_blobs(rig.cameras[c].intrinsics, cameras[c], look)); !written) {
        spdlog::error("{}", written.error());
        return 1;
      }
    }
    if ((f + 1) % 100 == 0) spdlog::info("images: {} of {} frames", f + 1, frames);
  }
  spdlog::info("{}: {} frames of {} cameras as cam<i>_%04d.png", dir, frames, rig.cameras.size());
  return 0;
}

int run_wand(const SimulateOptions& o) {
  const auto prepared = prepare(o);
  if (!prepared) {
    spdlog::error("{}", prepared.error());
    return 1;
  }
  const auto& [rig, noise] = *prepared;
  WandSession session;
  session.frames = o.frames;
  session.wand_length_m = o.wand_mm / 1000.0;
  session.markers = o.markers;
  const TrackingVolume box = session_box(rig);
  session.box_centre_m =
      o.volume_centre.size() == 3 ? Eigen::Vector3d(o.volume_centre[0], o.volume_centre[1], o.volume_centre[2]) : box.centre_m;
  session.box_size_m = o.volume.size() == 3 ? Eigen::Vector3d(o.volume[0], o.volume[1], o.volume[2]) : box.size_m;
  if (session.box_size_m.minCoeff() <= session.wand_length_m) {
    spdlog::error("--wand-mm: a {} mm wand does not fit the {:.2f} x {:.2f} x {:.2f} m volume it is waved in", o.wand_mm,
                  session.box_size_m.x(), session.box_size_m.y(), session.box_size_m.z());
    return 1;
  }
  const Detections d = simulate_wand_session(rig, session, noise);
  if (const int written = write(d, o, o.markers >= 2 ? "a two-marker wand" : "one marker"); written != 0) return written;
  return o.images.empty() ? 0 : write_images(d, rig, session.frames, o.images);
}

int run_lframe(const SimulateOptions& o) {
  const auto prepared = prepare(o);
  if (!prepared) {
    spdlog::error("{}", prepared.error());
    return 1;
  }
  const auto& [rig, noise] = *prepared;
  LFrame frame;
  frame.long_m = o.lframe_mm[0] / 1000.0;
  frame.short_m = o.lframe_mm[1] / 1000.0;
  if (o.lframe_mm.size() == 3) frame.middle_m = o.lframe_mm[2] / 1000.0;
  frame.height_m = o.height_mm / 1000.0;
  if (const auto ok = frame.check(); !ok) {
    spdlog::error("{}", ok.error());
    return 1;
  }
  Rigid3d world_from_frame;
  world_from_frame.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(o.yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitY()));
  world_from_frame.translation = Eigen::Vector3d(o.at_m[0], o.at_m[1], o.at_m[2]);
  return write(simulate_lframe_session(rig, frame, world_from_frame, o.frames, noise), o, "an L-frame");
}

int run_floor(const SimulateOptions& o) {
  const auto prepared = prepare(o);
  if (!prepared) {
    spdlog::error("{}", prepared.error());
    return 1;
  }
  const auto& [rig, noise] = *prepared;
  std::vector<Eigen::Vector3d> places;
  if (o.places.empty()) {
    const TrackingVolume box = session_box(rig);
    const double hx = 0.4 * box.size_m.x(), hz = 0.4 * box.size_m.z();
    places = {{box.centre_m.x() - hx, 0, box.centre_m.z() + hz},
              {box.centre_m.x() + hx, 0, box.centre_m.z() + hz},
              {box.centre_m.x() + hx, 0, box.centre_m.z() - hz},
              {box.centre_m.x() - hx, 0, box.centre_m.z() - hz}};
  } else {
    if (o.places.size() % 2 != 0 || o.places.size() < 6) {
      spdlog::error("--places: expected X,Z pairs of three places or more, got {} numbers", o.places.size());
      return 1;
    }
    for (std::size_t i = 0; i + 1 < o.places.size(); i += 2) places.emplace_back(o.places[i], 0.0, o.places[i + 1]);
  }
  return write(simulate_floor_session(rig, places, o.height_mm / 1000.0, o.frames_per_place, noise), o, "a marker touched on the floor");
}

}  // namespace

void add_simulate(CLI::App& app, int& exit_code) {
  CLI::App* simulate = app.add_subcommand("simulate", "write a calibration session seen by the simulated rig (the truth is the rig given)");
  simulate->require_subcommand(1);
  // One set of options per subcommand: their defaults differ.
  auto o = std::make_shared<SimulateOptions>();
  CLI::App* wand = simulate->add_subcommand("wand", "a wand (or one marker) waved through the rig's volume, as rhot's detections CSV");
  wand->add_option("--rig", o->rig, "the true rig (OpenCV YAML)")->required();
  wand->add_option("--out", o->out, "detections CSV to write")->required();
  wand->add_option("--frames", o->frames, "frames")->capture_default_str()->check(CLI::Range(1, 1000000));
  wand->add_option("--wand-mm", o->wand_mm, "distance between the wand's markers 0 and 1")
      ->check(finite_number())
      ->capture_default_str()
      ->check(CLI::Range(10.0, 5000.0));
  wand->add_option("--markers", o->markers, "2: a wand with labelled ends; 1: one unlabelled marker")
      ->capture_default_str()
      ->check(CLI::Range(1, 2));
  wand->add_option("--volume-m", o->volume, "size of the box waved through, X Y Z metres (default: the rig's volume)")
      ->check(finite_number())
      ->expected(3);
  wand->add_option("--volume-centre-m", o->volume_centre, "its centre, X Y Z metres")->check(finite_number())->expected(3);
  wand->add_option("--images", o->images, "also draw every camera's frames as PNG image sequences DIR/cam<i>_%04d.png (for `record`)");
  add_noise_options(wand, o->noise);
  wand->callback([o, &exit_code] { exit_code = run_wand(*o); });

  o = std::make_shared<SimulateOptions>();
  CLI::App* lframe = simulate->add_subcommand("lframe", "an L-frame lying still on the floor (docs/calibration.md has its geometry)");
  lframe->add_option("--rig", o->rig, "the true rig (OpenCV YAML)")->required();
  lframe->add_option("--out", o->out, "detections CSV to write")->required();
  lframe->add_option("--frames", o->frames, "frames")->default_val(60)->check(CLI::Range(1, 1000000));
  lframe->add_option("--lframe-mm", o->lframe_mm, "long arm, short arm[, middle marker] in mm")
      ->check(finite_number())
      ->delimiter(',')
      ->expected(2, 3)
      ->capture_default_str();
  lframe->add_option("--height-mm", o->height_mm, "the markers' centres above the floor")->check(finite_number())->capture_default_str();
  lframe->add_option("--at-m", o->at_m, "where the corner lies, X,Y,Z metres (Y: the floor's or desk's height)")
      ->check(finite_number())
      ->delimiter(',')
      ->expected(3)
      ->capture_default_str();
  lframe->add_option("--yaw-deg", o->yaw_deg, "the frame turned about +Y")->check(finite_number())->capture_default_str();
  add_noise_options(lframe, o->noise);
  lframe->callback([o, &exit_code] { exit_code = run_lframe(*o); });

  o = std::make_shared<SimulateOptions>();
  CLI::App* floor = simulate->add_subcommand("floor", "one marker held still at places on the floor, one after the other");
  floor->add_option("--rig", o->rig, "the true rig (OpenCV YAML)")->required();
  floor->add_option("--out", o->out, "detections CSV to write")->required();
  floor->add_option("--places", o->places, "X,Z,X,Z,... metres (default: four corners of the volume's floor)")
      ->check(finite_number())
      ->delimiter(',');
  floor->add_option("--frames-per-place", o->frames_per_place, "frames held at each place")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  floor->add_option("--height-mm", o->height_mm, "the marker's centre above the floor")->check(finite_number())->capture_default_str();
  add_noise_options(floor, o->noise);
  floor->callback([o, &exit_code] { exit_code = run_floor(*o); });

  add_simulate_board(*simulate, exit_code);
}

}  // namespace rhot::calib_tool
