#include "tools/gltf/Bvh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>
#include <vector>

#include "tracking/hand/JointFrames.h"

namespace rhot {

namespace {

// A joint of the BVH hierarchy: the OpenXR joint and its parent (none for the wrist).
struct BvhJoint {
  HandJoint joint;
  std::optional<HandJoint> parent;
};

// Depth first, as the file lists them: wrist; palm; each digit base to end.
std::vector<BvhJoint> hierarchy() {
  std::vector<BvhJoint> out{{HandJoint::kWrist, std::nullopt}, {HandJoint::kPalm, HandJoint::kWrist}};
  for (int j = static_cast<int>(HandJoint::kThumbMetacarpal); j < kHandJointCount; ++j) {
    const auto joint = static_cast<HandJoint>(j);
    if (!joint_child(joint)) continue;  // tips are End Sites
    out.push_back({joint, joint_parent(joint)});
  }
  return out;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

std::string number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6f", v);
  return text;
}

std::string triple(const Eigen::Vector3d& v) { return number(v.x()) + " " + number(v.y()) + " " + number(v.z()); }

// Z, X, Y rotations in degrees of R = Rz(z) Rx(x) Ry(y), x within +-90 and z, y within +-180 (so a
// small rotation has small angles, and a turning joint's angles change smoothly). With
// R = Rz Rx Ry: R(2,1) = sin x, (R(1,1), -R(0,1)) = cos x (cos z, sin z),
// (R(2,2), -R(2,0)) = cos x (cos y, sin y).
Eigen::Vector3d zxy_degrees(const Eigen::Quaterniond& q) {
  const Eigen::Matrix3d r = q.normalized().toRotationMatrix();
  const double x = std::asin(std::clamp(r(2, 1), -1.0, 1.0));
  if (std::abs(r(2, 1)) > 1.0 - 1e-12) {
    // cos x = 0: only z + y (or z - y) is defined; y = 0 and z takes it all, from
    // R(0,0) = cos(z + s y) and R(1,0) = sin(z + s y) with y = 0.
    return Eigen::Vector3d(std::atan2(r(1, 0), r(0, 0)), x, 0.0) * (180.0 / std::numbers::pi);
  }
  const double z = std::atan2(-r(0, 1), r(1, 1));
  const double y = std::atan2(-r(2, 0), r(2, 2));
  return Eigen::Vector3d(z, x, y) * (180.0 / std::numbers::pi);
}

// One hand's poses, frame by frame, with every frame filled (see Bvh.h).
struct HandTrack {
  std::vector<const HandInput*> pose;  // per frame; null: never seen
  bool ever_seen = false;
};

HandTrack track(const Recording& r, std::size_t h) {
  HandTrack t;
  const HandInput* last = nullptr;
  for (const RecordedFrame& f : r.frames) {
    if (f.hands[h].seen) {
      last = &f.hands[h];
      break;
    }
  }
  t.ever_seen = last != nullptr;
  for (const RecordedFrame& f : r.frames) {
    if (f.hands[h].seen) last = &f.hands[h];
    t.pose.push_back(last);
  }
  return t;
}

}  // namespace

std::expected<std::string, std::string> hands_bvh(const Recording& recording, const BvhSettings& settings) {
  if (recording.frames.empty()) return std::unexpected(std::string("the recording has no frames"));
  if (!(settings.units_per_metre > 0.0)) return std::unexpected(std::string("units per metre: must be positive"));
  const double u = settings.units_per_metre;
  const std::vector<BvhJoint> joints = hierarchy();
  const std::array<std::string, 2> prefix{"left_", "right_"};
  std::array<HandTrack, 2> tracks{track(recording, 0), track(recording, 1)};

  // Per hand: each joint's orientation per frame, and each bone's offset in its parent's frame
  // (the median over the frames seen).
  std::array<std::vector<std::array<Eigen::Quaterniond, kHandJointCount>>, 2> frames_of;
  std::array<std::array<Eigen::Vector3d, kHandJointCount>, 2> offset{};  // of joint j in its parent's frame
  for (std::size_t h = 0; h < 2; ++h) {
    std::array<std::array<std::vector<double>, 3>, kHandJointCount> samples;
    for (std::size_t f = 0; f < recording.frames.size(); ++f) {
      const HandInput* hand = tracks[h].pose[f];
      if (!hand) {
        std::array<Eigen::Quaterniond, kHandJointCount> rest;
        rest.fill(Eigen::Quaterniond::Identity());
        frames_of[h].push_back(rest);
        continue;
      }
      const auto orientation = joint_orientations(hand->world_from_hand.rotation, hand->joints_world);
      frames_of[h].push_back(orientation);
      if (!recording.frames[f].hands[h].seen) continue;
      for (int j = 0; j < kHandJointCount; ++j) {
        const auto parent = joint_parent(static_cast<HandJoint>(j));
        const auto p = static_cast<std::size_t>(parent ? *parent : HandJoint::kWrist);
        if (j == static_cast<int>(HandJoint::kWrist)) continue;
        const Eigen::Vector3d v = orientation[p].conjugate() * (hand->joints_world[static_cast<std::size_t>(j)] - hand->joints_world[p]);
        for (int a = 0; a < 3; ++a) samples[static_cast<std::size_t>(j)][static_cast<std::size_t>(a)].push_back(v(a));
      }
    }
    for (int j = 0; j < kHandJointCount; ++j) {
      for (int a = 0; a < 3; ++a)
        offset[h][static_cast<std::size_t>(j)](a) = median(samples[static_cast<std::size_t>(j)][static_cast<std::size_t>(a)]);
    }
  }

  std::string out =
      "HIERARCHY\nROOT hands\n{\n  OFFSET 0.000000 0.000000 0.000000\n"
      "  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n";
  for (std::size_t h = 0; h < 2; ++h) {
    // Write joints depth first; a joint closes after its descendants.
    std::vector<HandJoint> open;
    const auto close_to = [&](std::optional<HandJoint> parent) {
      while (!open.empty() && (!parent || open.back() != *parent)) {
        open.pop_back();
        out += std::string(2 * (open.size() + 1), ' ') + "}\n";
      }
    };
    for (const BvhJoint& b : joints) {
      close_to(b.parent);
      const std::string pad(2 * (open.size() + 1), ' ');
      out += pad + "JOINT " + prefix[h] + std::string(joint_name(b.joint)) + "\n" + pad + "{\n";
      const Eigen::Vector3d o = b.parent ? offset[h][static_cast<std::size_t>(b.joint)] : Eigen::Vector3d::Zero();
      out += pad + "  OFFSET " + triple(u * o) + "\n";
      out += pad + (b.parent ? "  CHANNELS 3 Zrotation Xrotation Yrotation\n"
                             : "  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n");
      open.push_back(b.joint);
      const auto child = joint_child(b.joint);
      if (b.joint == HandJoint::kPalm || (child && !joint_child(*child))) {
        // The palm ends here; a distal joint's End Site is its tip.
        const Eigen::Vector3d end = b.joint == HandJoint::kPalm ? Eigen::Vector3d::Zero() : offset[h][static_cast<std::size_t>(*child)];
        out += pad + "  End Site\n" + pad + "  {\n" + pad + "    OFFSET " + triple(u * end) + "\n" + pad + "  }\n";
      }
    }
    close_to(std::nullopt);
  }
  out += "}\nMOTION\nFrames: " + std::to_string(recording.frames.size()) + "\nFrame Time: " + number(1.0 / recording.rate_hz) + "\n";
  for (std::size_t f = 0; f < recording.frames.size(); ++f) {
    std::string line = "0.000000 0.000000 0.000000 0.000000 0.000000 0.000000";
    for (std::size_t h = 0; h < 2; ++h) {
      const auto& orientation = frames_of[h][f];
      const HandInput* hand = tracks[h].pose[f];
      for (const BvhJoint& b : joints) {
        const auto j = static_cast<std::size_t>(b.joint);
        if (!b.parent) {
          line += " " + triple(u * (hand ? hand->joints_world[j] : Eigen::Vector3d::Zero()));
          line += " " + triple(zxy_degrees(orientation[j]));
        } else {
          line += " " + triple(zxy_degrees(orientation[static_cast<std::size_t>(*b.parent)].conjugate() * orientation[j]));
        }
      }
    }
    out += line + "\n";
  }
  return out;
}

}  // namespace rhot
