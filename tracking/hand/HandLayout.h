#pragma once
// Where a hand's markers are, as data (assets/hands/*.json):
//
//   {
//     "format": "rhot-hand-layout", "version": 1, "name": "low-cost", "side": "right",
//     "marker_diameter_mm": 6.0,
//     "hand_star_mm": [[x, y, z], ...4],          the star on the back of the hand, hand frame, mm
//     "fingertip_markers": { "index_tip": 3.0, ... }  a marker per fingertip joint named here, its
//                                                    centre this many mm beyond the tip along the
//                                                    distal bone
//   }
//
// The hand frame is HandJoints.h's: origin at the wrist joint, fingers along -Z, back of the hand +Y.

#include <array>
#include <expected>
#include <filesystem>
#include <optional>
#include <string>

#include <Eigen/Core>

#include "tracking/hand/HandJoints.h"
#include "tracking/rigid/StarSet.h"

namespace rhot {

struct HandLayout {
  std::string name;
  HandSide side = HandSide::kRight;
  double marker_diameter_mm = 6.0;
  std::array<Eigen::Vector3d, 4> hand_star_m;                   // hand frame, metres
  std::array<std::optional<double>, 5> fingertip_offset_m{};    // per finger (thumb..little): nothing when unmarked

  // The hand star as a one-star set, for StarLibrary.
  StarSet hand_star_set() const;
};

[[nodiscard]] std::expected<HandLayout, std::string> load_hand_layout(const std::filesystem::path& file);

}  // namespace rhot
