#include "tracking/hand/HandTracker.h"

#include <algorithm>
#include <chrono>

namespace rhot {

HandTracker::HandTracker(const HandLayout& layout, const HandPose& skeleton, HandTrackerSettings settings)
    : layout_(layout),
      settings_(settings),
      star_(StarLibrary(layout.hand_star_set())),
      hand_filter_(settings.position, settings.rotation),
      solver_(layout.side, skeleton) {
  tip_filters_.fill(OneEuroFilter<3>(settings.position));
  out_.state = solver_.state();
}

const TrackedHand& HandTracker::update(double time_s, std::span<const Eigen::Vector3d> points) {
  const TrackedStar& star = star_.update(time_s, points)[0];
  out_.hand_seen = star.seen_now();
  out_.fingertip_point.fill(-1);
  std::array<std::optional<Eigen::Vector3d>, kFingerCount> tips{};
  if (out_.hand_seen) {
    out_.world_from_hand = settings_.filter ? hand_filter_.filter(star.world_from_star, time_s) : star.world_from_star;
    const Rigid3d hand_from_world = out_.world_from_hand.inverse();
    std::vector<bool> taken(points.size(), false);
    for (const int p : star.point) {
      if (p >= 0) taken[static_cast<std::size_t>(p)] = true;
    }
    // Each marked fingertip's marker where the last solve puts it; nearest pairs first.
    struct Pair {
      double d;
      int finger, point;
    };
    std::vector<Pair> pairs;
    std::array<Eigen::Vector3d, kFingerCount> along{};
    const HandState& last = solver_.state();
    for (int f = 0; f < kFingerCount; ++f) {
      const auto fi = static_cast<std::size_t>(f);
      if (!layout_.fingertip_offset_m[fi]) continue;
      const auto joints = chain_joints(static_cast<Finger>(f));
      const Eigen::Vector3d tip = last.pose.position_m[static_cast<std::size_t>(joints[3])];
      along[fi] = (tip - last.pose.position_m[static_cast<std::size_t>(joints[2])]).normalized();
      const Eigen::Vector3d predicted = tip + *layout_.fingertip_offset_m[fi] * along[fi];
      for (std::size_t q = 0; q < points.size(); ++q) {
        if (taken[q]) continue;
        const double d = (hand_from_world * points[q] - predicted).norm();
        if (d < kFingertipGate_m) pairs.push_back({d, f, static_cast<int>(q)});
      }
    }
    std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) { return a.d < b.d; });
    for (const Pair& pr : pairs) {
      const auto fi = static_cast<std::size_t>(pr.finger);
      if (out_.fingertip_point[fi] >= 0 || taken[static_cast<std::size_t>(pr.point)]) continue;
      out_.fingertip_point[fi] = pr.point;
      taken[static_cast<std::size_t>(pr.point)] = true;
      tips[fi] = hand_from_world * points[static_cast<std::size_t>(pr.point)] - *layout_.fingertip_offset_m[fi] * along[fi];
    }
    for (std::size_t fi = 0; fi < kFingerCount; ++fi) {
      if (!settings_.filter) break;
      if (tips[fi]) {
        tips[fi] = tip_filters_[fi].filter(*tips[fi], time_s);
      } else {
        tip_filters_[fi].reset();  // a tip seen again starts afresh, not from where it was lost
      }
    }
  }
  const auto start = std::chrono::steady_clock::now();
  out_.state = solver_.update(time_s, tips);
  last_ik_us_ = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
  for (std::size_t j = 0; j < kHandJointCount; ++j) out_.joints_world[j] = out_.world_from_hand * out_.state.pose.position_m[j];
  return out_;
}

}  // namespace rhot
