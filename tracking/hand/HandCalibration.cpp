#include "tracking/hand/HandCalibration.h"

#include <cmath>
#include <fstream>

#include <nlohmann/json.hpp>

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

std::expected<std::pair<HandPose, HandSide>, std::string> load_hand_calibration(const std::filesystem::path& file) {
  const std::string path = file.string();
  std::ifstream in(file);
  if (!in) return std::unexpected(path + ": hand calibration file not found");
  try {
    const nlohmann::json j = nlohmann::json::parse(in);
    if (!j.is_object() || j.value("format", std::string()) != "rhot-hand-calibration")
      throw std::runtime_error("format: expected \"rhot-hand-calibration\"");
    if (!j.contains("version") || j["version"] != 1) throw std::runtime_error("version: expected 1");
    const std::string side = j.value("side", std::string());
    if (side != "left" && side != "right") throw std::runtime_error("side: expected \"left\" or \"right\"");
    HandPose pose;
    for (int k = 0; k < kHandJointCount; ++k) {
      const std::string name(joint_name(static_cast<HandJoint>(k)));
      const auto& p = j.contains("joints_mm") && j["joints_mm"].contains(name) ? j["joints_mm"][name] : nlohmann::json();
      if (!p.is_array() || p.size() != 3 || !p[0].is_number() || !p[1].is_number() || !p[2].is_number()) {
        throw std::runtime_error("joints_mm." + name + ": expected [x, y, z]");
      }
      pose.position_m[static_cast<std::size_t>(k)] = 1e-3 * Eigen::Vector3d(p[0].get<double>(), p[1].get<double>(), p[2].get<double>());
      const auto& r = j.contains("radii_mm") && j["radii_mm"].contains(name) ? j["radii_mm"][name] : nlohmann::json();
      if (!r.is_number() || !(r.get<double>() > 0.0)) throw std::runtime_error("radii_mm." + name + ": expected a positive number");
      pose.radius_m[static_cast<std::size_t>(k)] = 1e-3 * r.get<double>();
      if (!pose.position_m[static_cast<std::size_t>(k)].allFinite() || !std::isfinite(pose.radius_m[static_cast<std::size_t>(k)])) {
        throw std::runtime_error("joints_mm." + name + ": not finite");
      }
    }
    return std::make_pair(pose, side == "left" ? HandSide::kLeft : HandSide::kRight);
  } catch (const nlohmann::json::parse_error& e) {
    return std::unexpected(path + ": not JSON: " + e.what());
  } catch (const std::exception& e) {
    return std::unexpected(path + ": " + e.what());
  }
}

}  // namespace rhot
