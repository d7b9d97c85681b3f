// Live tracking takes whatever a frame source delivers without stopping: frames that do not fit
// the rig are dropped, non-finite detections too.

#include "engine/tracked/LiveTracking.h"

#include <limits>

#include <gtest/gtest.h>

#include "tracking/camera/RigFile.h"

namespace rhot {
namespace {

// A source of the test's own, delivering the frames it is given, then ending.
class ListSource final : public FrameSource {
 public:
  ListSource(CameraRig rig, std::vector<RigFrame> frames) : rig_(std::move(rig)), frames_(std::move(frames)) {}
  const CameraRig& rig() const override { return rig_; }
  std::optional<RigFrame> next(double) override {
    if (next_ >= frames_.size()) return std::nullopt;
    return frames_[next_++];
  }

 private:
  CameraRig rig_;
  std::vector<RigFrame> frames_;
  std::size_t next_ = 0;
};

RigFrame frame_of(std::size_t cameras, std::uint64_t index) {
  RigFrame f;
  f.index = index;
  for (std::size_t c = 0; c < cameras; ++c) f.cameras.push_back(CameraFrame{static_cast<int>(c), 0.0, {}});
  return f;
}

TEST(LiveTracking, FramesThatDoNotFitTheRigAreDroppedAndTheStreamEnds) {
  auto rig = load_rig(std::string(RHOT_ASSET_DIR) + "/rigs/seated-4.yaml");
  ASSERT_TRUE(rig.has_value());
  std::array<HandLayout, 2> layouts;
  for (std::size_t h = 0; h < 2; ++h) {
    auto layout = load_hand_layout(std::string(RHOT_ASSET_DIR) + "/hands/" + (h == 0 ? "low-cost-left.json" : "low-cost-right.json"));
    ASSERT_TRUE(layout.has_value());
    layouts[h] = *layout;
  }
  std::vector<RigFrame> frames;
  frames.push_back(frame_of(1, 0));  // one camera for a rig of four
  RigFrame swapped = frame_of(4, 1);
  std::swap(swapped.cameras[0], swapped.cameras[1]);
  swapped.cameras[0].detections.push_back({Eigen::Vector2d(100, 100), -1});
  frames.push_back(swapped);  // cameras out of rig order
  RigFrame nan = frame_of(4, 2);
  nan.cameras[2].detections.push_back({Eigen::Vector2d(std::numeric_limits<double>::quiet_NaN(), 5.0), -1});
  nan.cameras[2].detections.push_back({Eigen::Vector2d(640, 360), -1});
  nan.cameras[3].detections.push_back({Eigen::Vector2d(1.0, std::numeric_limits<double>::infinity()), -1});
  frames.push_back(nan);
  LiveTracking live(std::make_unique<ListSource>(*rig, frames), TrackedObjects{}, layouts);
  const std::vector<std::size_t> expected_detections{0, 0, 1};
  for (std::size_t f = 0; f < 4; ++f) {
    for (const TrackingStage& stage : live.stages()) stage.run(static_cast<double>(f) / 90.0);
    ASSERT_EQ(live.frame().cameras.size(), 4u) << "frame " << f;
    if (f < 3) {
      EXPECT_EQ(live.results().counts.detections, expected_detections[f]) << "frame " << f;
      EXPECT_FALSE(live.ended());
    }
  }
  EXPECT_TRUE(live.ended()) << "the list ran out";
  EXPECT_EQ(live.results().counts.detections, 0u);
  EXPECT_FALSE(live.results().hands[1].seen);
}

}  // namespace
}  // namespace rhot
