// Three markers followed as a rigid body among unlabelled points (tracking/rigid/TriangleTracker.h):
// the glove's back of the hand, its edges as the shared take's glove has them (55.2, 44.8 and
// 32.4 mm), among ten finger markers within a hand's reach, with 0.3 mm of noise.

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "tracking/rigid/TriangleTracker.h"

namespace rhot {
namespace {

// A triangle with the glove's edges: 0-1 55.2 mm, 1-2 32.4 mm, 0-2 44.8 mm.
std::array<Eigen::Vector3d, 3> glove_back() {
  const double a = 0.0552, b = 0.0324, c = 0.0448;  // 0-1, 1-2, 0-2
  const double x = (a * a + c * c - b * b) / (2.0 * a);
  return {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(a, 0, 0), Eigen::Vector3d(x, std::sqrt(c * c - x * x), 0)};
}

struct Scene {
  std::vector<Eigen::Vector3d> points;
  std::array<int, 3> back{0, 1, 2};  // where the triangle's markers are among the points
};

// The triangle at `pose` (points 0-2, unless `missing` drops one: -1 for none), then ten finger
// markers scattered 60-150 mm from it, all with noise.
Scene scene_at(const Rigid3d& pose, std::mt19937_64& rng, int missing = -1, int fingers = 10) {
  Scene s;
  std::normal_distribution<double> noise(0.0, 0.0003);
  const auto back = glove_back();
  for (int k = 0; k < 3; ++k) {
    if (k == missing) {
      s.back[static_cast<std::size_t>(k)] = -1;
      continue;
    }
    s.back[static_cast<std::size_t>(k)] = static_cast<int>(s.points.size());
    const Eigen::Vector3d n{noise(rng), noise(rng), noise(rng)};
    s.points.push_back(pose * back[static_cast<std::size_t>(k)] + n);
  }
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int f = 0; f < fingers; ++f) {
    Eigen::Vector3d d{unit(rng), unit(rng), unit(rng)};
    d = d.normalized() * (0.06 + 0.09 * (unit(rng) + 1.0) / 2.0);
    s.points.push_back(pose * (Eigen::Vector3d(0.03, 0.01, 0.0) + d));
  }
  // Not in marker order: shuffle, and follow where the triangle's markers went.
  std::vector<int> order(s.points.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::shuffle(order.begin(), order.end(), rng);
  std::vector<Eigen::Vector3d> shuffled(s.points.size());
  std::vector<int> where(s.points.size());
  for (std::size_t i = 0; i < order.size(); ++i) {
    shuffled[i] = s.points[static_cast<std::size_t>(order[i])];
    where[static_cast<std::size_t>(order[i])] = static_cast<int>(i);
  }
  for (int& b : s.back) b = b >= 0 ? where[static_cast<std::size_t>(b)] : -1;
  s.points = std::move(shuffled);
  return s;
}

Rigid3d moving_pose(double t) {
  Rigid3d pose;
  pose.rotation = Eigen::AngleAxisd(0.8 * std::sin(2.0 * t), Eigen::Vector3d(0.3, 1.0, 0.2).normalized()) *
                  Eigen::AngleAxisd(0.5 * t, Eigen::Vector3d::UnitZ());
  pose.translation = Eigen::Vector3d(0.3 * std::sin(1.7 * t), 1.0 + 0.2 * std::cos(2.3 * t), 0.25 * std::sin(3.1 * t));
  return pose;
}

double turn_deg(const Rigid3d& a, const Rigid3d& b) {
  return Eigen::AngleAxisd(a.rotation * b.rotation.conjugate()).angle() * 180.0 / std::numbers::pi;
}

TEST(TriangleTracker, FoundAmongFingerMarkersAfterThreeFramesAndFollowedThroughFastMotion) {
  TriangleTracker tracker(glove_back());
  EXPECT_NEAR(tracker.edge_separation_m(), 0.0552 - 0.0448, 1e-9);
  std::mt19937_64 rng(3);
  int seen = 0, frames = 0;
  double worst_mm = 0.0, worst_deg = 0.0, sum_deg = 0.0;
  for (int f = 0; f < 900; ++f) {  // 10 s at 90 Hz: up to 1.3 m/s and 2 rad/s
    const double t = f / 90.0;
    const Rigid3d truth = moving_pose(t);
    const Scene s = scene_at(truth, rng);
    const TrackedTriangle& out = tracker.update(t, s.points);
    if (f < 2) {
      EXPECT_FALSE(out.seen) << "frame " << f << ": believed before confirm_frames frames";
      continue;
    }
    ++frames;
    if (!out.seen) continue;
    ++seen;
    EXPECT_EQ(out.point, s.back) << "frame " << f;
    EXPECT_EQ(out.markers_seen, 3);
    worst_mm = std::max(worst_mm, 1e3 * (out.world_from_body.translation - truth.translation).norm());
    worst_deg = std::max(worst_deg, turn_deg(out.world_from_body, truth));
    sum_deg += turn_deg(out.world_from_body, truth);
  }
  EXPECT_EQ(seen, frames) << "every frame after the first two";
  // 0.3 mm of noise on markers about 25 mm from their centre turns the frame by about 0.7 degrees
  // about each axis (measured: 0.90 degrees on average, 3.7 at worst over the 898 frames).
  EXPECT_LT(worst_mm, 1.5);
  EXPECT_LT(sum_deg / seen, 1.2);
  EXPECT_LT(worst_deg, 5.0);
}

TEST(TriangleTracker, TwoMarkersKeepItFollowedAndALongGapLosesIt) {
  TriangleTracker tracker(glove_back());
  std::mt19937_64 rng(5);
  double t = 0.0;
  for (int f = 0; f < 20; ++f, t += 1.0 / 90.0) tracker.update(t, scene_at(moving_pose(t), rng).points);
  ASSERT_TRUE(tracker.last().seen);
  // One marker gone for half a second: the two left place the body, within a few millimetres
  // (the rotation about their edge is the prediction's).
  double worst_mm = 0.0;
  for (int f = 0; f < 45; ++f, t += 1.0 / 90.0) {
    const Rigid3d truth = moving_pose(t);
    const Scene s = scene_at(truth, rng, f % 3);
    const TrackedTriangle& out = tracker.update(t, s.points);
    ASSERT_TRUE(out.seen) << "frame " << f;
    EXPECT_EQ(out.markers_seen, 2);
    EXPECT_EQ(out.point[static_cast<std::size_t>(f % 3)], -1);
    for (std::size_t k = 0; k < 3; ++k) {
      if (static_cast<int>(k) != f % 3) {
        EXPECT_EQ(out.point[k], s.back[k]);
      }
    }
    const auto back = glove_back();
    for (std::size_t k = 0; k < 3; ++k) worst_mm = std::max(worst_mm, 1e3 * (out.world_from_body * back[k] - truth * back[k]).norm());
  }
  EXPECT_LT(worst_mm, 5.0);
  // Nothing of it for longer than lost_after_s: no longer followed, and found anew only after
  // three frames of one match.
  for (int f = 0; f < 30; ++f, t += 1.0 / 90.0) tracker.update(t, std::vector<Eigen::Vector3d>{});
  EXPECT_FALSE(tracker.last().seen);
  EXPECT_FALSE(tracker.last().followed);
  for (int f = 0; f < 3; ++f, t += 1.0 / 90.0) {
    const TrackedTriangle& out = tracker.update(t, scene_at(moving_pose(t), rng).points);
    EXPECT_EQ(out.seen, f == 2) << "frame " << f << " after the gap";
  }
}

TEST(TriangleTracker, TwoMatchesOfItsEdgesAreNeverTakenForIt) {
  // Two gloves in view (or three finger markers that happen to match): found anew, the tracker
  // cannot tell which, and believes neither.
  TriangleTracker tracker(glove_back());
  std::mt19937_64 rng(9);
  Rigid3d other;
  other.translation = Eigen::Vector3d(0.5, 1.0, 0.0);
  for (int f = 0; f < 30; ++f) {
    const double t = f / 90.0;
    Scene s = scene_at(moving_pose(t), rng);
    const Scene twin = scene_at(other, rng, -1, 0);
    s.points.insert(s.points.end(), twin.points.begin(), twin.points.end());
    EXPECT_FALSE(tracker.update(t, s.points).seen) << "frame " << f;
  }
  // Followed, a second match outside the follow gate is no match at all.
  TriangleTracker followed(glove_back());
  double t = 0.0;
  for (int f = 0; f < 5; ++f, t += 1.0 / 90.0) followed.update(t, scene_at(moving_pose(t), rng).points);
  ASSERT_TRUE(followed.last().seen);
  for (int f = 0; f < 30; ++f, t += 1.0 / 90.0) {
    const Rigid3d truth = moving_pose(t);
    Scene s = scene_at(truth, rng);
    const Scene twin = scene_at(other, rng, -1, 0);
    s.points.insert(s.points.end(), twin.points.begin(), twin.points.end());
    const TrackedTriangle& out = followed.update(t, s.points);
    ASSERT_TRUE(out.seen);
    EXPECT_EQ(out.point, s.back);
    EXPECT_LT((out.world_from_body.translation - truth.translation).norm(), 0.002);
  }
}

TEST(TriangleTracker, PointsThatAreNotFiniteAreNeverUsed) {
  TriangleTracker tracker(glove_back());
  std::mt19937_64 rng(11);
  double t = 0.0;
  for (int f = 0; f < 10; ++f, t += 1.0 / 90.0) {
    Scene s = scene_at(moving_pose(t), rng);
    s.points.push_back(Eigen::Vector3d::Constant(std::nan("")));
    s.points.push_back(Eigen::Vector3d(std::numeric_limits<double>::infinity(), 0.0, 0.0));
    const TrackedTriangle& out = tracker.update(t, s.points, std::vector<double>(s.points.size(), std::nan("")));
    if (out.seen) {
      EXPECT_TRUE(out.world_from_body.translation.allFinite());
      EXPECT_EQ(out.point, s.back);
    }
  }
  EXPECT_TRUE(tracker.last().seen);
}

}  // namespace
}  // namespace rhot
