#pragma once
// Pictures of a planned (or any) rig's coverage for people: horizontal slices of the volume
// coloured by how many cameras see each place and by the predicted error there, and the rig from
// above with each camera's field of view where it meets the volume's floor. PNG files written
// with OpenCV.

#include <expected>
#include <filesystem>
#include <string>

#include "tracking/plan/Coverage.h"

namespace rhot {

// The slice of the report's grid nearest height_m (world Y), from above (world X right, -Z up the
// picture): cameras per place (0 dark, 1 red, 2 amber, 3 or more green, brighter with more), with
// the coverage fractions of the slice in the corner.
[[nodiscard]] std::expected<void, std::string> write_coverage_slice(const std::filesystem::path& file, const CoverageReport& report,
                                                                    double height_m);

// The same slice coloured by the predicted RMS 3D error (green at 0 to red at `scale_mm` and
// beyond; dark where fewer than two cameras see), with the scale written in the corner.
[[nodiscard]] std::expected<void, std::string> write_error_slice(const std::filesystem::path& file, const CoverageReport& report,
                                                                 double height_m, double scale_mm);

// The rig from above: the volume's outline, each camera's centre and name, and the outline of its
// image where its rays meet the volume's bottom (its footprint there), 1 m grid lines.
[[nodiscard]] std::expected<void, std::string> write_plan_top_view(const std::filesystem::path& file, const CameraRig& rig,
                                                                   const TrackingVolume& volume);

}  // namespace rhot
