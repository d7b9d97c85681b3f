#pragma once
// rhot's hands for other processes on the same machine, through shared memory: a running rhot
// publishes every frame's hands (HandShareWriter), and readers such as rhot's OpenXR API layer
// (engine/xrlayer) take the newest whenever they like (HandShareReader). Neither ever waits for
// the other: the block is one snapshot guarded by a sequence counter (a seqlock), the writer
// makes it odd while it writes and even again after, and a reader that sees the count change
// under it reads again.
//
// The block (POSIX shared memory, name "/rhot-hands" unless RHOT_HANDS_SHM says otherwise) is
// HandShareBlock below, format version kHandShareVersion; docs/openxr.md describes it field by
// field. One writer at a time owns it (an advisory lock the kernel drops when the writer dies):
// a second rhot does not publish, and says so. It outlives the writer: a rhot that stops cleanly
// marks it stopped, one that crashes just stops updating it, and a rhot started again takes it
// over (clearing whatever a crash left half-written), so a reader keeps its mapping and only has
// to watch the times; a reader also maps the block again if it was removed and made anew. The
// block is never made smaller (a reader's mapping stays valid), and both sides refuse a block
// another user owns (its hands could be anyone's).
//
// Dependency-free (the C++ standard library and POSIX): the layer links it into applications.

#include <atomic>
#include <cstdint>
#include <expected>
#include <memory>
#include <optional>
#include <string>

namespace rhot {

inline constexpr std::uint32_t kHandShareMagic = 0x524E4448;  // "HDNR"
inline constexpr std::uint32_t kHandShareVersion = 1;
inline constexpr int kHandShareJoints = 26;  // XR_HAND_JOINT_COUNT_EXT, in OpenXR's order

struct HandShareJoint {
  float position[3];     // metres, rhot's world
  float orientation[4];  // x, y, z, w: OpenXR's joint frame (-Z along the bone, +Y out of the back of the hand)
  float radius;          // metres
  float velocity[3];     // metres per second, rhot's world
};

struct HandShareHand {
  std::uint32_t tracked;  // 1: seen in this frame; 0: the joints are not to be used
  std::uint32_t reserved;
  HandShareJoint joints[kHandShareJoints];
};

struct HandShareSnapshot {
  double capture_s;    // when the cameras saw these hands, on CLOCK_MONOTONIC (the steady clock), seconds
  double published_s;  // when rhot wrote them, same clock
  std::uint64_t frame;
  float world_from_stage[16];  // column-major 4 x 4: the rig registered to the headset's STAGE space; identity without one
  HandShareHand hands[2];      // 0 left, 1 right
};

struct HandShareBlock {
  std::uint32_t magic;
  std::uint32_t version;
  std::uint32_t size;                  // sizeof(HandShareBlock)
  std::int32_t pid;                    // the writer's
  std::atomic<std::uint32_t> running;  // 1 while a writer is publishing, 0 once it stopped cleanly
  std::uint32_t reserved;
  std::atomic<std::uint64_t> sequence;  // odd while the snapshot is being written
  HandShareSnapshot snapshot;
};

// The block's name: RHOT_HANDS_SHM if set (it must start with '/'), else "/rhot-hands".
std::string hand_share_name();

// The publishing side. Creates the block if it is not there, or takes over the one a previous
// rhot left.
class HandShareWriter {
 public:
  // Fails, naming the block, where shared memory cannot be created or mapped, another user owns
  // the block, or another process is publishing in it.
  [[nodiscard]] static std::expected<std::unique_ptr<HandShareWriter>, std::string> open(const std::string& name);
  HandShareWriter(const HandShareWriter&) = delete;
  HandShareWriter& operator=(const HandShareWriter&) = delete;
  ~HandShareWriter();  // marks the block stopped (its readers see the hands go untracked at once)

  void publish(const HandShareSnapshot& snapshot);
  const std::string& name() const { return name_; }

 private:
  HandShareWriter(std::string name, HandShareBlock* block, int fd) : name_(std::move(name)), block_(block), fd_(fd) {}
  std::string name_;
  HandShareBlock* block_ = nullptr;
  int fd_ = -1;  // held open: its lock says this process owns the block
};

// The reading side. Never blocks; opens the block lazily and keeps trying (at most every
// retry_s) while there is none.
class HandShareReader {
 public:
  explicit HandShareReader(std::string name, double retry_s = 0.1) : name_(std::move(name)), retry_s_(retry_s) {}
  HandShareReader(const HandShareReader&) = delete;
  HandShareReader& operator=(const HandShareReader&) = delete;
  ~HandShareReader();

  // The newest snapshot, if a writer is publishing: nullopt where there is no block (yet), its
  // writer stopped, or a consistent copy could not be taken in a few tries (a writer stuck midway,
  // or crashed there). now_s: the steady clock, for the retries. While nothing new comes, the
  // name is looked up again every retry_s, in case the block was removed and made anew.
  std::optional<HandShareSnapshot> read(double now_s);

 private:
  bool open(double now_s);
  void close();
  std::string name_;
  double retry_s_;
  double last_try_s_ = -1e300;
  const HandShareBlock* block_ = nullptr;
  unsigned long inode_ = 0;
  std::uint64_t last_sequence_ = 0;
  double last_change_s_ = 0.0;
};

}  // namespace rhot
