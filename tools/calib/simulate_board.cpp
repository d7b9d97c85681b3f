// rhot-calib simulate board: pictures of a calibration board taken by a camera whose intrinsics
// and distortion are known, and that camera (truth.yaml), so `rhot-calib intrinsics` can be tried,
// and checked, without a camera.

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <expected>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <system_error>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <spdlog/spdlog.h>

#include "tools/calib/Calib.h"
#include "tracking/calib/Intrinsics.h"
#include "tracking/camera/RigFile.h"
#include "tracking/media/Media.h"
#include "tracking/sim/BoardImages.h"

namespace rhot::calib_tool {

namespace {

namespace fs = std::filesystem;

struct SimulateBoardOptions {
  std::string out;
  std::string board = "chess:9x6:25";
  int views = 20;
  std::string size = "1280x720";
  double fx = 1000.0;
  std::optional<double> fy, cx, cy;
  double k1 = -0.15, k2 = 0.06, p1 = 0.0008, p2 = -0.0005, k3 = 0.0;
  double noise = 1.0;
  double blur = 0.7;
  std::uint64_t seed = 1;
  bool json = false;
};

std::optional<std::pair<int, int>> parse_size(const std::string& text) {
  const std::size_t x = text.find('x');
  if (x == std::string::npos) return std::nullopt;
  int w = 0, h = 0;
  const char* begin = text.data();
  const char* end = text.data() + text.size();
  const auto rw = std::from_chars(begin, begin + x, w);
  const auto rh = std::from_chars(begin + x + 1, end, h);
  if (rw.ec != std::errc() || rw.ptr != begin + x || rh.ec != std::errc() || rh.ptr != end) return std::nullopt;
  return std::pair{w, h};
}

// The board as tracking/sim draws it: chess and circle grids analytically, ChArUco from its picture.
std::expected<BoardLayout, std::string> layout_for(const BoardSpec& board) {
  BoardLayout layout;
  layout.cols = board.cols;
  layout.rows = board.rows;
  layout.spacing_m = board.square_mm / 1000.0;
  layout.margin = 1.0;
  layout.circle_diameter = 0.5;  // as board_picture prints them
  switch (board.kind) {
    case BoardKind::chess:
      layout.pattern = BoardPattern::chess;
      break;
    case BoardKind::circles:
      layout.pattern = BoardPattern::circles;
      break;
    case BoardKind::asymmetric_circles:
      layout.pattern = BoardPattern::asymmetric_circles;
      break;
    case BoardKind::charuco: {
      auto picture = board_picture(board, 100);
      if (!picture) return std::unexpected(picture.error());
      layout.pattern = BoardPattern::texture;
      layout.texture = cv::Mat(picture->height_px, picture->width_px, CV_8UC1, picture->grey.data()).clone();
      layout.texture_corner_m = picture->corner_board_m;
      layout.texel_m = picture->pixel_m;
      break;
    }
  }
  return layout;
}

int run_simulate_board(const SimulateBoardOptions& o) {
  if (o.out.empty()) return fail("simulate board: --out is required: the folder to write the pictures and truth.yaml into");
  const auto board = parse_board_spec(o.board);
  if (!board) return fail(board.error());
  const auto size = parse_size(o.size);
  if (!size || size->first < 64 || size->second < 64 || size->first > 4096 || size->second > 4096) {
    return fail("simulate board: --size must be WIDTHxHEIGHT in pixels, each 64 to 4096 (e.g. 1280x720), got \"" + o.size + "\"");
  }
  if (o.views < 1 || o.views > 500) return fail("simulate board: --views must be 1 to 500, got " + std::to_string(o.views));

  CameraIntrinsics camera;
  camera.width_px = size->first;
  camera.height_px = size->second;
  camera.fx = o.fx;
  camera.fy = o.fy.value_or(o.fx);
  camera.cx = o.cx.value_or(0.5 * (camera.width_px - 1));
  camera.cy = o.cy.value_or(0.5 * (camera.height_px - 1));
  camera.distortion = {o.k1, o.k2, o.p1, o.p2, o.k3};
  CameraRig truth;
  truth.name = "truth";
  truth.cameras.push_back(Camera{"truth", camera, Rigid3d::identity()});
  if (auto ok = check_rig(truth); !ok) return fail("simulate board: the camera: " + ok.error());

  auto layout = layout_for(*board);
  if (!layout) return fail(layout.error());
  BoardRenderSettings render;
  render.noise_sigma = o.noise;
  render.blur_sigma_px = o.blur;
  if (auto ok = render.check(); !ok) return fail("simulate board: " + ok.error());

  const std::vector<Rigid3d> poses = board_poses(camera, *layout, o.views, o.seed);
  if (static_cast<int>(poses.size()) < o.views) {
    spdlog::warn("the board fits in view in only {} of {} poses; is it too large for the camera?", poses.size(), o.views);
  }
  if (poses.empty()) return fail("simulate board: board " + board->to_string() + " does not fit in the camera's view at any pose");

  std::error_code error;
  fs::create_directories(o.out, error);
  if (error) return fail(o.out + ": cannot create the folder: " + error.message());
  std::vector<std::string> written;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    char file_name[32];
    std::snprintf(file_name, sizeof file_name, "board_%02zu.png", i);
    spdlog::info("rendering board {}/{}: {}", i + 1, poses.size(), file_name);
    render.seed = o.seed * 1000 + i;
    const cv::Mat image = render_board(camera, poses[i], *layout, render);
    const fs::path file = fs::path(o.out) / file_name;
    if (auto ok = write_image(file, image); !ok) return fail(ok.error());
    written.push_back(file.string());
  }
  const fs::path truth_file = fs::path(o.out) / "truth.yaml";
  if (auto saved = save_rig(truth, truth_file); !saved) return fail(saved.error());
  spdlog::info("wrote {} pictures and {}; try: rhot-calib intrinsics --board {} {} --out cam.yaml", written.size(), truth_file.string(),
               board->to_string(), o.out);
  if (o.json) {
    nlohmann::json j;
    j["board"] = board->to_string();
    j["out"] = o.out;
    j["images"] = written;
    j["truth"] = truth_file.string();
    j["camera"] = {{"width", camera.width_px}, {"height", camera.height_px}, {"fx", camera.fx}, {"fy", camera.fy}, {"cx", camera.cx},
                   {"cy", camera.cy},          {"dist", camera.distortion}};
    j["noise_sigma"] = o.noise;
    j["blur_sigma_px"] = o.blur;
    j["seed"] = o.seed;
    print_json(j);
  }
  return 0;
}

}  // namespace

