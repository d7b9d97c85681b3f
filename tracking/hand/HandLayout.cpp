#include "tracking/hand/HandLayout.h"

#include "tracking/core/MarkerColour.h"
#include "tracking/core/Solvers.h"

#include "tracking/hand/HandSolver.h"

#include <algorithm>
#include <cmath>
#include <fstream>

#include <Eigen/Geometry>

#include "base/Json.h"

namespace rhot {

std::vector<Eigen::Vector3d> HandLayout::hand_star_m() const {
  std::vector<Eigen::Vector3d> out;
  for (std::size_t m = 0; m < hand_frame_markers; ++m) out.push_back(markers[m].offset_m);
  return out;
}

const LayoutMarker* HandLayout::fingertip(int finger) const {
  const int m = fingertip_marker[static_cast<std::size_t>(finger)];
  return m >= 0 ? &markers[static_cast<std::size_t>(m)] : nullptr;
}

int HandLayout::finger_of_marker(std::size_t marker) const {
  return marker < hand_frame_markers ? -1 : static_cast<int>(finger_of_bone(markers[marker].bone));
}

int HandLayout::marker_index(std::string_view marker_name) const {
  for (std::size_t m = 0; m < markers.size(); ++m) {
    if (markers[m].name == marker_name) return static_cast<int>(m);
  }
  return -1;
}

StarSet HandLayout::hand_star_set() const {
  StarSet set;
  if (!has_hand_star()) return set;
  set.rules.marker_diameter_mm = marker_diameter_mm;
  set.rules.variation_mm = 1.5;
  set.rules.box_mm = {200, 200, 200};
  MarkerStar star;
  star.id = 0;
  for (std::size_t m = 0; m < 4; ++m) star.markers_mm[m] = markers[m].offset_m * 1000.0;
  set.stars.push_back(star);
  return set;
}

std::optional<Rigid3d> labelled_hand_frame(const HandLayout& layout, std::span<const Eigen::Vector3d> markers_world) {
  std::vector<std::size_t> back;
  for (std::size_t m = 0; m < layout.hand_frame_markers && m < markers_world.size(); ++m) {
    if (markers_world[m].allFinite()) back.push_back(m);
  }
  if (back.size() < 3) return std::nullopt;
  Eigen::Matrix3Xd from(3, static_cast<Eigen::Index>(back.size())), to(3, static_cast<Eigen::Index>(back.size()));
  for (std::size_t k = 0; k < back.size(); ++k) {
    from.col(static_cast<Eigen::Index>(k)) = layout.markers[back[k]].offset_m;
    to.col(static_cast<Eigen::Index>(k)) = markers_world[back[k]];
  }
  const Eigen::Matrix4d t = umeyama_transform(from, to, false);
  if (!t.allFinite()) return std::nullopt;
  Rigid3d out;
  out.rotation = Eigen::Quaterniond(Eigen::Matrix3d(t.block<3, 3>(0, 0))).normalized();
  out.translation = t.block<3, 1>(0, 3);
  return out;
}

std::string camera_hand_star_problem(const HandLayout& layout) {
  if (layout.has_hand_star()) return "";
  return "the layout \"" + layout.name + "\" has " + std::to_string(layout.hand_frame_markers) +
         " markers on the back of the hand; the runtime follows hands through cameras by a marker star of four: this layout serves "
         "takes and rhot-eval's single hands only";
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
    if (!layouts[h].has_hand_star()) return {};  // no star to clash: the hand is not followed through cameras
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

std::array<Eigen::Quaterniond, 3> finger_bone_frames(const FingerChain& chain, const std::array<Eigen::Vector3d, 4>& joints) {
  std::array<Eigen::Quaterniond, 3> out;
  out.fill(Eigen::Quaterniond::Identity());
  const Eigen::Vector3d first = joints[1] - joints[0];
  for (std::size_t k = 0; k < 3; ++k) {
    const Eigen::Vector3d bone = joints[k + 1] - joints[k];
    if (!(bone.norm() > 1e-9) || !(first.norm() > 1e-9) || !bone.allFinite()) continue;  // no direction: the hand's axes
    const Eigen::Vector3d z = -bone.normalized();
    const Eigen::Vector3d y = bone_back_normal(chain, first.normalized(), -z);
    if (!y.allFinite()) continue;
    Eigen::Matrix3d r;
    r.col(0) = y.cross(z);
    r.col(1) = y;
    r.col(2) = z;
    out[k] = Eigen::Quaterniond(r).normalized();
  }
  return out;
}

std::array<Eigen::Quaterniond, kHandJointCount> marker_frames(const HandPose& pose, HandSide side) {
  return marker_frames(pose, hand_chains(reference_open_hand(side), side));
}

std::array<Eigen::Quaterniond, kHandJointCount> marker_frames(const HandPose& pose, const std::array<FingerChain, kFingerCount>& chains) {
  std::array<Eigen::Quaterniond, kHandJointCount> out;
  out.fill(Eigen::Quaterniond::Identity());
  for (int f = 0; f < kFingerCount; ++f) {
    const auto joints = chain_joints(static_cast<Finger>(f));
    std::array<Eigen::Vector3d, 4> at;
    for (std::size_t k = 0; k < 4; ++k) at[k] = pose.position_m[static_cast<std::size_t>(joints[k])];
    const auto frames = finger_bone_frames(chains[static_cast<std::size_t>(f)], at);
    for (std::size_t k = 0; k < 3; ++k) out[static_cast<std::size_t>(joints[k])] = frames[k];
    out[static_cast<std::size_t>(joints[3])] = frames[2];
  }
  return out;
}

Eigen::Vector3d layout_marker_in_hand(const LayoutMarker& marker, const HandPose& pose,
                                      const std::array<Eigen::Quaterniond, kHandJointCount>& frames) {
  const auto j = static_cast<std::size_t>(marker.bone);
  if (marker.bone == HandJoint::kWrist) return marker.offset_m;  // the hand frame itself
  return pose.position_m[j] + frames[j] * marker.offset_m;
}

std::vector<Eigen::Vector3d> layout_markers(const HandLayout& layout, const Rigid3d& world_from_hand, const HandPose& pose) {
  std::vector<Eigen::Vector3d> out;
  const auto frames = marker_frames(pose, layout.side);
  for (const LayoutMarker& m : layout.markers) out.push_back(world_from_hand * layout_marker_in_hand(m, pose, frames));
  if (!layout.segment_stars.empty()) {
    const auto chains = hand_chains(reference_open_hand(layout.side), layout.side);
    for (const SegmentStar& s : layout.segment_stars) {
      const Rigid3d hand_from_star = hand_from_segment_star(pose, s.bone, chains[static_cast<std::size_t>(finger_of_bone(s.bone))]);
      for (const Eigen::Vector3d& m : s.star.markers_mm) out.push_back(world_from_hand * (hand_from_star * (1e-3 * m)));
    }
  }
  return out;
}

std::vector<std::string> layout_marker_names(const HandLayout& layout) {
  std::vector<std::string> out;
  for (const LayoutMarker& m : layout.markers) out.push_back(m.name);
  for (const SegmentStar& s : layout.segment_stars) {
    for (std::size_t k = 0; k < s.star.markers_mm.size(); ++k)
      out.push_back(std::string(joint_name(s.bone)) + "_star_" + std::to_string(k));
  }
  return out;
}

std::vector<int> layout_marker_colours(const HandLayout& layout) {
  std::vector<int> out;
  for (const LayoutMarker& m : layout.markers) out.push_back(m.colour);
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

// The joints a marker may be given on: the wrist (the back of the hand) and every finger's chain.
bool marker_bone(HandJoint joint) {
  if (joint == HandJoint::kWrist) return true;
  if (joint == HandJoint::kPalm) return false;
  const auto chain = chain_joints(finger_of_bone(joint));
  return std::find(chain.begin(), chain.end(), joint) != chain.end();
}

std::string marker_bone_list() {
  std::string out = "wrist";
  for (int j = 0; j < kHandJointCount; ++j) {
    if (j != static_cast<int>(HandJoint::kWrist) && marker_bone(static_cast<HandJoint>(j)))
      out += ", " + std::string(joint_name(static_cast<HandJoint>(j)));
  }
  return out;
}

// A finger's last bone: its distal joint and its tip (a marker there is its fingertip marker).
bool on_last_bone(HandJoint joint) {
  if (joint == HandJoint::kWrist) return false;
  const auto chain = chain_joints(finger_of_bone(joint));
  return joint == chain[3] || static_cast<int>(joint) + 1 == static_cast<int>(chain[3]);
}

int read_colour(const JsonNode& node) {
  const auto colour = marker_colour_from_name(node.string());
  if (!colour) node.fail("expected a marker colour (" + marker_colour_list() + "), got " + describe_json(node.raw()));
  return *colour;
}

// The earlier form: "hand_star_mm", "fingertip_markers" and "marker_colours".
std::vector<LayoutMarker> read_star_and_tips(const JsonNode& j) {
  std::vector<LayoutMarker> markers;
  if (!j.has("hand_star_mm")) j.fail("missing required key \"markers\" (or the earlier form's \"hand_star_mm\")");
  const JsonNode star = j["hand_star_mm"];
  if (!star.raw().is_array() || star.raw().size() != 4)
    star.fail("expected four [x, y, z] marker centres, got " + describe_json(star.raw()));
  const auto corners = star.elements();
  for (std::size_t m = 0; m < 4; ++m) markers.push_back({"hand_star_" + std::to_string(m), HandJoint::kWrist, point_mm(corners[m]), -1});
  if (auto tips_node = j.optional("fingertip_markers")) {
    if (!tips_node->raw().is_object())
      tips_node->fail("expected an object of fingertip joint names, got " + describe_json(tips_node->raw()));
    for (const auto& [name, value] : tips_node->raw().items()) {
      const JsonNode tip = (*tips_node)[name.c_str()];
      std::optional<HandJoint> joint;
      for (int f = 0; f < kFingerCount; ++f) {
        if (joint_name(chain_joints(static_cast<Finger>(f))[3]) == name) joint = chain_joints(static_cast<Finger>(f))[3];
      }
      if (!joint) tip.fail("not a fingertip joint (thumb_tip, index_tip, middle_tip, ring_tip, little_tip)");
      markers.push_back({name, *joint, Eigen::Vector3d(0.0, 0.0, -1e-3 * tip.number()), -1});
    }
  }
  if (auto colours = j.optional("marker_colours")) {
    if (!colours->raw().is_object()) colours->fail("expected an object of marker names and colours, got " + describe_json(colours->raw()));
    for (const auto& [name, value] : colours->raw().items()) {
      const JsonNode node = (*colours)[name.c_str()];
      const int colour = read_colour(node);
      if (name == "hand_star") {
        for (std::size_t m = 0; m < 4; ++m) markers[m].colour = colour;
        continue;
      }
      const bool fingertip = std::ranges::any_of(std::array{0, 1, 2, 3, 4},
                                                 [&](int f) { return joint_name(chain_joints(static_cast<Finger>(f))[3]) == name; });
      if (!fingertip) node.fail("not \"hand_star\" or a fingertip joint (thumb_tip, index_tip, middle_tip, ring_tip, little_tip)");
      const auto it = std::find_if(markers.begin() + 4, markers.end(), [&](const LayoutMarker& m) { return m.name == name; });
      if (it == markers.end()) node.fail("a colour for a fingertip without a marker (add it to \"fingertip_markers\")");
      it->colour = colour;
    }
  }
  return markers;
}

// The form of any number of markers, each on a bone.
std::vector<LayoutMarker> read_markers(const JsonNode& list) {
  std::vector<LayoutMarker> markers;
  for (const JsonNode& e : list.elements()) {
    e.expect_object({"name", "bone", "offset_mm", "colour"});
    LayoutMarker m;
    const JsonNode name = e["name"];
    m.name = name.non_empty_string();
    for (std::size_t k = 0; k < markers.size(); ++k) {
      if (markers[k].name == m.name) name.fail("\"" + m.name + "\" names marker " + std::to_string(k) + " already");
    }
    const JsonNode bone = e["bone"];
    const std::string bone_name = bone.string();
    std::optional<HandJoint> joint;
    for (int k = 0; k < kHandJointCount; ++k) {
      if (joint_name(static_cast<HandJoint>(k)) == bone_name) joint = static_cast<HandJoint>(k);
    }
    if (!joint) bone.fail("expected a joint (" + marker_bone_list() + "), got " + describe_json(bone.raw()));
    if (!marker_bone(*joint)) bone.fail("\"" + bone_name + "\" moves with the hand: give the back of the hand's markers on \"wrist\"");
    m.bone = *joint;
    const JsonNode offset = e["offset_mm"];
    m.offset_m = point_mm(offset);
    if (m.offset_m.cwiseAbs().maxCoeff() > 0.15) offset.fail("expected each coordinate within 150 mm of the joint");
    if (auto colour = e.optional("colour")) m.colour = read_colour(*colour);
    markers.push_back(std::move(m));
  }
  return markers;
}

// The back of the hand's markers, as the layout places them: four must be a star, three a triangle
// whose markers the cameras can tell apart. `where` is the node a problem is reported against.
void check_back_of_hand(const HandLayout& layout, const JsonNode& where) {
  // Four markers must be a star: edges distinct, markers apart, faces apart (it sits in the hand's
  // frame, not in a box of its own, so the box rule does not apply).
  for (const std::string& problem : check_star_set(layout.hand_star_set())) {
    if (problem.find("is not inside the box") != std::string::npos) continue;
    where.fail(problem.substr(problem.find(": ") + 2));
  }
  // Three markers give a frame only where they make a triangle: each at least 5 mm off the line
  // through the other two.
  for (std::size_t a = 0; a < layout.hand_frame_markers; ++a) {
    for (std::size_t b = a + 1; b < layout.hand_frame_markers; ++b) {
      for (std::size_t c = b + 1; c < layout.hand_frame_markers; ++c) {
        const Eigen::Vector3d p = layout.markers[a].offset_m, q = layout.markers[b].offset_m, r = layout.markers[c].offset_m;
        const double area2 = (q - p).cross(r - p).norm();
        const double longest = std::max({(q - p).norm(), (r - p).norm(), (r - q).norm()});
        if (longest < 1e-9 || area2 / longest < 0.005) {
          where.fail("the back of the hand's markers \"" + layout.markers[a].name + "\", \"" + layout.markers[b].name + "\" and \"" +
                     layout.markers[c].name + "\" are nearly in a line (each must be 5 mm off the line through the others)");
        }
      }
    }
  }
  if (layout.hand_frame_markers == 3) {
    // Three markers are told apart by their edges (TriangleTracker.h): no two within 3 mm.
    const auto& mk = layout.markers;
    const std::array<double, 3> edge{(mk[0].offset_m - mk[1].offset_m).norm(), (mk[1].offset_m - mk[2].offset_m).norm(),
                                     (mk[0].offset_m - mk[2].offset_m).norm()};
    if (std::min({std::abs(edge[0] - edge[1]), std::abs(edge[1] - edge[2]), std::abs(edge[0] - edge[2])}) < 0.003) {
      where.fail("the back of the hand's three markers make a triangle with two edges within 3 mm of each other (" +
                 std::to_string(std::lround(1e3 * edge[0])) + ", " + std::to_string(std::lround(1e3 * edge[1])) + " and " +
                 std::to_string(std::lround(1e3 * edge[2])) + " mm): through cameras its markers cannot be told apart");
    }
  }
}

HandLayout read_layout(const JsonNode& j, const std::filesystem::path& folder) {
  j.expect_object({"format", "version", "name", "side", "marker_diameter_mm", "markers", "hand_star_mm", "fingertip_markers", "star_set",
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
  std::vector<LayoutMarker> markers;
  const auto marker_list = j.optional("markers");
  if (marker_list) {
    for (const char* older : {"hand_star_mm", "fingertip_markers", "marker_colours"}) {
      if (auto node = j.optional(older)) node->fail("a layout with \"markers\" gives every marker there (with its \"colour\")");
    }
    markers = read_markers(*marker_list);
  } else {
    markers = read_star_and_tips(j);
  }
  const JsonNode& where = marker_list ? *marker_list : j["hand_star_mm"];
  // In order: the back of the hand, the fingertips (thumb first), the rest as given.
  std::vector<std::size_t> back, rest;
  std::array<std::optional<std::size_t>, kFingerCount> tip{};
  for (std::size_t k = 0; k < markers.size(); ++k) {
    const HandJoint bone = markers[k].bone;
    if (bone == HandJoint::kWrist) {
      back.push_back(k);
    } else if (on_last_bone(bone)) {
      auto& slot = tip[static_cast<std::size_t>(finger_of_bone(bone))];
      if (slot) {
        where.fail("\"" + markers[k].name + "\" and \"" + markers[*slot].name +
                   "\" are both on the last bone of a finger, whose one marker there is its fingertip marker");
      }
      slot = k;
    } else {
      rest.push_back(k);
    }
  }
  if (back.size() < 3 || back.size() > 4) {
    where.fail("expected three or four markers on \"wrist\" (the back of the hand, which gives the hand its frame), got " +
               std::to_string(back.size()));
  }
  for (const std::size_t k : back) {
    if (markers[k].colour != markers[back[0]].colour) {
      where.fail("the back of the hand's markers share one colour: \"" + markers[k].name + "\" differs from \"" + markers[back[0]].name +
                 "\"");
    }
  }
  for (const std::size_t k : back) layout.markers.push_back(markers[k]);
  layout.hand_frame_markers = back.size();
  for (std::size_t f = 0; f < kFingerCount; ++f) {
    if (!tip[f]) continue;
    layout.fingertip_marker[f] = static_cast<int>(layout.markers.size());
    layout.markers.push_back(markers[*tip[f]]);
  }
  for (const std::size_t k : rest) layout.markers.push_back(markers[k]);
  check_back_of_hand(layout, where);
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
