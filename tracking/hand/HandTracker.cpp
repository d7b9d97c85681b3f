#include "tracking/hand/HandTracker.h"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace rhot {

HandTracker::HandTracker(const HandLayout& layout, const HandPose& skeleton, HandTrackerSettings settings)
    : layout_(layout),
      settings_(settings),
      star_(std::make_unique<StarTracker>(StarLibrary(layout.hand_star_set()))),
      hand_filter_(settings.position, settings.rotation),
      solver_(layout.side, skeleton) {
  tip_filters_.fill(OneEuroFilter<3>(settings.position));
  if (!layout.segment_stars.empty()) segments_.emplace(StarLibrary(layout.segment_star_set()));
  every_tip_marked_ = std::ranges::all_of(layout.fingertip_offset_m, [](const auto& offset) { return offset.has_value(); });
  if (settings.fingertip_model && every_tip_marked_) {
    // Made whole now, fitted later, and no predictor kept: a long run's memory stays what it was
    // after its first frames.
    HiddenMarkerModel model;
    model.markers = {"thumb_tip", "index_tip", "middle_tip", "ring_tip", "little_tip"};
    model.memory_s = kFingertipMemory_s;
    model.ridge_m2 = kFingertipRidge_m2;
    model.source = "fitted as the hand is tracked";
    model.mean_m = Eigen::VectorXd::Zero(3 * kFingerCount);
    model.covariance_m2 = Eigen::MatrixXd::Zero(3 * kFingerCount, 3 * kFingerCount);
    model.training_frames = 0;
    tip_estimator_.emplace(std::move(model), false);
  }
  out_.state = solver_.state();
}

std::array<std::optional<Eigen::Vector3d>, kFingerCount> HandTracker::predict_hidden_tips(
    double time_s, const std::array<std::optional<Eigen::Vector3d>, kFingerCount>& tips) {
  std::array<std::optional<Eigen::Vector3d>, kFingerCount> out{};
  if (!tip_estimator_) return out;
  if (!out_.hand_seen) {
    tip_estimator_->hand_lost();
    return out;
  }
  // Only finite tips are statistics: a NaN point handed to update() must not reach the model.
  if (std::ranges::all_of(tips, [](const auto& tip) { return tip.has_value() && tip->allFinite(); })) {
    Eigen::VectorXd x(3 * kFingerCount);
    for (int f = 0; f < kFingerCount; ++f) x.segment<3>(3 * f) = *tips[static_cast<std::size_t>(f)];
    tip_statistics_.add(x);
    const int frames = tip_statistics_.frames();
    if (frames >= kFingertipModelFrames && frames - fingertip_model_frames() >= kFingertipModelRefit) {
      tip_estimator_->set_statistics(tip_statistics_.mean_m(), tip_statistics_.covariance_m2(), frames);
    }
  }
  if (fingertip_model_frames() == 0) return out;
  std::array<Eigen::Vector3d, kFingerCount> hand;
  for (std::size_t f = 0; f < kFingerCount; ++f) hand[f] = tips[f].value_or(Eigen::Vector3d::Constant(std::nan("")));
  const auto estimated = tip_estimator_->update_in_hand(time_s, hand);
  for (std::size_t f = 0; f < kFingerCount; ++f) {
    if (!tips[f] && estimated[f].how == MarkerEstimate::kPredicted) out[f] = estimated[f].position_m;
  }
  return out;
}

const TrackedHand& HandTracker::update(double time_s, std::span<const Eigen::Vector3d> points, std::span<const double> sigma_m,
                                       std::span<const int> colour) {
  const std::vector<TrackedStar>& stars = star_->update(time_s, points, sigma_m);
  std::vector<bool> taken(points.size(), false);
  HandTracker* const self = this;
  const int star = 0;
  track_hands({&self, 1}, {&star, 1}, stars, time_s, points, sigma_m, taken, colour);
  return out_;
}

