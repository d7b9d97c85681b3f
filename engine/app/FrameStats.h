#pragma once
// Frame statistics: per-system and whole-frame times, their p50/p99/max, and how many frames
// missed the budget. Percentiles are exact (nearest rank) over the most recent `window` frames;
// counts, mean and max cover the whole run.

#include <cstdint>
#include <deque>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

namespace rhot {

struct TimingSummary {
  std::uint64_t count = 0;  // samples over the whole run
  double mean_ms = 0.0;
  double p50_ms = 0.0;  // over the window
  double p99_ms = 0.0;  // over the window
  double max_ms = 0.0;  // over the whole run
};

class FrameStats {
 public:
  // Precondition: budget_ms > 0, window_frames > 0.
  explicit FrameStats(std::vector<std::string> stage_names, double budget_ms = 11.1, std::size_t window_frames = 65536);

  // Records one frame: the whole frame's time and each stage's (indexed like stage_names).
  // Precondition: stage_ms.size() == number of stages; times finite and >= 0.
  void record(double frame_ms, const std::vector<double>& stage_ms);

  std::uint64_t frames() const { return frame_.count; }
  std::uint64_t frames_over_budget() const { return over_budget_; }
  double budget_ms() const { return budget_ms_; }
  const std::vector<std::string>& stage_names() const { return names_; }

  TimingSummary frame_summary() const;
  // The whole frame's times of the last `n` frames (fewer at the start), oldest first.
  std::vector<double> recent_frame_ms(std::size_t n) const;
  // A stage's time in the last frame (0 before the first).
  double last_stage_ms(std::size_t stage) const;
  TimingSummary stage_summary(std::size_t stage) const;

  // {"frames", "budget_ms", "frames_over_budget", "budget_miss_fraction", "p50_ms", "p99_ms",
  //  "max_ms", "mean_ms", "stages": {name: {"p50_ms", ...}}}
  nlohmann::json to_json() const;

 private:
  struct Series {
    std::deque<double> window;
    std::uint64_t count = 0;
    double sum = 0.0;
    double max = 0.0;
  };
  void push(Series& s, double ms) const;
  static TimingSummary summarize(const Series& s);

  std::vector<std::string> names_;
  double budget_ms_;
  std::size_t window_;
  Series frame_;
  std::vector<Series> stages_;
  std::uint64_t over_budget_ = 0;
};

// Nearest-rank percentile (q in [0, 1]) of unsorted samples; 0 for none.
double percentile(std::vector<double> samples, double q);

}  // namespace rhot
