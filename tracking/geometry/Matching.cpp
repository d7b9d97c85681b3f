#include "tracking/geometry/Matching.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <unordered_map>

#include <Eigen/Geometry>
#include <opencv2/calib3d.hpp>

#include "base/Capacity.h"
#include "base/Check.h"
#include "base/Jobs.h"
#include "tracking/geometry/EpipolarIndex.h"

namespace rhot {

// The working storage of one frame's matching, named so that MatchScratch (kept by a RigMatcher
// from frame to frame) can hold it.
namespace matching_detail {

// Detections of one camera: pixels, undistorted normalised coordinates, and a coarse grid over
// the image for nearest-detection lookups.
struct CameraDetections {
  std::vector<Eigen::Vector2d> pixel;
  std::vector<int> colour;  // per detection: its marker colour, -1 for none
  std::vector<Eigen::Vector2d> normalised;
  double cell_px = 16.0;  // set by build
  int cols = 0;
  int rows = 0;
  // The grid as compressed rows: detections of cell c are items[cell_start[c] .. cell_start[c + 1]),
  // each with what a lookup needs, so that a lookup reads one run of memory after cell_start.
  // Plain doubles rather than an Eigen vector, which would pad the item to 32 bytes: the items
  // of every camera then fit the cache together better.
  struct Item {
    double x = 0.0;
    double y = 0.0;
    int detection = -1;
    int colour = -1;
  };
  std::vector<int> cell_start;
  std::vector<Item> items;
  // Per detection: it seeded (or joined) a cluster three or more cameras confirm; and how many
  // are not (Matcher::keep counts them down).
  std::vector<char> explained;
  std::size_t open = 0;
  // Per detection: the first link of its list of clusters (see Membership), -1 for none.
  std::vector<int> first_link;
  // build's own: the detections OpenCV undistorts, and each detection's cell while filling the grid.
  std::vector<cv::Point2d> hard_in;
  std::vector<cv::Point2d> hard_out;
  std::vector<std::size_t> hard;
  std::vector<int> cell_of;
  std::vector<int> fill;

  // What the frame's detections replace (the storage is kept).
  void build(const Camera& camera, const CameraFrame& frame) {
    const std::size_t n = frame.detections.size();
    for (auto* v : {&pixel, &normalised}) reserve_room(*v, n);
    for (auto* v : {&colour, &cell_of, &first_link}) reserve_room(*v, n);
    reserve_room(explained, n);
    reserve_room(items, n);
    pixel.clear();
    colour.clear();
    for (const Detection& d : frame.detections) {
      pixel.push_back(d.pixel);
      colour.push_back(d.colour);
    }
    // Undistorted by Newton's method; OpenCV's iteration for the few it does not converge on.
    normalised.resize(pixel.size());
    const CameraIntrinsics& k = camera.intrinsics;
    hard_in.clear();
    hard.clear();
    for (std::size_t i = 0; i < pixel.size(); ++i) {
      const Eigen::Vector2d distorted((pixel[i].x() - k.cx) / k.fx, (pixel[i].y() - k.cy) / k.fy);
      if (const auto xy = undistort_normalised(k.distortion, distorted)) {
        normalised[i] = *xy;
      } else {
        hard_in.emplace_back(pixel[i].x(), pixel[i].y());
        hard.push_back(i);
      }
    }
    if (!hard_in.empty()) {
      cv::undistortPoints(hard_in, hard_out, cv::Matx33d(k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1), cv::Vec<double, 5>(k.distortion.data()),
                          cv::noArray(), cv::noArray(), cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 20, 1e-12));
      for (std::size_t h = 0; h < hard.size(); ++h) normalised[hard[h]] = {hard_out[h].x, hard_out[h].y};
    }
    // About one detection a cell: a lookup visits one to four cells holding a detection or two,
    // and the grid stays small enough to sit in the cache beside the other cameras'.
    const double area = static_cast<double>(camera.intrinsics.width_px) * camera.intrinsics.height_px;
    cell_px = std::clamp(std::sqrt(area / static_cast<double>(std::max<std::size_t>(pixel.size(), 1))), 8.0, 256.0);
    cols = std::max(1, static_cast<int>(std::ceil(camera.intrinsics.width_px / cell_px)) + 1);
    rows = std::max(1, static_cast<int>(std::ceil(camera.intrinsics.height_px / cell_px)) + 1);
    reserve_room(cell_start, static_cast<std::size_t>(cols * rows) + 1);
    reserve_room(fill, static_cast<std::size_t>(cols * rows));
    cell_start.assign(static_cast<std::size_t>(cols * rows) + 1, 0);
    cell_of.resize(pixel.size());
    for (std::size_t i = 0; i < pixel.size(); ++i) {
      cell_of[i] = cell(pixel[i]);
      if (cell_of[i] >= 0) ++cell_start[static_cast<std::size_t>(cell_of[i]) + 1];
    }
    for (std::size_t c = 1; c < cell_start.size(); ++c) cell_start[c] += cell_start[c - 1];
    items.assign(static_cast<std::size_t>(cell_start.back()), Item{});
    fill.assign(cell_start.begin(), cell_start.end() - 1);
    for (std::size_t i = 0; i < pixel.size(); ++i) {
      if (cell_of[i] < 0) continue;
      items[static_cast<std::size_t>(fill[static_cast<std::size_t>(cell_of[i])]++)] = {pixel[i].x(), pixel[i].y(), static_cast<int>(i),
                                                                                       colour[i]};
    }
    explained.assign(pixel.size(), 0);
    open = pixel.size();
    first_link.assign(pixel.size(), -1);
  }
  int cell(const Eigen::Vector2d& p) const {
    const int x = static_cast<int>(std::floor((p.x() + 0.5) / cell_px));
    const int y = static_cast<int>(std::floor((p.y() + 0.5) / cell_px));
    return (x < 0 || y < 0 || x >= cols || y >= rows) ? -1 : y * cols + x;
  }
  // Nearest detection of a colour (-1: uncoloured) within `radius` of p, or -1. Visits only the
  // cells the disc overlaps. With `alone`: whether it is the only one of its colour within `radius`.
  int nearest(const Eigen::Vector2d& p, double radius, int of_colour, bool* alone = nullptr) const {
    if (alone != nullptr) *alone = true;
    // Far outside the grid (or NaN): nothing to find, and the cell arithmetic below would overflow.
    if (!(p.x() > -radius - 1.0 && p.y() > -radius - 1.0 && p.x() < cols * cell_px && p.y() < rows * cell_px)) return -1;
    // Truncation rather than std::floor (a call's worth of instructions without SSE4.1): they
    // differ only between -1 and 0, where the first cell is clamped to 0 either way and the last
    // is at most one column or row more, whose detections lie further than `radius` (the distance
    // test below refuses them but for a rounding tie at exactly `radius`).
    const int x0 = std::max(0, static_cast<int>((p.x() + 0.5 - radius) / cell_px));
    const int y0 = std::max(0, static_cast<int>((p.y() + 0.5 - radius) / cell_px));
    const int x1 = std::min(cols - 1, static_cast<int>((p.x() + 0.5 + radius) / cell_px));
    const int y1 = std::min(rows - 1, static_cast<int>((p.y() + 0.5 + radius) / cell_px));
    int best = -1;
    double best_d2 = radius * radius;
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const auto c = static_cast<std::size_t>(y * cols + x);
        for (int s = cell_start[c]; s < cell_start[c + 1]; ++s) {
          const Item& item = items[static_cast<std::size_t>(s)];
          if (item.colour != of_colour) continue;
          const double dx = item.x - p.x();
          const double dy = item.y - p.y();
          const double d2 = dx * dx + dy * dy;
          if (alone != nullptr && best >= 0 && d2 <= radius * radius) *alone = false;
          if (d2 <= best_d2) {
            best_d2 = d2;
            best = item.detection;
          }
        }
      }
    }
    return best;
  }
};

