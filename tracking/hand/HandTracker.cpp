#include "tracking/hand/HandTracker.h"

#include "base/Jobs.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <tuple>

#include <cmath>

#include "tracking/hand/FingerFit.h"
#include "tracking/rigid/RigidFit.h"

namespace rhot {

HandTracker::HandTracker(const HandLayout& layout, const HandPose& skeleton, HandTrackerSettings settings)
    : layout_(layout),
      settings_(settings),
      star_(layout.has_hand_star() ? std::make_unique<StarTracker>(StarLibrary(layout.hand_star_set())) : nullptr),
      hand_filter_(settings.frame_position, settings.rotation),
      solver_(layout.side, skeleton) {
  if (layout.hand_frame_markers == 3)
    triangle_.emplace(std::array{layout.markers[0].offset_m, layout.markers[1].offset_m, layout.markers[2].offset_m});
  if (!layout.segment_stars.empty()) segments_.emplace(StarLibrary(layout.segment_star_set()));
  if (star_) star_->set_motion(0, hand_star_motion());
  for (std::size_t s = 0; segments_ && s < layout.segment_stars.size(); ++s) segments_->set_motion(static_cast<int>(s), hand_star_motion());
  const std::size_t n = layout.markers.size();
  marker_filters_.assign(n, OneEuroFilter<3>(settings.position));
  predicted_marker_.assign(n, Eigen::Vector3d::Zero());
  gate_m_.assign(n, kUnfoundMarkerGate_m);
  tight_gate_m_.assign(n, kFingertipGate_m);
  miss2_m2_.assign(n, std::pow(kFingertipGate_m / kGateSigmas, 2));
  marker_found_s_.assign(n, std::nullopt);
  reach_points_.reserve(n);
  untrusted_frames_.assign(n, 0);
  // Room for the points near each marker made once: the lists never grow while the hand is tracked.
  for (auto* lists : {&reappearing_, &reappearing_now_, &reachable_, &reachable_now_}) {
    lists->assign(n, {});
    for (auto& list : *lists) list.reserve(kNearPointsKept);
  }
  out_.marker_point.assign(n, -1);
  // Room for a frame's candidate points and reachable points, made once (each grows, doubling,
  // only past it).
  candidates_.reserve(kPointsRoom);
  reach_.reserve(kPointsRoom);
  marker_picks_.reserve(n * kNearPointsKept);
  shape_at_star_.assign(n, Eigen::Vector3d::Zero());
  for (auto* list : {&frame_from_, &frame_to_}) list->reserve(n);
  frame_weight_.reserve(n);
  frame_marker_.reserve(n);
  frame_point_.reserve(n);
  every_tip_marked_ = std::ranges::all_of(layout.fingertip_marker, [](int m) { return m >= 0; });
  const bool tips_coloured = every_tip_marked_ && std::ranges::all_of(layout.fingertip_marker, [&](int m) {
                               return layout.markers[static_cast<std::size_t>(m)].colour >= 0;
                             });
  frame_from_markers_ = settings.frame_from_markers == HandTrackerSettings::MarkerFrame::kOn ||
                        (settings.frame_from_markers == HandTrackerSettings::MarkerFrame::kWhereColoured && tips_coloured);
  // The model takes 63 markers at most (HiddenMarkerEstimator's sets of visible markers are bits).
  if (settings.fingertip_model && every_tip_marked_ && n - layout.hand_frame_markers <= 63) {
    // The fingertips first (predict_hidden_tips reads them there), then the other finger markers.
    for (const int m : layout.fingertip_marker) modelled_.push_back(m);
    for (std::size_t m = layout.hand_frame_markers; m < n; ++m) {
      if (std::ranges::find(layout.fingertip_marker, static_cast<int>(m)) == layout.fingertip_marker.end())
        modelled_.push_back(static_cast<int>(m));
    }
    // Made whole now, fitted later, and no predictor kept: a long run's memory stays what it was
    // after its first frames.
    HiddenMarkerModel model;
    for (const int m : modelled_) model.markers.push_back(layout.markers[static_cast<std::size_t>(m)].name);
    model.memory_s = kFingertipMemory_s;
    model.ridge_m2 = kFingertipRidge_m2;
    model.source = "fitted as the hand is tracked";
    const auto dims = static_cast<Eigen::Index>(3 * modelled_.size());
    model.mean_m = Eigen::VectorXd::Zero(dims);
    model.covariance_m2 = Eigen::MatrixXd::Zero(dims, dims);
    model.training_frames = 0;
    tip_statistics_.emplace(static_cast<int>(modelled_.size()));
    tip_estimator_.emplace(std::move(model), false);
  }
  out_.state = solver_.state();
}

std::array<std::optional<Eigen::Vector3d>, kFingerCount> HandTracker::predict_hidden_tips(
    double time_s, const std::vector<std::optional<Eigen::Vector3d>>& seen) {
  std::array<std::optional<Eigen::Vector3d>, kFingerCount> out{};
  if (!tip_estimator_) return out;
  if (!out_.hand_seen) {
    tip_estimator_->hand_lost();
    return out;
  }
  // Only finite places are statistics: a NaN point handed to update() must not reach the model. Nor
  // a frame fitted to the finger markers themselves (frame_from_markers): in it they lie where the
  // fit put them.
  if (out_.frame_source == HandFrameSource::kStar &&
      std::ranges::all_of(seen, [](const auto& at) { return at.has_value() && at->allFinite(); })) {
    Eigen::VectorXd& x = tip_sample_;
    x.resize(static_cast<Eigen::Index>(3 * seen.size()));
    for (std::size_t k = 0; k < seen.size(); ++k) x.segment<3>(static_cast<Eigen::Index>(3 * k)) = *seen[k];
    tip_statistics_->add(x);
    const int frames = tip_statistics_->frames();
    if (frames >= kFingertipModelFrames && frames - fingertip_model_frames() >= kFingertipModelRefit) {
      tip_estimator_->set_statistics(tip_statistics_->mean_m(), tip_statistics_->covariance_m2(), frames);
    }
  }
  if (fingertip_model_frames() == 0) return out;
  std::vector<Eigen::Vector3d>& hand = tip_hand_;
  hand.resize(seen.size());
  for (std::size_t k = 0; k < seen.size(); ++k) hand[k] = seen[k].value_or(Eigen::Vector3d::Constant(std::nan("")));
  const auto estimated = tip_estimator_->update_in_hand(time_s, hand);
  for (std::size_t f = 0; f < kFingerCount; ++f) {
    if (!seen[f] && estimated[f].how == MarkerEstimate::kPredicted) out[f] = estimated[f].position_m;
  }
  return out;
}

const TrackedHand& HandTracker::update(double time_s, std::span<const Eigen::Vector3d> points, std::span<const double> sigma_m,
                                       std::span<const int> colour) {
  std::vector<TrackedStar> triangle_star;
  if (triangle_) {
    // Three markers on the back of the hand: followed as a triangle (TriangleTracker.h), handed on
    // as a star whose fourth marker is never seen.
    const TrackedTriangle& t = triangle_->update(time_s, points, sigma_m);
    TrackedStar& star = triangle_star.emplace_back();
    star.world_from_star = t.world_from_body;
    star.measured = t.world_from_body;
    star.velocity_m_s = t.velocity_m_s;
    star.markers_seen = t.markers_seen;
    for (std::size_t k = 0; k < 3; ++k) star.point[k] = t.point[k];
    star.confirmed = t.followed;
    star.frames_since_seen = t.seen ? 0 : 1;
  }
  const std::vector<TrackedStar>& stars = star_ ? star_->update(time_s, points, sigma_m) : triangle_star;
  std::vector<bool> taken(points.size(), false);
  HandTracker* const self = this;
  const int star = 0;
  track_hands({&self, 1}, {&star, 1}, stars, time_s, points, sigma_m, taken, colour);
  return out_;
}

const TrackedHand& HandTracker::update_labelled(double time_s, std::span<const Eigen::Vector3d> markers_world) {
  const std::size_t n = std::min(markers_world.size(), layout_.markers.size());
  const auto world_from_hand = labelled_hand_frame(layout_, markers_world.first(n));
  labelled_ = true;
  begin(time_s, world_from_hand.has_value(), world_from_hand.value_or(Rigid3d{}));
  std::vector<int> marker_point(layout_.markers.size(), -1);
  for (std::size_t m = 0; m < n; ++m) {
    if (markers_world[m].allFinite()) marker_point[m] = static_cast<int>(m);
  }
  finish(time_s, markers_world.first(n), {}, marker_point);
  if (out_.hand_seen) {
    for (std::size_t m = 0; m < layout_.hand_frame_markers && m < n; ++m) out_.marker_point[m] = marker_point[m];
  }
  labelled_ = false;
  return out_;
}

void HandTracker::begin(double time_s, const TrackedStar& star) {
  // The fit of this frame: the hand solver weighs it itself (a filtered pose would lag the hand).
  begin(time_s, star.measured_now(), star.measured);
  if (!out_.hand_seen) return;
  star_seen_s_ = time_s;
  shape_stale_ = true;
  for (std::size_t m = 0; m < layout_.hand_frame_markers && m < star.point.size(); ++m) out_.marker_point[m] = star.point[m];
}

void HandTracker::begin(double time_s, bool seen, const Rigid3d& world_from_hand) {
  out_.hand_seen = seen;
  out_.frame_source = seen ? HandFrameSource::kStar : HandFrameSource::kNone;
  out_.fingertip_point.fill(-1);
  std::ranges::fill(out_.marker_point, -1);
  if (!out_.hand_seen) return;
  if (!hand_first_seen_s_) hand_first_seen_s_ = time_s;
  const double unfound_gate_m = time_s - *hand_first_seen_s_ <= kUnfoundSearch_s ? kUnfoundMarkerGate_m : kFingertipGateMax_m;
  if (settings_.filter || (settings_.filter_frame && !labelled_)) {
    // A hand seen again after a while starts its filter afresh, not from where it was lost.
    const std::optional<double> last_s = hand_filter_.last_sample_s();
    if (last_s && !(time_s - *last_s <= kFrameFilterGap_s)) hand_filter_.reset();
    out_.world_from_hand = hand_filter_.filter(world_from_hand, time_s);
  } else {
    out_.world_from_hand = world_from_hand;
  }
  // Each finger marker where the last solve puts it.
  const HandPose& last = solver_.state().pose;
  const auto frames = marker_frames(last, solver_.chains());
  for (std::size_t m = layout_.hand_frame_markers; m < layout_.markers.size(); ++m) {
    predicted_marker_[m] = layout_marker_in_hand(layout_.markers[m], last, frames);
    tight_gate_m_[m] = std::clamp(kGateSigmas * std::sqrt(miss2_m2_[m]), kFingertipGateMin_m, kFingertipGate_m);
    gate_m_[m] = marker_found_s_[m] ? std::min(kFingertipGateMax_m, tight_gate_m_[m] + kGateGrowth_mps * (time_s - *marker_found_s_[m]))
                                    : unfound_gate_m;
  }
}

bool HandTracker::frame_from_markers(double time_s, std::span<const Eigen::Vector3d> points, const std::vector<bool>& taken,
                                     std::span<const int> colour) {
  if (!frame_from_markers_ || out_.hand_seen || labelled_ || !star_seen_s_) return false;
  // Each marker where the fingers were in the star's last frame (hand frame; the solver's state is
  // that frame's solve until a frame without the star is finished): the frame is fitted to that one
  // shape for as long as the star is hidden. Fitted to the fingers' latest solve instead, which
  // followed the last fitted frame, frame and fingers drifted together (a turning hand's frame 40
  // degrees off within a second, its fingertips still on their markers).
  if (shape_stale_) {
    const HandPose& pose = solver_.state().pose;
    const auto frames = marker_frames(pose, solver_.chains());
    for (std::size_t m = 0; m < layout_.markers.size(); ++m) shape_at_star_[m] = layout_marker_in_hand(layout_.markers[m], pose, frames);
    shape_stale_ = false;
  }
  // A small allowance: the hold is whole frames of time, and 179/90 - 89/90 is not exactly 1.
  if (!(time_s > *star_seen_s_) || time_s - *star_seen_s_ > kMarkerFrameHold_s + 1e-9) return false;
  // Where the last frame (the star's, or this rule's) puts each marker.
  const Rigid3d last = out_.world_from_hand;
  std::vector<MarkerPick>& picks = marker_picks_;
  picks.clear();
  for (std::size_t m = 0; m < layout_.markers.size(); ++m) {
    const Eigen::Vector3d at = last * shape_at_star_[m];
    const int want = layout_.markers[m].colour;
    // At most kNearPointsKept points a marker (the room made for them once: nothing allocated).
    std::size_t near = 0;
    for (std::size_t q = 0; q < points.size() && near < kNearPointsKept; ++q) {
      if (q < taken.size() && taken[q]) continue;
      if (want >= 0 && q < colour.size() && colour[q] != want) continue;
      const double d = (points[q] - at).norm();
      if (!(d < kMarkerFrameGate_m)) continue;  // NaN never passes
      picks.push_back({d, static_cast<int>(m), static_cast<int>(q)});
      ++near;
    }
  }
  std::sort(picks.begin(), picks.end(), [](const MarkerPick& a, const MarkerPick& b) {
    return std::tie(a.distance_m, a.marker, a.point) < std::tie(b.distance_m, b.marker, b.point);
  });
  frame_from_.clear();
  frame_to_.clear();
  frame_weight_.clear();
  frame_marker_.clear();
  frame_point_.clear();
  for (const MarkerPick& p : picks) {
    if (std::ranges::find(frame_marker_, p.marker) != frame_marker_.end()) continue;
    if (std::ranges::find(frame_point_, p.point) != frame_point_.end()) continue;
    const auto m = static_cast<std::size_t>(p.marker);
    frame_marker_.push_back(p.marker);
    frame_point_.push_back(p.point);
    frame_from_.push_back(shape_at_star_[m]);
    frame_to_.push_back(points[static_cast<std::size_t>(p.point)]);
    frame_weight_.push_back(m < layout_.hand_frame_markers ? 1.0 : kMarkerFrameFingerWeight);
  }
  // Fitted, while any marker misses by more than kMarkerFrameMiss_m the one that weighs most in the
  // fit's misses (its weighted square miss: a wrong star marker pulls the fit toward itself, so
  // that the right finger markers miss more) dropped and the rest fitted again.
  while (static_cast<int>(frame_marker_.size()) >= kMarkerFrameMarkers) {
    const auto fit = fit_rigid(frame_from_, frame_to_, frame_weight_);
    if (!fit) return false;  // in a line: no frame
    std::size_t worst = 0;
    double worst_m = 0.0, worst_weighted = -1.0;
    for (std::size_t k = 0; k < frame_from_.size(); ++k) {
      const double miss_m = (fit->to_from_from * frame_from_[k] - frame_to_[k]).norm();
      worst_m = std::max(worst_m, miss_m);
      if (frame_weight_[k] * miss_m * miss_m > worst_weighted) {
        worst_weighted = frame_weight_[k] * miss_m * miss_m;
        worst = k;
      }
    }
    if (worst_m <= kMarkerFrameMiss_m) {
      // The frame near the last: within the gate, and turned by at most kMarkerFrameTurn_rad.
      if ((fit->to_from_from.translation - last.translation).norm() > kMarkerFrameGate_m ||
          fit->to_from_from.rotation.angularDistance(last.rotation) > kMarkerFrameTurn_rad)
        return false;
      frame_before_markers_ = last;
      filter_before_markers_ = hand_filter_;  // with its clock
      begin(time_s, true, fit->to_from_from);
      out_.frame_source = HandFrameSource::kMarkers;
      // The back of the hand's markers used are this hand's (track_hands takes them); its finger
      // markers' points are shared out as on any frame.
      for (std::size_t k = 0; k < frame_marker_.size(); ++k) {
        if (static_cast<std::size_t>(frame_marker_[k]) < layout_.hand_frame_markers)
          out_.marker_point[static_cast<std::size_t>(frame_marker_[k])] = frame_point_[k];
      }
      return true;
    }
    const auto at = static_cast<std::ptrdiff_t>(worst);
    for (auto* list : {&frame_from_, &frame_to_}) list->erase(list->begin() + at);
    frame_weight_.erase(frame_weight_.begin() + at);
    frame_marker_.erase(frame_marker_.begin() + at);
    frame_point_.erase(frame_point_.begin() + at);
  }
  return false;
}

void HandTracker::confirm_frame_from_markers(double time_s) {
  if (out_.frame_source != HandFrameSource::kMarkers) return;
  // The markers the frame was fitted to that are still this hand's: its star's that no hand took
  // before it, and its fingers' whose points the share-out gave it.
  int kept = 0;
  if (tip_points_.size() != layout_.markers.size()) tip_points_.assign(layout_.markers.size(), -1);
  for (std::size_t k = 0; k < frame_marker_.size(); ++k) {
    const auto m = static_cast<std::size_t>(frame_marker_[k]);
    const int p = m < layout_.hand_frame_markers ? out_.marker_point[m] : tip_points_[m];
    kept += p == frame_point_[k] ? 1 : 0;
  }
  if (kept >= kMarkerFrameMarkers) return;
  // Refused: unseen, the last known frame (and its filter) as they were before the fit.
  begin(time_s, false, {});
  out_.world_from_hand = frame_before_markers_;
  hand_filter_ = filter_before_markers_;
  std::ranges::fill(tip_points_, -1);
}

const std::vector<HandTracker::FingertipCandidate>& HandTracker::fingertip_candidates(std::span<const Eigen::Vector3d> points,
                                                                                      const std::vector<bool>& taken,
                                                                                      std::span<const int> colour) {
  std::vector<FingertipCandidate>& out = candidates_;
  out.clear();
  for (auto& r : reappearing_now_) r.clear();
  for (auto& r : reachable_now_) r.clear();
  if (!out_.hand_seen) return out;
  const Rigid3d hand_from_world = out_.world_from_hand.inverse();
  for (std::size_t m = layout_.hand_frame_markers; m < layout_.markers.size(); ++m) {
    const int want = layout_.markers[m].colour;
    for (std::size_t q = 0; q < points.size(); ++q) {
      if (taken[q] || !points[q].allFinite()) continue;  // a NaN distance would pass every gate
      const Eigen::Vector3d p = hand_from_world * points[q];
      const double d = (p - predicted_marker_[m]).norm();
      if (want >= 0 && q < colour.size()) {
        // A coloured marker is known by its colour: any point of it near the finger.
        if (colour[q] != want || d >= kColourGate_m) continue;
        out.push_back({d, static_cast<int>(m), static_cast<int>(q), false, true});
        continue;
      }
      if (d >= gate_m_[m]) continue;
      bool persists = true;
      if (d >= tight_gate_m_[m]) {
        // Outside the tight gate: a marker found again only if it was there the frame before (listed
        // without, for track_hands's contest between hands).
        if (reappearing_now_[m].size() < kNearPointsKept) reappearing_now_[m].push_back(p);
        persists = std::any_of(reappearing_[m].begin(), reappearing_[m].end(),
                               [&](const Eigen::Vector3d& before) { return (p - before).norm() < tight_gate_m_[m]; });
      }
      out.push_back({d, static_cast<int>(m), static_cast<int>(q), !followed(m) || d >= tight_gate_m_[m], persists});
    }
  }
  return out;
}

void HandTracker::untangle_neighbours(std::span<const Eigen::Vector3d> points, std::span<int> marker_point) const {
  if (!out_.hand_seen || marker_point.size() != layout_.markers.size()) return;
  const Rigid3d hand_from_world = out_.world_from_hand.inverse();
  const auto in_hand = [&](int p) { return hand_from_world * points[static_cast<std::size_t>(p)]; };
  const auto usable = [&](int p) {
    return p >= 0 && static_cast<std::size_t>(p) < points.size() && points[static_cast<std::size_t>(p)].allFinite();
  };
  // A finger that carries other markers is judged with them found; one marked at its tip alone
  // (the low-cost layout) by its tip's point alone, which it must reach within its joint limits.
  const auto others_found = [&](std::size_t f) {
    bool carries = false;
    for (std::size_t m = layout_.hand_frame_markers; m < layout_.markers.size(); ++m) {
      if (layout_.finger_of_marker(m) != static_cast<int>(f) || static_cast<int>(m) == layout_.fingertip_marker[f]) continue;
      carries = true;
      if (usable(marker_point[m])) return true;
    }
    return !carries;
  };
  // Finger f's fit miss with its tip's marker on point p and its other markers on theirs.
  const auto miss = [&](std::size_t f, int p) {
    std::array<FingerPoint, kMaxFingerPoints> on_finger;
    std::size_t count = 0;
    const auto tip = static_cast<std::size_t>(layout_.fingertip_marker[f]);
    on_finger[count++] = finger_point(layout_.markers[tip], in_hand(p), 1.0);
    for (std::size_t m = layout_.hand_frame_markers; m < layout_.markers.size() && count < on_finger.size(); ++m) {
      if (m != tip && layout_.finger_of_marker(m) == static_cast<int>(f) && usable(marker_point[m]))
        on_finger[count++] = finger_point(layout_.markers[m], in_hand(marker_point[m]), kOtherMarkerWeight);
    }
    return fit_finger(solver_.chains()[f], std::span<const FingerPoint>(on_finger.data(), count), solver_.state().angles[f],
                      finger_fit_settings(static_cast<Finger>(f)))
        .rms_m;
  };
  for (std::size_t f = 0; f + 1 < kFingerCount; ++f) {
    const int ta = layout_.fingertip_marker[f], tb = layout_.fingertip_marker[f + 1];
    if (ta < 0 || tb < 0) continue;
    if (layout_.markers[static_cast<std::size_t>(ta)].colour >= 0 || layout_.markers[static_cast<std::size_t>(tb)].colour >= 0) continue;
    int& pa = marker_point[static_cast<std::size_t>(ta)];
    int& pb = marker_point[static_cast<std::size_t>(tb)];
    const bool a = usable(pa), b = usable(pb);
    if (!others_found(f) || !others_found(f + 1)) continue;
    if (!a || !b || (in_hand(pa) - in_hand(pb)).norm() > kUntangleReach_m) continue;
    const double kept = miss(f, pa) + miss(f + 1, pb);
    if (kept < kUntangleMiss_m) continue;
    if (miss(f, pb) + miss(f + 1, pa) + kUntangleMargin_m < kept) std::swap(pa, pb);
  }
}

std::optional<double> HandTracker::reach_side(std::size_t m, const Eigen::Vector3d& p) const {
  const auto f = static_cast<std::size_t>(layout_.finger_of_marker(m));
  const FingerChain& chain = solver_.chains()[f];
  const LayoutMarker& marker = layout_.markers[m];
  // Farther from the finger's root than the whole finger (at its longest) and the marker's offset,
  // or farther to the side of its plane than its widest sideways turn takes it: out of reach,
  // without a fit.
  const Eigen::Vector3d v = p - chain.root_m;
  const double distance_m = v.norm();
  const double side_m = std::abs(v.dot(chain.rest_direction.cross(chain.up)));
  const double slack_m = marker.offset_m.norm() + kReachMiss_m;
  const double tolerance = settings_.finger_length_tolerance;
  const double longest = 1.0 + (std::isfinite(tolerance) ? std::clamp(tolerance, 0.0, kFingerLengthToleranceMax) : 0.0);
  if (distance_m > longest * (chain.length_m[0] + chain.length_m[1] + chain.length_m[2]) + slack_m) return std::nullopt;
  if (side_m > std::sin(chain.limits.abduction_max_rad) * distance_m + slack_m) return std::nullopt;
  // Whatever the angles, the marker lies within its bones' lengths (those before its joint) and its
  // offset of the root.
  double marker_reach_m = marker.offset_m.norm();
  const int joint = finger_point(marker, p, 1.0).joint;
  for (int k = 0; k < std::min(joint, 3); ++k) marker_reach_m += chain.length_m[static_cast<std::size_t>(k)];
  // The finger and its marker scaled by `scale` about its root reach p where they reach p's place
  // scaled back; the miss scales with them. A place beyond the scaled marker's reach by more than
  // the miss is not reached by any fit, so it gets none (the search's cost is in these fits).
  const auto reaches = [&](double scale) {
    if (distance_m > scale * marker_reach_m + kReachMiss_m) return false;
    const Eigen::Vector3d q = chain.root_m + v / scale;
    const FingerPoint point = finger_point(marker, q, 1.0);
    const FingerFit fit =
        fit_finger(chain, std::span<const FingerPoint>(&point, 1), solver_.state().angles[f], finger_fit_settings(static_cast<Finger>(f)));
    return scale * (finger_point_at(chain, fit.angles, point) - q).norm() <= kReachMiss_m;
  };
  if (reaches(1.0) || (longest > 1.0 && (reaches(longest) || reaches(1.0 / longest)))) return side_m;
  return std::nullopt;
}

const std::vector<HandTracker::Reach>& HandTracker::reach_candidates(std::span<const Eigen::Vector3d> points,
                                                                     const std::vector<bool>& taken) {
  reach_.clear();
  if (!out_.hand_seen) return reach_;
  const Rigid3d hand_from_world = out_.world_from_hand.inverse();
  std::vector<Reach>& reach = reach_;
  for (std::size_t m = layout_.hand_frame_markers; m < layout_.markers.size(); ++m) {
    // A marker followed frame to frame keeps its point within its tight gate; one given its point by
    // reach on the last frame may take it by reach again (not contesting the other hand's: below).
    if (layout_.markers[m].colour >= 0 || layout_.finger_of_marker(m) < 0 || (followed(m) && reachable_[m].empty())) continue;
    for (std::size_t q = 0; q < points.size(); ++q) {
      if (taken[q] || !points[q].allFinite()) continue;
      const Eigen::Vector3d p = hand_from_world * points[q];
      const auto side = reach_side(m, p);
      if (!side) continue;
      const bool persists = std::any_of(reachable_[m].begin(), reachable_[m].end(),
                                        [&](const Eigen::Vector3d& before) { return (p - before).norm() < kReachPersist_m; });
      reach.push_back({*side, (p - predicted_marker_[m]).norm(), static_cast<int>(m), static_cast<int>(q), persists, p});
    }
  }
  return reach;
}

void HandTracker::take_by_reach(std::span<const Eigen::Vector3d> points, std::vector<bool>& taken, const std::vector<bool>& contested,
                                std::span<int> marker_point) {
  if (!out_.hand_seen || marker_point.size() != layout_.markers.size()) return;
  // A finger with another marker found is held by it already (a glove's middle marker): its
  // estimate has not drifted, and its free neighbours' markers are within its reach.
  std::vector<bool>& held = held_;
  held.assign(layout_.markers.size(), false);
  for (std::size_t m = layout_.hand_frame_markers; m < layout_.markers.size(); ++m) {
    const int f = layout_.finger_of_marker(m);
    for (std::size_t o = layout_.hand_frame_markers; o < layout_.markers.size(); ++o) {
      if (o != m && f >= 0 && layout_.finger_of_marker(o) == f && marker_point[o] >= 0) held[m] = true;
    }
  }
  std::vector<Reach>& reach = reach_;
  // What the next frame's persistence asks of a point: that it was reachable and free this frame, by
  // a marker without a point (contested or not; a marker followed until this frame looks now).
  for (const Reach& r : reach) {
    const auto m = static_cast<std::size_t>(r.marker);
    if (marker_point[m] < 0 && !held[m] && !taken[static_cast<std::size_t>(r.point)] && reachable_now_[m].size() < kNearPointsKept)
      reachable_now_[m].push_back(r.in_hand);
  }
  const Rigid3d hand_from_world = out_.world_from_hand.inverse();
  for (std::size_t m = layout_.hand_frame_markers; m < layout_.markers.size(); ++m) {
    if (!followed(m) || !reachable_[m].empty() || marker_point[m] >= 0 || held[m] || layout_.markers[m].colour >= 0 ||
        layout_.finger_of_marker(m) < 0)
      continue;
    for (std::size_t q = 0; q < points.size() && reachable_now_[m].size() < kNearPointsKept; ++q) {
      if (taken[q] || !points[q].allFinite()) continue;
      const Eigen::Vector3d p = hand_from_world * points[q];
      if (reach_side(m, p)) reachable_now_[m].push_back(p);
    }
  }
  // A point two fingers reach goes to the one in whose plane it lies nearest (curled fingers lie in
  // their own planes, a neighbour's some 18 mm away); the estimates, which drifted while the markers
  // were hidden, only break ties.
  std::sort(reach.begin(), reach.end(),
            [](const Reach& a, const Reach& b) { return std::tie(a.side_m, a.predicted_m) < std::tie(b.side_m, b.predicted_m); });
  for (const Reach& r : reach) {
    int& slot = marker_point[static_cast<std::size_t>(r.marker)];
    const auto q = static_cast<std::size_t>(r.point);
    if (!r.persists || slot >= 0 || held[static_cast<std::size_t>(r.marker)] || taken[q] || (q < contested.size() && contested[q]))
      continue;
    slot = r.point;
    taken[static_cast<std::size_t>(r.point)] = true;
    reach_points_.push_back(r.point);  // at most one a marker: room made for them all
  }
}

std::vector<Eigen::Vector3d> HandTracker::markers_in_hand() const {
  const HandPose& pose = solver_.state().pose;
  const auto frames = marker_frames(pose, solver_.chains());
  std::vector<Eigen::Vector3d> out;
  for (const LayoutMarker& m : layout_.markers) out.push_back(layout_marker_in_hand(m, pose, frames));
  return out;
}

const TrackedHand& HandTracker::finish(double time_s, std::span<const Eigen::Vector3d> points, std::span<const double> sigma_m,
                                       std::span<const int> marker_point) {
  // Each finger marker found this frame (hand frame; NaN where not).
  std::vector<Eigen::Vector3d>& found = found_;
  found.assign(layout_.markers.size(), Eigen::Vector3d::Constant(std::nan("")));
  // This frame's lists become the last frame's; the emptied ones keep their room for the next.
  reappearing_.swap(reappearing_now_);
  reachable_.swap(reachable_now_);
  for (auto& r : reappearing_now_) r.clear();
  for (auto& r : reachable_now_) r.clear();
  if (out_.hand_seen) {
    const Rigid3d hand_from_world = out_.world_from_hand.inverse();
    for (std::size_t m = layout_.hand_frame_markers; m < layout_.markers.size() && m < marker_point.size(); ++m) {
      const int p = marker_point[m];
      if (p < 0 || static_cast<std::size_t>(p) >= points.size() || !points[static_cast<std::size_t>(p)].allFinite()) continue;
      out_.marker_point[m] = p;
      found[m] = hand_from_world * points[static_cast<std::size_t>(p)];
      // Followed (found the frame before too): how far its predicted place missed it.
      if (last_time_s_ && marker_found_s_[m] == last_time_s_ && time_s > *last_time_s_) {
        const double weight = 1.0 - std::exp(-(time_s - *last_time_s_) / kMissMemory_s);
        miss2_m2_[m] += weight * ((found[m] - predicted_marker_[m]).squaredNorm() - miss2_m2_[m]);
      }
      marker_found_s_[m] = time_s;
      const int f = layout_.finger_of_marker(m);
      if (layout_.fingertip_marker[static_cast<std::size_t>(f)] == static_cast<int>(m))
        out_.fingertip_point[static_cast<std::size_t>(f)] = p;
    }
    for (std::size_t m = layout_.hand_frame_markers; m < layout_.markers.size() && settings_.filter; ++m) {
      if (found[m].allFinite()) {
        found[m] = marker_filters_[m].filter(found[m], time_s);
      } else {
        marker_filters_[m].reset();  // a marker seen again starts afresh, not from where it was lost
      }
    }
  }
  std::array<FingerEvidence, kFingerCount> evidence{};
  const auto segment_tips = measure_segments(time_s, points, sigma_m, found, evidence);
  const auto start = std::chrono::steady_clock::now();
  std::vector<std::optional<Eigen::Vector3d>>& seen = seen_;
  seen.assign(modelled_.size(), std::nullopt);
  for (std::size_t k = 0; k < modelled_.size(); ++k) {
    const Eigen::Vector3d& at = found[static_cast<std::size_t>(modelled_[k])];
    if (at.allFinite()) seen[k] = at;
  }
  const auto predicted = predict_hidden_tips(time_s, seen);
  for (std::size_t fi = 0; fi < kFingerCount; ++fi) {
    FingerEvidence& e = evidence[fi];
    if (e.kind == FingerEvidence::Kind::kMeasured) continue;
    const int tip = layout_.fingertip_marker[fi];
    const bool tip_seen = tip >= 0 && found[static_cast<std::size_t>(tip)].allFinite();
    if (tip_seen || (!segment_tips[fi] && predicted[fi])) {
      // The finger's markers fitted together: its tip's (seen, or predicted where hidden), weighing
      // most, and its others seen.
      // On the stack (the fit takes kMaxFingerPoints at most): nothing allocated per finger and frame.
      std::array<FingerPoint, kMaxFingerPoints> on_finger;
      std::size_t count = 0;
      const auto add = [&](const FingerPoint& point) {
        if (count < on_finger.size()) on_finger[count++] = point;
      };
      const Eigen::Vector3d tip_at = tip_seen ? found[static_cast<std::size_t>(tip)] : *predicted[fi];
      add(finger_point(layout_.markers[static_cast<std::size_t>(tip)], tip_at, 1.0));
      // A last bone's segment star seen too gives the tip joint itself.
      if (segment_tips[fi]) add(FingerPoint{3, Eigen::Vector3d::Zero(), *segment_tips[fi], 1.0});
      for (std::size_t m = layout_.hand_frame_markers; m < layout_.markers.size(); ++m) {
        if (static_cast<int>(m) != tip && layout_.finger_of_marker(m) == static_cast<int>(fi) && found[m].allFinite())
          add(finger_point(layout_.markers[m], found[m], kOtherMarkerWeight));
      }
      const std::span<const FingerPoint> finger(on_finger.data(), count);
      e.kind = tip_seen ? FingerEvidence::Kind::kFitted : FingerEvidence::Kind::kPredictedFit;
      e.angles = fit_finger(solver_.chains()[fi], finger, solver_.state().angles[fi], finger_fit_settings(static_cast<Finger>(fi))).angles;
    } else if (segment_tips[fi]) {
      e.kind = FingerEvidence::Kind::kTip;
      e.tip_m = *segment_tips[fi];
    }
  }
  out_.state = solver_.update(time_s, evidence);
  if (out_.frame_source == HandFrameSource::kMarkers) {
    // The joints the hand frame fixes (wrist, palm, the fingers' metacarpal joints and knuckles)
    // are fitted to seen markers, not measured by the star: kMarkerFrameConfidence
    // (docs/tracking.md, "A hand whose star is hidden"). Seen fingertips keep theirs.
    const auto fitted = [&](HandJoint j) {
      double& c = out_.state.confidence[static_cast<std::size_t>(j)];
      c = std::min(c, kMarkerFrameConfidence);
    };
    fitted(HandJoint::kWrist);
    fitted(HandJoint::kPalm);
    for (int f = 1; f < kFingerCount; ++f) {
      const HandJoint knuckle = chain_joints(static_cast<Finger>(f))[0];
      fitted(knuckle);
      fitted(static_cast<HandJoint>(static_cast<int>(knuckle) - 1));  // its metacarpal joint
    }
  }
  // A tip marker whose point reach found: not trusted until found in kReacquiredFrames frames.
  for (std::size_t fi = 0; fi < kFingerCount; ++fi) {
    const int tip = layout_.fingertip_marker[fi];
    if (tip < 0) continue;
    const auto m = static_cast<std::size_t>(tip);
    const int p = m < marker_point.size() ? marker_point[m] : -1;
    if (p >= 0 && std::find(reach_points_.begin(), reach_points_.end(), p) != reach_points_.end()) untrusted_frames_[m] = kReacquiredFrames;
    if (!found[m].allFinite() || untrusted_frames_[m] <= 0) continue;
    --untrusted_frames_[m];
    if (evidence[fi].kind == FingerEvidence::Kind::kMeasured) continue;  // its segment stars measure it
    const auto joints = chain_joints(static_cast<Finger>(fi));
    for (std::size_t k = 1; k < joints.size(); ++k) {
      double& c = out_.state.confidence[static_cast<std::size_t>(joints[k])];
      c = std::min(c, kReacquiredConfidence);
    }
  }
  reach_points_.clear();
  last_time_s_ = time_s;
  last_ik_us_ = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
  for (std::size_t j = 0; j < kHandJointCount; ++j) out_.joints_world[j] = out_.world_from_hand * out_.state.pose.position_m[j];
  return out_;
}

std::array<std::optional<Eigen::Vector3d>, kFingerCount> HandTracker::measure_segments(double time_s,
                                                                                       std::span<const Eigen::Vector3d> points,
                                                                                       std::span<const double> sigma_m,
                                                                                       std::span<const Eigen::Vector3d> found,
                                                                                       std::array<FingerEvidence, kFingerCount>& evidence) {
  // Stars on finger bones: each seen star places its bone; a finger whose three bones are placed
  // has its angles measured, and a seen last bone gives its tip.
  std::array<std::optional<Eigen::Vector3d>, kFingerCount> tips{};
  out_.segment_stars_seen = 0;
  if (!segments_ || labelled_) return tips;
  const auto& stars = segments_->update(time_s, points, sigma_m);
  if (!out_.hand_seen) return tips;
  const Rigid3d hand_from_world = out_.world_from_hand.inverse();
  const HandPose& skeleton = solver_.state().pose;
  std::array<std::array<std::optional<Eigen::Vector3d>, 3>, kFingerCount> bone{};
  for (std::size_t s = 0; s < stars.size(); ++s) {
    if (!stars[s].measured_now()) continue;
    ++out_.segment_stars_seen;
    const HandJoint first = layout_.segment_stars[s].bone;
    const auto f = static_cast<std::size_t>(finger_of_bone(first));
    const auto joints = chain_joints(static_cast<Finger>(f));
    const auto k = static_cast<std::size_t>(std::find(joints.begin(), joints.end(), first) - joints.begin());
    if (k > 2) continue;  // not a bone of the chain (a finger's metacarpal)
    const Rigid3d hand_from_star = hand_from_world * stars[s].measured;
    bone[f][k] = hand_from_star.rotation * Eigen::Vector3d::UnitY();
    if (k == 2) {
      const double length = solver_.chains()[f].length_m[k];
      tips[f] = hand_from_star * Eigen::Vector3d(0.0, 0.5 * length, -segment_star_lift_m(skeleton, first));
    }
  }
  for (std::size_t f = 0; f < kFingerCount; ++f) {
    const auto& b = bone[f];
    const FingerChain& chain = solver_.chains()[f];
    if (b[0] && b[1] && b[2]) {
      evidence[f].kind = FingerEvidence::Kind::kMeasured;
      evidence[f].angles = angles_from_bones(chain, {*b[0], *b[1], *b[2]});
    } else if (const int tip = layout_.fingertip_marker[f];
               b[0] && b[1] && !tips[f] && (tip < 0 || !found[static_cast<std::size_t>(tip)].allFinite())) {
      // The last bone's star hidden: the first two bones measured, the last hinge coupled.
      FingerAngles a = angles_from_bones(chain, {*b[0], *b[1], *b[1]});
      a.flexion_rad[2] = chain.limits.coupling * a.flexion_rad[1];
      evidence[f].kind = FingerEvidence::Kind::kMeasured;
      evidence[f].angles = clamp_to_limits(chain.limits, a);
    }
  }
  return tips;
}

namespace {

// A point a hand's marker could take back after a gap (track_hands): how far from that marker's
// predicted place (a finger that reaches it: at most kFingertipGateMin_m).
struct Returning {
  int point;
  std::size_t hand;
  double distance_m;
};

// contested[h * point_count + q]: hand h may not take point q back, the other hand's nearest
// returning marker being less than kContestRatio times farther from it than this hand's nearest
// (HandTracker.h). Sorts `returning`.
void contest(std::vector<Returning>& returning, std::size_t hand_count, std::size_t point_count, std::vector<bool>& contested) {
  std::sort(returning.begin(), returning.end(), [](const Returning& a, const Returning& b) {
    return std::tie(a.point, a.hand, a.distance_m) < std::tie(b.point, b.hand, b.distance_m);
  });
  contested.assign(hand_count * point_count, false);
  // Each hand's nearest entry for a point (the first of its run) against the other hands' nearest.
  const auto nearest_of_its_hand = [&](std::size_t i) {
    return i == 0 || returning[i - 1].point != returning[i].point || returning[i - 1].hand != returning[i].hand;
  };
  for (std::size_t i = 0; i < returning.size(); ++i) {
    if (!nearest_of_its_hand(i)) continue;
    for (std::size_t k = i + 1; k < returning.size() && returning[k].point == returning[i].point; ++k) {
      const Returning& a = returning[i];
      const Returning& b = returning[k];
      if (a.hand == b.hand || !nearest_of_its_hand(k)) continue;
      const auto q = static_cast<std::size_t>(a.point);
      if (b.distance_m < HandTracker::kContestRatio * a.distance_m) contested[a.hand * point_count + q] = true;
      if (a.distance_m < HandTracker::kContestRatio * b.distance_m) contested[b.hand * point_count + q] = true;
    }
  }
}

}  // namespace

void track_hands(std::span<HandTracker* const> hands, std::span<const int> hand_star, const std::vector<TrackedStar>& stars, double time_s,
                 std::span<const Eigen::Vector3d> points, std::span<const double> sigma_m, std::vector<bool>& taken,
                 std::span<const int> colour, JobPool* jobs) {
  // Each hand's own work on the pool where there is one (it reads the points and `taken`, and
  // writes only that hand's state); the sharing out between them in order, as on one thread.
  const auto per_hand = [&](auto&& fn) {
    if (jobs != nullptr) {
      jobs->for_each(hands.size(), fn);
    } else {
      for (std::size_t h = 0; h < hands.size(); ++h) fn(h);
    }
  };
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
    int marker, point;
    bool returning, persists;
  };
  // Each hand's candidates (and below its points per marker) in its own kept storage; the picks
  // in the calling thread's (nothing allocated once frames have shown them their largest counts).
  per_hand([&](std::size_t h) {
    if (hand_star[h] < 0 || static_cast<std::size_t>(hand_star[h]) >= stars.size()) {
      hands[h]->begin(time_s, false, {});  // no star to follow this hand by
    } else {
      hands[h]->begin(time_s, stars[static_cast<std::size_t>(hand_star[h])]);
    }
    hands[h]->frame_from_markers(time_s, points, taken, colour);
  });
  // The back of the hand's markers a frame was found by are taken, in hand order: a point two hands
  // found their frames by is the first's (the second is judged without it, below).
  for (std::size_t h = 0; h < hands.size(); ++h) {
    TrackedHand& out = hands[h]->out_;
    if (out.frame_source != HandFrameSource::kMarkers) continue;
    for (std::size_t m = 0; m < hands[h]->layout().hand_frame_markers && m < out.marker_point.size(); ++m) {
      int& p = out.marker_point[m];
      if (p < 0) continue;
      if (taken[static_cast<std::size_t>(p)]) {
        p = -1;
      } else {
        taken[static_cast<std::size_t>(p)] = true;
      }
    }
  }
  per_hand([&](std::size_t h) {
    hands[h]->fingertip_candidates(points, taken, colour);
    hands[h]->reach_candidates(points, taken);
  });
  thread_local std::vector<Pick> picks;
  picks.clear();
  for (std::size_t h = 0; h < hands.size(); ++h) {
    for (const auto& c : hands[h]->candidates_) picks.push_back({c.distance_m, h, c.marker, c.point, c.returning, c.persists});
  }
  // Nearest first over every hand: a point goes to the fingertip it fits best, whichever hand's.
  std::sort(picks.begin(), picks.end(), [](const Pick& a, const Pick& b) {
    return std::tie(a.distance_m, a.hand, a.marker, a.point) < std::tie(b.distance_m, b.hand, b.marker, b.point);
  });
  // Two hands on one object (a hand-over, a bar in both hands) hide each other's fingers, and a
  // hidden finger's estimate, centimetres off, is poor evidence of which hand a marker coming back
  // belongs to (HandTracker::kContestRatio).
  thread_local std::vector<Returning> returning;
  returning.clear();
  for (const Pick& p : picks) {
    if (p.returning) returning.push_back({p.point, p.hand, p.distance_m});
  }
  for (std::size_t h = 0; h < hands.size(); ++h) {
    // A finger that reaches the point could be there however far its estimate drifted: it counts as
    // no farther from it than the tightest gate.
    for (const HandTracker::Reach& r : hands[h]->reach_) {
      if (!hands[h]->followed(static_cast<std::size_t>(r.marker)))
        returning.push_back({r.point, h, std::min(r.predicted_m, HandTracker::kFingertipGateMin_m)});
    }
  }
  thread_local std::vector<bool> contested;
  contest(returning, hands.size(), points.size(), contested);
  for (std::size_t h = 0; h < hands.size(); ++h) hands[h]->tip_points_.assign(hands[h]->layout().markers.size(), -1);
  for (const Pick& p : picks) {
    int& slot = hands[p.hand]->tip_points_[static_cast<std::size_t>(p.marker)];
    const auto q = static_cast<std::size_t>(p.point);
    if (!p.persists || slot >= 0 || taken[q] || (p.returning && contested[p.hand * points.size() + q])) continue;
    slot = p.point;
    taken[q] = true;
  }
  // A marker left without a point takes a free one its finger reaches, hand by hand, where the
  // other hand does not contest it.
  thread_local std::vector<bool> contested_here;
  for (std::size_t h = 0; h < hands.size(); ++h) {
    contested_here.assign(contested.begin() + static_cast<std::ptrdiff_t>(h * points.size()),
                          contested.begin() + static_cast<std::ptrdiff_t>((h + 1) * points.size()));
    hands[h]->take_by_reach(points, taken, contested_here, hands[h]->tip_points_);
  }
  per_hand([&](std::size_t h) {
    hands[h]->confirm_frame_from_markers(time_s);
    hands[h]->untangle_neighbours(points, hands[h]->tip_points_);
    hands[h]->finish(time_s, points, sigma_m, hands[h]->tip_points_);
  });
}

}  // namespace rhot
