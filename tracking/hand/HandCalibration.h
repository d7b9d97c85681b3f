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

#include "tracking/hand/HandLayout.h"
#include "tracking/hand/HandSolver.h"
#include "tracking/hand/HandTracker.h"

namespace rhot {

using FingertipSample = std::array<std::optional<Eigen::Vector3d>, kFingerCount>;  // tip joints, hand frame

// The reference skeleton with each finger scaled to the mean root-to-tip distance of its samples
// (fingers without a sample keep their length). Nothing when no finger has a sample.
std::optional<HandPose> calibrate_flat_hand(const HandPose& reference, HandSide side, std::span<const FingertipSample> samples);

// One frame of a flat hand as a tracker with the reference skeleton saw it: each fingertip whose
// marker was found, the marker (world, from points_world) taken into the hand frame and moved back
// by the layout's offset along the straight finger. Unlike the tracker's solved tips, these are not
// held to the reference bones' reach, so a longer finger shows its length.
FingertipSample flat_hand_sample(const HandLayout& layout, const HandPose& reference, const TrackedHand& hand,
                                 std::span<const Eigen::Vector3d> points_world);

[[nodiscard]] std::expected<void, std::string> save_hand_calibration(const HandPose& skeleton, HandSide side,
                                                                     const std::filesystem::path& file);
[[nodiscard]] std::expected<std::pair<HandPose, HandSide>, std::string> load_hand_calibration(const std::filesystem::path& file);

}  // namespace rhot
