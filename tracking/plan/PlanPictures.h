#pragma once
// Pictures of a planned (or any) rig's coverage for people: horizontal slices of the volume
// coloured by how many cameras see each place and by the predicted error there, and the rig from
// above with each camera's field of view where it meets the volume's floor. PNG files written
// with OpenCV.

#include <expected>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "tracking/plan/Coverage.h"

namespace rhot {

// The coverage is known at the grid's points only, so a slice shows the grid's row of points
// nearest the height asked for (clamped to the volume). Its caption's height: the height asked
// for, and the row's where the two differ ("height 1.80 m (the grid's nearest row: 1.76 m)").
std::string slice_height_caption(const CoverageGrid& grid, double height_m);

// The slice of the report's grid nearest height_m (world Y), from above (world X right, -Z up the
// picture): cameras per place (0 dark, 1 red, 2 amber, 3 or more green, brighter with more), with
// the coverage fractions of the slice in the corner.
[[nodiscard]] std::expected<void, std::string> write_coverage_slice(const std::filesystem::path& file, const CoverageReport& report,
                                                                    double height_m);

// The same slice coloured by the predicted RMS 3D error (green at 0 to red at `scale_mm` and
// beyond; dark where fewer than two cameras see), with the scale written in the corner.
[[nodiscard]] std::expected<void, std::string> write_error_slice(const std::filesystem::path& file, const CoverageReport& report,
                                                                 double height_m, double scale_mm);

// The rig from above: the volume's outline, each camera's centre and its label (name and height),
// and the outline of its image where its rays meet the volume's bottom (its footprint there), 1 m
// grid lines. Labels do not cover one another (plan_top_view_labels); the caption counts those
// left out for want of room.
[[nodiscard]] std::expected<void, std::string> write_plan_top_view(const std::filesystem::path& file, const CameraRig& rig,
                                                                   const TrackingVolume& volume);

// A label's box in a picture, pixels: x right, y down, from min_px (top left) to max_px.
struct LabelBox {
  Eigen::Vector2d min_px{0, 0};
  Eigen::Vector2d max_px{0, 0};
  // Whether the two share some area (boxes that only touch do not).
  bool overlaps(const LabelBox& other) const;
};

// Places a label of sizes_px[i] (width, height) beside each point points_px[i], in order: each
// takes the first of its places around the point (to the right, as labels usually sit, then below
// right, left, below left, above, below, then the same further out) that lies inside the picture
// (0 to picture_px), covers no label placed before and no other point (within 4 px). A label
// with no such place is left out (nullopt). No two placed boxes overlap.
// Precondition: as many sizes as points.
std::vector<std::optional<LabelBox>> place_labels(const std::vector<Eigen::Vector2d>& points_px,
                                                  const std::vector<Eigen::Vector2d>& sizes_px, const Eigen::Vector2d& picture_px);

// The cameras' labels in write_plan_top_view's picture, in rig order, placed as it draws them;
// nullopt for a label left out. Error: a camera without a finite centre.
[[nodiscard]] std::expected<std::vector<std::optional<LabelBox>>, std::string> plan_top_view_labels(const CameraRig& rig,
                                                                                                    const TrackingVolume& volume);

}  // namespace rhot
