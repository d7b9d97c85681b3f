// rhot-eval hands --take: a recorded take's fingertips hidden by rule and estimated from the rest,
// against the recorded positions: by the hidden-marker estimator alone (tracking/hand/
// HiddenMarkers.h), or, with --layout, by the hand tracker: fed the take's labelled markers
// (--labelled: HandTracker::update_labelled, its fingertip model, IK and skeleton), or the take
// photographed by a simulated rig's cameras (--rig, with the world flags' noise, dropout, strays and
// calibration error: the whole camera path, the hand found by its back's markers among unlabelled
// points; --calibrate-seconds fitted to the take's labelled markers, or with --calibrate-from cameras
// to those the tracker found through the cameras).

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iostream>
#include <map>
#include <memory>
#include <numeric>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "base/Jobs.h"
#include "tools/common/NumberChecks.h"
#include "tools/eval/Eval.h"
#include "tracking/camera/RigFile.h"
#include "tracking/geometry/Matching.h"
#include "tracking/hand/HandCalibration.h"
#include "tracking/hand/HandTracker.h"
#include "tracking/hand/HiddenMarkers.h"
#include "tracking/sim/Realism.h"
#include "tracking/sim/SimulatedRig.h"
#include "tracking/take/MarkerTake.h"

namespace rhot::eval {
namespace {

// A refusal: said on stderr, exit status 1.
int fail(const std::string& what) {
  std::cerr << "rhot-eval: " << what << "\n";
  return 1;
}

// The glove's names (assets/hands: three on the back of the hand, a tip and a middle per finger).

double take_mean(const std::vector<double>& v) {
  return v.empty() ? 0.0 : std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
}

nlohmann::json take_report(const HiddenMarkerErrors& e) {
  nlohmann::json j;
  j["hidden_tip_mean_mm"] = take_mean(e.hidden_mm);
  j["hidden_tip_p95_mm"] = percentile(e.hidden_mm, 0.95);
  // Labelled points: a visible tip is its recorded position.
  j["visible_tip_mean_mm"] = 0.0;
  j["held_tip_mean_mm"] = take_mean(e.held_mm);
  j["held_tip_p95_mm"] = percentile(e.held_mm, 0.95);
  j["hidden_frames"] = e.hidden_frames;
  j["estimated_frames"] = e.hidden_mm.size();
  for (const auto& [name, errors] : e.hidden_by_marker_mm) {
    j["fingers"][name] = {{"mean_mm", take_mean(errors)}, {"p95_mm", percentile(errors, 0.95)}, {"frames", errors.size()}};
  }
  return j;
}

// Each layout marker's index in the take: by its name, or the take's name --map gives it.
std::expected<std::vector<int>, std::string> take_indices(const MarkerTake& take, const HandLayout& layout,
                                                          const std::vector<std::string>& maps) {
  std::map<std::string, std::string> take_name;  // layout name -> take name
  for (const std::string& m : maps) {
    const auto eq = m.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == m.size()) return std::unexpected("--map " + m + ": expected TAKE_NAME=LAYOUT_NAME");
    const std::string from = m.substr(0, eq), to = m.substr(eq + 1);
    if (!take.marker(from)) return std::unexpected("--map " + m + ": the take has no marker \"" + from + "\"");
    if (layout.marker_index(to) < 0) return std::unexpected("--map " + m + ": the layout has no marker \"" + to + "\"");
    take_name[to] = from;
  }
  std::vector<int> out;
  std::string missing;
  for (const LayoutMarker& lm : layout.markers) {
    const auto it = take_name.find(lm.name);
    const auto index = take.marker(it == take_name.end() ? lm.name : it->second);
    if (!index) missing += std::string(missing.empty() ? "" : ", ") + "\"" + lm.name + "\"";
    out.push_back(index.value_or(-1));
  }
  if (!missing.empty()) {
    std::string names;
    for (const std::string& n : take.marker_names) names += std::string(names.empty() ? "" : ", ") + n;
    return std::unexpected("the take has no marker for the layout's " + missing + " (its markers: " + names +
                           "; name one with --map TAKE_NAME=LAYOUT_NAME)");
  }
  return out;
}

// Frame f's markers in the layout's order (NaN in a gap).
std::vector<Eigen::Vector3d> layout_frame(const MarkerTake& take, const std::vector<int>& index, int f) {
  std::vector<Eigen::Vector3d> out;
  for (const int i : index) out.push_back(take.at(f, i));
  return out;
}

// The take's units against the layout's: the back of the hand's markers as far apart as the
// layout's within a factor of two (a take in the wrong units is 10 or 1,000 times off).
std::string units_problem(const MarkerTake& take, const HandLayout& layout, const std::vector<int>& index) {
  const std::size_t n = layout.hand_frame_markers;
  for (int f = 0; f < take.frame_count(); ++f) {
    const auto markers = layout_frame(take, index, f);
    if (!std::all_of(markers.begin(), markers.begin() + static_cast<std::ptrdiff_t>(n), [](const auto& p) { return p.allFinite(); }))
      continue;
    double in_take = 0.0, in_layout = 0.0;
    for (std::size_t a = 0; a < n; ++a) {
      for (std::size_t b = a + 1; b < n; ++b) {
        in_take += (markers[a] - markers[b]).norm();
        in_layout += (layout.markers[a].offset_m - layout.markers[b].offset_m).norm();
      }
    }
    const double ratio = in_take / in_layout;
    if (ratio > 0.5 && ratio < 2.0) return "";
    const auto mm = [](double m) {
      std::array<char, 32> text{};
      std::snprintf(text.data(), text.size(), "%.3g", 1e3 * m);
      return std::string(text.data());
    };
    return "the back of the hand's markers are " + mm(in_take) + " mm apart in all (frame " + std::to_string(f + 1) +
           ") where the layout's are " + mm(in_layout) + " mm: is the take in other units than it says?";
  }
  return "no frame shows every marker on the back of the hand";
}

// A layout marker hidden over a window of the take's time (--hide MARKER@T0-T1).
struct HideWindow {
  std::size_t marker = 0;
  double from_s = 0.0, to_s = 0.0;
};

// Each --hide MARKER@T0-T1: a finger marker of the layout, 0 <= T0 < T1 <= the take's length.
std::expected<std::vector<HideWindow>, std::string> parse_hides(const std::vector<std::string>& hides, const HandLayout& layout,
                                                                double take_s, double frame_rate_hz) {
  std::vector<HideWindow> out;
  for (const std::string& h : hides) {
    const std::string what = "--hide " + h + ": ";
    const std::size_t at = h.rfind('@');
    if (at == std::string::npos || h.find('-', at + 1) == std::string::npos)
      return std::unexpected(what + "expected MARKER@T0-T1 (seconds into the take), e.g. index_tip@12.5-13");
    const int marker = layout.marker_index(h.substr(0, at));
    if (marker < 0) {
      std::string names;
      for (std::size_t m = layout.hand_frame_markers; m < layout.markers.size(); ++m)
        names += (names.empty() ? "" : ", ") + layout.markers[m].name;
      return std::unexpected(what + "no marker \"" + h.substr(0, at) + "\" in the layout (its finger markers: " + names + ")");
    }
    if (static_cast<std::size_t>(marker) < layout.hand_frame_markers)
      return std::unexpected(what + "a marker on the back of the hand gives the hand its frame: hide finger markers");
    // T0 and T1 either side of a '-' (the first one that leaves two numbers: "1e-3-2" is 0.001 to 2).
    double from = std::nan(""), to = std::nan("");
    for (std::size_t dash = h.find('-', at + 1); dash != std::string::npos && !(std::isfinite(from) && std::isfinite(to));
         dash = h.find('-', dash + 1)) {
      from = finite_number(std::string_view(h).substr(at + 1, dash - at - 1)).value_or(std::nan(""));
      to = finite_number(std::string_view(h).substr(dash + 1)).value_or(std::nan(""));
    }
    if (!std::isfinite(from) || !std::isfinite(to) || from < 0.0)
      return std::unexpected(what + "the window's times must be seconds from 0 on, e.g. index_tip@12.5-13");
    if (!(to > from)) return std::unexpected(what + "the window ends before it starts");
    if (to > take_s + 1e-9) {
      std::array<char, 32> length{};
      std::snprintf(length.data(), length.size(), "%.2f", take_s);
      return std::unexpected(what + "the window ends after the take's end (" + length.data() + " s)");
    }
    if (std::ceil(from * frame_rate_hz - 1e-9) >= to * frame_rate_hz - 1e-9)
      return std::unexpected(what + "the window holds no frame of the take");
    out.push_back({static_cast<std::size_t>(marker), from, to});
  }
  return out;
}

// The errors of a tracker run over a whole take, its markers hidden by `hidden_at` (layout marker
// indices per frame) from frame `first` on and judged from there: each fingertip against its
// recorded place, hidden or seen, a hidden one also held where it was last seen (hand frame), and
// every other hidden finger marker apart.
struct TrackerErrors {
  std::vector<double> hidden_mm, held_mm, visible_mm;
  std::map<std::string, std::vector<double>> hidden_by_finger, visible_by_finger, hidden_other;
  int frames_judged = 0, hand_seen = 0, hidden_frames = 0;
  double ik_sum_us = 0.0;
  // Through a rig: finger markers in view and found by the tracker; markers given a point, and
  // given another marker's (or, hidden, any).
  long markers_in_view = 0, markers_found = 0, markers_given = 0, markers_wrong = 0;
};

TrackerErrors run_tracker_over_take(HandTracker& tracker, const MarkerTake& take, const std::vector<int>& index, int first,
                                    const std::function<std::vector<std::size_t>(int)>& hidden_at) {
  const HandLayout& layout = tracker.layout();
  TrackerErrors out;
  std::vector<Eigen::Vector3d> last_seen_hand(layout.markers.size(), Eigen::Vector3d::Constant(std::nan("")));
  for (int f = 0; f < take.frame_count(); ++f) {
    std::vector<Eigen::Vector3d> markers = layout_frame(take, index, f);
    const std::vector<std::size_t> hidden = f >= first ? hidden_at(f) : std::vector<std::size_t>{};
    for (const std::size_t m : hidden) markers[m] = Eigen::Vector3d::Constant(std::nan(""));
    const TrackedHand& hand = tracker.update_labelled(take.time_s(f), markers);
    if (f % 500 == 0) std::cerr << "rhot-eval: frame " << f + 1 << " of " << take.frame_count() << "\n";
    if (f >= first) ++out.frames_judged;
    if (!hand.hand_seen) continue;
    if (f >= first) {
      ++out.hand_seen;
      out.ik_sum_us += tracker.last_ik_us();
      const auto estimated = tracker.markers_in_hand();
      const auto error_mm = [&](std::size_t m) { return 1e3 * (hand.world_from_hand * estimated[m] - take.at(f, index[m])).norm(); };
      for (std::size_t k = 0; k < kFingerCount; ++k) {
        const auto m = static_cast<std::size_t>(layout.fingertip_marker[k]);
        if (!take.at(f, index[m]).allFinite()) continue;
        const double e = error_mm(m);
        const std::string& name = layout.markers[m].name;
        if (std::ranges::find(hidden, m) != hidden.end()) {
          ++out.hidden_frames;
          out.hidden_mm.push_back(e);
          out.hidden_by_finger[name].push_back(e);
          if (last_seen_hand[m].allFinite())
            out.held_mm.push_back(1e3 * (hand.world_from_hand * last_seen_hand[m] - take.at(f, index[m])).norm());
        } else {
          out.visible_mm.push_back(e);
          out.visible_by_finger[name].push_back(e);
        }
      }
      for (const std::size_t m : hidden) {
        if (std::ranges::find(layout.fingertip_marker, static_cast<int>(m)) == layout.fingertip_marker.end() &&
            take.at(f, index[m]).allFinite())
          out.hidden_other[layout.markers[m].name].push_back(error_mm(m));
      }
    }
    const Rigid3d hand_from_world = hand.world_from_hand.inverse();
    for (std::size_t m = 0; m < markers.size(); ++m) {
      if (markers[m].allFinite()) last_seen_hand[m] = hand_from_world * markers[m];
    }
  }
  return out;
}

// What both ways of feeding a take to the tracker (labelled, or through a rig) share: the layout,
// the take's marker of each layout marker, the first judged frame and which markers are hidden when.
struct TakePlan {
  HandLayout layout;
  std::vector<int> index;  // per layout marker, the take's
  int calibration_frames = 0;
  int first = 0;  // the first judged frame of the take
  std::optional<HideSchedule> schedule;
  std::vector<HideWindow> windows;

