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
#include <vector>
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

// Per-user hand from labelled frames of any layout (each frame: the layout's markers, world, in its
// order; NaN where not seen), a few seconds of the user's own motion. For each finger with a
// fingertip marker:
//  - its length first: the 90th percentile of its tip's distances from the knuckle (the marker less
//    its offset on the straight finger) stands for the straight finger (a ratio of 0.6-2.0 to the
//    reference's, else the finger is left as it is);
//  - then its knuckle's place, its length, its rest direction (turned sideways or up and down about
//    the knuckle: a user's finger may point elsewhere at rest than the reference's) and its other
//    markers' offsets (a glove's middle marker: its lift off the bone and its place along it)
//    together, fitted so that the finger's markers, on the finger fitted to them within its limits
//    as the tracker fits it (FingerFit.h), come nearest where they were seen (30 to 59 frames
//    spread evenly over the run; the other markers' misses weigh HandTracker::kOtherMarkerWeight
//    of the tip's, whose miss is what the tracker shows; a knuckle or an offset moved far costs,
//    so one the motion does not pin down stays).
// The finger's whole ray moves with its knuckle. Nothing when no fingertip was seen in 20 frames.
struct LabelledCalibration {
  int frames = 0;                                                   // frames with the back of the hand seen
  std::array<double, kFingerCount> scale{1.0, 1.0, 1.0, 1.0, 1.0};  // each finger's length against the reference's
  std::array<Eigen::Vector3d, kFingerCount> knuckle_moved_m{};
  std::array<double, kFingerCount> turned_rad{};                  // how far each finger's rest direction was turned      // hand frame
  std::array<std::array<double, 2>, kFingerCount> reach_rms_m{};  // the finger's markers' RMS miss, before and after the fit
  HandLayout layout;                                              // the layout given, its fingers' other markers' offsets fitted
};
std::optional<HandPose> calibrate_from_labelled(const HandLayout& layout, const HandPose& reference,
                                                std::span<const std::vector<Eigen::Vector3d>> frames,
                                                LabelledCalibration* report = nullptr);

[[nodiscard]] std::expected<void, std::string> save_hand_calibration(const HandPose& skeleton, HandSide side,
                                                                     const std::filesystem::path& file);
[[nodiscard]] std::expected<std::pair<HandPose, HandSide>, std::string> load_hand_calibration(const std::filesystem::path& file);

}  // namespace rhot
