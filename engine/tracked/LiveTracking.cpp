#include "engine/tracked/LiveTracking.h"

#include "base/Check.h"

#include <algorithm>
#include <limits>
#include <optional>
#include <string>

#include <spdlog/spdlog.h>

namespace rhot {

HandInput hand_input(const TrackedHand& tracked) {
  HandInput in;
  in.seen = tracked.hand_seen;
  in.world_from_hand = tracked.world_from_hand;
  in.joints_world = tracked.joints_world;
  in.radius_m = tracked.state.pose.radius_m;
  in.confidence = tracked.state.confidence;
  return in;
}

LiveTracking::LiveTracking(std::unique_ptr<FrameSource> source, const TrackedObjects& objects, const std::array<HandLayout, 2>& layouts,
                           LiveTrackingSettings settings)
    : source_(std::move(source)), settings_(std::move(settings)), layouts_(layouts) {
  RHOT_PRECONDITION(settings_.threads >= 0 && settings_.threads <= kMaxThreads, "LiveTracking: threads from 0 (every core) to kMaxThreads");
  if (settings_.jobs) {
    jobs_ = settings_.jobs;
  } else if (const int threads = threads_or_all(settings_.threads); threads > 1) {
    jobs_ = std::make_shared<JobPool>(threads);
  }
  matcher_ = std::make_unique<RigMatcher>(tracker_rig());
  for (const TrackedObject& o : objects.objects) object_from_star_.emplace_back(o.star_id, o.object_from_star);
  // One library for the objects' stars and both hand stars (ids -1 and -2, after the objects'), so
  // that one assignment a frame shares the points between them all.
  StarSet all = objects.stars;
  for (std::size_t h = 0; h < 2; ++h) {
    if (!layouts_[h].has_hand_star()) {
      hand_star_[h] = -1;  // three markers on the back: no star for the cameras, the hand never seen (Launch refuses such layouts)
      continue;
    }
    MarkerStar hand = layouts_[h].hand_star_set().stars[0];
    hand.id = -1 - static_cast<int>(h);
    hand_star_[h] = static_cast<int>(all.stars.size());
    all.stars.push_back(hand);
  }
  star_tracker_ = std::make_unique<StarTracker>(StarLibrary(all));
  for (const int s : hand_star_)
    if (s >= 0) star_tracker_->set_motion(s, hand_star_motion());
  stars_ = star_tracker_->stars();  // the hands' stages may run before the stars' first
  // A colour some finger marker wears and no hand star does: such a point is a finger's, never a
  // star's marker. Only where both hand stars are coloured (the objects' stars wear the hand stars'
  // colour, docs/colour-markers.md): an uncoloured star's markers may be seen in any colour.
  const bool stars_coloured = std::all_of(layouts_.begin(), layouts_.end(), [](const HandLayout& l) { return l.hand_star_colour() >= 0; });
  for (const HandLayout& layout : layouts_) {
    for (std::size_t m = layout.hand_frame_markers; m < layout.markers.size(); ++m) {
      const int colour = layout.markers[m].colour;
      const bool star_colour =
          std::any_of(layouts_.begin(), layouts_.end(), [&](const HandLayout& l) { return l.hand_star_colour() == colour; });
      if (stars_coloured && colour >= 0 && !star_colour &&
          std::find(fingertip_only_colours_.begin(), fingertip_only_colours_.end(), colour) == fingertip_only_colours_.end())
        fingertip_only_colours_.push_back(colour);
    }
  }
  HandTrackerSettings tracker_settings;
  tracker_settings.filter = settings_.filter_hands;
  tracker_settings.filter_frame = settings_.filter_hand_frames;
  for (std::size_t h = 0; h < 2; ++h) {
    hand_trackers_[h] = std::make_unique<HandTracker>(layouts_[h], reference_open_hand(layouts_[h].side), tracker_settings);
  }
}

std::vector<TrackingStage> LiveTracking::stages() {
  return {{"source", [this](double t) { read_source(t); }},
          {"matching", [this](double) { match(); }},
          {"stars", [this](double t) { track_stars(t); }},
          {"hands", [this](double t) { track_hands(t); }}};
}

namespace {

// What is wrong with a frame from outside, for matching: it needs one CameraFrame per camera of
// the rig, in rig order (else the frame is dropped whole), with finite pixels (else those
// detections are dropped).
struct FrameProblem {
  bool drop = false;
  std::string what;
};

std::optional<FrameProblem> sanitise(RigFrame& frame, std::size_t cameras) {
  const std::string at = "frame " + std::to_string(frame.index) + ": ";
  if (frame.cameras.size() != cameras) {
    return FrameProblem{true, at + std::to_string(frame.cameras.size()) + " cameras for a rig of " + std::to_string(cameras)};
  }
  std::size_t non_finite = 0;
  for (std::size_t c = 0; c < cameras; ++c) {
    CameraFrame& cf = frame.cameras[c];
    if (cf.camera != static_cast<int>(c)) {
      return FrameProblem{true, at + "camera " + std::to_string(cf.camera) + " where camera " + std::to_string(c) + " belongs"};
    }
    non_finite += std::erase_if(cf.detections, [](const Detection& d) { return !d.pixel.allFinite(); });
  }
  if (non_finite > 0) return FrameProblem{false, at + std::to_string(non_finite) + " non-finite detection(s)"};
  return std::nullopt;
}

}  // namespace

void LiveTracking::read_source(double t_s) {
  results_.t_s = t_s;
  results_.counts = {};
  const std::size_t cameras = source_->rig().cameras.size();
  std::optional<RigFrame> frame = ended_ ? std::nullopt : source_->next(t_s);
  bool dropped = false;
  if (frame) {
    if (const auto problem = sanitise(*frame, cameras)) {
      dropped = problem->drop;
      if (++bad_frames_ >= next_bad_frame_told_) {  // told at the 1st, 10th, 100th ... bad frame
        spdlog::warn("source: {}, {} ({} bad frame(s) so far)", problem->what, dropped ? "frame dropped" : "those dropped", bad_frames_);
        next_bad_frame_told_ *= 10;
      }
    }
  } else if (!ended_) {
    spdlog::info("source: the stream has ended after {} frames", frame_.cameras.empty() ? 0 : frame_.index + 1);
    ended_ = true;
  }
  results_.capture_steady_s = std::numeric_limits<double>::quiet_NaN();
  if (frame && !dropped) {
    frame_ = std::move(*frame);
    results_.capture_steady_s = frame_.capture_steady_s;
  } else {
    // Nothing to see this frame: one empty CameraFrame per camera.
    frame_.cameras.assign(cameras, CameraFrame{});
    for (std::size_t c = 0; c < cameras; ++c) frame_.cameras[c].camera = static_cast<int>(c);
  }
  for (const std::string& warning : source_->take_warnings()) spdlog::warn("{}", warning);
  for (const auto& camera : frame_.cameras) {
    results_.counts.detections += camera.detections.size();
    results_.counts.detections_per_camera.push_back(camera.detections.size());
    if (!camera.delivered) results_.counts.cameras_without_frame.push_back(camera.camera);
  }
}

void LiveTracking::match() {
  results_.points.clear();
  results_.point_cameras.clear();
  results_.point_colours.clear();
  double sum_rms = 0.0;
  // Gates as wide as the detection noise estimated so far; each point's uncertainty from it.
  // The matcher's own storage, kept from frame to frame (valid until the next frame).
  const std::span<const MatchedPoint> matched = matcher_->match_frame(frame_, match_settings_for(pixel_sigma_.sigma_px()), jobs_.get());
  point_sigmas_m(matched, pixel_sigma_.update(matched), point_sigma_m_);
  for (const MatchedPoint& m : matched) {
    results_.points.push_back(m.point.position_world);
    results_.point_cameras.push_back(m.point.cameras);
    results_.point_colours.push_back(m.colour);
    sum_rms += m.point.reprojection_rms_px;
  }
  results_.counts.points = results_.points.size();
  results_.counts.mean_reprojection_rms_px = results_.points.empty() ? 0.0 : sum_rms / static_cast<double>(results_.points.size());
}

void LiveTracking::track_stars(double t_s) {
  results_.world_from_object.clear();
  results_.object_certain.clear();
  // The points a star's marker may be: all of them, less those whose colour only fingertips wear.
  // With two colour cameras, fingertip markers beside blue star markers were taken
  // for the other hand's star, half a metre from that hand (rhot-eval colour, 2026-11-26).
  star_point_.clear();
  star_points_.clear();
  star_point_sigma_m_.clear();
  for (std::size_t p = 0; p < results_.points.size(); ++p) {
    const int colour = p < results_.point_colours.size() ? results_.point_colours[p] : -1;
    if (std::find(fingertip_only_colours_.begin(), fingertip_only_colours_.end(), colour) != fingertip_only_colours_.end()) continue;
    star_point_.push_back(static_cast<int>(p));
    star_points_.push_back(results_.points[p]);
    star_point_sigma_m_.push_back(point_sigma_m_[p]);
  }
  const auto& stars = star_tracker_->update(t_s, star_points_, star_point_sigma_m_);
  stars_ = stars;  // with this frame's point indices
  for (TrackedStar& s : stars_) {
    for (int& p : s.point) p = p >= 0 ? star_point_[static_cast<std::size_t>(p)] : -1;
  }
  for (const auto& [id, object_from_star] : object_from_star_) {
    for (const TrackedStar& s : stars) {
      if (s.id != id || !s.measured_now()) continue;
      ++results_.counts.stars_seen;
      results_.counts.seen_star_ids.push_back(id);
      const Rigid3d world_from_object = s.world_from_star * object_from_star.inverse();
      if (!world_from_object.translation.allFinite() || !world_from_object.rotation.coeffs().allFinite()) continue;
      results_.world_from_object[id] = world_from_object;
      results_.object_certain[id] = s.certain;
    }
  }
}

void LiveTracking::track_hands(double t_s) {
  // The hand stars were followed with the objects' (track_stars); the points left go to the fingertips.
  const std::array<HandTracker*, 2> hands{hand_trackers_[0].get(), hand_trackers_[1].get()};
  rhot::track_hands(hands, hand_star_, stars_, t_s, results_.points, point_sigma_m_, taken_, results_.point_colours, jobs_.get());
  for (std::size_t h = 0; h < 2; ++h) {
    const TrackedHand& tracked = hand_trackers_[h]->last();
    results_.hands[h] = hand_input(tracked);
    results_.counts.hands_seen[h] = tracked.hand_seen;
    results_.pinch[h] = {tracked.state.pinch.activation, tracked.state.pinch.active};
    results_.grip[h] = {tracked.state.grip.activation, tracked.state.grip.active};
  }
  results_.gestures_measured = true;
}

}  // namespace rhot
