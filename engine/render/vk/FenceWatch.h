#pragma once
// When the GPU finished a frame, on the steady clock: a thread of its own waits for the frame's
// fence and stamps the moment it signals, so the time is right to a fraction of a millisecond
// whatever the caller's thread is doing meanwhile (the next frame's tracking, or sleeping until
// the next refresh). Motion-to-photon latency is measured from this time (docs/latency.md).

#include <condition_variable>
#include <mutex>
#include <thread>

#include "engine/render/vk/VulkanContext.h"

namespace rhot::vk {

class FenceWatch {
 public:
  explicit FenceWatch(VkDevice device);
  ~FenceWatch();
  FenceWatch(const FenceWatch&) = delete;
  FenceWatch& operator=(const FenceWatch&) = delete;

  // Starts watching a fence just submitted with. Precondition: nothing is being watched (wait()
  // was called since the last watch()).
  void watch(VkFence fence);
  // Blocks until the watched fence has signalled; returns when it did (steady clock, seconds).
  // The fence may be reset afterwards: the watch no longer touches it.
  double wait();

 private:
  void loop();

  VkDevice device_;
  std::mutex mutex_;
  std::condition_variable changed_;
  VkFence fence_ = VK_NULL_HANDLE;  // watched, until done_
  bool done_ = false;
  double done_s_ = 0.0;
  bool stop_ = false;
  std::thread thread_;
};

}  // namespace rhot::vk