struct Cluster {
  std::vector<int> detection;  // per camera, -1 where none
  int colour = -1;             // its detections' colour (all share it)
  Eigen::Vector3d seed_point{0, 0, 0};
  int support = 0;
  int missing = 0;
  TriangulatedPoint point;
  std::vector<Observation> observations;
  // grow_seed's refinement, kept when it is of exactly the detections the cluster holds (refine
  // then starts from it instead of computing it again).
  bool has_seed_refined = false;
  TriangulatedPoint seed_refined;
  int followed = -1;  // the last frame's point it was grown from (MatchSettings::follow_points), -1 for a seed

  // Room for a point seen by every camera in each vector (done once: a cluster reused frame after
  // frame then never grows).
  void reserve(std::size_t cameras) {
    if (detection.capacity() >= cameras && observations.capacity() >= cameras && point.cameras.capacity() >= cameras &&
        seed_refined.cameras.capacity() >= cameras)
      return;
    detection.reserve(cameras);
    observations.reserve(cameras);
    point.cameras.reserve(cameras);
    seed_refined.cameras.reserve(cameras);
  }
};

// A seed grown into the other cameras (Matcher::grow_seed): a cluster, or a ghost (no detections).
struct Grown {
  Cluster cluster;
  bool confirmed = false;
};

// One detection's seeds in a pair of cameras: the candidates on its epipolar line that may seed
// (of its colour, meeting it inside the seed volume), nearest the line first, and those grown
// ahead of time (Matcher::seed_pair).
struct Candidate {
  double residual = 0.0;  // off the epipolar line (normalised units)
  int b = -1;
  Eigen::Vector3d x{0, 0, 0};  // where the two rays meet
  bool operator<(const Candidate& o) const { return residual < o.residual || (residual == o.residual && b < o.b); }
};
// A point of the last frame, looked for first in the next (MatchSettings::follow_points).
struct Followed {
  Eigen::Vector3d position{0, 0, 0};
  Eigen::Vector3d velocity{0, 0, 0};  // per second; zero until the point has been linked to one before it
  int colour = -1;
};
struct SeedPlan {
  std::vector<Candidate> candidates;
  std::vector<char> has_grown;  // per candidate: grown ahead, into MatchScratch::ahead[first_grown + c]
  std::size_t first_grown = 0;
};

}  // namespace matching_detail

// One frame's working storage, kept by RigMatcher::match_frame from frame to frame: every vector
// keeps its capacity, and clusters and points are reused in place (counted, never shrunk), so
// that once frames have shown it their largest counts, matching allocates nothing.
struct MatchScratch {
  std::vector<matching_detail::CameraDetections> cams;
  std::vector<std::pair<int, int>> links;
  std::vector<matching_detail::Cluster> clusters;  // the first cluster_count are this frame's
  std::size_t cluster_count = 0;
  EpipolarIndex index;
  std::vector<std::size_t> open;
  std::vector<matching_detail::SeedPlan> plans;
  std::vector<matching_detail::Grown> ahead;  // the seeds of a pair's plans grown ahead, plan after plan
  // MatchSettings::follow_points: the last frame's points and its time, each point grown from
  // where it is expected now (one slot each), and per point of this frame the followed point it
  // grew from (-1: seeded), with which followed points no point of this frame grew from.
  std::vector<matching_detail::Followed> followed;
  std::vector<matching_detail::Followed> next_followed;
  double followed_time_s = std::numeric_limits<double>::quiet_NaN();
  std::vector<matching_detail::Grown> from_followed;
  std::vector<int> point_followed;
  std::vector<char> followed_claimed;
  std::vector<std::size_t> followed_lost;
  std::size_t followed_points = 0;  // of this frame's points, those grown from a followed point
  matching_detail::Grown grown;     // the serial pass's seed
  std::vector<std::size_t> order;
  // Per camera and detection: kUsed, a point took it; kContested, two markers' points wanted it (Matcher::accept).
  std::vector<std::vector<char>> used;
  bool any_contested = false;
  Observation dropped;
  TriangulatedPoint again;
  std::vector<MatchedPoint> points;  // the first point_count are this frame's
  std::size_t point_count = 0;
};

namespace {

using namespace matching_detail;

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

// A two-view seed: the midpoint of the rays' closest approach, or nothing when the rays are
// (nearly) parallel or meet behind either camera. Refinement makes it optimal later.
std::optional<Eigen::Vector3d> ray_midpoint(const Eigen::Vector3d& o1, const Eigen::Vector3d& d1, const Eigen::Vector3d& o2,
                                            const Eigen::Vector3d& d2) {
  const Eigen::Vector3d w = o1 - o2;
  const double a = d1.dot(d1), b = d1.dot(d2), c = d2.dot(d2), d = d1.dot(w), e = d2.dot(w);
  const double denom = a * c - b * b;
  if (!(denom > 1e-10 * a * c)) return std::nullopt;
  const double s = (b * e - c * d) / denom;
  const double t = (a * e - b * d) / denom;
  if (!(s > 0.0 && t > 0.0)) return std::nullopt;
  return 0.5 * ((o1 + s * d1) + (o2 + t * d2));
}

}  // namespace

std::optional<double> estimate_pixel_sigma(std::span<const MatchedPoint> points) {
  double sum = 0.0;
  double dof = 0.0;
  for (const MatchedPoint& m : points) {
    const auto n = static_cast<double>(m.observations.size());
    if (n < 2.0) continue;
    sum += n * m.point.reprojection_rms_px * m.point.reprojection_rms_px;
    dof += 2.0 * n - 3.0;
  }
  if (dof <= 0.0) return std::nullopt;
  return std::sqrt(sum / dof);
}

MatchSettings match_settings_for(double sigma_px) {
  MatchSettings s;
  s.epipolar_tolerance_px = std::max(s.epipolar_tolerance_px, 4.0 * sigma_px);
  s.reprojection_tolerance_px = std::max(s.reprojection_tolerance_px, 5.0 * sigma_px);
  s.max_rms_px = std::max(s.max_rms_px, 2.5 * sigma_px);
  s.max_residual_px = std::max(s.max_residual_px, 3.7 * sigma_px);
  return s;
}

double PixelSigmaEstimate::update(std::span<const MatchedPoint> points) {
  if (const auto now = estimate_pixel_sigma(points)) {
    // The first frames average evenly, later ones exponentially.
    ++seen_;
    const double weight = 1.0 / std::min(static_cast<double>(seen_), frames_);
    variance_ += weight * (*now * *now - variance_);
  }
  return sigma_px();
}

double PixelSigmaEstimate::sigma_px() const { return std::max(std::sqrt(variance_), floor_px_); }

std::vector<double> point_sigmas_m(std::span<const MatchedPoint> points, double sigma_px) {
  std::vector<double> out;
  out.reserve(points.size());
  point_sigmas_m(points, sigma_px, out);
  return out;
}

