#include "tracking/hand/HandLayout.h"

#include "tracking/hand/HandSolver.h"

#include <algorithm>
#include <cmath>
#include <fstream>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

namespace rhot {

namespace {

double number(const nlohmann::json& j, const std::string& where) {
  if (!j.is_number()) throw std::runtime_error(where + ": expected a number");
  const double v = j.get<double>();
  if (!std::isfinite(v)) throw std::runtime_error(where + ": not a finite number");
  return v;
}

}  // namespace

StarSet HandLayout::hand_star_set() const {
  StarSet set;
  set.rules.marker_diameter_mm = marker_diameter_mm;
  set.rules.variation_mm = 1.5;
  set.rules.box_mm = {200, 200, 200};
  MarkerStar star;
  star.id = 0;
  for (std::size_t m = 0; m < 4; ++m) star.markers_mm[m] = hand_star_m[m] * 1000.0;
  set.stars.push_back(star);
  return set;
}

StarSet HandLayout::segment_star_set() const {
  StarSet set;
  set.rules = segment_star_rules;
  for (const SegmentStar& s : segment_stars) set.stars.push_back(s.star);
  return set;
}

double segment_star_lift_m(const HandPose& pose, HandJoint bone) { return pose.radius_m[static_cast<std::size_t>(bone)] + 0.001; }

Finger finger_of_bone(HandJoint bone) {
  if (bone <= HandJoint::kThumbTip) return Finger::kThumb;
  return static_cast<Finger>((static_cast<int>(bone) - static_cast<int>(HandJoint::kIndexMetacarpal)) / 5 + 1);
}

Eigen::Vector3d bone_back_normal(const FingerChain& chain, const Eigen::Vector3d& first_bone, const Eigen::Vector3d& bone) {
  // The finger's plane from its first bone (as angles_from_bones reads it): a root flexed to 90
  // degrees has no abduction left under the elliptical limit, so a vertical first bone means none.
  const Eigen::Vector3d lateral = chain.rest_direction.cross(chain.up);
  double along = first_bone.dot(chain.rest_direction);
  double across = first_bone.dot(lateral);
  if (along < 0.0) {
    along = -along;
    across = -across;
  }
  const double abduction = along * along + across * across > 1e-12 ? std::atan2(across, along) : 0.0;
  const Eigen::Vector3d forward = std::cos(abduction) * chain.rest_direction + std::sin(abduction) * lateral;
  const Eigen::Vector3d plane_normal = forward.cross(-chain.up);
  return bone.normalized().cross(plane_normal).normalized();
}

std::vector<Eigen::Vector3d> layout_markers(const HandLayout& layout, const Rigid3d& world_from_hand, const HandPose& pose) {
  std::vector<Eigen::Vector3d> out;
  for (const Eigen::Vector3d& m : layout.hand_star_m) out.push_back(world_from_hand * m);
  for (int f = 0; f < kFingerCount; ++f) {
    const auto offset = layout.fingertip_offset_m[static_cast<std::size_t>(f)];
    if (!offset) continue;
    const auto joints = chain_joints(static_cast<Finger>(f));
    const Eigen::Vector3d tip = pose.position_m[static_cast<std::size_t>(joints[3])];
    const Eigen::Vector3d along = (tip - pose.position_m[static_cast<std::size_t>(joints[2])]).normalized();
    out.push_back(world_from_hand * (tip + *offset * along));
  }
  if (!layout.segment_stars.empty()) {
    const auto chains = hand_chains(reference_open_hand(layout.side), layout.side);
    for (const SegmentStar& s : layout.segment_stars) {
      const Rigid3d hand_from_star = hand_from_segment_star(pose, s.bone, chains[static_cast<std::size_t>(finger_of_bone(s.bone))]);
      for (const Eigen::Vector3d& m : s.star.markers_mm) out.push_back(world_from_hand * (hand_from_star * (1e-3 * m)));
    }
  }
  return out;
}

Rigid3d hand_from_segment_star(const HandPose& pose, HandJoint bone, const FingerChain& chain) {
  const auto at = [&](HandJoint j) { return pose.position_m[static_cast<std::size_t>(j)]; };
  const auto next = [](HandJoint j) { return static_cast<HandJoint>(static_cast<int>(j) + 1); };
  const HandJoint first = chain_joints(finger_of_bone(bone))[0];
  const Eigen::Vector3d a = at(bone);
  const Eigen::Vector3d b = at(next(bone));
  const Eigen::Vector3d y = (b - a).normalized();
  const Eigen::Vector3d z = bone_back_normal(chain, at(next(first)) - at(first), y);
  Eigen::Matrix3d r;
  r.col(0) = y.cross(z);
  r.col(1) = y;
  r.col(2) = z;
  Rigid3d out;
  out.rotation = Eigen::Quaterniond(r).normalized();
  out.translation = 0.5 * (a + b) + segment_star_lift_m(pose, bone) * z;
  return out;
}

std::expected<HandLayout, std::string> load_hand_layout(const std::filesystem::path& file) {
  const std::string path = file.string();
  std::ifstream in(file);
  if (!in) return std::unexpected(path + ": hand layout file not found");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    return std::unexpected(path + ": not JSON: " + e.what());
  }
  HandLayout layout;
  try {
    if (!j.is_object() || j.value("format", std::string()) != "rhot-hand-layout")
      throw std::runtime_error("format: expected \"rhot-hand-layout\"");
    if (!j.contains("version") || j["version"] != 1) throw std::runtime_error("version: expected 1");
    layout.name = j.value("name", std::string());
    const std::string side = j.value("side", std::string());
    if (side != "left" && side != "right") throw std::runtime_error("side: expected \"left\" or \"right\"");
    layout.side = side == "left" ? HandSide::kLeft : HandSide::kRight;
    if (!j.contains("marker_diameter_mm")) throw std::runtime_error("marker_diameter_mm: missing");
    layout.marker_diameter_mm = number(j["marker_diameter_mm"], "marker_diameter_mm");
    if (!(layout.marker_diameter_mm > 0.0)) throw std::runtime_error("marker_diameter_mm: must be positive");
    const auto& star = j.contains("hand_star_mm") ? j["hand_star_mm"] : nlohmann::json();
    if (!star.is_array() || star.size() != 4) throw std::runtime_error("hand_star_mm: expected four [x, y, z] marker centres");
    for (std::size_t m = 0; m < 4; ++m) {
      const std::string where = "hand_star_mm[" + std::to_string(m) + "]";
      if (!star[m].is_array() || star[m].size() != 3) throw std::runtime_error(where + ": expected [x, y, z]");
      layout.hand_star_m[m] =
          1e-3 * Eigen::Vector3d(number(star[m][0], where + "[0]"), number(star[m][1], where + "[1]"), number(star[m][2], where + "[2]"));
    }
    if (j.contains("fingertip_markers")) {
      if (!j["fingertip_markers"].is_object()) throw std::runtime_error("fingertip_markers: expected an object of joint names");
      constexpr std::array<HandJoint, 5> tips{HandJoint::kThumbTip, HandJoint::kIndexTip, HandJoint::kMiddleTip, HandJoint::kRingTip,
                                              HandJoint::kLittleTip};
      for (const auto& [name, value] : j["fingertip_markers"].items()) {
        std::size_t finger = 5;
        for (std::size_t f = 0; f < 5; ++f) {
          if (joint_name(tips[f]) == name) finger = f;
        }
        if (finger == 5)
          throw std::runtime_error("fingertip_markers." + name +
                                   ": not a fingertip joint (thumb_tip, index_tip, middle_tip, ring_tip, little_tip)");
        layout.fingertip_offset_m[finger] = 1e-3 * number(value, "fingertip_markers." + name);
      }
    }
    if (j.contains("segment_stars")) {
      if (!j.contains("star_set") || !j["star_set"].is_string())
        throw std::runtime_error("star_set: expected the path of the segment stars' set");
      const auto set = load_star_set(file.parent_path() / j["star_set"].get<std::string>());
      if (!set) throw std::runtime_error("star_set: " + set.error());
      layout.segment_star_rules = set->rules;
      if (!j["segment_stars"].is_array()) throw std::runtime_error("segment_stars: expected an array of {bone, star_id}");
      constexpr std::array<HandJoint, 15> bones{HandJoint::kThumbMetacarpal, HandJoint::kThumbProximal,      HandJoint::kThumbDistal,
                                                HandJoint::kIndexProximal,   HandJoint::kIndexIntermediate,  HandJoint::kIndexDistal,
                                                HandJoint::kMiddleProximal,  HandJoint::kMiddleIntermediate, HandJoint::kMiddleDistal,
                                                HandJoint::kRingProximal,    HandJoint::kRingIntermediate,   HandJoint::kRingDistal,
                                                HandJoint::kLittleProximal,  HandJoint::kLittleIntermediate, HandJoint::kLittleDistal};
      for (std::size_t i = 0; i < j["segment_stars"].size(); ++i) {
        const auto& e = j["segment_stars"][i];
        const std::string where = "segment_stars[" + std::to_string(i) + "]";
        const std::string bone = e.is_object() ? e.value("bone", std::string()) : std::string();
        const auto it = std::find_if(bones.begin(), bones.end(), [&](HandJoint b) { return joint_name(b) == bone; });
        if (it == bones.end())
          throw std::runtime_error(where +
                                   ".bone: expected a finger bone named by its first joint (index_proximal, thumb_metacarpal, ...)");
        if (!e.contains("star_id") || !e["star_id"].is_number_integer()) throw std::runtime_error(where + ".star_id: expected an integer");
        const int id = e["star_id"].get<int>();
        const auto found = std::find_if(set->stars.begin(), set->stars.end(), [&](const MarkerStar& s) { return s.id == id; });
        if (found == set->stars.end()) throw std::runtime_error(where + ".star_id: no star " + std::to_string(id) + " in the set");
        for (const SegmentStar& other : layout.segment_stars) {
          if (other.bone == *it) throw std::runtime_error(where + ".bone: " + bone + " has a star already");
          if (other.star.id == id) throw std::runtime_error(where + ".star_id: star " + std::to_string(id) + " is on another bone already");
        }
        layout.segment_stars.push_back({*it, *found});
      }
    }
    // The star must be a star: edges distinct, markers apart, faces apart (it sits in the hand's
    // frame, not in a box of its own, so the box rule does not apply).
    for (const std::string& problem : check_star_set(layout.hand_star_set())) {
      if (problem.find("is not inside the box") != std::string::npos) continue;
      throw std::runtime_error("hand_star_mm: " + problem.substr(problem.find(": ") + 2));
    }
  } catch (const std::exception& e) {
    return std::unexpected(path + ": " + e.what());
  }
  return layout;
}

}  // namespace rhot
