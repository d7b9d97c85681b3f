#include "tracking/hand/HandLayout.h"

#include "tracking/core/MarkerColour.h"

#include "tracking/hand/HandSolver.h"

#include <algorithm>
#include <cmath>
#include <fstream>

#include <Eigen/Geometry>

#include "base/Json.h"

namespace rhot {

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

std::vector<std::string> check_hand_stars(const std::array<HandLayout, 2>& layouts, const StarSet& objects) {
  std::array<MarkerStar, 2> hand;
  std::array<std::string, 2> name;
  double variation_mm = 0.0;
  for (std::size_t h = 0; h < 2; ++h) {
    const StarSet set = layouts[h].hand_star_set();
    hand[h] = set.stars[0];
    variation_mm = std::max(variation_mm, set.rules.variation_mm);
    name[h] = std::string(layouts[h].side == HandSide::kLeft ? "left" : "right") + " hand star (" + layouts[h].name + ")";
  }
  if (!objects.stars.empty()) variation_mm = std::max(variation_mm, objects.rules.variation_mm);
  std::vector<std::string> problems = clashing_faces(hand[0], name[0], hand[1], name[1], variation_mm);
  for (std::size_t h = 0; h < 2; ++h) {
    for (const MarkerStar& star : objects.stars) {
      for (std::string& p : clashing_faces(hand[h], name[h], star, "object star " + std::to_string(star.id), variation_mm))
        problems.push_back(std::move(p));
    }
  }
  return problems;
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

std::vector<int> layout_marker_colours(const HandLayout& layout) {
  std::vector<int> out(4, layout.hand_star_colour);
  for (int f = 0; f < kFingerCount; ++f) {
    if (layout.fingertip_offset_m[static_cast<std::size_t>(f)]) out.push_back(layout.fingertip_colour[static_cast<std::size_t>(f)]);
  }
  for (const SegmentStar& s : layout.segment_stars) out.insert(out.end(), s.star.markers_mm.size(), -1);
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

namespace {

// A point [x, y, z] in millimetres -> metres.
Eigen::Vector3d point_mm(const JsonNode& n) {
  const auto v = n.numbers(3);
  return 1e-3 * Eigen::Vector3d(v[0], v[1], v[2]);
}

HandLayout read_layout(const JsonNode& j, const std::filesystem::path& folder) {
  j.expect_object({"format", "version", "name", "side", "marker_diameter_mm", "hand_star_mm", "fingertip_markers", "star_set",
                   "segment_stars", "description", "marker_colours"});
  const JsonNode format = j["format"];
  if (format.string() != "rhot-hand-layout") format.fail("expected \"rhot-hand-layout\", got " + describe_json(format.raw()));
  j["version"].integer_in(1, 1);
  HandLayout layout;
  if (auto name = j.optional("name")) layout.name = name->string();
  const JsonNode side = j["side"];
  const std::string side_name = side.string();
  if (side_name != "left" && side_name != "right") side.fail("expected \"left\" or \"right\", got " + describe_json(side.raw()));
  layout.side = side_name == "left" ? HandSide::kLeft : HandSide::kRight;
  layout.marker_diameter_mm = j["marker_diameter_mm"].positive();
  const JsonNode star = j["hand_star_mm"];
  if (!star.raw().is_array() || star.raw().size() != 4)
    star.fail("expected four [x, y, z] marker centres, got " + describe_json(star.raw()));
  const auto corners = star.elements();
  for (std::size_t m = 0; m < 4; ++m) layout.hand_star_m[m] = point_mm(corners[m]);
  if (auto tips_node = j.optional("fingertip_markers")) {
    if (!tips_node->raw().is_object())
      tips_node->fail("expected an object of fingertip joint names, got " + describe_json(tips_node->raw()));
    constexpr std::array<HandJoint, 5> tips{HandJoint::kThumbTip, HandJoint::kIndexTip, HandJoint::kMiddleTip, HandJoint::kRingTip,
                                            HandJoint::kLittleTip};
    for (const auto& [name, value] : tips_node->raw().items()) {
      const JsonNode tip = (*tips_node)[name.c_str()];
      std::size_t finger = 5;
      for (std::size_t f = 0; f < 5; ++f) {
        if (joint_name(tips[f]) == name) finger = f;
      }
      if (finger == 5) tip.fail("not a fingertip joint (thumb_tip, index_tip, middle_tip, ring_tip, little_tip)");
      layout.fingertip_offset_m[finger] = 1e-3 * tip.number();
    }
  }
  if (auto colours = j.optional("marker_colours")) {
    if (!colours->raw().is_object()) colours->fail("expected an object of marker names and colours, got " + describe_json(colours->raw()));
    for (const auto& [name, value] : colours->raw().items()) {
      const JsonNode node = (*colours)[name.c_str()];
      const auto colour = marker_colour_from_name(node.string());
      if (!colour) node.fail("expected a marker colour (" + marker_colour_list() + "), got " + describe_json(node.raw()));
      if (name == "hand_star") {
        layout.hand_star_colour = *colour;
        continue;
      }
      std::size_t finger = 5;
      for (std::size_t f = 0; f < 5; ++f) {
        if (joint_name(chain_joints(static_cast<Finger>(f))[3]) == name) finger = f;
      }
      if (finger == 5) node.fail("not \"hand_star\" or a fingertip joint (thumb_tip, index_tip, middle_tip, ring_tip, little_tip)");
      if (!layout.fingertip_offset_m[finger]) node.fail("a colour for a fingertip without a marker (add it to \"fingertip_markers\")");
      layout.fingertip_colour[finger] = *colour;
    }
  }
  if (auto list = j.optional("segment_stars")) {
    if (!j.has("star_set")) j.fail("missing \"star_set\", the path of the segment stars' set");
    const JsonNode set_node = j["star_set"];
    const std::filesystem::path set_file = set_node.non_empty_string();
    const auto set = load_star_set(set_file.is_absolute() ? set_file : folder / set_file);
    if (!set) set_node.fail(set.error());
    layout.segment_star_rules = set->rules;
    constexpr std::array<HandJoint, 15> bones{HandJoint::kThumbMetacarpal, HandJoint::kThumbProximal,      HandJoint::kThumbDistal,
                                              HandJoint::kIndexProximal,   HandJoint::kIndexIntermediate,  HandJoint::kIndexDistal,
                                              HandJoint::kMiddleProximal,  HandJoint::kMiddleIntermediate, HandJoint::kMiddleDistal,
                                              HandJoint::kRingProximal,    HandJoint::kRingIntermediate,   HandJoint::kRingDistal,
                                              HandJoint::kLittleProximal,  HandJoint::kLittleIntermediate, HandJoint::kLittleDistal};
    for (const JsonNode& e : list->elements()) {
      e.expect_object({"bone", "star_id"});
      const JsonNode bone_node = e["bone"];
      const std::string bone = bone_node.string();
      const auto it = std::find_if(bones.begin(), bones.end(), [&](HandJoint b) { return joint_name(b) == bone; });
      if (it == bones.end()) bone_node.fail("expected a finger bone named by its first joint (index_proximal, thumb_metacarpal, ...)");
      const JsonNode id_node = e["star_id"];
      const int id = id_node.integer_in(0, 1000000);
      const auto found = std::find_if(set->stars.begin(), set->stars.end(), [&](const MarkerStar& s) { return s.id == id; });
      if (found == set->stars.end()) id_node.fail("no star " + std::to_string(id) + " in the set");
      for (const SegmentStar& other : layout.segment_stars) {
        if (other.bone == *it) bone_node.fail(bone + " has a star already");
        if (other.star.id == id) id_node.fail("star " + std::to_string(id) + " is on another bone already");
      }
      layout.segment_stars.push_back({*it, *found});
    }
  }
  // The star must be a star: edges distinct, markers apart, faces apart (it sits in the hand's
  // frame, not in a box of its own, so the box rule does not apply).
  for (const std::string& problem : check_star_set(layout.hand_star_set())) {
    if (problem.find("is not inside the box") != std::string::npos) continue;
    star.fail(problem.substr(problem.find(": ") + 2));
  }
  return layout;
}

}  // namespace

std::expected<HandLayout, std::string> load_hand_layout(const std::filesystem::path& file) {
  auto layout =
      read_json_file<HandLayout>(file, "hand layout", [&](const JsonNode& root) { return read_layout(root, file.parent_path()); });
  if (!layout) return std::unexpected(layout.error().to_string());
  return *layout;
}

}  // namespace rhot