void point_sigmas_m(std::span<const MatchedPoint> points, double sigma_px, std::vector<double>& out) {
  out.clear();
  for (const MatchedPoint& m : points) out.push_back(m.point.sigma_m_per_px * sigma_px);
}

int truth_marker(const RigFrame& frame, const MatchedPoint& point) {
  int marker = -1;
  for (std::size_t k = 0; k < point.observations.size(); ++k) {
    const int t = frame.cameras[static_cast<std::size_t>(point.observations[k].camera)]
                      .detections[static_cast<std::size_t>(point.detection[k])]
                      .truth_marker;
    if (t < 0 || (k > 0 && t != marker)) return -1;
    marker = t;
  }
  return marker;
}

namespace {

// Half the size of the box two-view seeds may lie in (MatchSettings::seed_margin, seed_margin_m).
Eigen::Vector3d seed_box_half(const TrackingVolume& volume, const MatchSettings& settings) {
  return 0.5 * volume.size_m + settings.seed_margin * volume.size_m + Eigen::Vector3d::Constant(settings.seed_margin_m);
}

// One frame's matching, in three phases: seed clusters from epipolar pairs, refine them, accept
// the best without sharing detections.
class Matcher {
 public:
  Matcher(const CameraRig& rig, std::span<const CameraProjection> poses, const CameraVisibility& visibility, const RigFrame& frame,
          const MatchSettings& settings, JobPool* jobs, MatchScratch& scratch, bool follow)
      : rig_(rig),
        settings_(settings),
        jobs_(jobs),
        follow_(follow),
        time_s_(frame.time_s),
        n_(rig.cameras.size()),
        s_(scratch),
        cams_(scratch.cams),
        poses_(poses),
        visibility_(visibility),
        links_(scratch.links),
        clusters_(scratch.clusters),
        index_(scratch.index),
        open_(scratch.open),
        plans_(scratch.plans) {
    for (std::size_t c = 0; c < n_; ++c) {
      RHOT_PRECONDITION(frame.cameras[c].camera == static_cast<int>(c), "match_and_triangulate: cameras in rig order");
    }
    if (cams_.size() < n_) cams_.resize(n_);
    links_.clear();
    s_.cluster_count = 0;
    s_.point_count = 0;
    for_each(n_, [&](std::size_t c) { cams_[c].build(rig.cameras[c], frame.cameras[c]); });
    if (rig.volume && settings.seed_margin >= 0.0) {
      const Eigen::Vector3d half = seed_box_half(*rig.volume, settings);
      seed_lo_ = rig.volume->centre_m - half;
      seed_hi_ = rig.volume->centre_m + half;
    }
  }

  // The frame's points: the first point_count of the scratch's.
  std::span<const MatchedPoint> run() {
    // Room for the clusters ahead, from the most detections a camera has: a frame has about one
    // cluster a marker and seldom more than three, and clusters made ready one growth at a time
    // would reserve their per-camera storage in whichever later frame first needs more (thousands
    // of allocations at once on a large rig).
    std::size_t most = 0;
    for (const CameraDetections& c : cams_) most = std::max(most, c.pixel.size());
    if (clusters_.size() < 3 * most) grow_clusters(4 * most);  // with room for a third more detections
    if (follow_) follow_points();
    for (std::size_t i = 0; i < n_; ++i) {
      // Camera i's open detections, in order, kept for its pairs (each drops what the pairs
      // before it explained).
      open_.clear();
      reserve_room(open_, cams_[i].pixel.size());
      for (std::size_t a = 0; a < cams_[i].pixel.size(); ++a) {
        if (cams_[i].explained[a] == 0) open_.push_back(a);
      }
      for (std::size_t j = i + 1; j < n_ && cams_[i].open > 0; ++j) seed_pair(i, j);
    }
    for_each(
        s_.cluster_count, [&](std::size_t k) { refine(clusters_[k]); }, kShortJobs);
    accept();
    s_.followed_points = static_cast<std::size_t>(std::count_if(
        s_.point_followed.begin(), s_.point_followed.begin() + static_cast<std::ptrdiff_t>(s_.point_count), [](int f) { return f >= 0; }));
    if (follow_) {
      remember_points();
    } else {
      s_.followed.clear();
      s_.followed_time_s = std::numeric_limits<double>::quiet_NaN();
    }
    return std::span<const MatchedPoint>(s_.points).first(s_.point_count);
  }

 private:
  // fn(k) for k in [0, n): on the job pool where there is one, else in order. Every use writes
  // only what belongs to k, so the result is the same whatever the thread count.
  template <class F>
  void for_each(std::size_t n, F&& fn, std::size_t grain = 1) {
    if (jobs_ != nullptr) {
      jobs_->for_each(n, fn, grain);
    } else {
      for (std::size_t k = 0; k < n; ++k) fn(k);
    }
  }

  // The last frame's points, each grown from where it is expected now (where it was, moved on by
  // its velocity) into every camera that may see it, as a seed is but with no detection given:
  // those three or more cameras confirm are kept as a confirmed seed is, in the last frame's order,
  // before any pair of cameras is seeded, so that their detections seed nothing. A marker that
  // moves as it did costs one growth instead of its pairs' planning and the ghosts grown before its
  // seed; one that did not is seeded as before. Each grows into its own slot, side by side.
  void follow_points() {
    const std::vector<Followed>& followed = s_.followed;
    const double dt = time_s_ - s_.followed_time_s;
    if (followed.empty() || !(dt > 0.0 && dt <= kFollowedFor_s)) return;  // NaN fails too
    if (s_.from_followed.size() < followed.size()) {
      const std::size_t from = s_.from_followed.size();
      s_.from_followed.resize(followed.size() + followed.size() / 2 + 16);
      for (std::size_t k = from; k < s_.from_followed.size(); ++k) s_.from_followed[k].cluster.reserve(n_);
    }
    for_each(
        followed.size(),
        [&](std::size_t k) {
          const Followed& f = followed[k];
          Grown& g = s_.from_followed[k];
          grow(f.position + dt * f.velocity, f.colour, kNone, 0, kNone, 0, g);
          g.cluster.followed = static_cast<int>(k);
        },
        kShortJobs);
    for (std::size_t k = 0; k < followed.size(); ++k) {
      if (s_.from_followed[k].confirmed) keep(s_.from_followed[k]);
    }
  }

