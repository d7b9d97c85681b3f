#pragma once
// Per-user hand size. A user holds the hand flat (fingers straight, together) for a moment; each
// fingertip's distance from its finger's root (the knuckle; the thumb's CMC joint) over those
// frames gives the finger's length, and the finger's bones of the reference skeleton are scaled
// to it. The calibrated skeleton is stored as a file:
//
//   { "format": "rhot-hand-calibration", "version": 1, "side": "right",
//     "joints_mm": { "palm": [x, y, z], "wrist": [...], ... all 26 }, "radii_mm": { "palm": r, ... } }
//
// in the hand frame (HandJoints.h), millimetres.

#include <array>
#include <expected>
#include <filesystem>
#include <optional>
#include <span>
#include <string>

#include "tracking/hand/HandSolver.h"

namespace rhot {

using FingertipSample = std::array<std::optional<Eigen::Vector3d>, kFingerCount>;  // tip joints, hand frame

// The reference skeleton with each finger scaled to the mean root-to-tip distance of its samples
// (fingers without a sample keep their length). Nothing when no finger has a sample.
std::optional<HandPose> calibrate_flat_hand(const HandPose& reference, HandSide side, std::span<const FingertipSample> samples);

[[nodiscard]] std::expected<void, std::string> save_hand_calibration(const HandPose& skeleton, HandSide side,
                                                                     const std::filesystem::path& file);
[[nodiscard]] std::expected<std::pair<HandPose, HandSide>, std::string> load_hand_calibration(const std::filesystem::path& file);

}  // namespace rhot
