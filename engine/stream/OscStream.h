#pragma once
// What rhot tracks, sent to other programs as OSC over UDP (liblo), every frame: the runtime's
// "stream" stage (`rhot-demo --stream osc://HOST:PORT[,vmc]`, live or on replay).
//
// Two address spaces (docs/streaming.md has every message):
// - rhot's own (osc://HOST:PORT): /rhot/frame, /rhot/hand, /rhot/hand/joint (the 26 OpenXR joints,
//   world positions and orientations in rhot's frame: metres, right-handed, +Y up), /rhot/body;
// - the VMC protocol's (osc://HOST:PORT,vmc), for Virtual Motion Capture, VSeeFace, XR Animator
//   and the Unity and Blender receivers: /VMC/Ext/OK, /VMC/Ext/T, /VMC/Ext/Root/Pos, the hands as
//   /VMC/Ext/Bone/Pos of Unity's humanoid bones (LeftHand, LeftThumbProximal ... RightLittleDistal)
//   in Unity's frame (left-handed, +Y up, +Z forward), rotations relative to the T-pose hand,
//   positions local to the parent bone; tracked objects as /VMC/Ext/Tra/Pos; plus /rhot/frame.
// One bundle a frame. Hands not seen this frame are left out (receivers hold their last pose).
//
// The frame thread only copies the frame's results into a buffer of three (triple buffering: no
// lock, no allocation once warm, no I/O) and wakes a sender thread, which encodes and sends them
// (SCHED_BATCH: woken, it does not preempt the frame thread). When the sender is still busy with
// an earlier frame, the waiting frame is replaced by the newer one (counted as skipped): sending
// never makes the frame wait, whatever the sender's thread is doing. UDP needs no receiver: one that is not there, or goes away,
// costs nothing but a counted send error.

#include <array>
#include <atomic>
#include <cstdint>
#include <expected>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <thread>
#include <utility>
#include <variant>
#include <vector>

#include "engine/hand/HandInput.h"
#include "engine/tracked/TrackingResults.h"

namespace rhot {

struct StreamTarget {
  std::string host;
  std::string port;
  bool vmc = false;
};

// "osc://HOST:PORT" or "osc://HOST:PORT,vmc" (HOST a name or an IPv4 address: Debian's liblo sends
// over IPv4 only; PORT 1-65535). Errors name what is wrong with the text.
[[nodiscard]] std::expected<StreamTarget, std::string> parse_stream_url(std::string_view url);

// One frame as it is sent.
struct StreamFrame {
  std::uint64_t frame = 0;                              // counts frames handed to the stream, from 0
  double t_s = 0.0;                                     // the runtime's clock of the results
  std::array<HandInput, 2> hands;                       // 0 left, 1 right
  std::vector<std::pair<std::string, Rigid3d>> bodies;  // the tracked objects seen, by entity name
};

// One OSC message before encoding.
using OscArg = std::variant<std::int32_t, float, std::string>;
struct OscMessage {
  std::string address;
  std::vector<OscArg> args;
};

// The frame's messages in the order they are sent.
std::vector<OscMessage> stream_messages(const StreamFrame& frame, bool vmc);

// The humanoid bone a hand joint drives in the VMC protocol ("LeftIndexProximal"), empty for the
// joints Unity's humanoid has no bone for (palm, finger metacarpals, tips).
std::string vmc_bone_name(HandSide side, HandJoint joint);
// The joints sent as VMC bones, in the order sent: wrist, then thumb to little, base to end.
const std::array<HandJoint, 16>& vmc_hand_joints();

class OscStream {
 public:
  // Opens the UDP destination and starts the sender thread. Fails on a host that does not resolve
  // to an IPv4 address. Destroying it sends what was handed over first.
  [[nodiscard]] static std::expected<std::unique_ptr<OscStream>, std::string> open(const StreamTarget& target);
  ~OscStream();
  OscStream(const OscStream&) = delete;
  OscStream& operator=(const OscStream&) = delete;

  // Frame thread (one thread only): the frame's results, with the names of the tracked objects by star id (objects
  // without a name are sent as "star-ID").
  void send(const TrackingResults& results, const std::map<int, std::string>& names);

  struct Stats {
    std::uint64_t given = 0;    // frames handed over
    std::uint64_t sent = 0;     // bundles sent
    std::uint64_t skipped = 0;  // replaced by a newer frame before the sender took them
    std::uint64_t errors = 0;   // sends that failed (no receiver, network down)
  };
  Stats stats() const;
  // Waits until the sender has taken and sent (or failed to send) every frame handed over; for
  // tests and shutdown.
  void flush();

 private:
  explicit OscStream(const StreamTarget& target);
  void run();
  void send_frame(const StreamFrame& frame);

  StreamTarget target_;
  void* address_ = nullptr;  // lo_address (liblo stays out of this header)
  // Triple buffering: the frame thread fills buffers_[back_], the sender reads buffers_[front_],
  // and middle_ holds the third's index, with kFresh set while it holds a frame not yet taken.
  static constexpr int kFresh = 4;
  std::array<StreamFrame, 3> buffers_;
  int back_ = 0;   // the frame thread's
  int front_ = 1;  // the sender's
  std::atomic<int> middle_{2};
  std::atomic<std::uint64_t> published_{0};  // frames handed over; the sender waits on it
  std::atomic<std::uint64_t> done_{0};       // the last `published_` the sender has dealt with
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> sent_{0};
  std::atomic<std::uint64_t> skipped_{0};
  std::atomic<std::uint64_t> errors_{0};
  std::thread sender_;
};

}  // namespace rhot
