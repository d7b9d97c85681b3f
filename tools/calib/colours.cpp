// rhot-calib colours: a colour model (tracking/detect/ColourModel.h) learned from images in which
// the user holds the coloured markers up to the camera, with a picture of what it classifies.
//
//   rhot-calib colours IMAGES... --out colours.json [--expect red,yellow,...|any] [--mask FILE...]
//   rhot-calib colours --source video:DEV[,DEV...] [--frames N] [--every K] --out colours.json

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>
#include <spdlog/spdlog.h>

#include "tools/calib/Calib.h"
#include "tracking/core/MarkerColour.h"
#include "tracking/detect/ColourDetector.h"
#include "tracking/detect/ColourModel.h"
#include "tracking/media/Media.h"
#include "tracking/source/VideoSource.h"

namespace rhot::calib_tool {

namespace {

struct ColoursOptions {
  std::vector<std::string> images;
  std::string source;
  int frames = 10;
  int every = 5;
  std::vector<std::string> masks;
  std::string expect = "red,yellow,green,cyan,blue,magenta";
  std::string out, pictures, test_image;
  bool json = false;
};

// The images to learn from: the files given, or frames read from each device of the source.
std::expected<std::vector<cv::Mat>, std::string> read_images(const ColoursOptions& o) {
  std::vector<cv::Mat> out;
  for (const std::string& file : o.images) {
    auto image = read_image(file, ImageRead::kColour);
    if (!image) return std::unexpected(image.error());
    out.push_back(std::move(*image));
  }
  if (o.source.empty()) return out;
  if (o.source.rfind("video:", 0) != 0) return std::unexpected("--source: expected video:DEV[,DEV...], got \"" + o.source + "\"");
  auto devices = parse_video_devices(o.source.substr(6));
  if (!devices) return std::unexpected("--source: " + devices.error());
  for (const std::string& device : *devices) {
    const bool index = !device.empty() && device.size() <= 6 && device.find_first_not_of("0123456789") == std::string::npos;
    std::optional<VideoCapture> capture = VideoCapture::open(device, index ? VideoCapture::Kind::kDevice : VideoCapture::Kind::kAny);
    if (!capture) {
      if (auto module = media_module(); !module) return std::unexpected("--source: " + module.error());
      return std::unexpected("--source: cannot open \"" + device + "\"");
    }
    int taken = 0;
    for (int read = 0; taken < o.frames; ++read) {
      cv::Mat frame;
      if (!capture->read(frame) || frame.empty()) break;
      if (read % o.every != 0) continue;
      out.push_back(frame.clone());
      ++taken;
      spdlog::info("{}: frame {} ({} of {})", device, read, taken, o.frames);
    }
    if (taken == 0) return std::unexpected("--source: no frame from \"" + device + "\"");
  }
  return out;
}

int run(const ColoursOptions& o) {
  if (o.images.empty() && o.source.empty()) {
    spdlog::error("give images, or --source video:DEV to take frames from cameras");
    return 1;
  }
  ColourLearnSettings settings;
  if (o.expect != "any") {
    std::string list = o.expect;
    for (std::size_t start = 0; start <= list.size();) {
      const std::size_t comma = std::min(list.find(',', start), list.size());
      const std::string name = list.substr(start, comma - start);
      const auto colour = marker_colour_from_name(name);
      if (!colour) {
        spdlog::error("--expect: \"{}\" is not a marker colour ({}, or any)", name, marker_colour_list());
        return 1;
      }
      settings.expected.push_back(*colour);
      start = comma + 1;
    }
  }
  auto images = read_images(o);
  if (!images) {
    spdlog::error("{}", images.error());
    return 1;
  }
  std::vector<cv::Mat> masks;
  for (const std::string& file : o.masks) {
    auto read = read_image(file, ImageRead::kGrey);
    if (!read) {
      spdlog::error("--mask: {}", read.error());
      return 1;
    }
    masks.push_back(std::move(*read));
  }
  if (!masks.empty() && masks.size() != images->size()) {
    spdlog::error("--mask: one per image ({} images, {} masks)", images->size(), masks.size());
    return 1;
  }
  for (std::size_t i = 0; i < masks.size(); ++i) {
    if (masks[i].size() != (*images)[i].size()) {
      spdlog::error("{}: the mask is {}x{}, its image {}x{}", o.masks[i], masks[i].cols, masks[i].rows, (*images)[i].cols,
                    (*images)[i].rows);
      return 1;
    }
  }
  spdlog::info("learning from {} image(s)", images->size());
  const auto report = learn_colour_model(*images, masks, settings);
  if (!report) {
    spdlog::error("{}", report.error());
    return 1;
  }
  make_parent_folder(o.out);
  if (const auto saved = save_colour_model(report->model, o.out); !saved) {
    spdlog::error("{}", saved.error());
    return 1;
  }
  for (std::size_t k = 0; k < report->model.classes.size(); ++k) {
    const ColourClass& c = report->model.classes[k];
    spdlog::info("{}: hue {:.1f} +- {:.1f} degrees, saturation from {:.2f}, value from {:.2f} ({} pixels)", marker_colour_name(c.colour),
                 c.hue_deg, c.hue_tolerance_deg, c.min_saturation, c.min_value, report->pixels_per_class[k]);
  }
  // What the model takes for which colour in a test image (the first learning image by default),
  // and what the detector finds there: a bad model shows before tracking with it.
  auto test_read =
      o.test_image.empty() ? std::expected<cv::Mat, std::string>(images->front()) : read_image(o.test_image, ImageRead::kColour);
  if (!test_read) {
    spdlog::error("--test-image: {}", test_read.error());
    return 1;
  }
  const cv::Mat test = std::move(*test_read);
  ColourDetector detector(report->model);
  const auto detections = detector.detect(test);
  const std::filesystem::path dir = pictures_dir(o.pictures, o.out);
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  const std::filesystem::path picture = dir / (std::filesystem::path(o.out).stem().string() + "_classes.png");
  cv::Mat shown = classification_picture(detector.table(), test);
  for (const Detection& d : detections.value_or(std::vector<Detection>{})) {
    cv::circle(shown, cv::Point(static_cast<int>(std::lround(d.pixel.x())), static_cast<int>(std::lround(d.pixel.y()))),
               static_cast<int>(std::lround(std::sqrt(static_cast<double>(d.area_px) / 3.14159) + 4.0)), cv::Scalar(255, 255, 255), 1,
               cv::LINE_AA);
  }
  if (auto written = write_image(picture, shown); !written) {
    spdlog::error("{}", written.error());
    return 1;
  }
  spdlog::info("{}: {} colours; {} markers found in the test image, shown in {}", o.out, report->model.classes.size(),
               detections ? detections->size() : 0u, picture.string());
  if (o.json) {
    nlohmann::json j;
    j["out"] = o.out;
    j["picture"] = picture.string();
    j["images"] = images->size();
    j["blobs"] = report->blobs;
    j["markers_in_test_image"] = detections ? detections->size() : 0u;
    for (std::size_t k = 0; k < report->model.classes.size(); ++k) {
      const ColourClass& c = report->model.classes[k];
      j["colours"][std::string(marker_colour_name(c.colour))] = {
          {"hue_deg", c.hue_deg}, {"hue_tolerance_deg", c.hue_tolerance_deg}, {"pixels", report->pixels_per_class[k]}};
    }
    print_json(j);
  }
  return 0;
}

}  // namespace

void add_colours(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<ColoursOptions>();
  CLI::App* cmd = app.add_subcommand("colours",
                                     "learn the marker colours from images where the markers are held up to the camera; writes a colour "
                                     "file and a picture of what it classifies (docs/colour-markers.md)");
  cmd->add_option("images", o->images, "colour images (PNG, JPEG)")->check(CLI::ExistingFile);
  cmd->add_option("--source", o->source,
                  "take the images from cameras instead: video:DEV[,DEV...] (an index, a video file or an image sequence)");
  cmd->add_option("--frames", o->frames, "with --source: frames to take from each device")
      ->capture_default_str()
      ->check(CLI::Range(1, 10000));
  cmd->add_option("--every", o->every, "with --source: take every K-th frame")->capture_default_str()->check(CLI::Range(1, 10000));
  cmd->add_option("--expect", o->expect, "the colours to find, comma-separated, or any")->capture_default_str();
  cmd->add_option("--mask", o->masks, "per image, a grey mask: only its non-zero pixels are looked at (for a stubborn colour)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", o->out, "the colour file to write (JSON)")->required();
  cmd->add_option("--test-image", o->test_image, "image to show the model on (default: the first)")->check(CLI::ExistingFile);
  cmd->add_option("--pictures", o->pictures, "folder for the picture (default: --out's folder)");
  cmd->add_flag("--json", o->json, "print a JSON report on stdout");
  cmd->callback([o, &exit_code] { exit_code = run(*o); });
}

}  // namespace rhot::calib_tool
