#include "tracking/hand/HiddenMarkers.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <random>

#include <Eigen/Cholesky>
#include <nlohmann/json.hpp>

#include "base/Check.h"

namespace rhot {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Entries of a 3-per-marker vector that belong to the markers in `mask` (bit m: marker m).
std::vector<Eigen::Index> coordinates(std::uint64_t mask, int markers) {
  std::vector<Eigen::Index> out;
  for (int m = 0; m < markers; ++m) {
    if ((mask >> m & 1u) == 0) continue;
    for (int k = 0; k < 3; ++k) out.push_back(3 * m + k);
  }
  return out;
}

// The markers' indices in the take, or the first missing name.
std::expected<std::vector<int>, std::string> indices_in(const MarkerTake& take, std::span<const std::string> names) {
  std::vector<int> out;
  for (const std::string& name : names) {
    const auto m = take.marker(name);
    if (!m) return std::unexpected("the take has no marker \"" + name + "\"");
    out.push_back(*m);
  }
  return out;
}

std::string error_at(const std::filesystem::path& file, const std::string& what) { return file.string() + ": " + what; }

}  // namespace

std::optional<Rigid3d> hand_frame_from_markers(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  if (!a.allFinite() || !b.allFinite() || !c.allFinite()) return std::nullopt;
  const Eigen::Vector3d across = c - b, normal = across.cross(a - b);
  if (across.norm() < 1e-4 || normal.norm() < 1e-8) return std::nullopt;
  Eigen::Matrix3d r;
  r.col(0) = across.normalized();
  r.col(2) = normal.normalized();
  r.col(1) = r.col(2).cross(r.col(0));
  return Rigid3d{Eigen::Quaterniond(r).normalized(), (a + b + c) / 3.0};
}

std::vector<int> fingertip_markers(const HiddenMarkerModel& model) {
  std::vector<int> out;
  for (std::size_t m = 0; m < model.markers.size(); ++m) {
    const std::string& name = model.markers[m];
    if (name.size() > 4 && name.ends_with("_tip")) out.push_back(static_cast<int>(m));
  }
  return out;
}

HiddenMarkerEstimator::HiddenMarkerEstimator(HiddenMarkerModel model, bool keep_predictors)
    : model_(std::move(model)),
      keep_predictors_(keep_predictors),
      last_seen_(Eigen::VectorXd::Constant(3 * static_cast<Eigen::Index>(model_.markers.size()), kNaN)),
      hidden_since_s_(model_.markers.size(), kNaN),
      remembered_error_(model_.markers.size(), Eigen::Vector3d::Zero()) {}

const Eigen::MatrixXd& HiddenMarkerEstimator::gain(std::uint64_t visible) {
  const auto cached = gains_.find(visible);
  if (cached != gains_.end()) return cached->second;
  return gains_.emplace(visible, compute_gain(visible)).first->second;
}

Eigen::MatrixXd HiddenMarkerEstimator::compute_gain(std::uint64_t visible) const {
  const int n = static_cast<int>(model_.markers.size());
  const std::uint64_t all = n >= 64 ? ~0ull : (1ull << n) - 1;
  const std::vector<Eigen::Index> v = coordinates(visible, n), h = coordinates(all & ~visible, n);
  Eigen::MatrixXd c_vv = model_.covariance_m2(v, v);
  c_vv.diagonal().array() += model_.ridge_m2;
  const Eigen::MatrixXd c_hv = model_.covariance_m2(h, v);
  // gain = C_HV (C_VV + ridge)^-1, through the symmetric system: (C_VV + ridge) gain^T = C_VH.
  return c_vv.ldlt().solve(c_hv.transpose()).transpose();
}

Eigen::Vector3d HiddenMarkerEstimator::predict(int marker, std::uint64_t visible, const Eigen::VectorXd& hand_positions) {
  const int n = static_cast<int>(model_.markers.size());
  const std::vector<Eigen::Index> v = coordinates(visible, n);
  const std::uint64_t all = n >= 64 ? ~0ull : (1ull << n) - 1;
  const std::vector<Eigen::Index> h = coordinates(all & ~visible, n);
  const auto row = std::ranges::find(h, 3 * marker) - h.begin();
  const Eigen::VectorXd x_v = hand_positions(v) - model_.mean_m(v);
  if (keep_predictors_) return model_.mean_m.segment<3>(3 * marker) + gain(visible).middleRows(row, 3) * x_v;
  return model_.mean_m.segment<3>(3 * marker) + compute_gain(visible).middleRows(row, 3) * x_v;
}

