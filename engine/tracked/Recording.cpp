#include "engine/tracked/Recording.h"

#include <cmath>
#include <memory>
#include <sstream>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "base/Json.h"

namespace rhot {

namespace {

using nlohmann::json;

json pose_json(const Rigid3d& r) {
  return json::array(
      {r.translation.x(), r.translation.y(), r.translation.z(), r.rotation.x(), r.rotation.y(), r.rotation.z(), r.rotation.w()});
}

// A pose [x, y, z, qx, qy, qz, qw] (glTF's quaternion order).
Rigid3d pose_from(const JsonNode& n) {
  const auto v = n.numbers(7);
  Eigen::Quaterniond q(v[6], v[3], v[4], v[5]);
  if (q.norm() < 0.5 || q.norm() > 1.5) n.fail("the rotation is not a unit quaternion");
  Rigid3d r;
  r.translation = Eigen::Vector3d(v[0], v[1], v[2]);
  r.rotation = q.normalized();
  return r;
}

template <std::size_t N>
void numbers_into(const JsonNode& n, std::array<double, N>& out) {
  const auto v = n.numbers(N);
  for (std::size_t i = 0; i < N; ++i) out[i] = v[i];
}

struct Header {
  double rate_hz = 90.0;
  std::vector<std::string> objects;
};

Header read_header(const JsonNode& j) {
  j.expect_object({"format", "version", "rate_hz", "joints", "objects"});
  const JsonNode format = j["format"];
  if (format.string() != "rhot-recording") format.fail("expected \"rhot-recording\", got " + describe_json(format.raw()));
  j["version"].integer_in(1, 1);
  Header h;
  h.rate_hz = j["rate_hz"].positive();
  if (auto objects = j.optional("objects")) {
    for (const JsonNode& o : objects->elements()) h.objects.push_back(o.string());
  }
  return h;
}

RecordedFrame read_frame(const JsonNode& j) {
  j.expect_object({"t", "hands", "objects", "holding", "grasp_events"});
  RecordedFrame f;
  f.t_s = j["t"].number();
  const JsonNode hands = j["hands"];
  if (!hands.raw().is_array() || hands.raw().size() != 2) hands.fail("expected [left, right]");
  const auto sides = hands.elements();
  for (std::size_t h = 0; h < 2; ++h) {
    const JsonNode& hj = sides[h];
    hj.expect_object({"side", "seen", "wrist_pose", "joints", "radius", "confidence"});
    HandInput& in_hand = f.hands[h];
    if (auto seen = hj.optional("seen")) in_hand.seen = seen->boolean();
    in_hand.world_from_hand = pose_from(hj["wrist_pose"]);
    const JsonNode joints = hj["joints"];
    if (!joints.raw().is_array() || joints.raw().size() != kHandJointCount) joints.fail("expected 26 [x, y, z]");
    const auto points = joints.elements();
    for (std::size_t k = 0; k < kHandJointCount; ++k) {
      const auto p = points[k].numbers(3);
      in_hand.joints_world[k] = Eigen::Vector3d(p[0], p[1], p[2]);
    }
    numbers_into(hj["radius"], in_hand.radius_m);
    numbers_into(hj["confidence"], in_hand.confidence);
  }
  if (auto objects = j.optional("objects")) {
    if (!objects->raw().is_object()) objects->fail("expected {name: pose}, got " + describe_json(objects->raw()));
    for (const auto& [name, pose] : objects->raw().items()) f.objects[name] = pose_from((*objects)[name.c_str()]);
  }
  if (auto holding = j.optional("holding")) {
    if (!holding->raw().is_array() || holding->raw().size() != 2) holding->fail("expected [left, right] object names");
    const auto names = holding->elements();
    for (std::size_t h = 0; h < 2; ++h) f.holding[h] = names[h].string();
  }
  if (auto events = j.optional("grasp_events")) {
    for (const JsonNode& e : events->elements()) {
      e.expect_object({"type", "hand", "object", "reason"});
      RecordedGraspEvent ev{e["type"].string(), e["hand"].string(), e["object"].string(), ""};
      if (ev.type != "grasp" && ev.type != "release")
        e["type"].fail("expected \"grasp\" or \"release\", got " + describe_json(e["type"].raw()));
      if (ev.hand != "left" && ev.hand != "right") e["hand"].fail("expected \"left\" or \"right\", got " + describe_json(e["hand"].raw()));
      if (auto reason = e.optional("reason")) ev.reason = reason->string();
      f.grasp_events.push_back(std::move(ev));
    }
  }
  return f;
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
  json line{{"t", frame.t_s}, {"hands", hands}, {"objects", objects}};
  if (!frame.holding[0].empty() || !frame.holding[1].empty()) line["holding"] = frame.holding;
  if (!frame.grasp_events.empty()) {
    json events = json::array();
    for (const RecordedGraspEvent& e : frame.grasp_events)
      events.push_back({{"type", e.type}, {"hand", e.hand}, {"object", e.object}, {"reason", e.reason}});
    line["grasp_events"] = events;
  }
  *out_ << line.dump() << '\n';
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
  while (std::getline(in, line)) {
    ++number_of_line;
    if (line.empty()) continue;
    // Each line is a JSON document of its own, named "FILE:LINE" in errors.
    const std::string where = file.string() + ":" + std::to_string(number_of_line);
    if (number_of_line == 1) {
      auto header = parse_json<Header>(line, where, read_header);
      if (!header) return std::unexpected(header.error().to_string());
      rec.rate_hz = header->rate_hz;
      rec.objects = std::move(header->objects);
      continue;
    }
    // Every line is written whole, newline last, and flushed: a last line without its newline that
    // is not even JSON is the frame a crash interrupted. It is left out; anything else is an error.
    const bool cut_short = in.eof() && !json::accept(line);
    if (cut_short) {
      rec.warnings.push_back(where + ": the last line is cut short (was the recording interrupted?); it is left out, the " +
                             std::to_string(rec.frames.size()) + " frames before it are read");
      spdlog::warn("{}", rec.warnings.back());
      break;
    }
    auto frame = parse_json<RecordedFrame>(line, where, read_frame);
    if (!frame) return std::unexpected(frame.error().to_string());
    if (!rec.frames.empty() && !(frame->t_s > rec.frames.back().t_s)) return std::unexpected(where + ": /t: times must increase");
    rec.frames.push_back(std::move(*frame));
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