  // This frame's points, to be followed into the next: each with its velocity from the last
  // frame's point it grew from or, for a seeded one, from the last frame's point of its colour that
  // no point grew from, nearest to where that was expected (a marker lost by its followed point and
  // seeded again, or seeded for the first time in the last frame), within the distance
  // kFastest_mps would take it, and kLinkedWithin_m. A velocity over kFastest_mps (a point linked
  // to another marker's, a frame a fraction of a millisecond after the last) is taken as none. A
  // frame with no detections at all (a dropped frame) leaves the last frame's points to follow.
  void remember_points() {
    bool any = false;
    for (const CameraDetections& c : cams_) any = any || !c.pixel.empty();
    if (!any) return;
    const std::vector<Followed>& before = s_.followed;
    std::vector<Followed>& next = s_.next_followed;
    const double dt = time_s_ - s_.followed_time_s;
    const bool linked = !before.empty() && dt > 0.0 && dt <= kFollowedFor_s;
    reserve_room(next, s_.point_count);
    next.resize(s_.point_count);
    std::vector<char>& claimed = s_.followed_claimed;
    reserve_room(claimed, before.size());
    claimed.assign(before.size(), 0);
    std::size_t seeded = 0;
    for (std::size_t p = 0; p < s_.point_count && linked; ++p) {
      if (s_.point_followed[p] >= 0) {
        claimed[static_cast<std::size_t>(s_.point_followed[p])] = 1;
      } else {
        ++seeded;
      }
    }
    // The lost ones, to link seeded points to. Nearest by testing every pair: after the first
    // frames few points are seeded and few lost; where a frame has too many of both (the motion no
    // longer followed), the seeded points start with no velocity.
    std::vector<std::size_t>& lost = s_.followed_lost;
    reserve_room(lost, before.size());
    lost.clear();
    for (std::size_t q = 0; q < claimed.size() && seeded > 0; ++q) {
      if (claimed[q] == 0) lost.push_back(q);
    }
    const bool search = seeded * lost.size() <= kMostLinkTests;
    const double within = std::min(kLinkedWithin_m, kFastest_mps * dt + kLinkSlack_m);
    for (std::size_t p = 0; p < s_.point_count; ++p) {
      const MatchedPoint& m = s_.points[p];
      Followed& f = next[p];
      f.position = m.point.position_world;
      f.colour = m.colour;
      f.velocity.setZero();
      if (!linked) continue;
      int from = s_.point_followed[p];
      if (from < 0 && search) {
        double best = within * within;
        std::size_t best_at = lost.size();
        for (std::size_t l = 0; l < lost.size(); ++l) {
          const Followed& q = before[lost[l]];
          if (claimed[lost[l]] != 0 || q.colour != f.colour) continue;
          const double d2 = (q.position + dt * q.velocity - f.position).squaredNorm();
          if (d2 < best) {
            best = d2;
            best_at = l;
          }
        }
        if (best_at < lost.size()) {
          from = static_cast<int>(lost[best_at]);
          claimed[lost[best_at]] = 1;
        }
      }
      if (from < 0) continue;
      const Eigen::Vector3d v = (f.position - before[static_cast<std::size_t>(from)].position) / dt;
      if (v.squaredNorm() <= kFastest_mps * kFastest_mps) f.velocity = v;
    }
    std::swap(s_.followed, next);
    s_.followed_time_s = time_s_;
  }

  // Seeds from every epipolar-consistent detection pair of cameras i < j, each grown into every
  // other camera. In order of i's detections: for each, its candidates nearest the line first,
  // skipping those already explained or already paired with it in a cluster, until one is
  // confirmed. With a job pool, the detections' candidates are first planned and their first
  // kGrownAhead grown in parallel, as if nothing this pair confirms changed what is explained
  // (growing reads only the detections); the plans are then committed in order, skipping what an
  // earlier detection's cluster explained meanwhile and growing on the spot where a plan ran out
  // or was not grown that far: the clusters, and all that follows, are exactly the serial ones.
  // open_ holds camera i's open detections as the pair before left them (run).
  void seed_pair(std::size_t i, std::size_t j) {
    const std::size_t open_j = cams_[j].open;
    if (cams_[i].open == 0 || open_j == 0) return;
    std::erase_if(open_, [&](std::size_t a) { return cams_[i].explained[a] != 0; });
    // cam_j_from_cam_i = R t; essential matrix E = [t]x R maps x_i to the epipolar line in j.
    const Rigid3d j_from_i = rig_.cameras[j].cam_from_world * rig_.cameras[i].cam_from_world.inverse();
    const Eigen::Matrix3d e = skew(j_from_i.translation) * j_from_i.rotation.toRotationMatrix();
    // Many lines against many detections: index camera j's detections by epipolar line
    // (EpipolarIndex); few: test every one.
    const bool indexed = open_.size() * open_j >= kIndexAbovePairs;
    if (indexed) index_.build(j_from_i.translation, cams_[j].normalised, cams_[j].explained);
    const bool ahead = jobs_ != nullptr && jobs_->threads() > 1 && open_.size() >= kGrowAheadFrom;
    if (plans_.size() < open_.size()) {
      // Room for more plans, each for kPlanRoom candidates (a detection's epipolar band holds a few
      // among a thousand markers), so that a plan that reaches a new count seldom allocates.
      const std::size_t from = plans_.size();
      plans_.resize(open_.size() + open_.size() / 2 + 16);
      for (std::size_t k = from; k < plans_.size(); ++k) {
        plans_[k].candidates.reserve(kPlanRoom);
        plans_[k].has_grown.reserve(kPlanRoom);
      }
    }
    const auto plan_one = [&](std::size_t k) { plan_seeds(i, open_[k], j, e, indexed, plans_[k]); };
    if (ahead) {
      // Planned and grown in one dispatch, each plan's first kGrownAhead seeds into its own run of
      // one pool (made ready once for points seen by every camera), so that growing ahead
      // allocates nothing once frames have filled it; seeds after those grow on the spot below.
      const std::size_t slots = open_.size() * kGrownAhead;
      if (s_.ahead.size() < slots) {
        const std::size_t from = s_.ahead.size();
        s_.ahead.resize(slots + slots / 2 + 16);
        for (std::size_t g = from; g < s_.ahead.size(); ++g) s_.ahead[g].cluster.reserve(n_);
      }
      for_each(open_.size(), [&](std::size_t k) {
        plan_one(k);
        plans_[k].first_grown = k * kGrownAhead;
        grow_ahead(i, open_[k], j, plans_[k]);
      });
    } else {
      for (std::size_t k = 0; k < open_.size(); ++k) plan_one(k);  // too few to be worth a dispatch
    }
    for (std::size_t k = 0; k < open_.size(); ++k) {
      SeedPlan& plan = plans_[k];
      const std::size_t a = open_[k];
      for (std::size_t c = 0; c < plan.candidates.size(); ++c) {
        const auto b = static_cast<std::size_t>(plan.candidates[c].b);
        if (cams_[j].explained[b] != 0 || explained_by_a_cluster(i, a, j, b)) continue;
        const Grown* g = &s_.grown;
        if (plan.has_grown[c] != 0) {
          g = &s_.ahead[plan.first_grown + c];
        } else {
          grow_seed(i, a, j, b, plan.candidates[c].x, s_.grown);
        }
        keep(*g);
        if (g->confirmed) break;  // a is explained: no more seeds from it
      }
    }
  }

  // Detection a of camera i: its candidates in camera j (written to plan, nothing grown yet).
  void plan_seeds(std::size_t i, std::size_t a, std::size_t j, const Eigen::Matrix3d& e, bool indexed, SeedPlan& plan) const {
    thread_local std::vector<int> near_line;
    plan.candidates.clear();
    const double fj = 0.5 * (rig_.cameras[j].intrinsics.fx + rig_.cameras[j].intrinsics.fy);
    const Eigen::Vector3d line = e * cams_[i].normalised[a].homogeneous();
    const double tolerance = settings_.epipolar_tolerance_px * line.head<2>().norm() / fj;
    near_line.clear();
    reserve_room(near_line, cams_[j].pixel.size());
    if (indexed) {
      index_.query(line, tolerance, near_line);
    } else {
      for (std::size_t b = 0; b < cams_[j].pixel.size(); ++b) {
        if (cams_[j].explained[b] == 0 && std::abs(line.dot(cams_[j].normalised[b].homogeneous())) <= tolerance) {
          near_line.push_back(static_cast<int>(b));
        }
      }
    }
    const Eigen::Vector3d ray_a = poses_[i].ray_direction_world(cams_[i].normalised[a]);
    reserve_room(plan.candidates, near_line.size());
    for (const int candidate : near_line) {
      const auto b = static_cast<std::size_t>(candidate);
      if (cams_[j].colour[b] != cams_[i].colour[a]) continue;
      const auto x =
          ray_midpoint(poses_[i].centre_world(), ray_a, poses_[j].centre_world(), poses_[j].ray_direction_world(cams_[j].normalised[b]));
      // Two rays that meet far outside the volume the rig is for: a ghost, almost always.
      if (!x || (x->array() < seed_lo_.array()).any() || (x->array() > seed_hi_.array()).any()) continue;
      plan.candidates.push_back({std::abs(line.dot(cams_[j].normalised[b].homogeneous())), candidate, *x});
    }
    // Nearest the line first: the true match is, more often than not, and once it is confirmed
    // the ghosts behind it are never grown.
    std::sort(plan.candidates.begin(), plan.candidates.end());
    const std::size_t count = plan.candidates.size();
    reserve_room(plan.has_grown, count);
    plan.has_grown.assign(count, 0);
  }