MarkerStatistics::MarkerStatistics(int markers)
    : mean_(Eigen::VectorXd::Zero(3 * markers)), scatter_(Eigen::MatrixXd::Zero(3 * markers, 3 * markers)) {}

void MarkerStatistics::add(const Eigen::VectorXd& x) {
  RHOT_PRECONDITION(x.size() == mean_.size() && x.allFinite(), "every marker seen, once each");
  ++frames_;
  const Eigen::VectorXd before = x - mean_;
  mean_ += before / frames_;
  scatter_.noalias() += before * (x - mean_).transpose();
}

Eigen::MatrixXd MarkerStatistics::covariance_m2() const {
  if (frames_ < 2) return Eigen::MatrixXd::Zero(mean_.size(), mean_.size());
  const Eigen::MatrixXd c = scatter_ / (frames_ - 1);
  return 0.5 * (c + c.transpose());
}

void HiddenMarkerEstimator::set_statistics(Eigen::VectorXd mean_m, Eigen::MatrixXd covariance_m2, int training_frames) {
  const auto n = 3 * static_cast<Eigen::Index>(model_.markers.size());
  RHOT_PRECONDITION(mean_m.size() == n && covariance_m2.rows() == n && covariance_m2.cols() == n, "statistics of another model's size");
  model_.mean_m = std::move(mean_m);
  model_.covariance_m2 = std::move(covariance_m2);
  model_.training_frames = training_frames;
  gains_.clear();
}

std::vector<HiddenMarkerEstimator::Marker> HiddenMarkerEstimator::update(double time_s,
                                                                         std::span<const Eigen::Vector3d, 3> frame_markers_world,
                                                                         std::span<const Eigen::Vector3d> markers_world) {
  const std::size_t n = model_.markers.size();
  std::vector<Marker> out(n);
  const std::optional<Rigid3d> world_from_hand =
      hand_frame_from_markers(frame_markers_world[0], frame_markers_world[1], frame_markers_world[2]);
  if (!world_from_hand) {
    // Seen markers are passed on; the hidden ones stay where they were last seen, in the last frame.
    for (std::size_t m = 0; m < n; ++m) {
      const Eigen::Vector3d last = last_seen_.segment<3>(3 * static_cast<Eigen::Index>(m));
      if (markers_world[m].allFinite()) {
        out[m] = {markers_world[m], MarkerEstimate::kSeen};
      } else if (last.allFinite() && last_frame_) {
        out[m] = {*last_frame_ * last, MarkerEstimate::kHeld};
      }
    }
    hand_lost();
    return out;
  }
  const Rigid3d hand_from_world = world_from_hand->inverse();
  std::vector<Eigen::Vector3d> markers_hand(n, Eigen::Vector3d::Constant(kNaN));
  for (std::size_t m = 0; m < n; ++m) {
    if (markers_world[m].allFinite()) markers_hand[m] = hand_from_world * markers_world[m];
  }
  out = update_in_hand(time_s, markers_hand);
  for (std::size_t m = 0; m < n; ++m) {
    out[m].position_m = out[m].how == MarkerEstimate::kSeen ? markers_world[m] : *world_from_hand * out[m].position_m;
  }
  last_frame_ = world_from_hand;
  return out;
}

