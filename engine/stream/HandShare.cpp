#include "engine/stream/HandShare.h"

#include <fcntl.h>
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
  if (ftruncate(fd, sizeof(HandShareBlock)) != 0) {
    const int err = errno;
    close(fd);
    return std::unexpected("cannot size the shared memory " + name + ": " + std::strerror(err));
  }
  void* mapped = mmap(nullptr, sizeof(HandShareBlock), PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  close(fd);
  if (mapped == MAP_FAILED) return std::unexpected("cannot map the shared memory " + name + ": " + std::strerror(errno));
  auto* block = static_cast<HandShareBlock*>(mapped);
  // A block of an older format (or a fresh, zeroed one) is laid out anew; readers check the
  // header before they trust the snapshot.
  if (block->magic != kHandShareMagic || block->version != kHandShareVersion || block->size != sizeof(HandShareBlock)) {
    block->magic = 0;  // not valid while it is being laid out
    std::atomic_thread_fence(std::memory_order_release);
    new (&block->running) std::atomic<std::uint32_t>(0);
    new (&block->sequence) std::atomic<std::uint64_t>(0);
    std::memset(&block->snapshot, 0, sizeof(block->snapshot));
    block->version = kHandShareVersion;
    block->size = sizeof(HandShareBlock);
    std::atomic_thread_fence(std::memory_order_release);
    block->magic = kHandShareMagic;
  }
  block->pid = static_cast<std::int32_t>(getpid());
  // A sequence left odd by a writer that crashed midway is made even (its snapshot is whatever it
  // got to; the next publish replaces it).
  std::uint64_t seq = block->sequence.load(std::memory_order_relaxed);
  if ((seq & 1u) != 0) block->sequence.store(seq + 1, std::memory_order_release);
  block->running.store(1, std::memory_order_release);
  return std::unique_ptr<HandShareWriter>(new HandShareWriter(name, block));
}

HandShareWriter::~HandShareWriter() {
  if (block_ == nullptr) return;
  block_->running.store(0, std::memory_order_release);
  munmap(block_, sizeof(HandShareBlock));
}

void HandShareWriter::publish(const HandShareSnapshot& snapshot) {
  const std::uint64_t seq = block_->sequence.load(std::memory_order_relaxed);
  block_->sequence.store(seq + 1, std::memory_order_relaxed);  // odd: writing
  std::atomic_thread_fence(std::memory_order_release);
  std::memcpy(&block_->snapshot, &snapshot, sizeof(snapshot));
  block_->sequence.store(seq + 2, std::memory_order_release);  // even: done
  block_->running.store(1, std::memory_order_release);
}

HandShareReader::~HandShareReader() {
  if (block_ != nullptr) munmap(const_cast<HandShareBlock*>(block_), sizeof(HandShareBlock));
}

std::optional<HandShareSnapshot> HandShareReader::read(double now_s) {
  if (block_ == nullptr) {
    if (now_s - last_try_s_ < retry_s_) return std::nullopt;
    last_try_s_ = now_s;
    const int fd = shm_open(name_.c_str(), O_RDONLY, 0);
    if (fd < 0) return std::nullopt;
    struct stat st {};
    const bool big_enough = fstat(fd, &st) == 0 && static_cast<std::size_t>(st.st_size) >= sizeof(HandShareBlock);
    void* mapped = big_enough ? mmap(nullptr, sizeof(HandShareBlock), PROT_READ, MAP_SHARED, fd, 0) : MAP_FAILED;
    close(fd);
    if (mapped == MAP_FAILED) return std::nullopt;
    block_ = static_cast<const HandShareBlock*>(mapped);
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
    if (block_->sequence.load(std::memory_order_relaxed) == before) return before == 0 ? std::nullopt : std::optional(copy);
  }
  return std::nullopt;
}

}  // namespace rhot