  // The plan's seeds grown in order, as the serial pass would with what is explained now, up to
  // the first confirmed one or the kGrownAhead-th.
  void grow_ahead(std::size_t i, std::size_t a, std::size_t j, SeedPlan& plan) {
    for (std::size_t c = 0; c < std::min(plan.candidates.size(), kGrownAhead); ++c) {
      const auto b = static_cast<std::size_t>(plan.candidates[c].b);
      if (cams_[j].explained[b] != 0 || explained_by_a_cluster(i, a, j, b)) continue;
      Grown& grown = s_.ahead[plan.first_grown + c];
      grow_seed(i, a, j, b, plan.candidates[c].x, grown);
      plan.has_grown[c] = 1;
      if (grown.confirmed) return;
    }
  }

  // Whether a cluster already holds detection a of camera i together with detection b of camera j.
  bool explained_by_a_cluster(std::size_t i, std::size_t a, std::size_t j, std::size_t b) const {
    for (int l = cams_[i].first_link[a]; l >= 0; l = links_[static_cast<std::size_t>(l)].second) {
      if (clusters_[static_cast<std::size_t>(links_[static_cast<std::size_t>(l)].first)].detection[j] == static_cast<int>(b)) return true;
    }
    return false;
  }

  // The seed (a in camera i, b in camera j, meeting near x) grown into every other camera; a
  // cluster unless it is a ghost (then with no detections). Confirmed when three or more views
  // agree: its detections are then explained and seed nothing more (keep). Reads only the
  // detections, so seeds can grow side by side. Written into `out` (its storage kept).
  void grow_seed(std::size_t i, std::size_t a, std::size_t j, std::size_t b, const Eigen::Vector3d& x, Grown& out) const {
    grow(x, cams_[i].colour[a], i, a, j, b, out);
  }

  // A point near x grown into every camera that may see it, as a seed is (grow_seed) but with the
  // detections of cameras i and j given (i and j kNone: none given, every camera looked in, and
  // the two that disagree most may be dropped whichever cameras they are, while three remain).
  void grow(const Eigen::Vector3d& x, int colour, std::size_t i, std::size_t a, std::size_t j, std::size_t b, Grown& out) const {
    thread_local std::vector<Observation> grown;
    // Per camera: where the seed projects, and whether the detection found there was the only one
    // of its colour within the tolerance (then the refined point's lookup can be skipped, below).
    thread_local std::vector<Eigen::Vector2d> seen_at;
    thread_local std::vector<char> alone;
    if (seen_at.size() < n_) {
      seen_at.resize(n_);
      alone.resize(n_);
    }
    out.confirmed = false;
    Cluster& cl = out.cluster;
    cl.reserve(n_);
    if (grown.capacity() < n_) grown.reserve(n_);
    cl.has_seed_refined = false;
    cl.followed = -1;
    cl.seed_point = x;
    cl.colour = colour;
    cl.detection.assign(n_, -1);
    if (i != kNone) {
      cl.detection[i] = static_cast<int>(a);
      cl.detection[j] = static_cast<int>(b);
    }
    int unseen = 0;  // cameras that should see the point and have no detection near it
    const CameraVisibility::CameraSet seeing = visibility_.cameras_at(x);
    for (std::size_t k = 0; k < n_; ++k) {
      if (k == i || k == j || !CameraVisibility::contains(seeing, k)) continue;
      const auto p = poses_[k].project(x);
      if (!p || !poses_[k].in_image(*p)) continue;
      bool only = false;
      cl.detection[k] = cams_[k].nearest(*p, settings_.reprojection_tolerance_px, cl.colour, &only);
      seen_at[k] = *p;
      alone[k] = only ? 1 : 0;
      if (cl.detection[k] < 0) ++unseen;
    }
    grown.clear();
    for (std::size_t k = 0; k < n_; ++k) {
      if (cl.detection[k] >= 0) grown.push_back({static_cast<int>(k), cams_[k].pixel[static_cast<std::size_t>(cl.detection[k])]});
    }
    // A pair no third camera confirms, where more than two cameras should have seen it, is a
    // ghost: the acceptance rule would refuse it anyway (more missing than support).
    if (grown.size() == 2 && unseen > 2) {
      cl.detection.clear();
      return;
    }
    // Three or more views that agree after refinement (every residual small) explain their
    // detections; a coincidental third detection near a ghost rarely survives refinement.
    if (grown.size() >= 3) {
      TriangulatedPoint& refined = cl.seed_refined;
      bool ok = refine_point_into(poses_, grown, rays_meeting_point(cl, cl.seed_point), 5, refined);
      // A neighbouring marker's detection picked up in one or two cameras need not spoil the
      // others' agreement: the worst goes (never a, b), while three views or more remain.
      for (int drop = 0; drop < 2 && ok && refined.max_residual_px > settings_.max_residual_px && grown.size() > 3; ++drop) {
        const auto worst = static_cast<std::size_t>(refined.worst_observation);
        const auto camera = static_cast<std::size_t>(grown[worst].camera);
        if (camera == i || camera == j) break;
        cl.detection[camera] = -1;
        grown.erase(grown.begin() + static_cast<std::ptrdiff_t>(worst));
        ok = refine_point_into(poses_, grown, refined.position_world, 5, refined);
      }
      if (ok) {
        out.confirmed = refined.max_residual_px <= settings_.max_residual_px;
        cl.seed_point = refined.position_world;
        // Where two markers project close together in one camera, the refined point picks the
        // right detection more often than the two-view seed did.
        bool changed = false;
        for (std::size_t k = 0; k < n_; ++k) {
          if (k == i || k == j || cl.detection[k] < 0) continue;
          if (const auto p = poses_[k].project(cl.seed_point)) {
            // The detection found from the seed, alone within the tolerance there, is still the
            // nearest from here if it is within the tolerance less the distance moved: every
            // other detection is further than the tolerance from the seed's projection, so
            // further than that from here. The lookup would return it again.
            const double moved = (*p - seen_at[k]).norm();
            const double off = (*p - cams_[k].pixel[static_cast<std::size_t>(cl.detection[k])]).norm();
            if (alone[k] != 0 && off + moved < settings_.reprojection_tolerance_px) continue;
            const int d = cams_[k].nearest(*p, settings_.reprojection_tolerance_px, cl.colour);
            if (d >= 0 && d != cl.detection[k]) {
              cl.detection[k] = d;
              changed = true;
            }
          }
        }
        cl.has_seed_refined = !changed;
      }
    }
  }

