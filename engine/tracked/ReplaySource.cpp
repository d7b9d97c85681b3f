#include "engine/tracked/ReplaySource.h"

#include <cmath>
#include <cstdio>

#include <spdlog/spdlog.h>

#include "base/Check.h"

namespace rhot {

std::expected<std::unique_ptr<ReplaySource>, std::string> ReplaySource::open(const std::filesystem::path& file, double speed,
                                                                             const TrackedObjects& objects) {
  auto recording = load_recording(file);
  if (!recording) return std::unexpected(recording.error());
  if (!(speed > 0.0) || !std::isfinite(speed)) return std::unexpected(std::string("replay speed must be a positive number"));
  return std::unique_ptr<ReplaySource>(new ReplaySource(file.string(), std::move(*recording), speed, objects));
}

ReplaySource::ReplaySource(std::string file, Recording recording, double speed, const TrackedObjects& objects)
    : file_(std::move(file)), recording_(std::move(recording)), speed_(speed) {
  for (const TrackedObject& o : objects.objects) {
    if (!o.name.empty()) objects_.emplace_back(o.star_id, o.name);
  }
}

std::vector<TrackingStage> ReplaySource::stages() {
  return {{"replay", [this](double t) { replay(t); }}};
}

void ReplaySource::set_speed(double speed) {
  RHOT_PRECONDITION(std::isfinite(speed) && speed > 0.0, "ReplaySource::set_speed: speed must be finite and positive");
  speed_ = speed;
}

void ReplaySource::replay(double t_s) {
  // The recording's clock runs at the replay speed, which may change between frames.
  clock_s_ = started_ ? clock_s_ + (t_s - last_t_s_) * speed_ : t_s * speed_;
  started_ = true;
  last_t_s_ = t_s;
  ++frames_played_;
  // Past the last frame's time (a nanosecond's slack for the clock's sums): said once.
  if (!end_notice_ && clock_s_ > recording_.duration_s() + 1e-9) {
    char figures[160];
    std::snprintf(figures, sizeof figures, " ended at frame %llu of the run (%.3f s): its %zu frames (%.3f s) have played",
                  static_cast<unsigned long long>(frames_played_), t_s, recording_.frames.size(), recording_.duration_s());
    end_notice_ = "replay: the recording " + file_ + figures + ", and its last frame is held from here on";
    spdlog::info("{}", *end_notice_);
  }
  const RecordedFrame frame = recording_.at(clock_s_);
  results_ = TrackingResults{};
  results_.t_s = t_s;
  results_.hands = frame.hands;
  results_.counts.hands_seen = {frame.hands[0].seen, frame.hands[1].seen};
  for (const auto& [id, name] : objects_) {
    const auto pose = frame.objects.find(name);
    if (pose == frame.objects.end()) continue;
    results_.world_from_object[id] = pose->second;
    ++results_.counts.stars_seen;
    results_.counts.seen_star_ids.push_back(id);
  }
}

}  // namespace rhot
