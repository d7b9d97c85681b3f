#pragma once
// Recording a session as it is tracked: the runtime's "record" stage.

#include <expected>
#include <filesystem>
#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "engine/tracked/Recording.h"
#include "engine/tracked/TrackedObjects.h"
#include "engine/tracked/TrackingResults.h"

namespace rhot {

// Writes what tracking delivered each frame into a recording (Recording.h): the hands, and each
// named tracked object where it was last seen.
class SessionRecorder {
 public:
  [[nodiscard]] static std::expected<SessionRecorder, std::string> open(const std::filesystem::path& file, double rate_hz,
                                                                        const TrackedObjects& objects);
  // Appends one frame, with what the hands held after its physics and its grasps and releases
  // (RecordedFrame::holding, grasp_events); after a write error it logs once and records nothing
  // more.
  void record(const TrackingResults& results, const std::array<std::string, 2>& holding = {},
              const std::vector<RecordedGraspEvent>& grasp_events = {});

 private:
  SessionRecorder(RecordingWriter writer, const TrackedObjects& objects);
  std::optional<RecordingWriter> writer_;
  std::map<int, std::string> name_of_star_;
  std::map<std::string, Rigid3d> last_pose_;  // by entity name, as last tracked
};

}  // namespace rhot