  // Where the rays of a cluster's detections meet, least squares, each ray weighted as its pixel
  // error would be (its camera's focal length over the distance from `near`, squared): within a
  // fraction of a millimetre of the refined point where the two-view seed is millimetres off,
  // so that refinement from it takes one pass where it took two or three. `near` where the rays
  // do not fix a point.
  Eigen::Vector3d rays_meeting_point(const Cluster& cl, const Eigen::Vector3d& near) const {
    // Sum over the rays of w (I - u u^T) (x - c) = 0, solved for x - near (so that a rig far from
    // the origin loses nothing to cancellation), in scalars: a (symmetric) dx = b.
    double a00 = 0.0, a01 = 0.0, a02 = 0.0, a11 = 0.0, a12 = 0.0, a22 = 0.0;
    double b0 = 0.0, b1 = 0.0, b2 = 0.0;
    for (std::size_t k = 0; k < n_; ++k) {
      if (cl.detection[k] < 0) continue;
      const Eigen::Vector3d d = poses_[k].ray_direction_world(cams_[k].normalised[static_cast<std::size_t>(cl.detection[k])]);
      const Eigen::Vector3d c = poses_[k].centre_world() - near;
      const double f = 0.5 * (rig_.cameras[k].intrinsics.fx + rig_.cameras[k].intrinsics.fy);
      const double w = f * f / std::max(c.squaredNorm(), 1e-6);
      const double v = w / d.squaredNorm();  // w u u^T = v d d^T
      const double m00 = w - v * d.x() * d.x(), m01 = -v * d.x() * d.y(), m02 = -v * d.x() * d.z();
      const double m11 = w - v * d.y() * d.y(), m12 = -v * d.y() * d.z(), m22 = w - v * d.z() * d.z();
      a00 += m00;
      a01 += m01;
      a02 += m02;
      a11 += m11;
      a12 += m12;
      a22 += m22;
      b0 += m00 * c.x() + m01 * c.y() + m02 * c.z();
      b1 += m01 * c.x() + m11 * c.y() + m12 * c.z();
      b2 += m02 * c.x() + m12 * c.y() + m22 * c.z();
    }
    // Cramer's rule by cofactors. The matrix is positive semi-definite, so its determinant is at
    // most the product of its diagonal: rays that (nearly) fix no point give a small fraction of it.
    const double c00 = a11 * a22 - a12 * a12, c01 = a02 * a12 - a01 * a22, c02 = a01 * a12 - a02 * a11;
    const double det = a00 * c00 + a01 * c01 + a02 * c02;
    if (!(det > 1e-12 * a00 * a11 * a22)) return near;
    const double c11 = a00 * a22 - a02 * a02, c12 = a01 * a02 - a00 * a12, c22 = a00 * a11 - a01 * a01;
    const Eigen::Vector3d dx((c00 * b0 + c01 * b1 + c02 * b2) / det, (c01 * b0 + c11 * b1 + c12 * b2) / det,
                             (c02 * b0 + c12 * b1 + c22 * b2) / det);
    // Views that agree meet within millimetres of the two-view seed; further off (a neighbour's
    // detection among them), the seed is the better start.
    return dx.allFinite() && dx.squaredNorm() < kRaysStartWithin_m * kRaysStartWithin_m ? Eigen::Vector3d(near + dx) : near;
  }

  // A grown seed kept as a cluster (a ghost, with no detections, is not); a confirmed one
  // explains its detections.
  void keep(const Grown& g) {
    if (g.cluster.detection.empty()) return;
    const int index = static_cast<int>(s_.cluster_count);
    for (std::size_t k = 0; k < n_; ++k) {
      if (g.cluster.detection[k] < 0) continue;
      const auto d = static_cast<std::size_t>(g.cluster.detection[k]);
      links_.emplace_back(index, cams_[k].first_link[d]);
      cams_[k].first_link[d] = static_cast<int>(links_.size()) - 1;
      if (g.confirmed && cams_[k].explained[d] == 0) {
        cams_[k].explained[d] = 1;
        --cams_[k].open;
      }
    }
    if (s_.cluster_count == clusters_.size()) grow_clusters(2 * clusters_.size() + 16);
    Cluster& cl = clusters_[s_.cluster_count++];
    // Copied field by field into a cluster of an earlier frame, whose vectors keep their storage;
    // what refine fills starts as a new cluster's.
    cl.detection = g.cluster.detection;
    cl.colour = g.cluster.colour;
    cl.seed_point = g.cluster.seed_point;
    cl.support = 0;
    cl.missing = 0;
    cl.point.position_world.setZero();
    cl.point.reprojection_rms_px = 0.0;
    cl.point.max_residual_px = 0.0;
    cl.point.worst_observation = 0;
    cl.point.cameras.clear();
    cl.point.sigma_m_per_px = 0.0;
    cl.observations.clear();
    cl.has_seed_refined = g.cluster.has_seed_refined;
    if (cl.has_seed_refined) cl.seed_refined = g.cluster.seed_refined;
    cl.followed = g.cluster.followed;
  }

  // Room for `count` clusters, each made ready for a point seen by every camera.
  void grow_clusters(std::size_t count) {
    const std::size_t from = clusters_.size();
    clusters_.resize(count);
    for (std::size_t k = from; k < count; ++k) clusters_[k].reserve(n_);
  }

  // Refines a cluster, counts its support and the cameras that should have seen it.
  void refine(Cluster& cl) {
    for (std::size_t k = 0; k < n_; ++k) {
      if (cl.detection[k] >= 0) cl.observations.push_back({static_cast<int>(k), cams_[k].pixel[static_cast<std::size_t>(cl.detection[k])]});
    }
    cl.support = static_cast<int>(cl.observations.size());
    if (cl.has_seed_refined) {
      std::swap(cl.point, cl.seed_refined);
      cl.has_seed_refined = false;
    } else if (!refine_point_into(poses_, cl.observations, cl.seed_point, 5, cl.point)) {
      cl.support = 0;
      return;
    }
    // A two-view seed predicts the other cameras only roughly; with the refined point, look again
    // for detections the first pass missed. The cameras that still see nothing there are missing
    // unless the point moves (counted again below if it does).
    bool grew = false;
    int missing = 0;
    const CameraVisibility::CameraSet seeing = visibility_.cameras_at(cl.point.position_world);
    for (std::size_t k = 0; k < n_; ++k) {
      if (cl.detection[k] >= 0 || !CameraVisibility::contains(seeing, k)) continue;
      const auto p = poses_[k].project(cl.point.position_world);
      if (!p || !poses_[k].in_image(*p)) continue;
      const int d = cams_[k].nearest(*p, settings_.reprojection_tolerance_px, cl.colour);
      if (d < 0) {
        ++missing;
        continue;
      }
      cl.detection[k] = d;
      cl.observations.push_back({static_cast<int>(k), cams_[k].pixel[static_cast<std::size_t>(d)]});
      grew = true;
    }
    if (grew) {
      std::sort(cl.observations.begin(), cl.observations.end(),
                [](const Observation& a, const Observation& b) { return a.camera < b.camera; });
      if (!refine_point_into(poses_, cl.observations, cl.point.position_world, 5, cl.point)) {
        cl.support = 0;
        return;
      }
    }
    // Drop, one at a time, observations that disagree with the others: a neighbouring marker's
    // detection picked up while growing.
    const bool moved = grew || cl.point.max_residual_px > settings_.max_residual_px;
    while (cl.point.max_residual_px > settings_.max_residual_px) {
      const auto worst_at = static_cast<std::size_t>(cl.point.worst_observation);
      if (cl.observations.size() <= 2) {
        cl.observations.clear();
        break;
      }
      cl.detection[static_cast<std::size_t>(cl.observations[worst_at].camera)] = -1;
      cl.observations.erase(cl.observations.begin() + static_cast<std::ptrdiff_t>(worst_at));
      if (!refine_point_into(poses_, cl.observations, cl.point.position_world, 5, cl.point)) {
        cl.observations.clear();
        break;
      }
    }
    cl.support = static_cast<int>(cl.observations.size());
    if (cl.support < 2) return;
    if (!moved) {
      cl.missing = missing;
      return;
    }
    const CameraVisibility::CameraSet seeing_now = visibility_.cameras_at(cl.point.position_world);
    for (std::size_t k = 0; k < n_; ++k) {
      if (cl.detection[k] >= 0 || !CameraVisibility::contains(seeing_now, k)) continue;
      const auto p = poses_[k].project(cl.point.position_world);
      if (p && poses_[k].in_image(*p)) ++cl.missing;
    }
  }