  // The layout markers hidden at the take's frame f: the rule's gaps, or the windows named.
  std::vector<std::size_t> hidden_at(const MarkerTake& take, int f) const {
    std::vector<std::size_t> out;
    if (f < first) return out;
    if (windows.empty()) {
      for (const std::size_t k : schedule->hidden(f)) out.push_back(static_cast<std::size_t>(layout.fingertip_marker[k]));
      return out;
    }
    const double t = take.time_s(f);
    for (const HideWindow& w : windows) {
      if (t >= w.from_s && t < w.to_s && std::ranges::find(out, w.marker) == out.end()) out.push_back(w.marker);
    }
    return out;
  }
};

std::expected<TakePlan, std::string> plan_take(const HandsArgs& args, const MarkerTake& take) {
  TakePlan plan;
  auto layout = load_hand_layout(args.layout_file);
  if (!layout) return std::unexpected(layout.error());
  plan.layout = std::move(*layout);
  if (!plan.layout.segment_stars.empty())
    return std::unexpected(args.layout_file +
                           ": a layout with segment stars is not read from takes (their stars' markers have no names there)");
  if (!std::ranges::all_of(plan.layout.fingertip_marker, [](int m) { return m >= 0; }))
    return std::unexpected(args.layout_file + ": the take's fingertips are hidden in turn: the layout must mark all five");
  if (take.frame_rate_hz < 20.0 || take.frame_rate_hz > 2000.0)
    return std::unexpected(args.take_file + ": frame rate " + std::to_string(take.frame_rate_hz) +
                           " Hz: the hand tracker takes 20 to 2,000 Hz");
  auto index = take_indices(take, plan.layout, args.maps);
  if (!index) return std::unexpected(args.take_file + ": " + index.error());
  plan.index = std::move(*index);
  if (const std::string units = units_problem(take, plan.layout, plan.index); !units.empty())
    return std::unexpected(args.take_file + ": " + units);
  plan.calibration_frames = static_cast<int>(std::lround(args.calibrate_seconds * take.frame_rate_hz));
  if (plan.calibration_frames >= take.frame_count())
    return std::unexpected("--calibrate-seconds: the take is only " + std::to_string(take.frame_count() / take.frame_rate_hz) + " s long");
  plan.first = std::max(plan.calibration_frames, static_cast<int>(std::lround(args.evaluate_from_s * take.frame_rate_hz)));
  if (plan.first >= take.frame_count()) return std::unexpected("--evaluate-from-s: after the take's end");
  plan.schedule =
      HideSchedule::make({.gap_s = args.hide_gap_s, .together = args.hide_together, .seed = args.seed, .first_frame = plan.first},
                         take.frame_rate_hz, kFingerCount);
  if (!plan.schedule) return std::unexpected("--hide-gap-s: expected a positive number of seconds");
  auto windows = parse_hides(args.hides, plan.layout, take.frame_count() / take.frame_rate_hz, take.frame_rate_hz);
  if (!windows) return std::unexpected(windows.error());
  plan.windows = std::move(*windows);
  for (const HideWindow& w : plan.windows) {
    if (w.to_s <= plan.first / take.frame_rate_hz)
      return std::unexpected("--hide " + plan.layout.markers[w.marker].name + ": the window ends before the judged part begins (" +
                             std::to_string(plan.first / take.frame_rate_hz) + " s: --calibrate-seconds, --evaluate-from-s)");
  }
  return plan;
}

// The report of a tracker's run over a take, in the keys both ways share.
nlohmann::json tracker_report(const HandsArgs& args, const MarkerTake& take, const TakePlan& plan, const TrackerErrors& e,
                              const LabelledCalibration& calibration, const HandTracker& tracker) {
  nlohmann::json j;
  j["take"] = args.take_file;
  j["layout"] = args.layout_file;
  j["frames"] = take.frame_count();
  j["frame_rate_hz"] = take.frame_rate_hz;
  j["evaluated_frames"] = {plan.first + 1, take.frame_count()};
  j["hide_gap_s"] = args.hide_gap_s;
  j["hide_together"] = args.hide_together;
  j["seed"] = args.seed;
  j["filter"] = args.filter;
  j["filter_frame"] = args.filter_frame;
  j["hidden_tip_mean_mm"] = take_mean(e.hidden_mm);
  j["hidden_tip_p95_mm"] = percentile(e.hidden_mm, 0.95);
  j["visible_tip_mean_mm"] = take_mean(e.visible_mm);
  j["visible_tip_p95_mm"] = percentile(e.visible_mm, 0.95);
  j["held_tip_mean_mm"] = take_mean(e.held_mm);
  j["held_tip_p95_mm"] = percentile(e.held_mm, 0.95);
  j["hidden_frames"] = e.hidden_frames;
  j["hand_seen_fraction"] = e.frames_judged > 0 ? static_cast<double>(e.hand_seen) / e.frames_judged : 0.0;
  j["ik_mean_us"] = e.hand_seen > 0 ? e.ik_sum_us / e.hand_seen : 0.0;
  j["fingertip_model_frames"] = tracker.fingertip_model_frames();
  j["calibrate_seconds"] = args.calibrate_seconds;
  j["calibration"] = {{"finger_scale", calibration.scale}, {"frames", calibration.frames}};
  for (const double a : calibration.turned_rad) j["calibration"]["finger_turned_deg"].push_back(a * 180.0 / 3.14159265358979);
  for (std::size_t k = 0; k < kFingerCount; ++k) {
    const Eigen::Vector3d& moved = calibration.knuckle_moved_m[k];
    j["calibration"]["knuckle_moved_mm"].push_back({1e3 * moved.x(), 1e3 * moved.y(), 1e3 * moved.z()});
    j["calibration"]["reach_rms_mm"].push_back({1e3 * calibration.reach_rms_m[k][0], 1e3 * calibration.reach_rms_m[k][1]});
  }
  for (const auto& [name, errors] : e.hidden_by_finger) {
    j["fingers"][name] = {{"hidden_mean_mm", take_mean(errors)},
                          {"hidden_p95_mm", percentile(errors, 0.95)},
                          {"hidden_frames", errors.size()},
                          {"visible_mean_mm", e.visible_by_finger.contains(name) ? take_mean(e.visible_by_finger.at(name)) : 0.0}};
  }
  for (const auto& [name, errors] : e.hidden_other) {
    j["hidden_markers"][name] = {
        {"hidden_mean_mm", take_mean(errors)}, {"hidden_p95_mm", percentile(errors, 0.95)}, {"hidden_frames", errors.size()}};
  }
  for (const std::string& h : args.hides) j["hide"].push_back(h);
  return j;
}

// The skeleton and layout the tracker runs with: the reference hand's, or fitted to the markers of
// the calibration frames (calibrate_from_labelled) where there are any.
struct FittedHand {
  HandPose skeleton;
  HandLayout layout;
  LabelledCalibration calibration;

