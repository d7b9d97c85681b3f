#pragma once
// A recording's hands as a BVH file (Biovision hierarchy), for Blender, MotionBuilder, Maya and
// every other animation package.
//
// The hierarchy: a root "hands" at the origin (its six channels always zero); under it each hand's
// wrist ("left_wrist", "right_wrist": position and rotation channels), and under the wrist the
// palm, the thumb and the four fingers joint by joint with OpenXR's names ("left_index_proximal"),
// three rotation channels each, each tip an End Site. Rotation channels are Zrotation Xrotation
// Yrotation, in degrees; positions in the unit asked for; rhot's world axes (+Y up, -Z forward).
//
// The rest pose (every rotation zero) has each joint's frame on the world's axes, so a digit runs
// along -Z from its base, and each OFFSET is the bone in its parent joint's frame (JointFrames.h:
// -Z along the bone): (0, 0, -length) for a digit's bone, the hand frame's offset for the wrist's
// children. The lengths and offsets are the user's, the median over the frames the hand was seen;
// the rotations are the joints' orientations (JointFrames.h) relative to their parent's. So a
// skeleton of fixed bone lengths, as rhot's hand tracker fits, comes back joint for joint.
//
// One frame per recorded frame, at the recording's rate. A hand not seen keeps its last seen pose
// (its first seen pose before it is first seen; the rest pose if it never is).

#include <expected>
#include <string>

#include "engine/tracked/Recording.h"

namespace rhot {

struct BvhSettings {
  double units_per_metre = 100.0;  // centimetres, as most BVH files
};

// The BVH text, or why there is none (an empty recording).
[[nodiscard]] std::expected<std::string, std::string> hands_bvh(const Recording& recording, const BvhSettings& settings = {});

}  // namespace rhot
