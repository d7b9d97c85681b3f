#pragma once
// The camera rig registered to a headset's tracking space: a marker star fixed on the headset,
// tracked by rhot (its pose in rhot's world) while the headset's runtime reports the head's pose
// in its STAGE space. Over a short motion, every sample i says
//
//   world_from_star(i) = world_from_stage * stage_from_head(i) * head_from_star
//
// with two unknown rigid transforms: world_from_stage (the registration: where the runtime's
// space lies in rhot's) and head_from_star (where the star sits on the headset). This is the
// AX = YB form of hand-eye calibration. It is solved in closed form from the samples' relative
// motions (rotation axes aligned, then translations by least squares), then refined over every
// sample with Ceres (robust to a few bad samples). The head must turn about at least two
// different axes, or the star's offset along the one axis cannot be told from the registration.
//
// The registration file is OpenCV YAML (docs/openxr.md): world_from_stage and head_from_star as
// 4 x 4 matrices, with the residuals and the sample count.

#include <expected>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "tracking/core/Rigid3.h"

namespace rhot {

struct HeadsetPoseSample {
  double t_s = 0.0;         // when (for the picture)
  Rigid3d world_from_star;  // tracked by rhot
  Rigid3d stage_from_head;  // reported by the headset's runtime for the same moment
};

struct HeadsetRegistration {
  Rigid3d world_from_stage;
  Rigid3d head_from_star;
  std::size_t samples = 0;           // used (all of them; the robust loss weighs the bad ones down)
  double rms_mm = 0.0;               // of each sample's star position against world_from_stage * stage_from_head * head_from_star
  double rms_deg = 0.0;              // the same for its orientation
  double turn_deg = 0.0;             // the head's largest turn between two samples
  double second_axis_ratio = 0.0;    // how much of the head's turning is about a second axis (0: one axis only)
  std::vector<double> residual_mm;   // per sample
  std::vector<double> residual_deg;  // per sample
};

struct HeadsetRegistrationSettings {
  std::size_t min_samples = 30;
  double min_turn_deg = 2.0;            // the head must turn at least this much between some samples
  double min_second_axis_ratio = 0.02;  // and about a second axis, by this fraction of the first
};

// Solves for the registration. Fails, saying what the motion lacked, with too few samples, too
// little turning, turning about one axis only, or samples that are not finite.
[[nodiscard]] std::expected<HeadsetRegistration, std::string> register_headset(std::span<const HeadsetPoseSample> samples,
                                                                               const HeadsetRegistrationSettings& settings = {});

// The registration file (OpenCV YAML). Reading fails, naming the file and the entry, on a missing
// or malformed entry, a matrix that is not a rigid transform, or a value that is not finite.
[[nodiscard]] std::expected<void, std::string> write_headset_registration(const std::filesystem::path& file,
                                                                          const HeadsetRegistration& registration);
[[nodiscard]] std::expected<HeadsetRegistration, std::string> read_headset_registration(const std::filesystem::path& file);

// The residuals over time as a picture (PNG): each sample's position error (mm) and orientation
// error (degrees), with the RMS of each and the head's turn in the caption.
[[nodiscard]] std::expected<void, std::string> write_registration_picture(const std::filesystem::path& file,
                                                                          std::span<const HeadsetPoseSample> samples,
                                                                          const HeadsetRegistration& registration);

}  // namespace rhot