std::vector<HiddenMarkerEstimator::Marker> HiddenMarkerEstimator::update_in_hand(double time_s,
                                                                                 std::span<const Eigen::Vector3d> markers_hand) {
  const int n = static_cast<int>(model_.markers.size());
  RHOT_PRECONDITION(static_cast<int>(markers_hand.size()) == n, "one position per modelled marker");
  std::vector<Marker> out(static_cast<std::size_t>(n));
  Eigen::VectorXd x = Eigen::VectorXd::Constant(3 * n, kNaN);
  std::uint64_t visible = 0;
  for (int m = 0; m < n; ++m) {
    const Eigen::Vector3d& p = markers_hand[static_cast<std::size_t>(m)];
    if (!p.allFinite()) continue;
    out[static_cast<std::size_t>(m)] = {p, MarkerEstimate::kSeen};
    x.segment<3>(3 * m) = p;
    visible |= 1ull << m;
  }
  // Markers hidden from this frame on: the predictor's error on the last frame, from the markers
  // seen both then and now (their positions then, before this frame's overwrite them).
  const std::uint64_t known_before = visible & previous_visible_;
  for (int m = 0; m < n; ++m) {
    const auto i = static_cast<std::size_t>(m);
    if ((visible >> m & 1u) != 0) {
      hidden_since_s_[i] = kNaN;
      continue;
    }
    if (!std::isnan(hidden_since_s_[i])) continue;
    hidden_since_s_[i] = time_s;
    remembered_error_[i].setZero();
    if (last_seen_.segment<3>(3 * m).allFinite() && known_before != 0) {
      remembered_error_[i] = last_seen_.segment<3>(3 * m) - predict(m, known_before, last_seen_);
    }
  }
  for (int m = 0; m < n; ++m) {
    if ((visible >> m & 1u) != 0) last_seen_.segment<3>(3 * m) = x.segment<3>(3 * m);
  }
  for (int m = 0; m < n; ++m) {
    const auto i = static_cast<std::size_t>(m);
    if (out[i].how == MarkerEstimate::kSeen) continue;
    const Eigen::Vector3d last = last_seen_.segment<3>(3 * m);
    if (visible != 0) {
      const double fade = model_.memory_s > 0.0 ? std::exp(-(time_s - hidden_since_s_[i]) / model_.memory_s) : 0.0;
      out[i] = {predict(m, visible, x) + fade * remembered_error_[i], MarkerEstimate::kPredicted};
    } else if (last.allFinite()) {
      out[i] = {last, MarkerEstimate::kHeld};
    }
  }
  previous_visible_ = visible;
  return out;
}

std::vector<std::string> glove_finger_markers(const MarkerTake& take) {
  std::vector<std::string> markers;
  for (const char* finger : {"thumb", "index", "middle", "ring", "little"}) {
    for (const char* part : {"_tip", "_middle"}) {
      std::string name = std::string(finger) + part;
      if (take.marker(name)) markers.push_back(std::move(name));
    }
  }
  return markers;
}

std::optional<HideSchedule> HideSchedule::make(const HideSettings& settings, double frame_rate_hz, std::size_t tips) {
  if (!(settings.gap_s > 0.0) || !std::isfinite(settings.gap_s) || !(frame_rate_hz > 0.0) || tips == 0) return std::nullopt;
  HideSchedule out;
  out.first_ = settings.first_frame;
  out.gap_ = static_cast<int>(std::clamp(std::round(settings.gap_s * frame_rate_hz), 1.0, 1e6));
  std::mt19937 rng(settings.seed);
  out.offset_ = std::uniform_int_distribution<int>(0, 2 * out.gap_ - 1)(rng);
  out.together_ = settings.together;
  out.tips_ = tips;
  return out;
}

std::vector<std::size_t> HideSchedule::hidden(int frame) const {
  std::vector<std::size_t> out;
  const int since = frame - first_ + offset_;
  if (since < 0 || since % (2 * gap_) >= gap_) return out;
  const auto k = static_cast<std::size_t>(since / (2 * gap_)) % tips_;
  out.push_back(k);
  if (together_ >= 2 && tips_ >= 2) out.push_back(k + 1 < tips_ ? k + 1 : k - 1);
  return out;
}