void HandTracker::begin(double time_s, const TrackedStar& star) {
  out_.hand_seen = star.seen_now();
  out_.fingertip_point.fill(-1);
  if (!out_.hand_seen) return;
  out_.world_from_hand = settings_.filter ? hand_filter_.filter(star.world_from_star, time_s) : star.world_from_star;
  // Each marked fingertip's marker where the last solve puts it: beyond the tip along the last bone.
  const HandState& last = solver_.state();
  for (int f = 0; f < kFingerCount; ++f) {
    const auto fi = static_cast<std::size_t>(f);
    if (!layout_.fingertip_offset_m[fi]) continue;
    const auto joints = chain_joints(static_cast<Finger>(f));
    const Eigen::Vector3d tip = last.pose.position_m[static_cast<std::size_t>(joints[3])];
    along_[fi] = (tip - last.pose.position_m[static_cast<std::size_t>(joints[2])]).normalized();
    predicted_marker_[fi] = tip + *layout_.fingertip_offset_m[fi] * along_[fi];
    gate_m_[fi] = tip_found_s_[fi] ? std::min(kFingertipGateMax_m, kFingertipGate_m + kGateGrowth_mps * (time_s - *tip_found_s_[fi]))
                                   : kFingertipGateMax_m;
  }
}

std::vector<HandTracker::FingertipCandidate> HandTracker::fingertip_candidates(std::span<const Eigen::Vector3d> points,
                                                                               const std::vector<bool>& taken,
                                                                               std::span<const int> colour) {
  std::vector<FingertipCandidate> out;
  for (auto& r : reappearing_now_) r.clear();
  if (!out_.hand_seen) return out;
  const Rigid3d hand_from_world = out_.world_from_hand.inverse();
  for (int f = 0; f < kFingerCount; ++f) {
    const auto fi = static_cast<std::size_t>(f);
    if (!layout_.fingertip_offset_m[fi]) continue;
    for (std::size_t q = 0; q < points.size(); ++q) {
      if (taken[q]) continue;
      const Eigen::Vector3d p = hand_from_world * points[q];
      const double d = (p - predicted_marker_[fi]).norm();
      const int want = layout_.fingertip_colour[fi];
      if (want >= 0 && q < colour.size()) {
        // A coloured fingertip's marker is known by its colour: any point of it near the finger.
        if (colour[q] != want || d >= kColourGate_m) continue;
        out.push_back({d, f, static_cast<int>(q)});
        continue;
      }
      if (d >= gate_m_[fi]) continue;
      if (d >= kFingertipGate_m) {
        // Outside the tight gate: a marker found again only if it was there the frame before.
        reappearing_now_[fi].push_back(p);
        const bool persists = std::any_of(reappearing_[fi].begin(), reappearing_[fi].end(),
                                          [&](const Eigen::Vector3d& before) { return (p - before).norm() < kFingertipGate_m; });
        if (!persists) continue;
      }
      out.push_back({d, f, static_cast<int>(q)});
    }
  }
  return out;
}