  // The clusters, best first (most support, then smallest RMS), each accepted unless it is weak
  // or shares detections with a better one; into the scratch's points.
  void accept() {
    std::vector<std::size_t>& order = s_.order;
    reserve_room(order, s_.cluster_count);
    order.resize(s_.cluster_count);
    for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      if (clusters_[a].support != clusters_[b].support) return clusters_[a].support > clusters_[b].support;
      if (clusters_[a].point.reprojection_rms_px != clusters_[b].point.reprojection_rms_px)
        return clusters_[a].point.reprojection_rms_px < clusters_[b].point.reprojection_rms_px;
      return a < b;  // a tie (two clusters of the same detections) to the one kept first, whatever the library's sort
    });
    std::vector<std::vector<char>>& used = s_.used;
    if (used.size() < n_) used.resize(n_);
    for (std::size_t c = 0; c < n_; ++c) {
      reserve_room(used[c], cams_[c].pixel.size());
      used[c].assign(cams_[c].pixel.size(), 0);
    }
    s_.any_contested = false;
    for (const std::size_t k : order) {
      Cluster& cl = clusters_[k];
      if (cl.support < 2 || cl.point.reprojection_rms_px > settings_.max_rms_px || cl.missing > cl.support) continue;
      int conflicts = 0;  // cameras whose detection a better point already took
      for (std::size_t c = 0; c < n_; ++c) {
        if (cl.detection[c] >= 0 && (used[c][static_cast<std::size_t>(cl.detection[c])] & kUsed) != 0) ++conflicts;
      }
      if (conflicts > 0) {
        // Two markers whose projections nearly coincide in a camera share a detection there: on
        // a large rig, two markers a couple of centimetres apart line up in one or two of the
        // thirty cameras that see them. A point that keeps at least as many detections of its
        // own as it shares, and three or more, is still found without the shared ones; a second
        // cluster of one marker shares nearly all of its detections, a ghost made of other
        // markers' detections most of them, and neither comes of this. (Refusing every cluster
        // that shares two found 37 of the 100 markers of MarkersThatLineUpInAFewOfThirtyCameras.)
        // Wanted by such a point (once it is refined without them), or by one three or more
        // cameras see sharing a single detection (two views that share a detection with a better
        // point are as likely a ghost), the shared detections are contested: most likely the two
        // markers' blobs merged into one, which lies off both (see drop_contested).
        const int own = cl.support - conflicts;
        if (conflicts == 1 && cl.support >= 3) mark_taken_contested(cl);
        // Its own views, not its support, against the cameras that should see it and show nothing
        // (the rule every cluster passed above), where it shares more than one.
        const bool kept_without = own >= 3 && conflicts <= own && (conflicts == 1 || cl.missing <= own);
        if (!kept_without || !refit_without_taken(cl, conflicts > 1)) continue;
      }
      if (s_.point_count == s_.points.size()) {
        // Room for more points at once, each made ready to be seen by every camera.
        s_.points.resize(s_.points.size() + s_.points.size() / 2 + 16);
        for (std::size_t p = s_.point_count; p < s_.points.size(); ++p) {
          s_.points[p].point.cameras.reserve(n_);
          s_.points[p].observations.reserve(n_);
          s_.points[p].detection.reserve(n_);
        }
        s_.point_followed.resize(s_.points.size());
      }
      s_.point_followed[s_.point_count] = cl.followed;
      MatchedPoint& m = s_.points[s_.point_count++];
      m.point = cl.point;
      m.observations = cl.observations;
      m.colour = cl.colour;
      m.detection.clear();
      for (std::size_t c = 0; c < n_; ++c) {
        if (cl.detection[c] < 0) continue;
        used[c][static_cast<std::size_t>(cl.detection[c])] |= kUsed;
        m.detection.push_back(cl.detection[c]);
      }
    }
    if (s_.any_contested) drop_contested();
  }

  // The detections of a cluster that better points took (accept), marked contested.
  void mark_taken_contested(const Cluster& cl) {
    for (std::size_t c = 0; c < n_; ++c) {
      if (cl.detection[c] < 0) continue;
      char& flags = s_.used[c][static_cast<std::size_t>(cl.detection[c])];
      if ((flags & kUsed) == 0) continue;
      flags |= kContested;
      s_.any_contested = true;
    }
  }

  // A cluster without the detections better points took (accept), refined from the rest: false
  // where they do not agree. With `contest`, those detections are then contested. (Looking in those
  // cameras again for a detection no point took found, among a thousand markers, a third marker's
  // as often as the cluster's own: 2.8 times the mixed points on stage-32.)
  bool refit_without_taken(Cluster& cl, bool contest) {
    const auto taken = [&](std::size_t c) {
      return cl.detection[c] >= 0 && (s_.used[c][static_cast<std::size_t>(cl.detection[c])] & kUsed) != 0;
    };
    std::erase_if(cl.observations, [&](const Observation& o) { return taken(static_cast<std::size_t>(o.camera)); });
    TriangulatedPoint& again = s_.again;
    if (again.cameras.capacity() < n_) again.cameras.reserve(n_);
    if (!refine_point_into(poses_, cl.observations, cl.point.position_world, 5, again) ||
        again.max_residual_px > settings_.max_residual_px || again.reprojection_rms_px > settings_.max_rms_px)
      return false;
    std::swap(cl.point, again);
    if (contest) mark_taken_contested(cl);
    for (std::size_t c = 0; c < n_; ++c) {
      if (taken(c)) cl.detection[c] = -1;
    }
    return true;
  }

  // A detection that two markers' points both wanted (accept) is taken out of the point that kept
  // it, where three or more observations remain and agree without it: two markers projecting onto
  // one detection in a camera are, most often, two blobs merged into one, which lies between them
  // and is neither marker's. The point is then its own marker's alone. A point with three
  // observations or fewer keeps it.
  void drop_contested() {
    for (std::size_t p = 0; p < s_.point_count; ++p) {
      MatchedPoint& m = s_.points[p];
      for (std::size_t o = 0; o < m.observations.size() && m.observations.size() >= 4;) {
        const auto camera = static_cast<std::size_t>(m.observations[o].camera);
        const auto detection = m.detection[o];
        if ((s_.used[camera][static_cast<std::size_t>(detection)] & kContested) == 0) {
          ++o;
          continue;
        }
        s_.dropped = m.observations[o];
        m.observations.erase(m.observations.begin() + static_cast<std::ptrdiff_t>(o));
        TriangulatedPoint& again = s_.again;
        if (again.cameras.capacity() < n_) again.cameras.reserve(n_);
        if (refine_point_into(poses_, m.observations, m.point.position_world, 5, again) &&
            again.max_residual_px <= settings_.max_residual_px && again.reprojection_rms_px <= settings_.max_rms_px) {
          std::swap(m.point, again);
          m.detection.erase(m.detection.begin() + static_cast<std::ptrdiff_t>(o));
        } else {
          m.observations.insert(m.observations.begin() + static_cast<std::ptrdiff_t>(o), s_.dropped);
          ++o;
        }
      }
    }
  }

  const CameraRig& rig_;
  const MatchSettings& settings_;
  JobPool* jobs_;  // nullptr: everything in order on the caller
  bool follow_;    // the last frame's points looked for first (MatchSettings::follow_points, match_frame only)
  double time_s_;  // the frame's
  std::size_t n_;
  MatchScratch& s_;  // the storage below, and the clusters' and points' counts
  std::vector<CameraDetections>& cams_;
  std::span<const CameraProjection> poses_;
  const CameraVisibility& visibility_;
  // The clusters containing each detection (to skip redundant seeds), as singly linked lists:
  // links_[l] = {cluster, next link}, heads in CameraDetections::first_link. A detection that
  // seeded or joined a cluster three or more cameras confirm seeds nothing more: its marker is
  // found, and pairing it with another detection could only make a ghost. This is what keeps
  // seeding near linear in the markers.
  std::vector<std::pair<int, int>>& links_;
  std::vector<Cluster>& clusters_;  // the first s_.cluster_count are this frame's
  // seed_pair's: camera j's open detections by epipolar line, camera i's open detections and
  // their plans.
  static constexpr std::size_t kIndexAbovePairs = 512;
  // Seeds are grown ahead in parallel for a pair with at least this many open detections in its
  // first camera (fewer: the dispatch costs more than it saves). From 4 with 8 seeds grown ahead,
  // against 16 with 4: stage-32's 1,000 markers on two threads about 4 % faster, room-8's about
  // 10 %, 100 markers the same (docs/PERFORMANCE.md, "Where two threads lose their time").
  static constexpr std::size_t kGrowAheadFrom = 4;
  static constexpr std::size_t kPlanRoom = 64;
  // Seeds of a plan grown ahead at most (a detection's first or second candidate is confirmed,
  // most often; among a thousand markers, the fifth to eighth often enough to be worth growing
  // ahead); the commit grows any after them on the spot.
  static constexpr std::size_t kGrownAhead = 8;
  // Items a thread takes at once from loops of short items (a refinement, a followed point's
  // growth: microseconds each): stage-32's refinement on two threads 0.64 -> 0.51 ms against one.
  static constexpr std::size_t kShortJobs = 8;
  // No camera given to grow (grow).
  static constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();
  // Points are followed from a frame at most this long before (a tenth of a second, give or take
  // a 10 Hz source's rounding; a slower source, or a gap, and every marker is seeded again). A
  // seeded point is linked to a lost one within what kFastest_mps makes of the time between, plus
  // kLinkSlack_m, and at most kLinkedWithin_m, of where that was expected, testing at most
  // kMostLinkTests pairs; a velocity over kFastest_mps (a hand thrown hard moves 10 m/s) is none.
  static constexpr double kFollowedFor_s = 0.1001;
  static constexpr double kFastest_mps = 15.0;
  static constexpr double kLinkSlack_m = 0.02;
  static constexpr double kLinkedWithin_m = 0.15;
  static constexpr std::size_t kMostLinkTests = 4'000'000;
  // The rays' meeting point starts a seed's refinement when it lies within this of the seed.
  static constexpr double kRaysStartWithin_m = 0.05;
  static constexpr char kUsed = 1;
  static constexpr char kContested = 2;
  EpipolarIndex& index_;
  std::vector<std::size_t>& open_;
  std::vector<SeedPlan>& plans_;
  // Where seeds may lie (MatchSettings::seed_margin): everywhere without a volume.
  Eigen::Vector3d seed_lo_ = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());
  Eigen::Vector3d seed_hi_ = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
};

