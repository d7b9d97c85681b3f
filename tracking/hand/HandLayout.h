#pragma once
// Where a hand's markers are, as data (assets/hands/*.json): any number of markers, each on a
// named bone (OpenXR's joint names, HandJoints.h) at an offset in that joint's frame:
//
//   {
//     "format": "rhot-hand-layout", "version": 1, "name": "glove-13", "side": "right",
//     "marker_diameter_mm": 6.0,
//     "markers": [
//       { "name": "hand_top", "bone": "wrist", "offset_mm": [x, y, z] },      the back of the hand
//       { "name": "index_middle", "bone": "index_proximal", "offset_mm": [0, 14, -26] },
//       { "name": "index_tip", "bone": "index_tip", "offset_mm": [0, 0, -8], "colour": "yellow" }
//     ],
//     "star_set": "../stars/seed-case.json",        stars on finger bones (seed 003): the set they
//     "segment_stars": [                             come from (relative to this file), and per bone
//       { "bone": "index_proximal", "star_id": 3 }   (named by its first joint) the star's id
//     ]
//   }
//
// A marker's offset is in its joint's frame (marker_frames below): -Z along the bone that starts
// at the joint, toward the fingertip; +Y out of the back of the finger; a tip joint's frame is its
// distal joint's. "wrist" is the hand frame itself: the markers on it (three
// or four) are the back of the hand, which gives the hand its frame; four of them are followed
// through cameras as a marker star (StarTracker); three as a triangle (TriangleTracker), by a lone
// HandTracker only (the runtime shares its stars out among a scene's and needs four), or labelled
// (a take's). Each other marker is on a finger's bone: the finger's root (a finger's proximal joint,
// the thumb's metacarpal), its two hinges or its tip. A finger's marker on its tip joint or its
// distal bone is its fingertip marker (at most one), which the fingers' IK reaches for; its other
// markers (a glove's middle markers) are matched and followed as well, and tell where a hidden
// fingertip is (HiddenMarkers.h).
//
// The earlier form is still read: "hand_star_mm" (four [x, y, z] on the wrist, mm),
// "fingertip_markers" ({ "index_tip": 3.0 }: a marker that many mm beyond the tip along the distal
// bone, offset [0, 0, -3]) and "marker_colours" ({ "hand_star": "blue", "index_tip": "yellow" }).
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
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "tracking/core/Rigid3.h"
#include "tracking/hand/HandSolver.h"
#include "tracking/hand/HandJoints.h"
#include "tracking/rigid/StarSet.h"

namespace rhot {

struct SegmentStar {
  HandJoint bone = HandJoint::kIndexProximal;  // the bone from this joint to the next
  MarkerStar star;                             // star frame, millimetres
};

// A marker on the skin: its centre at offset_m in the frame of joint `bone` (see above).
struct LayoutMarker {
  std::string name;
  HandJoint bone = HandJoint::kWrist;
  Eigen::Vector3d offset_m = Eigen::Vector3d::Zero();
  int colour = -1;  // tracking/core/MarkerColour.h; -1 for none
};

struct HandLayout {
  std::string name;
  HandSide side = HandSide::kRight;
  double marker_diameter_mm = 6.0;
  // Every marker on the skin (the segment stars' apart), in this order: the back of the hand's (on
  // the wrist, hand_frame_markers of them), each marked finger's fingertip marker (thumb first),
  // then the fingers' other markers in the file's order.
  std::vector<LayoutMarker> markers;
  std::size_t hand_frame_markers = 0;
  std::array<int, 5> fingertip_marker{-1, -1, -1, -1, -1};  // per finger (thumb..little), its index in markers; -1 unmarked
  std::vector<SegmentStar> segment_stars;
  StarSetRules segment_star_rules;  // of the set the segment stars come from