std::expected<HiddenMarkerErrors, std::string> evaluate_hidden_markers(const MarkerTake& take, const HiddenMarkerModel& model,
                                                                       const HideSettings& settings) {
  const auto frame_index = indices_in(take, model.frame_markers);
  if (!frame_index) return std::unexpected(frame_index.error());
  const auto marker_index = indices_in(take, model.markers);
  if (!marker_index) return std::unexpected(marker_index.error());
  const int first = std::max(settings.first_frame, 0);
  const int end = settings.end_frame < 0 ? take.frame_count() : std::min(settings.end_frame, take.frame_count());
  if (end <= first) return std::unexpected("no frames to evaluate");
  const std::vector<int> tips = fingertip_markers(model);
  if (tips.empty()) return std::unexpected("the model has no fingertip marker (a name ending in \"_tip\")");

  HideSettings from_first = settings;
  from_first.first_frame = first;
  const auto schedule = HideSchedule::make(from_first, take.frame_rate_hz, tips.size());
  if (!schedule) return std::unexpected("the hiding gap must be a positive number of seconds");
  HiddenMarkerEstimator estimator(model);
  HiddenMarkerErrors errors;
  const int n = static_cast<int>(model.markers.size());
  std::vector<Eigen::Vector3d> held_hand(static_cast<std::size_t>(n), Eigen::Vector3d::Constant(kNaN));
  std::vector<Eigen::Vector3d> markers(static_cast<std::size_t>(n));
  for (int f = first; f < end; ++f) {
    std::vector<int> hidden;
    for (const std::size_t k : schedule->hidden(f)) hidden.push_back(tips[k]);
    const std::array<Eigen::Vector3d, 3> frame{take.at(f, (*frame_index)[0]), take.at(f, (*frame_index)[1]), take.at(f, (*frame_index)[2])};
    for (int m = 0; m < n; ++m) {
      const bool hide = std::ranges::find(hidden, m) != hidden.end();
      markers[static_cast<std::size_t>(m)] =
          hide ? Eigen::Vector3d::Constant(kNaN) : take.at(f, (*marker_index)[static_cast<std::size_t>(m)]);
    }
    const auto estimate = estimator.update(take.time_s(f), frame, markers);
    const std::optional<Rigid3d> world_from_hand = hand_frame_from_markers(frame[0], frame[1], frame[2]);
    for (int m = 0; m < n; ++m) {
      const auto i = static_cast<std::size_t>(m);
      if (world_from_hand && markers[i].allFinite()) held_hand[i] = world_from_hand->inverse() * markers[i];
    }
    for (const int m : hidden) {
      const auto i = static_cast<std::size_t>(m);
      const Eigen::Vector3d& recorded = take.at(f, (*marker_index)[i]);
      if (!recorded.allFinite() || !world_from_hand || !held_hand[i].allFinite()) continue;
      ++errors.hidden_frames;
      if (estimate[i].how == MarkerEstimate::kUnknown) continue;
      const double e = 1e3 * (estimate[i].position_m - recorded).norm();
      errors.hidden_mm.push_back(e);
      errors.hidden_by_marker_mm[model.markers[i]].push_back(e);
      errors.held_mm.push_back(1e3 * (*world_from_hand * held_hand[i] - recorded).norm());
    }
  }
  return errors;
}

std::expected<HiddenMarkerModel, std::string> fit_hidden_marker_model(const MarkerTake& take,
                                                                      const std::array<std::string, 3>& frame_markers,
                                                                      const std::vector<std::string>& markers,
                                                                      const HiddenMarkerFitSettings& settings) {
  if (markers.empty() || markers.size() > 63) return std::unexpected("a model holds 1 to 63 markers");
  const auto frame_index = indices_in(take, frame_markers);
  if (!frame_index) return std::unexpected(frame_index.error());
  const auto marker_index = indices_in(take, markers);
  if (!marker_index) return std::unexpected(marker_index.error());
  const int first = std::max(settings.first_frame, 0);
  const int end = settings.end_frame < 0 ? take.frame_count() : std::min(settings.end_frame, take.frame_count());
  const auto n = static_cast<Eigen::Index>(markers.size());
  MarkerStatistics samples(static_cast<int>(n));
  for (int f = first; f < end; ++f) {
    const auto world_from_hand =
        hand_frame_from_markers(take.at(f, (*frame_index)[0]), take.at(f, (*frame_index)[1]), take.at(f, (*frame_index)[2]));
    if (!world_from_hand) continue;
    Eigen::VectorXd x(3 * n);
    bool all = true;
    for (Eigen::Index m = 0; m < n && all; ++m) {
      const Eigen::Vector3d& p = take.at(f, (*marker_index)[static_cast<std::size_t>(m)]);
      all = p.allFinite();
      if (all) x.segment<3>(3 * m) = world_from_hand->inverse() * p;
    }
    if (all) samples.add(x);
  }
  const int needed = static_cast<int>(3 * n + 10);
  if (samples.frames() < needed) {
    return std::unexpected("only " + std::to_string(samples.frames()) + " frames with the hand's frame and every marker seen (" +
                           std::to_string(needed) + " needed)");
  }
  HiddenMarkerModel model;
  model.frame_markers = frame_markers;
  model.markers = markers;
  model.training_frames = samples.frames();
  model.mean_m = samples.mean_m();
  model.covariance_m2 = samples.covariance_m2();

  // The ridge and the memory that hide the tips best over the fitted frames.
  double best = std::numeric_limits<double>::infinity();
  HiddenMarkerModel candidate = model;
  for (const double ridge : settings.ridge_candidates_m2) {
    for (const double memory : settings.memory_candidates_s) {
      candidate.ridge_m2 = ridge;
      candidate.memory_s = memory;
      const auto errors = evaluate_hidden_markers(take, candidate, {.first_frame = first, .end_frame = end});
      if (!errors || errors->hidden_mm.empty()) continue;
      double sum = 0.0;
      for (const double e : errors->hidden_mm) sum += e;
      if (sum / static_cast<double>(errors->hidden_mm.size()) < best) {
        best = sum / static_cast<double>(errors->hidden_mm.size());
        model.ridge_m2 = ridge;
        model.memory_s = memory;
      }
    }
  }
  return model;
}

