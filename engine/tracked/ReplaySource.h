#pragma once
// A recording played back (Recording.h) as tracking results, entering the runtime where live
// results do: one stage, "replay", takes the recorded hands and objects at the recording's clock,
// which runs at the playback speed (changeable between frames, from the overlay). Objects are
// matched to the scene's tracked entities by name. A recording has no cameras, points or
// gestures.

#include <cstdint>
#include <expected>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "engine/tracked/Recording.h"
#include "engine/tracked/ResultSource.h"
#include "engine/tracked/TrackedObjects.h"

namespace rhot {

class ReplaySource final : public ResultSource, public Playback {
 public:
  // Fails on a recording that cannot be read (naming the file and line) or a speed that is not a
  // positive number.
  [[nodiscard]] static std::expected<std::unique_ptr<ReplaySource>, std::string> open(const std::filesystem::path& file, double speed,
                                                                                      const TrackedObjects& objects);

  std::vector<TrackingStage> stages() override;
  TrackingResults& results() override { return results_; }
  Playback* playback() override { return this; }

  double speed() const override { return speed_; }
  void set_speed(double speed) override;

  const Recording& recording() const { return recording_; }
  // The recording's frame taken at t_s. Past the recording's end its last frame is held (the run
  // goes on), and the first frame past it logs end_notice() once, as info.
  void replay(double t_s);
  // Once the playback has passed the recording's end, the line saying so: the file, the run's frame
  // and time it ended at, the recording's frames and length. Empty before.
  const std::optional<std::string>& end_notice() const { return end_notice_; }

 private:
  ReplaySource(std::string file, Recording recording, double speed, const TrackedObjects& objects);
  std::string file_;
  Recording recording_;
  double speed_ = 1.0;
  std::vector<std::pair<int, std::string>> objects_;  // star id, entity name
  TrackingResults results_;
  double clock_s_ = 0.0;
  double last_t_s_ = 0.0;
  bool started_ = false;
  std::uint64_t frames_played_ = 0;  // replay() calls: the run's frames
  std::optional<std::string> end_notice_;
};

}  // namespace rhot
