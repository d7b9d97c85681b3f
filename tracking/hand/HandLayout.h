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
//     "marker_colours": { "hand_star": "blue",     optional: coloured markers (tracking/core/MarkerColour.h):
//                         "index_tip": "yellow" }  the hand star's and fingertips' colours
//     "star_set": "../stars/seed-case.json",        stars on finger bones (seed 003): the set they
//     "segment_stars": [                             come from (relative to this file), and per bone
//       { "bone": "index_proximal", "star_id": 3 }   (named by its first joint) the star's id
//     ]
//   }
//
// A segment star stands on the back of its bone, as in seed 003's Fig. 1: its frame's y along the
// bone (from its first joint toward the next), z out of the back of the finger, perpendicular to
// the bone in the finger's flexion plane (the box's tall side), its base centred over the bone's
// middle, lifted off the bone's axis by the first joint's radius plus 1 mm so it clears the skin.
//
// The hand frame is HandJoints.h's: origin at the wrist joint, fingers along -Z, back of the hand +Y.

#include <array>
#include <expected>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "tracking/core/Rigid3.h"
#include "tracking/hand/HandSolver.h"
#include "tracking/hand/HandJoints.h"
#include "tracking/rigid/StarSet.h"

namespace rhot {

struct SegmentStar {
  HandJoint bone = HandJoint::kIndexProximal;  // the bone from this joint to the next
  MarkerStar star;                             // star frame, millimetres
};

struct HandLayout {
  std::string name;
  HandSide side = HandSide::kRight;
  double marker_diameter_mm = 6.0;
  std::array<Eigen::Vector3d, 4> hand_star_m;                 // hand frame, metres
  std::array<std::optional<double>, 5> fingertip_offset_m{};  // per finger (thumb..little): nothing when unmarked
  int hand_star_colour = -1;                                  // the hand star's markers' colour, -1 for none
  std::array<int, 5> fingertip_colour{-1, -1, -1, -1, -1};    // per finger, -1 for none
  std::vector<SegmentStar> segment_stars;
  StarSetRules segment_star_rules;  // of the set the segment stars come from

  // The hand star as a one-star set, for StarLibrary.
  StarSet hand_star_set() const;
  // The segment stars as a set (in layout order), for StarLibrary.
  StarSet segment_star_set() const;
};

[[nodiscard]] std::expected<HandLayout, std::string> load_hand_layout(const std::filesystem::path& file);

// Whether two hands and the objects' stars can be told apart from any three of their markers: every
// face of either hand star that differs from a face of the other hand's star, or of an object's
// star, by less than the larger variation (the hand stars' 1.5 mm or the objects' set's) in every
// edge, under any correspondence; mirror images included (layouts[0] is the left hand). Empty when
// they all differ.
std::vector<std::string> check_hand_stars(const std::array<HandLayout, 2>& layouts, const StarSet& objects);

// Where a segment star sits: star frame -> hand frame, for a hand in `pose` whose finger planes
// point `up` (HandSolver's chains give it).
Rigid3d hand_from_segment_star(const HandPose& pose, HandJoint bone, const FingerChain& chain);
// The back of a finger's bone pointing along `bone`, for a finger whose first bone points along
// `first_bone` (both hand frame).
Eigen::Vector3d bone_back_normal(const FingerChain& chain, const Eigen::Vector3d& first_bone, const Eigen::Vector3d& bone);
// Every marker of a layout on a hand in `pose` (hand star, fingertip markers, segment stars), world.
std::vector<Eigen::Vector3d> layout_markers(const HandLayout& layout, const Rigid3d& world_from_hand, const HandPose& pose);

// Each marker's colour (-1 for none), in layout_markers' order.
std::vector<int> layout_marker_colours(const HandLayout& layout);

// The finger a bone (named by its first joint) belongs to.
Finger finger_of_bone(HandJoint bone);
// How far a segment star's base is above its bone's axis.
double segment_star_lift_m(const HandPose& pose, HandJoint bone);

}  // namespace rhot
