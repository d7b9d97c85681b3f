// Matching on a job pool gives the serial points, bit for bit, whatever the thread count; and
// the cameras' visibility grid (CameraVisibility) changes no point.

#include <bit>
#include <filesystem>
#include <span>
#include <vector>

#include <gtest/gtest.h>

#include "base/Jobs.h"
#include "tracking/camera/RigFile.h"
#include "tracking/geometry/Matching.h"
#include "tracking/sim/SimulatedRig.h"

namespace rhot {
namespace {

// Every field of every point, doubles compared by their bits.
void expect_identical(const std::vector<MatchedPoint>& serial, const std::vector<MatchedPoint>& pooled, int threads) {
  ASSERT_EQ(serial.size(), pooled.size()) << threads << " threads";
  const auto bits = [](double v) { return std::bit_cast<std::uint64_t>(v); };
  for (std::size_t k = 0; k < serial.size(); ++k) {
    const MatchedPoint& s = serial[k];
    const MatchedPoint& p = pooled[k];
    SCOPED_TRACE(testing::Message() << threads << " threads, point " << k);
    for (int a = 0; a < 3; ++a) ASSERT_EQ(bits(s.point.position_world[a]), bits(p.point.position_world[a]));
    ASSERT_EQ(bits(s.point.reprojection_rms_px), bits(p.point.reprojection_rms_px));
    ASSERT_EQ(bits(s.point.sigma_m_per_px), bits(p.point.sigma_m_per_px));
    ASSERT_EQ(s.point.cameras, p.point.cameras);
    ASSERT_EQ(s.detection, p.detection);
    ASSERT_EQ(s.colour, p.colour);
    ASSERT_EQ(s.observations.size(), p.observations.size());
    for (std::size_t o = 0; o < s.observations.size(); ++o) {
      ASSERT_EQ(s.observations[o].camera, p.observations[o].camera);
      ASSERT_EQ(bits(s.observations[o].pixel.x()), bits(p.observations[o].pixel.x()));
      ASSERT_EQ(bits(s.observations[o].pixel.y()), bits(p.observations[o].pixel.y()));
    }
  }
}

// A crowded stage: 400 markers wandering through stage-32's volume, 0.3 px of noise, 10 % dropout.
SimulatedRig crowded_stage(const CameraRig& rig) {
  const TrackingVolume volume = rig.volume.value();
  SimulatedRigSettings settings;
  settings.dropout = 0.1;
  settings.sigma_px = 0.3;
  return SimulatedRig(rig, random_trajectories(400, volume.centre_m - 0.5 * volume.size_m, volume.centre_m + 0.5 * volume.size_m, 11),
                      settings);
}

// A crowded stage (32 cameras, 400 markers, noise and dropout): many seeds per camera pair, so the
// seeds are grown ahead on the pool and what one detection's cluster explains changes what the
// next may seed.
TEST(MatchingThreads, TheSameSeedGivesTheSamePointsWhateverTheThreadCount) {
  const auto rig = load_rig(std::filesystem::path(RHOT_ASSET_DIR) / "rigs" / "stage-32.yaml");
  ASSERT_TRUE(rig.has_value()) << (rig ? "" : rig.error());
  SimulatedRig sim = crowded_stage(*rig);
  JobPool two(2);
  JobPool three(3);
  JobPool eight(8);
  for (int f = 0; f < 2; ++f) {
    const RigFrame frame = sim.next();
    const std::vector<MatchedPoint> serial = match_and_triangulate(*rig, frame);
    ASSERT_GT(serial.size(), 300U) << "a crowded frame";
    expect_identical(serial, match_and_triangulate(*rig, frame, {}, &two), 2);
    expect_identical(serial, match_and_triangulate(*rig, frame, {}, &three), 3);
    expect_identical(serial, match_and_triangulate(*rig, frame, {}, &eight), 8);
  }
}

// Frame after frame, following the last frame's points (RigMatcher::match_frame): what one frame
// found decides what the next looks for first, and still the points are the same whatever the
// thread count.
TEST(MatchingThreads, PointsFollowedFrameAfterFrameAreTheSameWhateverTheThreadCount) {
  const auto rig = load_rig(std::filesystem::path(RHOT_ASSET_DIR) / "rigs" / "stage-32.yaml");
  ASSERT_TRUE(rig.has_value()) << (rig ? "" : rig.error());
  SimulatedRig sim = crowded_stage(*rig);
  JobPool two(2);
  JobPool three(3);
  RigMatcher serial(*rig), on_two(*rig), on_three(*rig);
  const auto copy = [](std::span<const MatchedPoint> points) { return std::vector<MatchedPoint>(points.begin(), points.end()); };
  for (int f = 0; f < 4; ++f) {
    const RigFrame frame = sim.next();
    const std::vector<MatchedPoint> one = copy(serial.match_frame(frame));
    ASSERT_GT(one.size(), 300U) << "a crowded frame";
    if (f >= 2) {
      EXPECT_GT(serial.followed_points(), one.size() * 9 / 10) << "frame " << f << ": followed, not seeded";
    }
    expect_identical(one, copy(on_two.match_frame(frame, {}, &two)), 2);
    EXPECT_EQ(on_two.followed_points(), serial.followed_points());
    expect_identical(one, copy(on_three.match_frame(frame, {}, &three)), 3);
    EXPECT_EQ(on_three.followed_points(), serial.followed_points());
  }
}

// The same frames matched with the rig's visibility grid and without one (the same rig with no
// tracking volume; seeds anywhere in both, so that only the grid differs): the same points.
TEST(MatchingThreads, TheCamerasVisibilityGridChangesNoPoint) {
  const auto rig = load_rig(std::filesystem::path(RHOT_ASSET_DIR) / "rigs" / "stage-32.yaml");
  ASSERT_TRUE(rig.has_value()) << (rig ? "" : rig.error());
  const TrackingVolume volume = rig->volume.value();
  CameraRig no_volume = *rig;
  no_volume.volume.reset();
  const RigMatcher with_grid(*rig);
  const RigMatcher without(no_volume);
  // Markers over a box wider than the volume, so that cells near its edge, which many cameras do
  // not see, are used.
  SimulatedRigSettings settings;
  settings.dropout = 0.1;
  settings.sigma_px = 0.3;
  SimulatedRig sim(*rig, random_trajectories(300, volume.centre_m - 0.8 * volume.size_m, volume.centre_m + 0.8 * volume.size_m, 5),
                   settings);
  MatchSettings anywhere;
  anywhere.seed_margin = -1.0;
  for (int f = 0; f < 2; ++f) {
    const RigFrame frame = sim.next();
    const std::vector<MatchedPoint> plain = without.match(frame, anywhere);
    ASSERT_GT(plain.size(), 200U);
    expect_identical(plain, with_grid.match(frame, anywhere), 1);
    // The grid was asked, and left cameras out where the points are: it is not all cameras.
    long left_out = 0;
    for (const MatchedPoint& m : plain) {
      EXPECT_EQ(without.visibility().cameras_at(m.point.position_world), CameraVisibility::kAllCameras);
      left_out += 32 - std::popcount(with_grid.visibility().cameras_at(m.point.position_world) & 0xffffffffU);
    }
    EXPECT_GT(left_out, static_cast<long>(plain.size())) << "cameras left out over the frame's points";
  }
}

}  // namespace
}  // namespace rhot
