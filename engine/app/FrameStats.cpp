#include "engine/app/FrameStats.h"

#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>

#include "base/Check.h"

namespace rhot {

double percentile(std::vector<double> samples, double q) {
  if (samples.empty()) return 0.0;
  // Nearest rank: the smallest value with at least q of the samples at or below it.
  const auto n = samples.size();
  std::size_t rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(n)));
  rank = std::clamp<std::size_t>(rank, 1, n);
  std::nth_element(samples.begin(), samples.begin() + static_cast<std::ptrdiff_t>(rank - 1), samples.end());
  return samples[rank - 1];
}

FrameStats::FrameStats(std::vector<std::string> stage_names, double budget_ms, std::size_t window_frames)
    : names_(std::move(stage_names)), budget_ms_(budget_ms), window_(window_frames), stages_(names_.size()) {
  RHOT_PRECONDITION(budget_ms > 0.0, "FrameStats: the budget must be positive");
  RHOT_PRECONDITION(window_frames > 0, "FrameStats: the window must hold at least one frame");
}

void FrameStats::push(Series& s, double ms) const {
  RHOT_PRECONDITION(std::isfinite(ms) && ms >= 0.0, "FrameStats::record: times must be finite and >= 0");
  if (s.window.size() == window_) s.window.pop_front();
  s.window.push_back(ms);
  ++s.count;
  s.sum += ms;
  s.max = std::max(s.max, ms);
}

void FrameStats::record(double frame_ms, const std::vector<double>& stage_ms) {
  RHOT_PRECONDITION(stage_ms.size() == stages_.size(), "FrameStats::record: one time per stage");
  push(frame_, frame_ms);
  for (std::size_t i = 0; i < stages_.size(); ++i) push(stages_[i], stage_ms[i]);
  if (frame_ms > budget_ms_) ++over_budget_;
}

TimingSummary FrameStats::summarize(const Series& s) {
  TimingSummary t;
  t.count = s.count;
  if (s.count == 0) return t;
  const std::vector<double> samples(s.window.begin(), s.window.end());
  t.mean_ms = s.sum / static_cast<double>(s.count);
  t.p50_ms = percentile(samples, 0.50);
  t.p99_ms = percentile(samples, 0.99);
  t.max_ms = s.max;
  return t;
}

TimingSummary FrameStats::frame_summary() const { return summarize(frame_); }

TimingSummary FrameStats::stage_summary(std::size_t stage) const {
  RHOT_PRECONDITION(stage < stages_.size(), "FrameStats::stage_summary: no such stage");
  return summarize(stages_[stage]);
}

nlohmann::json FrameStats::to_json() const {
  const auto put = [](nlohmann::json& j, const TimingSummary& t) {
    j["p50_ms"] = t.p50_ms;
    j["p99_ms"] = t.p99_ms;
    j["max_ms"] = t.max_ms;
    j["mean_ms"] = t.mean_ms;
  };
  nlohmann::json j;
  j["frames"] = frames();
  j["budget_ms"] = budget_ms_;
  j["frames_over_budget"] = over_budget_;
  j["budget_miss_fraction"] = frames() == 0 ? 0.0 : static_cast<double>(over_budget_) / static_cast<double>(frames());
  j["window_frames"] = std::min<std::uint64_t>(frames(), window_);
  put(j, frame_summary());
  nlohmann::json stages = nlohmann::json::object();
  for (std::size_t i = 0; i < names_.size(); ++i) put(stages[names_[i]], stage_summary(i));
  j["stages"] = std::move(stages);
  return j;
}

std::vector<double> FrameStats::recent_frame_ms(std::size_t n) const {
  const std::size_t k = std::min(n, frame_.window.size());
  return {frame_.window.end() - static_cast<std::ptrdiff_t>(k), frame_.window.end()};
}

double FrameStats::last_stage_ms(std::size_t stage) const {
  RHOT_PRECONDITION(stage < stages_.size(), "FrameStats::last_stage_ms: no such stage");
  return stages_[stage].window.empty() ? 0.0 : stages_[stage].window.back();
}

}  // namespace rhot
