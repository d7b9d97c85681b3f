#include "engine/app/FrameLoop.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>

#include <spdlog/spdlog.h>

#include "engine/core/World.h"
#include "base/Check.h"

namespace rhot {

using Clock = std::chrono::steady_clock;

namespace {
double wall_seconds() { return std::chrono::duration<double>(Clock::now().time_since_epoch()).count(); }
}  // namespace

std::expected<void, std::string> FrameLoopSettings::check() const {
  if (!std::isfinite(rate_hz) || rate_hz < 1.0 || rate_hz > 10000.0) {
    return std::unexpected("rate_hz must be from 1 to 10000, got " + std::to_string(rate_hz));
  }
  if (!std::isfinite(budget_ms) || budget_ms <= 0.0) {
    return std::unexpected("budget_ms must be greater than 0, got " + std::to_string(budget_ms));
  }
  if (stats_window_frames == 0) return std::unexpected("stats_window_frames must be at least 1");
  return {};
}

FrameLoop::FrameLoop(World& world, Systems& systems, FrameLoopSettings settings)
    : world_(world),
      systems_(systems),
      settings_(settings),
      dt_s_(1.0 / settings.rate_hz),
      stats_(systems.names(), settings.budget_ms, settings.stats_window_frames),
      stage_ms_(systems.size(), 0.0) {
  const auto ok = settings_.check();
  RHOT_PRECONDITION(ok.has_value(), "FrameLoop: " + (ok ? std::string() : ok.error()));
  RHOT_PRECONDITION(systems.names().size() == systems.size(), "FrameLoop: call Systems::build() first");
}

void FrameLoop::step() {
  if (settings_.pace) settings_.pace();
  const FrameContext frame{frame_index_, dt_s_, time_s()};
  const auto start = Clock::now();
  systems_.run(world_, frame, stage_ms_);
  const double frame_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  stats_.record(frame_ms, stage_ms_);
  ++frame_index_;

  if (frame_ms > settings_.budget_ms) {
    ++misses_since_warning_;
    const double now = wall_seconds();
    if (now - last_warning_s_ >= 1.0) {
      const auto slowest = std::max_element(stage_ms_.begin(), stage_ms_.end());
      const std::string stage =
          slowest == stage_ms_.end() ? "none" : systems_.names()[static_cast<std::size_t>(slowest - stage_ms_.begin())];
      spdlog::warn(
          "frame {} took {:.2f} ms, over its {:.2f} ms budget (slowest stage: {} {:.2f} ms); {} frame(s) "
          "over budget since the last warning",
          frame.frame_index, frame_ms, settings_.budget_ms, stage, slowest == stage_ms_.end() ? 0.0 : *slowest, misses_since_warning_);
      last_warning_s_ = now;
      misses_since_warning_ = 0;
    }
  }
}

std::uint64_t FrameLoop::run(std::uint64_t frames, const std::function<bool()>& keep_running) {
  const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(dt_s_));
  auto deadline = Clock::now();
  std::uint64_t ran = 0;
  while ((frames == 0 || ran < frames) && (!keep_running || keep_running())) {
    step();
    ++ran;
    if (settings_.real_time) {
      deadline += period;
      const auto now = Clock::now();
      if (now < deadline) {
        std::this_thread::sleep_until(deadline);
      } else if (now - deadline > period) {
        deadline = now;  // fell more than a frame behind: resynchronise rather than race to catch up
      }
    }
  }
  return ran;
}

}  // namespace rhot