  // The back of the hand's markers (hand frame, metres).
  std::vector<Eigen::Vector3d> hand_star_m() const;
  // Whether the back of the hand is a marker star of four (followed through cameras).
  bool has_hand_star() const { return hand_frame_markers == 4; }
  // The back of the hand's colour (they share one), -1 for none.
  int hand_star_colour() const { return hand_frame_markers > 0 ? markers.front().colour : -1; }
  // A finger's fingertip marker, if it has one.
  const LayoutMarker* fingertip(int finger) const;
  int fingertip_colour(int finger) const { return fingertip(finger) != nullptr ? fingertip(finger)->colour : -1; }
  // The finger a marker (an index in markers) is on; -1 for the back of the hand's.
  int finger_of_marker(std::size_t marker) const;
  // The index of a marker by name, -1 for none.
  int marker_index(std::string_view name) const;

  // The hand star as a one-star set, for StarLibrary (has_hand_star() layouts only).
  StarSet hand_star_set() const;
  // The segment stars as a set (in layout order), for StarLibrary.
  StarSet segment_star_set() const;
};

[[nodiscard]] std::expected<HandLayout, std::string> load_hand_layout(const std::filesystem::path& file);

// The hand frame from labelled markers (world, in the layout's order; NaN where not seen): the
// layout's back-of-hand markers fitted to the seen ones (Kabsch, no scale; all of three, or three
// of four). Nothing with fewer seen, or non-finite.
std::optional<Rigid3d> labelled_hand_frame(const HandLayout& layout, std::span<const Eigen::Vector3d> markers_world);

// Why the runtime cannot follow a layout's hands through cameras (fewer than four markers on the
// back of the hand: no marker star to share out among the stars of a scene), for a message; empty
// when it can. A lone HandTracker follows three as a triangle (TriangleTracker.h).
std::string camera_hand_star_problem(const HandLayout& layout);

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
// Where a layout's marker is on a hand in `pose` (hand frame); `frames`: marker_frames(pose).
Eigen::Vector3d layout_marker_in_hand(const LayoutMarker& marker, const HandPose& pose,
                                      const std::array<Eigen::Quaterniond, kHandJointCount>& frames);
// The frame of every joint a marker is given in (hand frame): the wrist's and palm's are the hand
// frame's axes; a finger joint's -Z runs along its bone toward the fingertip and +Y out of the back
// of the finger, square to the bone in the finger's flexion plane (bone_back_normal with the
// finger's chain: `chains`, the hand's own, a calibrated hand's turned as its fingers are; by
// `side`, the reference hand's), X = Y x Z; a tip's is its distal joint's. For the fingers these
// are OpenXR's joint frames (JointFrames.h) up to the finger's abduction; unlike those, the
// thumb's turn with the thumb as it flexes, so a thumbnail's marker stays on the thumbnail.
// FingerFit.h places a finger's markers alike.
std::array<Eigen::Quaterniond, kHandJointCount> marker_frames(const HandPose& pose, HandSide side);
std::array<Eigen::Quaterniond, kHandJointCount> marker_frames(const HandPose& pose, const std::array<FingerChain, kFingerCount>& chains);
// The same for one finger's three bones, from its joints (root, two hinges, tip; hand frame) and its chain.
std::array<Eigen::Quaterniond, 3> finger_bone_frames(const FingerChain& chain, const std::array<Eigen::Vector3d, 4>& joints);
// Every marker of a layout on a hand in `pose` (its markers in order, then the segment stars'), world;
// the fingers' marker frames the reference hand's (marker_frames(pose, side)): where the
// simulation puts a hand's markers. A tracker's own (HandTracker::markers_in_hand) turn with its
// calibrated fingers.
std::vector<Eigen::Vector3d> layout_markers(const HandLayout& layout, const Rigid3d& world_from_hand, const HandPose& pose);
// Their names: the markers', then "<bone>_star_<k>" for a segment star's k-th marker.
std::vector<std::string> layout_marker_names(const HandLayout& layout);

// Each marker's colour (-1 for none), in layout_markers' order.
std::vector<int> layout_marker_colours(const HandLayout& layout);

// The finger a bone (named by its first joint) belongs to.
Finger finger_of_bone(HandJoint bone);
// How far a segment star's base is above its bone's axis.
double segment_star_lift_m(const HandPose& pose, HandJoint bone);

}  // namespace rhot
