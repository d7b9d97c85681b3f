#include "engine/stream/OscStream.h"

#include <charconv>
#include <cmath>
#include <cstring>

#include <lo/lo.h>
#include <netdb.h>
#include <pthread.h>
#include <sched.h>
#include <sys/socket.h>

#include "tracking/hand/JointFrames.h"

namespace rhot {

namespace {

constexpr std::string_view kScheme = "osc://";

std::string url_error(std::string_view url, std::string_view what) {
  return "--stream: " + std::string(what) + ", got \"" + std::string(url) + "\"";
}

// Unity's frame from rhot's: Z flipped (rhot looks down -Z, right-handed; Unity down +Z,
// left-handed). A rotation's axis is a pseudovector: (x, y, z, w) -> (-x, -y, z, w).
Eigen::Vector3d to_unity(const Eigen::Vector3d& p) { return {p.x(), p.y(), -p.z()}; }
Eigen::Quaterniond to_unity(const Eigen::Quaterniond& q) { return {q.w(), -q.x(), -q.y(), q.z()}; }

// The hand frame in the T-pose (arms out to the sides, palms down), which VMC's rotations are
// relative to: the left hand's fingers along -X, the right's along +X, backs up (HandJoints.h's
// hand frame: fingers along -Z, back along +Y).
Eigen::Quaterniond t_pose_hand(HandSide side) {
  Eigen::Matrix3d m;
  const double s = side == HandSide::kLeft ? 1.0 : -1.0;
  m.col(0) = Eigen::Vector3d(0, 0, -s);
  m.col(1) = Eigen::Vector3d(0, 1, 0);
  m.col(2) = Eigen::Vector3d(s, 0, 0);
  return Eigen::Quaterniond(m);
}

void add_pose(std::vector<OscArg>& args, const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  for (int i = 0; i < 3; ++i) args.emplace_back(static_cast<float>(p(i)));
  args.emplace_back(static_cast<float>(q.x()));
  args.emplace_back(static_cast<float>(q.y()));
  args.emplace_back(static_cast<float>(q.z()));
  args.emplace_back(static_cast<float>(q.w()));
}

bool finite_pose(const Rigid3d& p) { return p.translation.allFinite() && p.rotation.coeffs().allFinite(); }

bool finite_hand(const HandInput& h) {
  if (!h.world_from_hand.translation.allFinite() || !h.world_from_hand.rotation.coeffs().allFinite()) return false;
  for (const Eigen::Vector3d& p : h.joints_world) {
    if (!p.allFinite()) return false;
  }
  return true;
}

// The humanoid parent of a VMC hand joint: the wrist for each digit's first bone, else the joint
// before it.
HandJoint vmc_parent(HandJoint joint) {
  switch (joint) {
    case HandJoint::kThumbMetacarpal:
    case HandJoint::kIndexProximal:
    case HandJoint::kMiddleProximal:
    case HandJoint::kRingProximal:
    case HandJoint::kLittleProximal:
      return HandJoint::kWrist;
    default:
      return static_cast<HandJoint>(static_cast<int>(joint) - 1);
  }
}

void add_vmc_hand(std::vector<OscMessage>& out, HandSide side, const HandInput& hand) {
  const auto orientation = joint_orientations(hand.world_from_hand.rotation, hand.joints_world);
  const Eigen::Quaterniond rest_inverse = t_pose_hand(side).conjugate();
  // Each joint's rotation from the T-pose, in the world (rhot's frame).
  std::array<Eigen::Quaterniond, kHandJointCount> from_rest;
  for (std::size_t j = 0; j < from_rest.size(); ++j) from_rest[j] = (orientation[j] * rest_inverse).normalized();
  for (const HandJoint joint : vmc_hand_joints()) {
    const auto j = static_cast<std::size_t>(joint);
    Eigen::Vector3d position;
    Eigen::Quaterniond rotation;
    if (joint == HandJoint::kWrist) {
      // The arm is not tracked: the hand's rotation from the T-pose and its place in the world.
      position = hand.joints_world[j];
      rotation = from_rest[j];
    } else {
      const auto p = static_cast<std::size_t>(vmc_parent(joint));
      const Eigen::Quaterniond parent_inverse = from_rest[p].conjugate();
      position = parent_inverse * (hand.joints_world[j] - hand.joints_world[p]);
      rotation = (parent_inverse * from_rest[j]).normalized();
    }
    OscMessage m{"/VMC/Ext/Bone/Pos", {}};
    m.args.reserve(8);
    m.args.emplace_back(vmc_bone_name(side, joint));
    add_pose(m.args, to_unity(position), to_unity(rotation));
    out.push_back(std::move(m));
  }
}

}  // namespace

std::expected<StreamTarget, std::string> parse_stream_url(std::string_view url) {
  if (url.substr(0, kScheme.size()) != kScheme) return std::unexpected(url_error(url, "expected osc://HOST:PORT or osc://HOST:PORT,vmc"));
  std::string_view rest = url.substr(kScheme.size());
  StreamTarget t;
  if (const auto comma = rest.find(','); comma != std::string_view::npos) {
    const std::string_view option = rest.substr(comma + 1);
    if (option != "vmc") return std::unexpected(url_error(url, "unknown option \"" + std::string(option) + "\" (the one option is vmc)"));
    t.vmc = true;
    rest = rest.substr(0, comma);
  }
  const auto colon = rest.rfind(':');
  if (colon == std::string_view::npos || colon == 0)
    return std::unexpected(url_error(url, "expected osc://HOST:PORT or osc://HOST:PORT,vmc"));
  const std::string_view host = rest.substr(0, colon);
  // Debian's liblo sends over IPv4 only.
  if (host.front() == '[' || host.find(':') != std::string_view::npos) {
    return std::unexpected(url_error(url, "IPv6 addresses are not supported (liblo sends over IPv4): give an IPv4 address or a host name"));
  }
  const std::string_view port = rest.substr(colon + 1);
  int number = 0;
  const auto [end, ec] = std::from_chars(port.data(), port.data() + port.size(), number);
  if (port.empty() || ec != std::errc() || end != port.data() + port.size() || number < 1 || number > 65535) {
    return std::unexpected(url_error(url, "the port must be a number from 1 to 65535"));
  }
  t.host = std::string(host);
  t.port = std::string(port);
  return t;
}

const std::array<HandJoint, 16>& vmc_hand_joints() {
  static const std::array<HandJoint, 16> kJoints{HandJoint::kWrist,        HandJoint::kThumbMetacarpal, HandJoint::kThumbProximal,
                                                 HandJoint::kThumbDistal,  HandJoint::kIndexProximal,   HandJoint::kIndexIntermediate,
                                                 HandJoint::kIndexDistal,  HandJoint::kMiddleProximal,  HandJoint::kMiddleIntermediate,
                                                 HandJoint::kMiddleDistal, HandJoint::kRingProximal,    HandJoint::kRingIntermediate,
                                                 HandJoint::kRingDistal,   HandJoint::kLittleProximal,  HandJoint::kLittleIntermediate,
                                                 HandJoint::kLittleDistal};
  return kJoints;
}

std::string vmc_bone_name(HandSide side, HandJoint joint) {
  const std::string prefix = side == HandSide::kLeft ? "Left" : "Right";
  switch (joint) {
    case HandJoint::kWrist:
      return prefix + "Hand";
    // Unity's thumb bones are the metacarpal and the two phalanges.
    case HandJoint::kThumbMetacarpal:
      return prefix + "ThumbProximal";
    case HandJoint::kThumbProximal:
      return prefix + "ThumbIntermediate";
    case HandJoint::kThumbDistal:
      return prefix + "ThumbDistal";
    default:
      break;
  }
  const int j = static_cast<int>(joint);
  if (j < static_cast<int>(HandJoint::kIndexMetacarpal)) return {};
  static constexpr std::array<std::string_view, 4> kFingers{"Index", "Middle", "Ring", "Little"};
  static constexpr std::array<std::string_view, 5> kParts{"", "Proximal", "Intermediate", "Distal", ""};
  const auto finger = static_cast<std::size_t>((j - 6) / 5), part = static_cast<std::size_t>((j - 6) % 5);
  if (kParts[part].empty()) return {};  // metacarpal and tip
  return prefix + std::string(kFingers[finger]) + std::string(kParts[part]);
}

std::vector<OscMessage> stream_messages(const StreamFrame& frame, bool vmc) {
  std::vector<OscMessage> out;
  out.push_back({"/rhot/frame", {static_cast<std::int32_t>(frame.frame & 0x7fffffffU), static_cast<float>(frame.t_s)}});
  const std::array<HandSide, 2> sides{HandSide::kLeft, HandSide::kRight};
  if (vmc) {
    out.push_back({"/VMC/Ext/OK", {std::int32_t{1}}});
    out.push_back({"/VMC/Ext/T", {static_cast<float>(frame.t_s)}});
    OscMessage root{"/VMC/Ext/Root/Pos", {std::string("root")}};
    add_pose(root.args, Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity());
    out.push_back(std::move(root));
    for (std::size_t h = 0; h < 2; ++h) {
      if (frame.hands[h].seen && finite_hand(frame.hands[h])) add_vmc_hand(out, sides[h], frame.hands[h]);
    }
    for (const auto& [name, pose] : frame.bodies) {
      if (!finite_pose(pose)) continue;
      OscMessage m{"/VMC/Ext/Tra/Pos", {name}};
      add_pose(m.args, to_unity(pose.translation), to_unity(pose.rotation));
      out.push_back(std::move(m));
    }
    return out;
  }
  for (std::size_t h = 0; h < 2; ++h) {
    const HandInput& hand = frame.hands[h];
    const bool seen = hand.seen && finite_hand(hand);
    const std::string side = h == 0 ? "left" : "right";
    out.push_back({"/rhot/hand", {side, std::int32_t{seen ? 1 : 0}}});
    if (!seen) continue;
    const auto orientation = joint_orientations(hand.world_from_hand.rotation, hand.joints_world);
    for (int j = 0; j < kHandJointCount; ++j) {
      OscMessage m{"/rhot/hand/joint", {side, std::string(joint_name(static_cast<HandJoint>(j)))}};
      m.args.reserve(9);
      add_pose(m.args, hand.joints_world[static_cast<std::size_t>(j)], orientation[static_cast<std::size_t>(j)]);
      out.push_back(std::move(m));
    }
  }
  for (const auto& [name, pose] : frame.bodies) {
    if (!finite_pose(pose)) continue;
    OscMessage m{"/rhot/body", {name}};
    add_pose(m.args, pose.translation, pose.rotation);
    out.push_back(std::move(m));
  }
  return out;
}

std::expected<std::unique_ptr<OscStream>, std::string> OscStream::open(const StreamTarget& target) {
  addrinfo hints{};
  hints.ai_family = AF_INET;  // what liblo resolves and sends to
  hints.ai_socktype = SOCK_DGRAM;
  addrinfo* found = nullptr;
  if (const int e = getaddrinfo(target.host.c_str(), target.port.c_str(), &hints, &found); e != 0) {
    return std::unexpected("--stream: host \"" + target.host + "\" does not resolve: " + gai_strerror(e));
  }
  freeaddrinfo(found);
  std::unique_ptr<OscStream> s(new OscStream(target));
  if (!s->address_) return std::unexpected("--stream: cannot open a UDP destination at " + target.host + ":" + target.port);
  s->sender_ = std::thread([raw = s.get()] { raw->run(); });
  return s;
}

OscStream::OscStream(const StreamTarget& target) : target_(target) {
  address_ = lo_address_new_with_proto(LO_UDP, target.host.c_str(), target.port.c_str());
}

OscStream::~OscStream() {
  if (sender_.joinable()) flush();  // every frame handed over is sent (or counted) first
  stop_.store(true);
  published_.fetch_add(1);  // wakes the sender to see stop_
  published_.notify_one();
  if (sender_.joinable()) sender_.join();
  if (address_) lo_address_free(static_cast<lo_address>(address_));
}

void OscStream::send(const TrackingResults& results, const std::map<int, std::string>& names) {
  StreamFrame& slot = buffers_[static_cast<std::size_t>(back_)];
  slot.frame = published_.load(std::memory_order_relaxed);
  slot.t_s = results.t_s;
  slot.hands = results.hands;
  slot.bodies.resize(results.world_from_object.size());
  std::size_t n = 0;
  for (const auto& [id, pose] : results.world_from_object) {
    auto& [name, to] = slot.bodies[n++];
    if (const auto it = names.find(id); it != names.end()) {
      name.assign(it->second);
    } else {
      name.assign("star-");
      name.append(std::to_string(id));
    }
    to = pose;
  }
  const int previous = middle_.exchange(back_ | kFresh, std::memory_order_acq_rel);
  back_ = previous & ~kFresh;
  if (previous & kFresh) skipped_.fetch_add(1, std::memory_order_relaxed);
  published_.fetch_add(1, std::memory_order_release);
  published_.notify_one();
}

void OscStream::run() {
  // Woken every frame, this thread must not take the frame thread's core the moment it is woken
  // (on two cores it did: the frame waited out the whole send). SCHED_BATCH drops the wake-up
  // preemption but keeps a normal share of the CPU (SCHED_IDLE starved it on a busy machine).
  sched_param none{};
  pthread_setschedparam(pthread_self(), SCHED_BATCH, &none);
  std::uint64_t seen = 0;
  for (;;) {
    published_.wait(seen, std::memory_order_acquire);
    seen = published_.load(std::memory_order_acquire);
    if (middle_.load(std::memory_order_acquire) & kFresh) {
      front_ = middle_.exchange(front_, std::memory_order_acq_rel) & ~kFresh;
      send_frame(buffers_[static_cast<std::size_t>(front_)]);
    }
    done_.store(seen, std::memory_order_release);
    done_.notify_all();
    if (stop_.load()) return;
  }
}

void OscStream::send_frame(const StreamFrame& frame) {
  const std::vector<OscMessage> messages = stream_messages(frame, target_.vmc);
  constexpr lo_timetag kImmediate{0U, 1U};  // LO_TT_IMMEDIATE, which is a C compound literal
  lo_bundle bundle = lo_bundle_new(kImmediate);
  for (const OscMessage& m : messages) {
    lo_message message = lo_message_new();
    for (const OscArg& a : m.args) {
      if (const auto* i = std::get_if<std::int32_t>(&a)) {
        lo_message_add_int32(message, *i);
      } else if (const auto* f = std::get_if<float>(&a)) {
        lo_message_add_float(message, *f);
      } else {
        lo_message_add_string(message, std::get<std::string>(a).c_str());
      }
    }
    lo_bundle_add_message(bundle, m.address.c_str(), message);
  }
  const int bytes = lo_send_bundle(static_cast<lo_address>(address_), bundle);
  lo_bundle_free_recursive(bundle);
  (bytes < 0 ? errors_ : sent_).fetch_add(1, std::memory_order_relaxed);
}

OscStream::Stats OscStream::stats() const {
  const std::uint64_t published = published_.load() - (stop_.load() ? 1 : 0);
  return {published, sent_.load(), skipped_.load(), errors_.load()};
}

void OscStream::flush() {
  const std::uint64_t target = published_.load(std::memory_order_acquire);
  for (std::uint64_t d = done_.load(std::memory_order_acquire); d < target; d = done_.load(std::memory_order_acquire)) {
    done_.wait(d, std::memory_order_acquire);
  }
}

}  // namespace rhot
