#pragma once
// Pictures of a calibration for people: where a camera saw its targets and how far off the model
// put them, and a rig seen from above. PNG files written with OpenCV.

#include <expected>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "tracking/camera/Camera.h"

namespace rhot {

// One observation: where it was seen (pixels) and the model's error there (observed - predicted).
struct ResidualSample {
  Eigen::Vector2d pixel{0, 0};
  Eigen::Vector2d residual_px{0, 0};
  bool inlier = true;  // outliers are drawn in red
};

// One camera's image: a 16 x 16 grid with the cells no observation fell in shaded (coverage), a
// dot per observation, and its residual as a line magnified `magnify` times, coloured from green
// (0 px) to red (>= 2 px) and cut at 40 picture pixels, outliers as red crosses; `title` and the
// magnification written in the corner. The picture is the
// image size, halved until it is at most 1280 wide.
[[nodiscard]] std::expected<void, std::string> write_residual_picture(const std::filesystem::path& file, int width_px, int height_px,
                                                                      const std::vector<ResidualSample>& samples, double magnify,
                                                                      const std::string& title);

// The fraction (0..1) of a 16 x 16 grid over the image that holds at least one of the pixels.
double image_coverage(int width_px, int height_px, const std::vector<Eigen::Vector2d>& pixels);

// The rig from above (world X right, -Z up the picture, +Y towards the viewer): each camera as its
// centre, name and a wedge along its view direction, and the points as grey dots (a wand's
// reconstruction) or, 16 or fewer, numbered red discs (an L-frame's markers); a scale bar in metres.
[[nodiscard]] std::expected<void, std::string> write_rig_top_view(const std::filesystem::path& file, const CameraRig& rig,
                                                                  const std::vector<Eigen::Vector3d>& points_world,
                                                                  const std::string& title);

}  // namespace rhot
