#include "engine/render/vk/FenceWatch.h"

#include "base/Check.h"
#include "base/SteadyClock.h"

namespace rhot::vk {

FenceWatch::FenceWatch(VkDevice device) : device_(device), thread_([this] { loop(); }) {}

FenceWatch::~FenceWatch() {
  {
    const std::lock_guard lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  thread_.join();
}

void FenceWatch::watch(VkFence fence) {
  {
    const std::lock_guard lock(mutex_);
    RHOT_PRECONDITION(fence_ == VK_NULL_HANDLE, "FenceWatch::watch: the last fence was not waited for");
    fence_ = fence;
    done_ = false;
  }
  changed_.notify_all();
}

double FenceWatch::wait() {
  std::unique_lock lock(mutex_);
  RHOT_PRECONDITION(fence_ != VK_NULL_HANDLE, "FenceWatch::wait: no fence is watched");
  changed_.wait(lock, [this] { return done_; });
  fence_ = VK_NULL_HANDLE;
  return done_s_;
}

void FenceWatch::loop() {
  // Waits in short slices rather than one unbounded wait: lavapipe (Mesa 22.3) can oversleep a
  // fence that signals shortly after the wait begins by up to ~20 ms (measured: 64 x 64 per eye
  // took 20 ms with one wait, 2.5 ms when polling).
  constexpr std::uint64_t kSliceNs = 200'000;
  std::unique_lock lock(mutex_);
  for (;;) {
    changed_.wait(lock, [this] { return stop_ || (fence_ != VK_NULL_HANDLE && !done_); });
    if (stop_) return;
    const VkFence fence = fence_;
    lock.unlock();
    VkResult r = VK_TIMEOUT;
    while (r == VK_TIMEOUT) r = vkWaitForFences(device_, 1, &fence, VK_TRUE, kSliceNs);
    const double now = steady_now_s();
    // A lost device: the frame is as done as it will ever be; the caller's next Vulkan call reports it.
    lock.lock();
    done_ = true;
    done_s_ = now;
    changed_.notify_all();
  }
}

}  // namespace rhot::vk
