// rhot-simvideo: the demo's simulated cameras written as image sequences, one per camera
// (DIR/cam<i>_%04d.png), rhot-demo reads them back as real cameras would be read:
// --rig FILE --source video:DIR/cam0_%04d.png,DIR/cam1_%04d.png,...
//   infrared (default)  8-bit grey, each marker a Gaussian spot
//   --colour            colour images drawn by the renderer (engine/sim/ColourCameras.h): the
//                       hands with the colour layouts, the scene's objects, coloured markers;
//                       read back with --markers colour (rig default assets/rigs/stereo-640.yaml)

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

// GCC 12 reports -Wnull-dereference inside CLI11's option parsing (a false positive through
// libstdc++'s string move); the pragma covers only CLI11's lines.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wnull-dereference"
#include <CLI/CLI.hpp>
#pragma GCC diagnostic pop

#include "engine/sim/Demo.h"
#include "engine/scene/SceneLoader.h"
#include "tracking/media/Media.h"
#include "tracking/sim/SyntheticImages.h"
#include "tools/common/CliExit.h"

#ifndef RHOT_ASSET_DIR
#error "RHOT_ASSET_DIR must name the assets folder"
#endif

namespace {

// rhot-simvideo's flags.
struct Options {
  std::string scene_path = std::string(RHOT_ASSET_DIR) + "/scenes/default.json";
  std::string out_dir;
  int frames = 1080;
  rhot::DemoSettings settings;
  rhot::SyntheticImageSettings draw;
  bool colour = false;
};

void add_options(CLI::App& cli, Options& o) {
  o.settings.asset_dir = RHOT_ASSET_DIR;
  o.settings.sigma_px = 0.0;
  o.draw.noise_sigma = 2.0;
  cli.add_option("--rig", o.settings.rig_file, "Camera rig (OpenCV YAML; default: the scene's, else assets/rigs/seated-4.yaml)")
      ->check(CLI::ExistingFile);
  cli.add_option("--out", o.out_dir, "Folder for the images (created if missing)")->required();
  cli.add_option("--frames", o.frames, "Frames to render (90 per second of the script)")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000000));
  cli.add_option("--scene", o.scene_path, "Scene file (JSON)")->capture_default_str();
  cli.add_option("--blob-sigma", o.draw.blob_sigma_px, "Each marker's spot: Gaussian standard deviation, pixels")
      ->capture_default_str()
      ->check(CLI::Range(0.3, 20.0));
  cli.add_option("--peak", o.draw.peak, "A spot's peak above the background, grey levels")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 255.0));
  cli.add_option("--noise", o.draw.noise_sigma, "Image noise, standard deviation in grey levels")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 50.0));
  cli.add_option("--sigma", o.settings.sigma_px, "Noise on each marker's pixel position before drawing, pixels")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 50.0));
  cli.add_option("--seed", o.settings.seed, "Seed for both noises")->capture_default_str();
  cli.add_flag("--colour", o.colour,
               "Colour cameras drawn by the renderer, coloured markers (read back with rhot-demo --markers colour); --noise is then per "
               "colour channel");
  cli.add_option("--white-balance-k", o.settings.colour_cameras.kelvin,
                 "With --colour: the light's colour temperature (cameras balanced for 6500 K)")
      ->capture_default_str()
      ->check(CLI::Range(1500.0, 15000.0));
  cli.add_option("--device", o.settings.colour_cameras.device,
                 "With --colour: the Vulkan device (auto, gpu, cpu, an index or part of a name)")
      ->capture_default_str();
}

// Every camera's image of each frame as DIR/cam<i>_%04d.png (the renderer's with --colour, else
// drawn blobs): false after saying which could not be written.
bool write_frames(rhot::LiveTracking& p, Options& o, double rate_hz) {
  const std::size_t cameras = p.source().rig().cameras.size();
  auto* colour_source = dynamic_cast<rhot::ColourCameraSource*>(&p.source());
  const std::filesystem::path dir(o.out_dir);
  for (int f = 0; f < o.frames; ++f) {
    p.read_source(f / rate_hz);  // the simulated rig photographs the script's markers (no tracking needed)
    for (std::size_t c = 0; c < cameras; ++c) {
      o.draw.seed = o.settings.seed * 1000003ULL + static_cast<std::uint64_t>(f) * cameras + c;
      char name[64];
      std::snprintf(name, sizeof(name), "cam%zu_%04d.png", c, f);
      const std::string file = (dir / name).string();
      const cv::Mat image = colour_source != nullptr
                                ? colour_source->last_images()[c]
                                : rhot::draw_blobs(p.source().rig().cameras[c].intrinsics, p.frame().cameras[c], o.draw);
      if (auto written = rhot::write_image(file, image, 1); !written) {
        std::fprintf(stderr, "rhot-simvideo: %s\n", written.error().c_str());
        return false;
      }
    }
    if ((f + 1) % 90 == 0 || f + 1 == o.frames) std::fprintf(stderr, "rhot-simvideo: %d/%d frames\n", f + 1, o.frames);
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{
      "rhot-simvideo: renders the demo's simulated camera frames (the script's hands and objects seen by the rig) as PNG\n"
      "image sequences DIR/cam<i>_%04d.png, one per camera, for rhot-demo --source video:..."};
  Options o;
  add_options(cli, o);
  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return rhot::cli_exit_status(cli, e);
  }
  o.settings.colour_markers = o.colour;
  o.settings.colour_cameras.noise_sigma = o.draw.noise_sigma;
  for (const auto& checked : {o.draw.check(), o.settings.check()}) {
    if (!checked) {
      std::fprintf(stderr, "rhot-simvideo: %s\n", checked.error().c_str());
      return EXIT_FAILURE;
    }
  }

  const auto scene = rhot::load_scene_file(o.scene_path);
  if (!scene) {
    std::fprintf(stderr, "rhot-simvideo: cannot load scene: %s\n", scene.error().to_string().c_str());
    return EXIT_FAILURE;
  }
  std::error_code ec;
  std::filesystem::create_directories(o.out_dir, ec);
  if (ec) {
    std::fprintf(stderr, "rhot-simvideo: cannot create %s: %s\n", o.out_dir.c_str(), ec.message().c_str());
    return EXIT_FAILURE;
  }
  auto demo = rhot::Demo::create(*scene, nullptr, o.settings);
  if (!demo) {
    std::fprintf(stderr, "rhot-simvideo: %s\n", demo.error().c_str());
    return EXIT_FAILURE;
  }
  rhot::LiveTracking& p = *(*demo)->live();  // the simulated rig behind live tracking
  if (!write_frames(p, o, scene->settings.headset.refresh_hz)) return EXIT_FAILURE;
  const std::size_t cameras = p.source().rig().cameras.size();
  const std::filesystem::path dir(o.out_dir);
  std::string source = "video:";
  for (std::size_t c = 0; c < cameras; ++c) source += (c ? "," : "") + (dir / ("cam" + std::to_string(c) + "_%04d.png")).string();
  std::fprintf(stderr, "rhot-simvideo: %zu cameras x %d frames in %s; play them with%s\n", cameras, o.frames, o.out_dir.c_str(),
               o.colour ? " --markers colour" : "");
  std::printf("--source %s\n", source.c_str());
  return EXIT_SUCCESS;
}