  // The tracker, its fingertip model on (the take's fingertips are hidden in turn), its 1-euro
  // filters on where asked (--filter, --filter-frame).
  HandTracker tracker(bool filter, bool filter_frame) const {
    HandTrackerSettings settings;
    settings.fingertip_model = true;
    settings.filter = filter;
    settings.filter_frame = filter_frame;
    if (calibration.frames > 0) settings.finger_length_tolerance = 0.0;  // the skeleton fitted to the take's hand
    return HandTracker(layout, skeleton, settings);
  }
};

std::expected<FittedHand, std::string> fit_hand(const TakePlan& plan, const std::vector<std::vector<Eigen::Vector3d>>& frames) {
  FittedHand out{reference_open_hand(plan.layout.side), plan.layout, {}};
  if (plan.calibration_frames == 0) return out;
  const auto calibrated = calibrate_from_labelled(plan.layout, out.skeleton, frames, &out.calibration);
  if (!calibrated) return std::unexpected(std::string("--calibrate-seconds: no finger could be fitted from the calibration frames"));
  out.skeleton = *calibrated;
  out.layout = out.calibration.layout;
  return out;
}

int take_through_tracker(const HandsArgs& args, const MarkerTake& take) {
  const auto plan = plan_take(args, take);
  if (!plan) return fail(plan.error());
  std::vector<std::vector<Eigen::Vector3d>> frames;
  if (plan->calibration_frames > 0) std::cerr << "rhot-eval: fitting the fingers' lengths to frames 1-" << plan->calibration_frames << "\n";
  for (int f = 0; f < plan->calibration_frames; ++f) frames.push_back(layout_frame(take, plan->index, f));
  const auto fitted = fit_hand(*plan, frames);
  if (!fitted) return fail(fitted.error());
  HandTracker tracker = fitted->tracker(args.filter, args.filter_frame);
  const TrackerErrors e = run_tracker_over_take(tracker, take, plan->index, plan->first, [&](int f) { return plan->hidden_at(take, f); });
  nlohmann::json j = tracker_report(args, take, *plan, e, fitted->calibration, tracker);
  j["through"] = "hand tracker, labelled markers";
  std::cout << j.dump(2) << "\n";
  return 0;
}

// A take's marker at any time between its frames (linear; NaN where either frame is in a gap, and
// past the last frame).
Eigen::Vector3d take_at_time(const MarkerTake& take, int marker, double t_s) {
  const double u = t_s * take.frame_rate_hz;
  const auto f0 = static_cast<int>(std::floor(u));
  if (f0 < 0 || f0 >= take.frame_count()) return Eigen::Vector3d::Constant(std::nan(""));
  if (f0 + 1 == take.frame_count()) return u == f0 ? take.at(f0, marker) : Eigen::Vector3d::Constant(std::nan(""));
  const Eigen::Vector3d& a = take.at(f0, marker);
  const Eigen::Vector3d& b = take.at(f0 + 1, marker);
  const double w = u - f0;
  return (1.0 - w) * a + w * b;  // NaN if either is
}

// The rig that photographs a take: where the take is moved to (its back of the hand's mean place
// onto the rig's volume centre) and the world's noise, dropout, strays and calibration error.
struct TakeRig {
  CameraRig truth;
  CameraRig tracker_rig;  // as an imperfect calibration has it
  SimulatedRigSettings settings;
  Eigen::Vector3d shift_m{0, 0, 0};
  std::shared_ptr<JobPool> jobs;  // matching's threads (--threads)
};

// The tracker run over the take's first end_s seconds through the rig's cameras: every take marker
// photographed (the layout's, then the others: an object's, points the hand must leave alone),
// but those the plan hides when `hide`. each(t, take frame, hand, points) after every frame.
void run_through_rig(const MarkerTake& take, const TakePlan& plan, const TakeRig& r, HandTracker& tracker, double end_s, bool hide,
                     const std::function<void(double, int, const TrackedHand&, std::span<const Eigen::Vector3d>)>& each) {
  std::vector<int> order = plan.index;
  for (int i = 0; i < take.marker_count(); ++i) {
    if (std::ranges::find(order, i) == order.end()) order.push_back(i);
  }
  std::vector<std::size_t> hidden;
  SimulatedRig sim(r.truth, {}, r.settings);
  sim.set_scripted_markers([&](double t) {
    std::vector<Eigen::Vector3d> out;
    for (std::size_t k = 0; k < order.size(); ++k) {
      const bool off = std::ranges::find(hidden, k) != hidden.end();
      out.push_back(off ? Eigen::Vector3d::Constant(std::nan("")) : Eigen::Vector3d(take_at_time(take, order[k], t) + r.shift_m));
    }
    return out;
  });
  PixelSigmaEstimate pixel_sigma;
  const auto frames = static_cast<int>(std::floor(end_s * r.settings.rate_hz));
  std::vector<Eigen::Vector3d> points;
  const RigMatcher matcher(r.tracker_rig);
  for (int f = 0; f < frames; ++f) {
    const double t = f / r.settings.rate_hz;
    const int take_frame = std::clamp(static_cast<int>(std::lround(t * take.frame_rate_hz)), 0, take.frame_count() - 1);
    hidden = hide ? plan.hidden_at(take, take_frame) : std::vector<std::size_t>{};
    const RigFrame frame = sim.next();
    const auto matched = matcher.match(frame, match_settings_for(pixel_sigma.sigma_px()), r.jobs.get());
    points.clear();
    for (const MatchedPoint& m : matched) points.push_back(m.point.position_world);
    const TrackedHand& hand = tracker.update(frame.time_s, points, point_sigmas_m(matched, pixel_sigma.update(matched)));
    if (f % 900 == 0) std::cerr << "rhot-eval: " << (hide ? "" : "calibration: ") << "frame " << f + 1 << " of " << frames << "\n";
    each(frame.time_s, take_frame, hand, points);
  }
}

// The errors through the rig, judged from the plan's first frame: each fingertip's estimate
// against the take's marker at the rig frame's time, as run_tracker_over_take judges labelled ones.
TrackerErrors judge_through_rig(const MarkerTake& take, const TakePlan& plan, const TakeRig& r, HandTracker& tracker) {
  const HandLayout& layout = tracker.layout();
  TrackerErrors out;
  std::vector<Eigen::Vector3d> last_seen_hand(layout.markers.size(), Eigen::Vector3d::Constant(std::nan("")));
  const auto judge = [&](double t, int take_frame, const TrackedHand& hand, std::span<const Eigen::Vector3d> points) {
    const std::vector<std::size_t> hidden = plan.hidden_at(take, take_frame);
    const auto is_hidden = [&](std::size_t m) { return std::ranges::find(hidden, m) != hidden.end(); };
    const auto truth = [&](std::size_t m) { return Eigen::Vector3d(take_at_time(take, plan.index[m], t) + r.shift_m); };
    const bool judged = take_frame >= plan.first;
    out.frames_judged += judged ? 1 : 0;
    if (!hand.hand_seen) return;
    if (judged) {
      ++out.hand_seen;
      out.ik_sum_us += tracker.last_ik_us();
      const auto estimated = tracker.markers_in_hand();
      for (std::size_t m = layout.hand_frame_markers; m < layout.markers.size(); ++m) {
        const Eigen::Vector3d at = truth(m);
        if (!at.allFinite()) continue;
        // A finger marker in view: found by the tracker, and found where it is (a point within 10 mm
        // of it; else another marker's, a ghost or a stray taken for it). A hidden one given a point
        // took some other marker's.
        const int p = hand.marker_point[m];
        out.markers_in_view += is_hidden(m) ? 0 : 1;
        out.markers_found += p >= 0 && !is_hidden(m) ? 1 : 0;
        out.markers_given += p >= 0 ? 1 : 0;
        out.markers_wrong += p >= 0 && (is_hidden(m) || (points[static_cast<std::size_t>(p)] - at).norm() > 0.010) ? 1 : 0;
        const auto tip = std::ranges::find(layout.fingertip_marker, static_cast<int>(m));
        if (tip == layout.fingertip_marker.end()) continue;
        const double e = 1e3 * (hand.world_from_hand * estimated[m] - at).norm();
        const std::string& name = layout.markers[m].name;
        if (!is_hidden(m)) {
          out.visible_mm.push_back(e);
          out.visible_by_finger[name].push_back(e);
          continue;
        }
        ++out.hidden_frames;
        out.hidden_mm.push_back(e);
        out.hidden_by_finger[name].push_back(e);
        if (last_seen_hand[m].allFinite()) out.held_mm.push_back(1e3 * (hand.world_from_hand * last_seen_hand[m] - at).norm());
      }
    }
    const Rigid3d hand_from_world = hand.world_from_hand.inverse();
    for (std::size_t m = 0; m < layout.markers.size(); ++m) {
      const Eigen::Vector3d at = truth(m);
      if (at.allFinite() && !is_hidden(m)) last_seen_hand[m] = hand_from_world * at;
    }
  };
  run_through_rig(take, plan, r, tracker, take.time_s(take.frame_count() - 1), true, judge);
  return out;
}

int take_through_rig(const HandsArgs& args, const MarkerTake& take) {
  const auto plan = plan_take(args, take);
  if (!plan) return fail(plan.error());
  const auto world = world_settings(args.world);
  if (!world) return fail(world.error());
  const auto rig = load_rig(args.rig_file);
  if (!rig) return fail(rig.error());
  TakeRig r{*rig,
            perturbed_rig(*rig, world->calib_error_px, args.seed),
            world->rig_settings(args.seed),
            {},
            std::make_shared<JobPool>(threads_or_all(args.threads))};
  // The take's back of the hand, on average, onto the volume's centre (its axes as recorded).
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int n = 0;
  for (int f = 0; f < take.frame_count(); ++f) {
    for (std::size_t m = 0; m < plan->layout.hand_frame_markers; ++m) {
      const Eigen::Vector3d& at = take.at(f, plan->index[m]);
      if (!at.allFinite()) continue;
      sum += at;
      ++n;
    }
  }
  const Box box = evaluation_box(*rig, {}, args.volume_centre);
  r.shift_m = box.centre - sum / std::max(n, 1);

  // The per-user calibration: from the take's labelled markers (a labelled calibration session),
  // or through the cameras, from the markers the tracker found on the reference hand.
  std::vector<std::vector<Eigen::Vector3d>> frames;
  if (plan->calibration_frames > 0 && args.calibrate_from == "cameras") {
    HandTrackerSettings finder_settings;
    finder_settings.filter_frame = args.filter_frame;
    HandTracker finder(plan->layout, reference_open_hand(plan->layout.side), finder_settings);
    run_through_rig(take, *plan, r, finder, take.time_s(plan->calibration_frames), false,
                    [&](double, int, const TrackedHand& hand, std::span<const Eigen::Vector3d> points) {
                      if (!hand.hand_seen) return;
                      std::vector<Eigen::Vector3d>& found = frames.emplace_back();
                      for (const int p : hand.marker_point)
                        found.push_back(p >= 0 ? points[static_cast<std::size_t>(p)] : Eigen::Vector3d::Constant(std::nan("")));
                    });
    std::cerr << "rhot-eval: fitting the fingers to the markers found in " << frames.size() << " frames\n";
  } else {
    for (int f = 0; f < plan->calibration_frames; ++f) frames.push_back(layout_frame(take, plan->index, f));
  }
  const auto fitted = fit_hand(*plan, frames);
  if (!fitted) return fail(fitted.error());
  HandTracker tracker = fitted->tracker(args.filter, args.filter_frame);
  const TrackerErrors e = judge_through_rig(take, *plan, r, tracker);
  nlohmann::json j = tracker_report(args, take, *plan, e, fitted->calibration, tracker);
  j["through"] = "the rig's cameras";
  j["calibrate_from"] = args.calibrate_from;
  j["finger_markers_found_fraction"] =
      e.markers_in_view > 0 ? static_cast<double>(e.markers_found) / static_cast<double>(e.markers_in_view) : 0.0;
  j["finger_markers_wrong_fraction"] =
      e.markers_given > 0 ? static_cast<double>(e.markers_wrong) / static_cast<double>(e.markers_given) : 0.0;
  j["rig"] = args.rig_file;
  j["threads"] = r.jobs->threads();
  j["world"] = world_json(*world, args.world.world);
  j["shift_m"] = {r.shift_m.x(), r.shift_m.y(), r.shift_m.z()};
  std::cout << j.dump(2) << "\n";
  return 0;
}

}  // namespace

