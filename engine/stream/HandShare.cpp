#include "engine/stream/HandShare.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <new>

namespace rhot {

static_assert(std::atomic<std::uint64_t>::is_always_lock_free && std::atomic<std::uint32_t>::is_always_lock_free,
              "the block's counters are shared between processes: they must be lock-free");

std::string hand_share_name() {
  const char* env = std::getenv("RHOT_HANDS_SHM");
  if (env != nullptr && env[0] == '/' && env[1] != '\0') return env;
  return "/rhot-hands";
}

std::expected<std::unique_ptr<HandShareWriter>, std::string> HandShareWriter::open(const std::string& name) {
  const int fd = shm_open(name.c_str(), O_RDWR | O_CREAT, 0644);
  if (fd < 0) return std::unexpected("cannot open the shared memory " + name + " for the hands: " + std::strerror(errno));
  const auto fail = [&](const std::string& why) {
    ::close(fd);
    return std::unexpected(why);
  };
  struct stat st {};
  if (fstat(fd, &st) != 0) return fail("cannot read the shared memory " + name + ": " + std::strerror(errno));
  if (st.st_uid != geteuid()) return fail("the shared memory " + name + " belongs to another user (uid " + std::to_string(st.st_uid) + ")");
  if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const void* peek = mmap(nullptr, sizeof(HandShareBlock), PROT_READ, MAP_SHARED, fd, 0);
    std::string who = "another process";
    if (peek != MAP_FAILED && static_cast<std::size_t>(st.st_size) >= sizeof(HandShareBlock)) {
      who = "process " + std::to_string(static_cast<const HandShareBlock*>(peek)->pid);
    }
    if (peek != MAP_FAILED) munmap(const_cast<void*>(peek), sizeof(HandShareBlock));
    return fail(who + " is publishing its hands in " + name + " (start this one with --no-publish, or another RHOT_HANDS_SHM)");
  }
  // Never smaller: a reader holding a larger mapping of it would fault.
  if (static_cast<std::size_t>(st.st_size) < sizeof(HandShareBlock) && ftruncate(fd, sizeof(HandShareBlock)) != 0) {
    return fail("cannot size the shared memory " + name + ": " + std::strerror(errno));
  }
  void* mapped = mmap(nullptr, sizeof(HandShareBlock), PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  if (mapped == MAP_FAILED) return fail("cannot map the shared memory " + name + ": " + std::strerror(errno));
  auto* block = static_cast<HandShareBlock*>(mapped);
  if (block->magic != kHandShareMagic || block->version != kHandShareVersion || block->size != sizeof(HandShareBlock)) {
    // A fresh (zeroed) block, or one of another format: laid out anew. Readers check the header
    // before they trust the snapshot.
    block->magic = 0;
    std::atomic_thread_fence(std::memory_order_release);
    new (&block->running) std::atomic<std::uint32_t>(0);
    new (&block->sequence) std::atomic<std::uint64_t>(0);
    block->version = kHandShareVersion;
    block->size = sizeof(HandShareBlock);
    std::atomic_thread_fence(std::memory_order_release);
    block->magic = kHandShareMagic;
  }
  // Whatever a previous writer left (a crash may have stopped it midway) is cleared under the
  // seqlock: no hand tracked, published at time 0. Nobody else writes: this process holds the lock.
  block->running.store(0, std::memory_order_release);
  const std::uint64_t seq = block->sequence.load(std::memory_order_relaxed) | 1u;  // odd: being written
  block->sequence.store(seq, std::memory_order_relaxed);
  std::atomic_thread_fence(std::memory_order_release);
  std::memset(&block->snapshot, 0, sizeof(block->snapshot));
  block->sequence.store(seq + 1, std::memory_order_release);
  block->pid = static_cast<std::int32_t>(getpid());
  return std::unique_ptr<HandShareWriter>(new HandShareWriter(name, block, fd));
}

HandShareWriter::~HandShareWriter() {
  if (block_ == nullptr) return;
  block_->running.store(0, std::memory_order_release);
  munmap(block_, sizeof(HandShareBlock));
  ::close(fd_);  // drops the lock
}

void HandShareWriter::publish(const HandShareSnapshot& snapshot) {
  const std::uint64_t seq = block_->sequence.load(std::memory_order_relaxed);
  block_->sequence.store(seq + 1, std::memory_order_relaxed);  // odd: writing
  std::atomic_thread_fence(std::memory_order_release);
  std::memcpy(&block_->snapshot, &snapshot, sizeof(snapshot));
  block_->sequence.store(seq + 2, std::memory_order_release);  // even: done
  block_->running.store(1, std::memory_order_release);
}

HandShareReader::~HandShareReader() { close(); }

void HandShareReader::close() {
  if (block_ != nullptr) munmap(const_cast<HandShareBlock*>(block_), sizeof(HandShareBlock));
  block_ = nullptr;
  inode_ = 0;
}

// Maps the block the name now names, if it is another than the one mapped (or none is). At most
// once every retry_s. True where a block is mapped afterwards.
bool HandShareReader::open(double now_s) {
  if (now_s - last_try_s_ < retry_s_) return block_ != nullptr;
  last_try_s_ = now_s;
  const int fd = shm_open(name_.c_str(), O_RDONLY, 0);
  if (fd < 0) return block_ != nullptr;
  struct stat st {};
  const bool usable = fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && st.st_uid == geteuid() &&
                      static_cast<std::size_t>(st.st_size) >= sizeof(HandShareBlock);
  if (!usable || (block_ != nullptr && static_cast<unsigned long>(st.st_ino) == inode_)) {
    ::close(fd);
    return block_ != nullptr;
  }
  void* mapped = mmap(nullptr, sizeof(HandShareBlock), PROT_READ, MAP_SHARED, fd, 0);
  ::close(fd);
  if (mapped == MAP_FAILED) return block_ != nullptr;
  close();
  block_ = static_cast<const HandShareBlock*>(mapped);
  inode_ = static_cast<unsigned long>(st.st_ino);
  last_sequence_ = 0;
  last_change_s_ = now_s;
  return true;
}

std::optional<HandShareSnapshot> HandShareReader::read(double now_s) {
  // No block yet; or nothing new for a while (the block may have been removed and made anew).
  if (block_ == nullptr || now_s - last_change_s_ > retry_s_) {
    if (!open(now_s)) return std::nullopt;
  }
  if (block_->magic != kHandShareMagic || block_->version != kHandShareVersion || block_->size != sizeof(HandShareBlock)) {
    return std::nullopt;
  }
  if (block_->running.load(std::memory_order_acquire) == 0) return std::nullopt;
  HandShareSnapshot copy;
  for (int attempt = 0; attempt < 8; ++attempt) {
    const std::uint64_t before = block_->sequence.load(std::memory_order_acquire);
    if ((before & 1u) != 0) continue;
    std::memcpy(&copy, &block_->snapshot, sizeof(copy));
    std::atomic_thread_fence(std::memory_order_acquire);
    if (block_->sequence.load(std::memory_order_relaxed) != before) continue;
    if (before != last_sequence_) {
      last_sequence_ = before;
      last_change_s_ = now_s;
    }
    return copy;
  }
  return std::nullopt;
}

}  // namespace rhot