std::expected<void, std::string> save_hidden_marker_model(const HiddenMarkerModel& model, const std::filesystem::path& file) {
  nlohmann::json j;
  j["format"] = "rhot-hidden-marker-model";
  j["version"] = 1;
  j["source"] = model.source;
  j["frame_markers"] = model.frame_markers;
  j["markers"] = model.markers;
  j["training_frames"] = model.training_frames;
  j["ridge_mm2"] = model.ridge_m2 * 1e6;
  j["memory_s"] = model.memory_s;
  std::vector<double> mean(static_cast<std::size_t>(model.mean_m.size()));
  for (Eigen::Index i = 0; i < model.mean_m.size(); ++i) mean[static_cast<std::size_t>(i)] = model.mean_m[i] * 1e3;
  j["mean_mm"] = mean;
  std::vector<std::vector<double>> covariance;
  for (Eigen::Index r = 0; r < model.covariance_m2.rows(); ++r) {
    covariance.emplace_back();
    for (Eigen::Index c = 0; c < model.covariance_m2.cols(); ++c) covariance.back().push_back(model.covariance_m2(r, c) * 1e6);
  }
  j["covariance_mm2"] = covariance;
  std::ofstream out(file);
  out << j.dump(1) << '\n';
  if (!out) return std::unexpected(error_at(file, "cannot be written"));
  return {};
}

std::expected<HiddenMarkerModel, std::string> load_hidden_marker_model(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) return std::unexpected(error_at(file, "cannot be opened"));
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.is_object()) return std::unexpected(error_at(file, "not JSON"));
  HiddenMarkerModel model;
  try {
    if (j.value("format", "") != "rhot-hidden-marker-model")
      return std::unexpected(error_at(file, "format: expected \"rhot-hidden-marker-model\""));
    model.source = j.value("source", "");
    const auto frame = j.at("frame_markers").get<std::vector<std::string>>();
    if (frame.size() != 3) return std::unexpected(error_at(file, "frame_markers: expected three names"));
    std::ranges::copy(frame, model.frame_markers.begin());
    model.markers = j.at("markers").get<std::vector<std::string>>();
    model.training_frames = j.value("training_frames", 0);
    model.ridge_m2 = j.at("ridge_mm2").get<double>() * 1e-6;
    model.memory_s = j.at("memory_s").get<double>();
    const auto mean = j.at("mean_mm").get<std::vector<double>>();
    const auto covariance = j.at("covariance_mm2").get<std::vector<std::vector<double>>>();
    const std::size_t size = 3 * model.markers.size();
    if (model.markers.empty() || model.markers.size() > 63) return std::unexpected(error_at(file, "markers: expected 1 to 63 names"));
    if (mean.size() != size)
      return std::unexpected(error_at(file, "mean_mm: expected " + std::to_string(size) + " numbers (3 per marker)"));
    if (covariance.size() != size || std::ranges::any_of(covariance, [&](const auto& row) { return row.size() != size; })) {
      return std::unexpected(error_at(file, "covariance_mm2: expected " + std::to_string(size) + " rows of " + std::to_string(size)));
    }
    model.mean_m = Eigen::Map<const Eigen::VectorXd>(mean.data(), static_cast<Eigen::Index>(size)) * 1e-3;
    model.covariance_m2.resize(static_cast<Eigen::Index>(size), static_cast<Eigen::Index>(size));
    for (std::size_t r = 0; r < size; ++r) {
      for (std::size_t c = 0; c < size; ++c)
        model.covariance_m2(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = covariance[r][c] * 1e-6;
    }
  } catch (const nlohmann::json::exception& e) {
    return std::unexpected(error_at(file, std::string("missing or mistyped field: ") + e.what()));
  }
  if (!model.mean_m.allFinite() || !model.covariance_m2.allFinite() || !std::isfinite(model.ridge_m2) || model.ridge_m2 < 0.0 ||
      !std::isfinite(model.memory_s) || model.memory_s < 0.0) {
    return std::unexpected(error_at(file, "numbers must be finite, and ridge_mm2 and memory_s not negative"));
  }
  if (!model.covariance_m2.isApprox(model.covariance_m2.transpose(), 1e-9))
    return std::unexpected(error_at(file, "covariance_mm2: not symmetric"));
  return model;
}

}  // namespace rhot
