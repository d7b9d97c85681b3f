#include "engine/render/PngWriter.h"

#include <algorithm>

#include "base/Check.h"

namespace rhot {

PngWriter::PngWriter(unsigned threads, std::size_t max_queued) : max_queued_(max_queued) {
  RHOT_PRECONDITION(max_queued >= 1, "PngWriter: room for at least one image");
  if (threads == 0) threads = std::max(2u, std::thread::hardware_concurrency()) - 1;  // 0 when unknown
  for (unsigned i = 0; i < threads; ++i) threads_.emplace_back([this] { loop(); });
}

PngWriter::~PngWriter() {
  (void)finish();
  {
    const std::lock_guard lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  for (std::thread& t : threads_) t.join();
}

void PngWriter::write(Image image, std::filesystem::path file) {
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [this] { return queue_.size() < max_queued_; });
  queue_.push_back({std::move(image), std::move(file)});
  lock.unlock();
  changed_.notify_all();
}

std::optional<std::string> PngWriter::finish() {
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [this] { return queue_.empty() && busy_ == 0; });
  return error_;
}

std::optional<std::string> PngWriter::error() const {
  const std::lock_guard lock(mutex_);
  return error_;
}

std::size_t PngWriter::written() const {
  const std::lock_guard lock(mutex_);
  return written_;
}

void PngWriter::loop() {
  std::unique_lock lock(mutex_);
  for (;;) {
    changed_.wait(lock, [this] { return stop_ || !queue_.empty(); });
    if (queue_.empty()) return;  // stopping, nothing left
    Job job = std::move(queue_.front());
    queue_.pop_front();
    ++busy_;
    lock.unlock();
    changed_.notify_all();  // room in the queue
    const auto written = write_png(job.image, job.file);
    lock.lock();
    --busy_;
    if (written) {
      ++written_;
    } else if (!error_) {
      error_ = written.error();
    }
    changed_.notify_all();
  }
}

}  // namespace rhot