const TrackedHand& HandTracker::finish(double time_s, std::span<const Eigen::Vector3d> points, std::span<const double> sigma_m,
                                       const std::array<int, kFingerCount>& fingertip_point) {
  std::array<std::optional<Eigen::Vector3d>, kFingerCount> tips{};
  reappearing_ = reappearing_now_;
  if (out_.hand_seen) {
    const Rigid3d hand_from_world = out_.world_from_hand.inverse();
    for (std::size_t fi = 0; fi < kFingerCount; ++fi) {
      const int p = fingertip_point[fi];
      if (p < 0 || !layout_.fingertip_offset_m[fi]) continue;
      out_.fingertip_point[fi] = p;
      tip_found_s_[fi] = time_s;
      tips[fi] = hand_from_world * points[static_cast<std::size_t>(p)] - *layout_.fingertip_offset_m[fi] * along_[fi];
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
  // Stars on finger bones: each seen star places its bone; a finger whose three bones are placed
  // has its angles measured, and a seen last bone gives its tip.
  std::array<std::optional<FingerAngles>, kFingerCount> measured{};
  out_.segment_stars_seen = 0;
  if (segments_) {
    const auto& stars = segments_->update(time_s, points, sigma_m);
    if (out_.hand_seen) {
      const Rigid3d hand_from_world = out_.world_from_hand.inverse();
      const HandPose& skeleton = solver_.state().pose;
      std::array<std::array<std::optional<Eigen::Vector3d>, 3>, kFingerCount> bone{};
      for (std::size_t s = 0; s < stars.size(); ++s) {
        if (!stars[s].seen_now()) continue;
        ++out_.segment_stars_seen;
        const HandJoint first = layout_.segment_stars[s].bone;
        const auto f = static_cast<std::size_t>(finger_of_bone(first));
        const auto joints = chain_joints(static_cast<Finger>(f));
        const auto k = static_cast<std::size_t>(std::find(joints.begin(), joints.end(), first) - joints.begin());
        if (k > 2) continue;  // not a bone of the chain (a finger's metacarpal)
        const Rigid3d hand_from_star = hand_from_world * stars[s].world_from_star;
        bone[f][k] = hand_from_star.rotation * Eigen::Vector3d::UnitY();
        if (k == 2) {
          const double length = solver_.chains()[f].length_m[k];
          tips[f] = hand_from_star * Eigen::Vector3d(0.0, 0.5 * length, -segment_star_lift_m(skeleton, first));
        }
      }
      for (int f = 0; f < kFingerCount; ++f) {
        const auto& b = bone[static_cast<std::size_t>(f)];
        const FingerChain& chain = solver_.chains()[static_cast<std::size_t>(f)];
        if (b[0] && b[1] && b[2]) {
          measured[static_cast<std::size_t>(f)] = angles_from_bones(chain, {*b[0], *b[1], *b[2]});
        } else if (b[0] && b[1] && !tips[static_cast<std::size_t>(f)]) {
          // The last bone's star hidden: the first two bones measured, the last hinge coupled.
          FingerAngles a = angles_from_bones(chain, {*b[0], *b[1], *b[1]});
          a.flexion_rad[2] = chain.limits.coupling * a.flexion_rad[1];
          measured[static_cast<std::size_t>(f)] = clamp_to_limits(chain.limits, a);
        }
      }
    }
  }
  const auto start = std::chrono::steady_clock::now();
  const auto predicted = predict_hidden_tips(time_s, tips);
  out_.state = solver_.update(time_s, tips, measured, predicted);
  last_ik_us_ = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
  for (std::size_t j = 0; j < kHandJointCount; ++j) out_.joints_world[j] = out_.world_from_hand * out_.state.pose.position_m[j];
  return out_;
}

void track_hands(std::span<HandTracker* const> hands, std::span<const int> hand_star, const std::vector<TrackedStar>& stars, double time_s,
                 std::span<const Eigen::Vector3d> points, std::span<const double> sigma_m, std::vector<bool>& taken,
                 std::span<const int> colour) {
  taken.assign(points.size(), false);
  for (const TrackedStar& s : stars) {
    if (s.frames_since_seen != 0) continue;
    for (const int p : s.point) {
      if (p >= 0) taken[static_cast<std::size_t>(p)] = true;
    }
  }
  struct Pick {
    double distance_m;
    std::size_t hand;
    int finger, point;
  };
  std::vector<Pick> picks;
  for (std::size_t h = 0; h < hands.size(); ++h) {
    hands[h]->begin(time_s, stars[static_cast<std::size_t>(hand_star[h])]);
    for (const auto& c : hands[h]->fingertip_candidates(points, taken, colour)) picks.push_back({c.distance_m, h, c.finger, c.point});
  }
  // Nearest first over every hand: a point goes to the fingertip it fits best, whichever hand's.
  std::sort(picks.begin(), picks.end(), [](const Pick& a, const Pick& b) { return a.distance_m < b.distance_m; });
  std::vector<std::array<int, kFingerCount>> tip(hands.size());
  for (auto& t : tip) t.fill(-1);
  for (const Pick& p : picks) {
    int& slot = tip[p.hand][static_cast<std::size_t>(p.finger)];
    if (slot >= 0 || taken[static_cast<std::size_t>(p.point)]) continue;
    slot = p.point;
    taken[static_cast<std::size_t>(p.point)] = true;
  }
  for (std::size_t h = 0; h < hands.size(); ++h) hands[h]->finish(time_s, points, sigma_m, tip[h]);
}

}  // namespace rhot