// The grid of CameraVisibility: the box where two-view seeds may lie with the default
// MatchSettings (the tracking volume, twice its size plus 25 cm each way); none without a volume.
CameraVisibility visibility_over_seed_box(const CameraRig& rig) {
  if (!rig.volume) return {};
  const Eigen::Vector3d half = seed_box_half(*rig.volume, MatchSettings{});
  return CameraVisibility(rig.cameras, rig.volume->centre_m - half, rig.volume->centre_m + half);
}

}  // namespace

RigMatcher::RigMatcher(const CameraRig& rig)
    : rig_(rig),
      projections_(camera_projections(rig)),
      visibility_(visibility_over_seed_box(rig)),
      scratch_(std::make_unique<MatchScratch>()) {}

RigMatcher::~RigMatcher() = default;
RigMatcher::RigMatcher(RigMatcher&&) noexcept = default;
RigMatcher& RigMatcher::operator=(RigMatcher&&) noexcept = default;

std::vector<MatchedPoint> RigMatcher::match(const RigFrame& frame, const MatchSettings& settings, JobPool* jobs) const {
  RHOT_PRECONDITION(frame.cameras.size() == rig_.cameras.size(), "match_and_triangulate: one CameraFrame per camera of the rig");
  MatchScratch scratch;
  const std::span<const MatchedPoint> points = Matcher(rig_, projections_, visibility_, frame, settings, jobs, scratch, false).run();
  return {std::make_move_iterator(scratch.points.begin()),
          std::make_move_iterator(scratch.points.begin() + static_cast<std::ptrdiff_t>(points.size()))};
}

std::span<const MatchedPoint> RigMatcher::match_frame(const RigFrame& frame, const MatchSettings& settings, JobPool* jobs) {
  RHOT_PRECONDITION(frame.cameras.size() == rig_.cameras.size(), "match_and_triangulate: one CameraFrame per camera of the rig");
  if (!scratch_) scratch_ = std::make_unique<MatchScratch>();  // a matcher moved from, assigned to since
  return Matcher(rig_, projections_, visibility_, frame, settings, jobs, *scratch_, settings.follow_points).run();
}

std::size_t RigMatcher::followed_points() const { return scratch_ ? scratch_->followed_points : 0; }

std::vector<MatchedPoint> match_and_triangulate(const CameraRig& rig, const RigFrame& frame, const MatchSettings& settings, JobPool* jobs) {
  RHOT_PRECONDITION(frame.cameras.size() == rig.cameras.size(), "match_and_triangulate: one CameraFrame per camera of the rig");
  // No grid: for one frame its building would cost more than it saves (the points are the same).
  static const CameraVisibility kEveryCamera;
  const std::vector<CameraProjection> projections = camera_projections(rig);
  MatchScratch scratch;
  const std::span<const MatchedPoint> points = Matcher(rig, projections, kEveryCamera, frame, settings, jobs, scratch, false).run();
  return {std::make_move_iterator(scratch.points.begin()),
          std::make_move_iterator(scratch.points.begin() + static_cast<std::ptrdiff_t>(points.size()))};
}

}  // namespace rhot
