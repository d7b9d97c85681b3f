#include "engine/tracked/SessionRecorder.h"

#include <vector>

#include <spdlog/spdlog.h>

namespace rhot {

std::expected<SessionRecorder, std::string> SessionRecorder::open(const std::filesystem::path& file, double rate_hz,
                                                                  const TrackedObjects& objects) {
  std::map<int, std::string> names;
  for (const TrackedObject& o : objects.objects) {
    if (!o.name.empty()) names[o.star_id] = o.name;
  }
  std::vector<std::string> columns;
  for (const auto& [id, name] : names) columns.push_back(name);
  auto writer = RecordingWriter::open(file, rate_hz, columns);
  if (!writer) return std::unexpected(writer.error());
  return SessionRecorder(std::move(*writer), objects);
}

SessionRecorder::SessionRecorder(RecordingWriter writer, const TrackedObjects& objects) : writer_(std::move(writer)) {
  for (const TrackedObject& o : objects.objects) {
    if (!o.name.empty()) name_of_star_[o.star_id] = o.name;
  }
}

void SessionRecorder::record(const TrackingResults& results, const std::array<std::string, 2>& holding,
                             const std::vector<RecordedGraspEvent>& grasp_events) {
  if (!writer_) return;
  for (const auto& [id, pose] : results.world_from_object) {
    if (const auto name = name_of_star_.find(id); name != name_of_star_.end()) last_pose_[name->second] = pose;
  }
  RecordedFrame f;
  f.t_s = results.t_s;
  f.hands = results.hands;
  f.objects = last_pose_;
  f.holding = holding;
  f.grasp_events = grasp_events;
  if (auto written = writer_->write(f); !written) {
    spdlog::error("recording stopped: {}", written.error());
    writer_.reset();
  }
}

}  // namespace rhot