int hands_take(const HandsArgs& given) {
  HandsArgs args = given;
  const bool through_rig = !args.rig_file.empty();
  if (args.labelled == through_rig)
    return fail("hands --take: --labelled (the take's 3D points) or --rig FILE (the take photographed by the rig's cameras), one of them");
  if (through_rig && !args.layout_given) return fail("hands --take --rig: needs --layout (the markers the cameras follow)");
  if (args.labelled && args.filter_frame_given && args.filter_frame)
    return fail(
        "hands --take --labelled: --filter-frame steadies a hand frame found from the cameras' points; labelled markers "
        "give it as recorded (--filter filters it and the fingertips)");
  if (args.calibrate_from != "labelled" && (!through_rig || args.calibrate_seconds <= 0.0))
    return fail("hands --take: --calibrate-from cameras needs --rig and --calibrate-seconds (the markers found through the cameras)");
  // The frame filter (on by default) acts only where the frame comes from the cameras' points.
  if (args.labelled) args.filter_frame = false;
  const auto take = read_marker_take(args.take_file);
  if (!take) return fail(take.error());
  if (args.layout_given) {
    if (!args.model_file.empty())
      return fail("hands --take: --model is the estimator's alone (without --layout); the tracker fits its own");
    return through_rig ? take_through_rig(args, *take) : take_through_tracker(args, *take);
  }
  if (!args.maps.empty() || args.calibrate_seconds > 0.0 || !args.hides.empty())
    return fail("hands --take: --map, --calibrate-seconds and --hide need --layout");
  // (--filter-frame without --layout is --labelled's refusal above: a take without --layout is labelled.)
  if (args.filter) return fail("hands --take: --filter and --filter-frame need --layout (without it no tracker runs)");
  HiddenMarkerModel model;
  int unfitted_first = 0;
  if (!args.model_file.empty()) {
    auto loaded = load_hidden_marker_model(args.model_file);
    if (!loaded) return fail(loaded.error());
    model = std::move(*loaded);
    unfitted_first = static_cast<int>(std::min(static_cast<double>(take->frame_count() - 1), args.evaluate_from_s * take->frame_rate_hz));
  } else {
    const std::vector<std::string> markers = glove_finger_markers(*take);
    unfitted_first = static_cast<int>(args.fit_fraction * take->frame_count());
    std::cerr << "rhot-eval: fitting a hidden-marker model to frames 1-" << unfitted_first << " of " << take->frame_count() << "\n";
    auto fitted = fit_hidden_marker_model(*take, kGloveFrameMarkers, markers, {.end_frame = unfitted_first});
    if (!fitted) return fail(args.take_file + ": " + fitted.error());
    model = std::move(*fitted);
  }
  const HideSettings hide{.gap_s = args.hide_gap_s, .together = args.hide_together, .seed = args.seed, .first_frame = unfitted_first};
  const auto errors = evaluate_hidden_markers(*take, model, hide);
  if (!errors) return fail(args.take_file + ": " + errors.error());
  nlohmann::json j = take_report(*errors);
  j["take"] = args.take_file;
  j["frames"] = take->frame_count();
  j["frame_rate_hz"] = take->frame_rate_hz;
  j["hide_gap_s"] = args.hide_gap_s;
  j["hide_together"] = args.hide_together;
  j["seed"] = args.seed;
  j["model"] = {{"ridge_mm2", model.ridge_m2 * 1e6},
                {"memory_s", model.memory_s},
                {"training_frames", model.training_frames},
                {"file", args.model_file}};
  j["evaluated_frames"] = {unfitted_first + 1, take->frame_count()};
  if (unfitted_first > 0 && args.model_file.empty()) {
    HideSettings fitted_part = hide;
    fitted_part.first_frame = 0;
    fitted_part.end_frame = unfitted_first;
    const auto on_fitted = evaluate_hidden_markers(*take, model, fitted_part);
    if (on_fitted) j["fitted_part"] = take_report(*on_fitted);
  }
  std::cout << j.dump(2) << "\n";
  return 0;
}

}  // namespace rhot::eval
