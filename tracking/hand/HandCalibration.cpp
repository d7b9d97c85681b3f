#include "tracking/hand/HandCalibration.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <fstream>

#include <nlohmann/json.hpp>

#include "base/Json.h"
#include "tracking/hand/FingerFit.h"

namespace rhot {
namespace {

// A fingertip marker's offset from the tip on the straight finger: its joint's frame there has -Z
// along the rest direction and +Y the finger's up; a marker on the distal joint sits one distal
// bone short of the tip.
Eigen::Vector3d straight_tip_to_marker(const LayoutMarker& marker, const FingerChain& chain, Finger finger) {
  const Eigen::Vector3d x = chain.rest_direction.cross(chain.up);
  Eigen::Vector3d out = marker.offset_m.x() * x + marker.offset_m.y() * chain.up - marker.offset_m.z() * chain.rest_direction;
  if (marker.bone != chain_joints(finger)[3]) out -= chain.length_m[2] * chain.rest_direction;
  return out;
}

// How far a finger's markers, on the finger fitted to them as the tracker fits it (FingerFit.h:
// the tip marker weighing 1, the others HandTracker::kOtherMarkerWeight), are from where they were
// seen: the weighted RMS over every seen marker of `seen` (hand frame; per frame, the finger's
// markers in `markers`' order, the tip marker first, NaN where not seen). `warm`: each frame's
// angles to start its fit from (none: straight), the fitted ones on return.
double reach_rms(std::span<const LayoutMarker* const> markers, const FingerChain& chain, std::span<const std::vector<Eigen::Vector3d>> seen,
                 std::vector<FingerAngles>& warm) {
  double sum = 0.0, n = 0.0;
  warm.resize(seen.size());
  const FingerFitSettings settings = finger_fit_settings(finger_of_bone(markers[0]->bone));
  std::vector<FingerPoint> points;
  for (std::size_t i = 0; i < seen.size(); ++i) {
    points.clear();
    double weights = 0.0;
    for (std::size_t k = 0; k < markers.size(); ++k) {
      if (!seen[i][k].allFinite()) continue;
      const double weight = k == 0 ? 1.0 : HandTracker::kOtherMarkerWeight;
      points.push_back(finger_point(*markers[k], seen[i][k], weight));
      weights += weight;
    }
    const FingerFit fit = fit_finger(chain, points, warm[i], settings);
    warm[i] = fit.angles;
    sum += fit.rms_m * fit.rms_m * weights;
    n += weights;
  }
  return n > 0.0 ? std::sqrt(sum / n) : 0.0;
}

constexpr int kSimplexStarts = 1;

struct ReachFit {
  Eigen::Vector3d knuckle_moved_m = Eigen::Vector3d::Zero();
  double scale = 1.0;
  Eigen::Matrix3d turn = Eigen::Matrix3d::Identity();  // the finger's rest direction and plane turned about its knuckle
  std::vector<Eigen::Vector3d> offsets_m;              // each non-tip marker's fitted offset (markers[1...])
  double rms_before_m = 0.0, rms_after_m = 0.0;
};

// The knuckle's place, the finger's scale, its rest direction (turned sideways and up or down
// about the knuckle) and each other marker's offset (its lift off the bone and its place along it)
// that bring the markers nearest where they were seen (reach_rms), by Nelder and Mead's simplex
// from the reference knuckle, `scale`, the reference direction and the layout's offsets. The
// parameters are in millimetres, hundredths of the scale and hundredths of a radian (about a
// millimetre at a fingertip), so that all weigh alike; the simplex is started twice, the second
// time afresh from the first's best. Moving the knuckle costs as if it added (distance / 30 mm)^2
// mm^2 to the mean square, turning the finger (angle / 0.2 rad)^2 and moving an offset (distance /
// 10 mm)^2, so that what the motion does not pin down stays where it was.
ReachFit fit_reach(std::span<const LayoutMarker* const> markers, const FingerChain& chain, double scale,
                   std::span<const std::vector<Eigen::Vector3d>> seen) {
  const std::size_t others = markers.size() - 1;
  const auto n = static_cast<Eigen::Index>(6 + 2 * others);
  // q: knuckle moved (mm), scale x 100, turned sideways and up (0.01 rad), then per other marker
  // its offset's y and z moved (mm).
  const Eigen::Vector3d lateral = chain.rest_direction.cross(chain.up).normalized();
  const auto turn_of = [&](const Eigen::VectorXd& q) {
    return Eigen::Matrix3d(Eigen::AngleAxisd(0.01 * q(4), chain.up) * Eigen::AngleAxisd(0.01 * q(5), lateral));
  };
  const auto apply = [&](const Eigen::VectorXd& q, std::vector<LayoutMarker>& moved) {
    FingerChain c = chain;
    c.root_m += 1e-3 * q.head<3>();
    for (double& l : c.length_m) l *= 0.01 * q(3);
    const Eigen::Matrix3d turn = turn_of(q);
    c.rest_direction = turn * chain.rest_direction;
    c.up = turn * chain.up;
    moved.clear();
    for (std::size_t k = 0; k < markers.size(); ++k) {
      moved.push_back(*markers[k]);
      if (k == 0) continue;
      const auto i = static_cast<Eigen::Index>(6 + 2 * (k - 1));
      moved.back().offset_m.y() += 1e-3 * q(i);
      moved.back().offset_m.z() += 1e-3 * q(i + 1);
    }
    return c;
  };
  std::vector<LayoutMarker> moved;
  std::vector<const LayoutMarker*> moved_ptr;
  // Every evaluation starts each frame's fit from the angles fitted at the starting parameters
  // (found by the first evaluation, from the straight finger): the score of a set of parameters does
  // not depend on what was tried before it.
  std::vector<FingerAngles> start_angles, warm;
  const auto rms_at = [&](const Eigen::VectorXd& q) {
    const FingerChain c = apply(q, moved);
    moved_ptr.clear();
    for (const LayoutMarker& m : moved) moved_ptr.push_back(&m);
    warm = start_angles;
    const double rms = reach_rms(moved_ptr, c, seen, warm);
    if (start_angles.empty()) start_angles = warm;
    return rms;
  };
  const auto cost = [&](const Eigen::VectorXd& q) {
    if (!(q(3) >= 60.0 && q(3) <= 200.0)) return std::numeric_limits<double>::infinity();
    const double rms_mm = 1e3 * rms_at(q);
    return rms_mm * rms_mm + q.head<3>().squaredNorm() / (30.0 * 30.0) + q.segment<2>(4).squaredNorm() / (20.0 * 20.0) +
           q.tail(n - 6).squaredNorm() / (10.0 * 10.0);
  };
  Eigen::VectorXd q = Eigen::VectorXd::Zero(n);
  q(3) = 100.0 * scale;
  const Eigen::VectorXd start = q;
  const auto points = static_cast<std::size_t>(n + 1);
  for (int restart = 0; restart < kSimplexStarts; ++restart) {
    std::vector<Eigen::VectorXd> x(points, q);
    std::vector<double> fx(points);
    for (std::size_t i = 0; i < points; ++i) {
      if (i > 0) x[i](static_cast<Eigen::Index>(i - 1)) += 4.0;
      fx[i] = cost(x[i]);
    }
    std::vector<std::size_t> order(points);
    for (int iteration = 0; iteration < 150 * static_cast<int>(n); ++iteration) {
      for (std::size_t i = 0; i < points; ++i) order[i] = i;
      std::ranges::sort(order, [&](std::size_t a, std::size_t b) { return fx[a] < fx[b]; });
      const std::size_t best = order.front(), worst = order.back(), second = order[points - 2];
      double size = 0.0;
      for (std::size_t i = 0; i < points; ++i) size = std::max(size, (x[i] - x[best]).cwiseAbs().maxCoeff());
      if (size < 0.2) break;
      Eigen::VectorXd centre = Eigen::VectorXd::Zero(n);
      for (std::size_t i = 0; i < points; ++i) {
        if (i != worst) centre += x[i] / static_cast<double>(n);
      }
      const Eigen::VectorXd reflected = centre + (centre - x[worst]);
      const double fr = cost(reflected);
      if (fr < fx[best]) {
        const Eigen::VectorXd expanded = centre + 2.0 * (centre - x[worst]);
        const double fe = cost(expanded);
        x[worst] = fe < fr ? expanded : reflected;
        fx[worst] = std::min(fe, fr);
      } else if (fr < fx[second]) {
        x[worst] = reflected;
        fx[worst] = fr;
      } else {
        const Eigen::VectorXd contracted = centre + 0.5 * (x[worst] - centre);
        const double fc = cost(contracted);
        if (fc < fx[worst]) {
          x[worst] = contracted;
          fx[worst] = fc;
        } else {
          for (std::size_t i = 0; i < points; ++i) {
            if (i == best) continue;
            x[i] = x[best] + 0.5 * (x[i] - x[best]);
            fx[i] = cost(x[i]);
          }
        }
      }
    }
    q = x[static_cast<std::size_t>(std::min_element(fx.begin(), fx.end()) - fx.begin())];
  }
  ReachFit out;
  out.knuckle_moved_m = 1e-3 * q.head<3>();
  out.scale = 0.01 * q(3);
  out.turn = turn_of(q);
  out.rms_before_m = rms_at(start);
  out.rms_after_m = rms_at(q);
  apply(q, moved);
  for (std::size_t k = 1; k < moved.size(); ++k) out.offsets_m.push_back(moved[k].offset_m);
  return out;
}

}  // namespace

std::optional<HandPose> calibrate_from_labelled(const HandLayout& layout, const HandPose& reference,
                                                std::span<const std::vector<Eigen::Vector3d>> frames, LabelledCalibration* report) {
  LabelledCalibration local;
  LabelledCalibration& r = report != nullptr ? *report : local;
  constexpr std::size_t kReachSamples = 30;
  r = {};
  r.layout = layout;
  HandPose out = reference;
  // Every frame's markers in the hand's frame (where its back is seen).
  std::vector<std::vector<Eigen::Vector3d>> in_hand;
  for (const auto& markers : frames) {
    const auto world_from_hand = labelled_hand_frame(layout, markers);
    if (!world_from_hand) continue;
    const Rigid3d hand_from_world = world_from_hand->inverse();
    std::vector<Eigen::Vector3d> h;
    for (std::size_t m = 0; m < layout.markers.size(); ++m) {
      h.push_back(m < markers.size() && markers[m].allFinite() ? hand_from_world * markers[m] : Eigen::Vector3d::Constant(std::nan("")));
    }
    in_hand.push_back(std::move(h));
  }
  r.frames = static_cast<int>(in_hand.size());
  // The 90th percentile of each finger's tip's distances from the knuckle over the frames (the
  // marker less its offset on the straight finger) stands for the finger held straight.
  const auto chains = hand_chains(reference, layout.side);
  bool any = false;
  for (int f = 0; f < kFingerCount; ++f) {
    const auto fi = static_cast<std::size_t>(f);
    const LayoutMarker* tip = layout.fingertip(f);
    if (tip == nullptr) continue;
    const FingerChain& c = chains[fi];
    const auto m = static_cast<std::size_t>(layout.fingertip_marker[fi]);
    std::vector<double> reach;
    for (const auto& h : in_hand) {
      if (h[m].allFinite()) reach.push_back((h[m] - straight_tip_to_marker(*tip, c, static_cast<Finger>(f)) - c.root_m).norm());
    }
    if (reach.size() < 20) continue;
    std::ranges::sort(reach);
    const double scale =
        reach[static_cast<std::size_t>(0.9 * static_cast<double>(reach.size() - 1))] / (c.length_m[0] + c.length_m[1] + c.length_m[2]);
    if (!(scale > 0.6 && scale < 2.0)) continue;  // not this finger, or never straightened
    // Then the knuckle, the length and the finger's other markers' offsets together: where the
    // finger's markers, on the finger posed to reach its tip marker, come nearest the seen ones over
    // kReachSamples to twice that many frames spread evenly over the run (a middle marker pins the knuckle down where
    // the tip's path alone leaves it loose).
    std::vector<const LayoutMarker*> finger_markers{tip};
    std::vector<std::size_t> finger_marker_index{m};
    for (std::size_t k = layout.hand_frame_markers; k < layout.markers.size(); ++k) {
      if (k != m && layout.finger_of_marker(k) == f) {
        finger_markers.push_back(&layout.markers[k]);
        finger_marker_index.push_back(k);
      }
    }
    std::vector<std::vector<Eigen::Vector3d>> seen;
    for (const auto& h : in_hand) {
      if (!h[m].allFinite()) continue;
      std::vector<Eigen::Vector3d> frame;
      for (const std::size_t k : finger_marker_index) frame.push_back(h[k]);
      seen.push_back(std::move(frame));
    }
    std::vector<std::vector<Eigen::Vector3d>> samples;
    const std::size_t step = std::max<std::size_t>(1, seen.size() / kReachSamples);
    for (std::size_t i = 0; i < seen.size(); i += step) samples.push_back(seen[i]);
    const ReachFit fit = fit_reach(finger_markers, c, scale, samples);
    r.scale[fi] = fit.scale;
    r.knuckle_moved_m[fi] = fit.knuckle_moved_m;
    r.turned_rad[fi] = Eigen::AngleAxisd(fit.turn).angle();
    r.reach_rms_m[fi] = {fit.rms_before_m, fit.rms_after_m};
    for (std::size_t k = 1; k < finger_marker_index.size(); ++k) r.layout.markers[finger_marker_index[k]].offset_m = fit.offsets_m[k - 1];
    const auto joints = chain_joints(static_cast<Finger>(f));
    std::vector<HandJoint> ray(joints.begin(), joints.end());
    if (f != 0) ray.push_back(static_cast<HandJoint>(static_cast<int>(joints[0]) - 1));  // the metacarpal's base: its direction stays
    for (std::size_t k = 1; k < 4; ++k) {
      auto& p = out.position_m[static_cast<std::size_t>(joints[k])];
      p = c.root_m + fit.turn * (fit.scale * (p - c.root_m));
    }
    if (f != 0) {  // a finger's rest direction is its metacarpal's: the metacarpal's base turns about the knuckle too
      auto& base = out.position_m[static_cast<std::size_t>(joints[0]) - 1];
      base = c.root_m + fit.turn * (base - c.root_m);
    }
    for (const HandJoint j : ray) out.position_m[static_cast<std::size_t>(j)] += fit.knuckle_moved_m;
    any = true;
  }
  if (!any) return std::nullopt;
  return out;
}

std::optional<HandPose> calibrate_flat_hand(const HandPose& reference, HandSide side, std::span<const FingertipSample> samples) {
  HandPose out = reference;
  const auto chains = hand_chains(reference, side);
  bool any = false;
  for (int f = 0; f < kFingerCount; ++f) {
    const auto fi = static_cast<std::size_t>(f);
    const FingerChain& c = chains[fi];
    double sum = 0.0;
    int n = 0;
    for (const FingertipSample& s : samples) {
      if (!s[fi] || !s[fi]->allFinite()) continue;
      sum += (*s[fi] - c.root_m).norm();
      ++n;
    }
    if (n == 0) continue;
    const double length = c.length_m[0] + c.length_m[1] + c.length_m[2];
    const double scale = (sum / n) / length;
    if (!(scale > 0.5 && scale < 2.0)) continue;  // not a flat hand, or not this hand
    any = true;
    const auto joints = chain_joints(static_cast<Finger>(f));
    for (std::size_t k = 1; k < 4; ++k) {
      auto& p = out.position_m[static_cast<std::size_t>(joints[k])];
      p = c.root_m + scale * (p - c.root_m);
    }
  }
  if (!any) return std::nullopt;
  return out;
}

FingertipSample flat_hand_sample(const HandLayout& layout, const HandPose& reference, const TrackedHand& hand,
                                 std::span<const Eigen::Vector3d> points_world) {
  FingertipSample sample;
  // Only a frame the star measured: one fitted to the fingertips themselves (frame_from_markers)
  // would put them where the fit did.
  if (!hand.hand_seen || hand.frame_source != HandFrameSource::kStar) return sample;
  const auto chains = hand_chains(reference, layout.side);
  const Rigid3d hand_from_world = hand.world_from_hand.inverse();
  for (std::size_t f = 0; f < kFingerCount; ++f) {
    const int p = hand.fingertip_point[f];
    const LayoutMarker* marker = layout.fingertip(static_cast<int>(f));
    if (p < 0 || static_cast<std::size_t>(p) >= points_world.size() || marker == nullptr) continue;
    sample[f] =
        hand_from_world * points_world[static_cast<std::size_t>(p)] - straight_tip_to_marker(*marker, chains[f], static_cast<Finger>(f));
  }
  return sample;
}

std::expected<void, std::string> save_hand_calibration(const HandPose& skeleton, HandSide side, const std::filesystem::path& file) {
  nlohmann::json j;
  j["format"] = "rhot-hand-calibration";
  j["version"] = 1;
  j["side"] = side == HandSide::kLeft ? "left" : "right";
  for (int k = 0; k < kHandJointCount; ++k) {
    const std::string name(joint_name(static_cast<HandJoint>(k)));
    const Eigen::Vector3d p = 1000.0 * skeleton.position_m[static_cast<std::size_t>(k)];
    j["joints_mm"][name] = {p.x(), p.y(), p.z()};
    j["radii_mm"][name] = 1000.0 * skeleton.radius_m[static_cast<std::size_t>(k)];
  }
  std::ofstream out(file);
  if (!out) return std::unexpected(file.string() + ": cannot write");
  out << j.dump(2) << "\n";
  if (!out) return std::unexpected(file.string() + ": write failed");
  return {};
}

namespace {

std::pair<HandPose, HandSide> read_calibration(const JsonNode& j) {
  j.expect_object({"format", "version", "side", "joints_mm", "radii_mm"});
  const JsonNode format = j["format"];
  if (format.string() != "rhot-hand-calibration") format.fail("expected \"rhot-hand-calibration\", got " + describe_json(format.raw()));
  j["version"].integer_in(1, 1);
  const JsonNode side = j["side"];
  const std::string side_name = side.string();
  if (side_name != "left" && side_name != "right") side.fail("expected \"left\" or \"right\", got " + describe_json(side.raw()));
  const JsonNode joints = j["joints_mm"];
  const JsonNode radii = j["radii_mm"];
  HandPose pose;
  for (int k = 0; k < kHandJointCount; ++k) {
    const std::string name(joint_name(static_cast<HandJoint>(k)));
    const auto p = joints[name.c_str()].numbers(3);
    pose.position_m[static_cast<std::size_t>(k)] = 1e-3 * Eigen::Vector3d(p[0], p[1], p[2]);
    pose.radius_m[static_cast<std::size_t>(k)] = 1e-3 * radii[name.c_str()].positive();
  }
  return {pose, side_name == "left" ? HandSide::kLeft : HandSide::kRight};
}

}  // namespace

std::expected<std::pair<HandPose, HandSide>, std::string> load_hand_calibration(const std::filesystem::path& file) {
  auto calibration = read_json_file<std::pair<HandPose, HandSide>>(file, "hand calibration", read_calibration);
  if (!calibration) return std::unexpected(calibration.error().to_string());
  return *calibration;
}

}  // namespace rhot
