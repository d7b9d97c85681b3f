#pragma once
// Writes PNG files on threads of its own, so that capturing frames does not hold up the frame
// loop (encoding one 2160 x 1200 PNG takes about 0.2 s on one core). Images wait in a queue of at
// most `max_queued`; when it is full, write() waits for room rather than dropping a frame, so a
// capture is complete however fast the frames come.

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <filesystem>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "engine/render/Image.h"

namespace rhot {

class PngWriter {
 public:
  // threads 0: one fewer than the machine's cores, at least one. Precondition: max_queued >= 1.
  explicit PngWriter(unsigned threads = 0, std::size_t max_queued = 8);
  // Waits for every queued image to be written.
  ~PngWriter();
  PngWriter(const PngWriter&) = delete;
  PngWriter& operator=(const PngWriter&) = delete;

  // Queues an image for `file`; returns at once unless the queue is full.
  void write(Image image, std::filesystem::path file);
  // Waits until every queued image is written. The first failure, if any ("<file>: <why>").
  [[nodiscard]] std::optional<std::string> finish();
  // The first failure so far, without waiting.
  std::optional<std::string> error() const;
  std::size_t written() const;

 private:
  struct Job {
    Image image;
    std::filesystem::path file;
  };
  void loop();

  std::size_t max_queued_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<Job> queue_;
  std::size_t busy_ = 0;
  std::size_t written_ = 0;
  std::optional<std::string> error_;
  bool stop_ = false;
  std::vector<std::thread> threads_;
};

}  // namespace rhot
