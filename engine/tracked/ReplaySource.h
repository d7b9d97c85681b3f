#pragma once
// A recording played back (Recording.h) as tracking results, entering the runtime where live
// results do: one stage, "replay", takes the recorded hands and objects at the recording's clock,
// which runs at the playback speed (changeable between frames, from the overlay). Objects are
// matched to the scene's tracked entities by name. A recording has no cameras, points or
// gestures.

#include <expected>
#include <filesystem>
#include <memory>
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
  // The recording's frame taken at t_s.
  void replay(double t_s);

 private:
  ReplaySource(Recording recording, double speed, const TrackedObjects& objects);
  Recording recording_;
  double speed_ = 1.0;
  std::vector<std::pair<int, std::string>> objects_;  // star id, entity name
  TrackingResults results_;
  double clock_s_ = 0.0;
  double last_t_s_ = 0.0;
  bool started_ = false;
};

}  // namespace rhot
