#include "tracking/hand/HandCalibration.h"

#include <cmath>
#include <fstream>

#include <nlohmann/json.hpp>

#include "base/Json.h"

namespace rhot {

std::optional<HandPose> calibrate_flat_hand(const HandPose& reference, HandSide side, std::span<const FingertipSample> samples) {
  HandPose out = reference;
  const auto chains = hand_chains(reference, side);
  bool any = false;
  for (int f = 0; f < kFingerCount; ++f) {
    const auto fi = static_cast<std::size_t>(f);
    const FingerChain& c = chains[fi];
    double sum = 0.0;
    int n = 0;
    for (const FingertipSample& s : samples) {
      if (!s[fi] || !s[fi]->allFinite()) continue;
      sum += (*s[fi] - c.root_m).norm();
      ++n;
    }
    if (n == 0) continue;
    const double length = c.length_m[0] + c.length_m[1] + c.length_m[2];
    const double scale = (sum / n) / length;
    if (!(scale > 0.5 && scale < 2.0)) continue;  // not a flat hand, or not this hand
    any = true;
    const auto joints = chain_joints(static_cast<Finger>(f));
    for (std::size_t k = 1; k < 4; ++k) {
      auto& p = out.position_m[static_cast<std::size_t>(joints[k])];
      p = c.root_m + scale * (p - c.root_m);
    }
  }
  if (!any) return std::nullopt;
  return out;
}

FingertipSample flat_hand_sample(const HandLayout& layout, const HandPose& reference, const TrackedHand& hand,
                                 std::span<const Eigen::Vector3d> points_world) {
  FingertipSample sample;
  if (!hand.hand_seen) return sample;
  const auto chains = hand_chains(reference, layout.side);
  const Rigid3d hand_from_world = hand.world_from_hand.inverse();
  for (std::size_t f = 0; f < kFingerCount; ++f) {
    const int p = hand.fingertip_point[f];
    const LayoutMarker* marker = layout.fingertip(static_cast<int>(f));
    if (p < 0 || static_cast<std::size_t>(p) >= points_world.size() || marker == nullptr) continue;
    // The marker's offset in its joint's frame on the straight finger: -Z along the rest direction,
    // +Y the finger's up; a marker on the distal joint sits one distal bone short of the tip.
    const FingerChain& chain = chains[f];
    const Eigen::Vector3d x = chain.rest_direction.cross(chain.up);
    Eigen::Vector3d tip_to_marker =
        marker->offset_m.x() * x + marker->offset_m.y() * chain.up - marker->offset_m.z() * chain.rest_direction;
    if (marker->bone != chain_joints(static_cast<Finger>(f))[3]) tip_to_marker -= chain.length_m[2] * chain.rest_direction;
    sample[f] = hand_from_world * points_world[static_cast<std::size_t>(p)] - tip_to_marker;
  }
  return sample;
}

std::expected<void, std::string> save_hand_calibration(const HandPose& skeleton, HandSide side, const std::filesystem::path& file) {
  nlohmann::json j;
  j["format"] = "rhot-hand-calibration";
  j["version"] = 1;
  j["side"] = side == HandSide::kLeft ? "left" : "right";
  for (int k = 0; k < kHandJointCount; ++k) {
    const std::string name(joint_name(static_cast<HandJoint>(k)));
    const Eigen::Vector3d p = 1000.0 * skeleton.position_m[static_cast<std::size_t>(k)];
    j["joints_mm"][name] = {p.x(), p.y(), p.z()};
    j["radii_mm"][name] = 1000.0 * skeleton.radius_m[static_cast<std::size_t>(k)];
  }
  std::ofstream out(file);
  if (!out) return std::unexpected(file.string() + ": cannot write");
  out << j.dump(2) << "\n";
  if (!out) return std::unexpected(file.string() + ": write failed");
  return {};
}

namespace {

std::pair<HandPose, HandSide> read_calibration(const JsonNode& j) {
  j.expect_object({"format", "version", "side", "joints_mm", "radii_mm"});
  const JsonNode format = j["format"];
  if (format.string() != "rhot-hand-calibration") format.fail("expected \"rhot-hand-calibration\", got " + describe_json(format.raw()));
  j["version"].integer_in(1, 1);
  const JsonNode side = j["side"];
  const std::string side_name = side.string();
  if (side_name != "left" && side_name != "right") side.fail("expected \"left\" or \"right\", got " + describe_json(side.raw()));
  const JsonNode joints = j["joints_mm"];
  const JsonNode radii = j["radii_mm"];
  HandPose pose;
  for (int k = 0; k < kHandJointCount; ++k) {
    const std::string name(joint_name(static_cast<HandJoint>(k)));
    const auto p = joints[name.c_str()].numbers(3);
    pose.position_m[static_cast<std::size_t>(k)] = 1e-3 * Eigen::Vector3d(p[0], p[1], p[2]);
    pose.radius_m[static_cast<std::size_t>(k)] = 1e-3 * radii[name.c_str()].positive();
  }
  return {pose, side_name == "left" ? HandSide::kLeft : HandSide::kRight};
}

}  // namespace

std::expected<std::pair<HandPose, HandSide>, std::string> load_hand_calibration(const std::filesystem::path& file) {
  auto calibration = read_json_file<std::pair<HandPose, HandSide>>(file, "hand calibration", read_calibration);
  if (!calibration) return std::unexpected(calibration.error().to_string());
  return *calibration;
}

}  // namespace rhot