void add_simulate_board(CLI::App& simulate, int& exit_code) {
  CLI::App* cmd =
      simulate.add_subcommand("board",
                              "pictures of a calibration board from a camera of known intrinsics and distortion, and that camera "
                              "(truth.yaml), to try `intrinsics` on");
  auto o = std::make_shared<SimulateBoardOptions>();
  cmd->add_option("--out", o->out, "folder to write board_NN.png and truth.yaml into (created if missing)");
  cmd->add_option("--board", o->board, "the board, as `intrinsics --board` takes it (chess, circles, acircles, charuco)")
      ->capture_default_str();
  cmd->add_option("--views", o->views, "how many pictures, each from a different pose")->capture_default_str();
  cmd->add_option("--size", o->size, "image size WIDTHxHEIGHT, pixels")->capture_default_str();
  cmd->add_option("--fx", o->fx, "focal length, pixels")->capture_default_str();
  cmd->add_option("--fy", o->fy, "vertical focal length, pixels (default: fx)");
  cmd->add_option("--cx", o->cx, "principal point x, pixels (default: the image centre)");
  cmd->add_option("--cy", o->cy, "principal point y, pixels (default: the image centre)");
  cmd->add_option("--k1", o->k1, "radial distortion k1 (OpenCV's model)")->capture_default_str();
  cmd->add_option("--k2", o->k2, "radial distortion k2")->capture_default_str();
  cmd->add_option("--p1", o->p1, "tangential distortion p1")->capture_default_str();
  cmd->add_option("--p2", o->p2, "tangential distortion p2")->capture_default_str();
  cmd->add_option("--k3", o->k3, "radial distortion k3")->capture_default_str();
  cmd->add_option("--noise", o->noise, "Gaussian noise per pixel, grey levels (of 255)")->capture_default_str();
  cmd->add_option("--blur", o->blur, "Gaussian blur (focus), pixels")->capture_default_str();
  cmd->add_option("--seed", o->seed, "seed for the poses and the noise: the same seed gives the same pictures")->capture_default_str();
  cmd->add_flag("--json", o->json, "print a JSON report on stdout: the pictures, the true camera");
  cmd->callback([o, &exit_code] { exit_code = run_simulate_board(*o); });
}

}  // namespace rhot::calib_tool
