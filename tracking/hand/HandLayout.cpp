#include "tracking/hand/HandLayout.h"

#include <cmath>
#include <fstream>

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
    if (!j.is_object() || j.value("format", std::string()) != "rhot-hand-layout") throw std::runtime_error("format: expected \"rhot-hand-layout\"");
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
      layout.hand_star_m[m] = 1e-3 * Eigen::Vector3d(number(star[m][0], where + "[0]"), number(star[m][1], where + "[1]"), number(star[m][2], where + "[2]"));
    }
    if (j.contains("fingertip_markers")) {
      if (!j["fingertip_markers"].is_object()) throw std::runtime_error("fingertip_markers: expected an object of joint names");
      constexpr std::array<HandJoint, 5> tips{HandJoint::kThumbTip, HandJoint::kIndexTip, HandJoint::kMiddleTip, HandJoint::kRingTip, HandJoint::kLittleTip};
      for (const auto& [name, value] : j["fingertip_markers"].items()) {
        std::size_t finger = 5;
        for (std::size_t f = 0; f < 5; ++f) {
          if (joint_name(tips[f]) == name) finger = f;
        }
        if (finger == 5) throw std::runtime_error("fingertip_markers." + name + ": not a fingertip joint (thumb_tip, index_tip, middle_tip, ring_tip, little_tip)");
        layout.fingertip_offset_m[finger] = 1e-3 * number(value, "fingertip_markers." + name);
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
