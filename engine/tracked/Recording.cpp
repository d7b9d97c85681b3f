#include "engine/tracked/Recording.h"

#include <cmath>
#include <memory>
#include <sstream>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

namespace rhot {

namespace {

using nlohmann::json;

json pose_json(const Rigid3d& r) {
  return json::array(
      {r.translation.x(), r.translation.y(), r.translation.z(), r.rotation.x(), r.rotation.y(), r.rotation.z(), r.rotation.w()});
}

struct Failure {
  std::string message;
};

double number(const json& j, const std::string& where) {
  if (!j.is_number()) throw Failure{where + ": expected a number"};
  const double v = j.get<double>();
  if (!std::isfinite(v)) throw Failure{where + ": expected a finite number"};
  return v;
}

Rigid3d pose_from(const json& j, const std::string& where) {
  if (!j.is_array() || j.size() != 7) throw Failure{where + ": expected [x, y, z, qx, qy, qz, qw]"};
  Rigid3d r;
  r.translation = Eigen::Vector3d(number(j[0], where), number(j[1], where), number(j[2], where));
  Eigen::Quaterniond q(number(j[6], where), number(j[3], where), number(j[4], where), number(j[5], where));
  if (q.norm() < 0.5 || q.norm() > 1.5) throw Failure{where + ": the rotation is not a unit quaternion"};
  r.rotation = q.normalized();
  return r;
}

template <std::size_t N>
void numbers_into(const json& j, std::array<double, N>& out, const std::string& where) {
  if (!j.is_array() || j.size() != N) throw Failure{where + ": expected " + std::to_string(N) + " numbers"};
  for (std::size_t i = 0; i < N; ++i) out[i] = number(j[i], where);
}

}  // namespace

std::expected<RecordingWriter, std::string> RecordingWriter::open(const std::filesystem::path& file, double rate_hz,
                                                                  std::vector<std::string> objects) {
  RecordingWriter w;
  w.file_ = file;
  w.out_ = std::make_unique<std::ofstream>(file, std::ios::binary | std::ios::trunc);
  if (!*w.out_) return std::unexpected(file.string() + ": cannot write the recording");
  json names = json::array();
  for (int j = 0; j < kHandJointCount; ++j) names.push_back(std::string(joint_name(static_cast<HandJoint>(j))));
  const json header = {{"format", "rhot-recording"}, {"version", 1}, {"rate_hz", rate_hz}, {"joints", names}, {"objects", objects}};
  *w.out_ << header.dump() << '\n';
  w.out_->flush();
  if (!*w.out_) return std::unexpected(file.string() + ": cannot write the recording");
  return w;
}

std::expected<void, std::string> RecordingWriter::write(const RecordedFrame& frame) {
  json hands = json::array();
  for (std::size_t h = 0; h < 2; ++h) {
    const HandInput& in = frame.hands[h];
    json joints = json::array();
    for (const Eigen::Vector3d& p : in.joints_world) joints.push_back(json::array({p.x(), p.y(), p.z()}));
    hands.push_back({{"side", h == 0 ? "left" : "right"},
                     {"seen", in.seen},
                     {"wrist_pose", pose_json(in.world_from_hand)},
                     {"joints", joints},
                     {"radius", in.radius_m},
                     {"confidence", in.confidence}});
  }
  json objects = json::object();
  for (const auto& [name, pose] : frame.objects) objects[name] = pose_json(pose);
  *out_ << json{{"t", frame.t_s}, {"hands", hands}, {"objects", objects}}.dump() << '\n';
  out_->flush();
  if (!*out_) return std::unexpected(file_.string() + ": cannot write the recording");
  return {};
}

std::expected<Recording, std::string> load_recording(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return std::unexpected(file.string() + ": cannot read the recording");
  Recording rec;
  std::string line;
  long number_of_line = 0;
  try {
    while (std::getline(in, line)) {
      ++number_of_line;
      const std::string where = file.string() + ":" + std::to_string(number_of_line);
      if (line.empty()) continue;
      json j;
      try {
        j = json::parse(line);
      } catch (const json::exception& e) {
        throw Failure{where + ": not JSON (" + std::string(e.what()) + ")"};
      }
      if (number_of_line == 1) {
        if (!j.is_object() || j.value("format", std::string()) != "rhot-recording")
          throw Failure{where + ": format: expected \"rhot-recording\""};
        if (j.value("version", 0) != 1) throw Failure{where + ": version: expected 1"};
        rec.rate_hz = number(j.value("rate_hz", json()), where + ": rate_hz");
        if (!(rec.rate_hz > 0.0)) throw Failure{where + ": rate_hz: expected a positive rate"};
        if (j.contains("objects") && j["objects"].is_array()) {
          for (const json& o : j["objects"]) rec.objects.push_back(o.is_string() ? o.get<std::string>() : std::string());
        }
        continue;
      }
      if (!j.is_object()) throw Failure{where + ": expected a frame object"};
      RecordedFrame f;
      f.t_s = number(j.value("t", json()), where + ": t");
      if (!rec.frames.empty() && !(f.t_s > rec.frames.back().t_s)) throw Failure{where + ": t: times must increase"};
      if (!j.contains("hands") || !j["hands"].is_array() || j["hands"].size() != 2)
        throw Failure{where + ": hands: expected [left, right]"};
      for (std::size_t h = 0; h < 2; ++h) {
        const json& hj = j["hands"][h];
        const std::string hw = where + ": hands[" + std::to_string(h) + "]";
        if (!hj.is_object()) throw Failure{hw + ": expected an object"};
        HandInput& in_hand = f.hands[h];
        in_hand.seen = hj.value("seen", false);
        in_hand.world_from_hand = pose_from(hj.value("wrist_pose", json()), hw + ".wrist_pose");
        const json& joints = hj.value("joints", json());
        if (!joints.is_array() || joints.size() != kHandJointCount) throw Failure{hw + ".joints: expected 26 [x, y, z]"};
        for (std::size_t k = 0; k < kHandJointCount; ++k) {
          std::array<double, 3> p{};
          numbers_into(joints[k], p, hw + ".joints[" + std::to_string(k) + "]");
          in_hand.joints_world[k] = Eigen::Vector3d(p[0], p[1], p[2]);
        }
        numbers_into(hj.value("radius", json()), in_hand.radius_m, hw + ".radius");
        numbers_into(hj.value("confidence", json()), in_hand.confidence, hw + ".confidence");
      }
      if (j.contains("objects")) {
        if (!j["objects"].is_object()) throw Failure{where + ": objects: expected {name: pose}"};
        for (const auto& [name, pose] : j["objects"].items()) f.objects[name] = pose_from(pose, where + ": objects." + name);
      }
      rec.frames.push_back(std::move(f));
    }
  } catch (const Failure& f) {
    return std::unexpected(f.message);
  }
  if (number_of_line == 0) return std::unexpected(file.string() + ": empty; expected a rhot-recording header");
  if (rec.frames.empty()) return std::unexpected(file.string() + ": no frames");
  return rec;
}

RecordedFrame Recording::at(double t) const {
  const double start = frames.front().t_s;
  const double want = start + std::clamp(t, 0.0, duration_s());
  std::size_t i = 0;
  while (i + 1 < frames.size() && frames[i + 1].t_s < want) ++i;
  if (i + 1 >= frames.size()) return frames.back();
  const RecordedFrame& a = frames[i];
  const RecordedFrame& b = frames[i + 1];
  const double u = std::clamp((want - a.t_s) / (b.t_s - a.t_s), 0.0, 1.0);
  RecordedFrame out = u < 0.5 ? a : b;
  out.t_s = want;
  for (std::size_t h = 0; h < 2; ++h) {
    if (!a.hands[h].seen || !b.hands[h].seen) continue;
    for (std::size_t k = 0; k < kHandJointCount; ++k)
      out.hands[h].joints_world[k] = a.hands[h].joints_world[k] + u * (b.hands[h].joints_world[k] - a.hands[h].joints_world[k]);
    out.hands[h].world_from_hand.translation =
        a.hands[h].world_from_hand.translation + u * (b.hands[h].world_from_hand.translation - a.hands[h].world_from_hand.translation);
    out.hands[h].world_from_hand.rotation = a.hands[h].world_from_hand.rotation.slerp(u, b.hands[h].world_from_hand.rotation);
  }
  for (auto& [name, pose] : out.objects) {
    const auto pa = a.objects.find(name);
    const auto pb = b.objects.find(name);
    if (pa == a.objects.end() || pb == b.objects.end()) continue;
    pose.translation = pa->second.translation + u * (pb->second.translation - pa->second.translation);
    pose.rotation = pa->second.rotation.slerp(u, pb->second.rotation);
  }
  return out;
}

}  // namespace rhot
