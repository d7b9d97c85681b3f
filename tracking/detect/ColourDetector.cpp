#include "tracking/detect/ColourDetector.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <optional>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <opencv2/imgproc.hpp>

#include "tracking/core/MarkerColour.h"

namespace rhot {

std::expected<void, std::string> ColourDetectorSettings::check() const {
  const auto bad = [](const std::string& field, const std::string& expected, double v) {
    return std::unexpected(field + ": expected " + expected + ", got " + std::to_string(v));
  };
  if (min_area_px < 1) return bad("min_area_px", "at least 1", min_area_px);
  if (max_area_px < min_area_px) return bad("max_area_px", "at least min_area_px", max_area_px);
  if (!(max_elongation >= 1.0)) return bad("max_elongation", "at least 1", max_elongation);
  if (!(min_fill >= 0.0 && min_fill <= 1.0)) return bad("min_fill", "0 to 1", min_fill);
  if (!(min_confidence >= 0.0 && min_confidence <= 1.0)) return bad("min_confidence", "0 to 1", min_confidence);
  if (roi_margin_px < 1) return bad("roi_margin_px", "at least 1", roi_margin_px);
  if (full_scan_every < 1) return bad("full_scan_every", "at least 1", full_scan_every);
  if (max_blobs < 1) return bad("max_blobs", "at least 1", max_blobs);
  return {};
}

ColourDetector::ColourDetector(const ColourModel& model, ColourDetectorSettings settings) : table_(model), settings_(settings) {}

namespace {

// Two touching discs: elongation about 2 (just touching) down to 1 (one over the other). A blob
// more elongated than kPairFrom and at most kPairElongation is tried as two, each half round
// (elongation at most kHalfElongation) and full (fill at least kHalfFill), with a waist between.
constexpr double kPairFrom = 1.4;  // two discs overlapping by up to half a radius and more
constexpr double kPairElongation = 3.2;
constexpr double kHalfElongation = 2.0;
constexpr double kHalfFill = 0.7;
constexpr double kWaist = 0.75;   // the cut's width over the halves' at most
constexpr int kCutSteps = 6;      // the cut is looked for this many steps either side of the centroid,
constexpr double kCutStep = 0.5;  // px apart

// A marker partly hidden (behind its own finger, a knuckle, an object's edge) is a disc with a
// bite taken out: not round, not full, but its outer edge still lies on one circle. A blob that
// fails the shape tests is tried as such: a circle fitted to its edge pixels on the far side from
// the bite must hold the whole blob, carry edge pixels around at least kPartialArc of its
// circumference, and be covered at least kPartialCover by the blob. Its centre is the marker's.
constexpr int kPartialMinArea = 15;
constexpr double kPartialArc = 2.0 * std::numbers::pi / 3.0;
constexpr double kPartialCover = 0.3;
constexpr double kOnCircle = 1.0;  // px: an edge pixel this close to the circle is on it
constexpr double kRoundAt = 1.15;  // a blob less elongated is a whole marker, its centroid the centre

// Three or more markers of one colour whose images touch (a marker star seen edge-on), or two that
// the cut above does not part: the blob's distance transform peaks once per disc. A blob not quite
// one round disc (less full than kOneDiscFill, or elongated) of at least kDiscsMinArea pixels is
// tried as several: peaks at least kPeakOfLargest of the largest and kPeakSpacing of their radii
// apart, a waist between neighbours (the transform dips below kDiscWaist of the smaller radius on
// the way), and the discs together explain the blob (kDiscsExplain of its pixels inside them, as
// much of them inside it). Each disc's centre: a circle fitted to the blob's outline nearest its
// peak, or for a disc too small to hold a circle (a peak under kFitFromRadius: a star's markers
// 3-4 px in radius about 1.1 m away, whose shaded rims are not classified) the centroid of its own
// pixels. Two discs alone whose larger peak is that small are refused: a short stub of cable as
// thick is the same shape. Where discs are small, the cover may miss by kOutlineSlack of a pixel
// per pixel of their outline (pixels there are in or out by a fraction of a pixel) instead of
// 1 - kDiscsExplain of the blob. Peaks lower than kDiscMinRadius are left alone. A cable of a marker's colour peaks all
// along its length (3 px for one 6 px wide); what keeps it out is that discs cover it poorly.
constexpr double kOneDiscFill = 0.9;
constexpr int kDiscsMinArea = 30;
constexpr double kPeakOfLargest = 0.6;
constexpr double kPeakSpacing = 1.4;
constexpr double kDiscWaist = 0.8;
constexpr double kDiscsExplain = 0.95;  // a cable of a marker's colour, 6 px wide, 0.88
constexpr double kOutlineSlack = 0.1;   // or, where more, this many pixels per pixel of the discs' outline
constexpr int kMaxDiscs = 6;
constexpr double kDiscMinRadius = 2.0;  // px, a peak's distance to the outside (a disc of radius about 2.5 px and more)
constexpr double kFitFromRadius = 3.0;  // px: a lower peak's disc is centred on its own pixels' centroid

// A peak of a blob's distance transform: a disc's centre, in the blob's mask.
struct DiscPeak {
  cv::Point at;
  double value;  // px to the nearest pixel outside the blob
};

// A blob's mask (its box, at corner in the image), distance transform and peaks.
struct BlobPeaks {
  cv::Mat1b mask;
  cv::Point corner;
  cv::Mat1f dist;
  std::vector<DiscPeak> peaks;
};

int find_root(std::vector<int>& parent, int i) {
  while (parent[static_cast<std::size_t>(i)] != i) {
    parent[static_cast<std::size_t>(i)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(i)])];
    i = parent[static_cast<std::size_t>(i)];
  }
  return i;
}

std::expected<void, std::string> check_image(const cv::Mat& bgr) {
  if (bgr.empty()) return std::unexpected("empty image");
  if (bgr.type() != CV_8UC3) {
    return std::unexpected("expected an 8-bit BGR image (CV_8UC3), got type " + std::to_string(bgr.type()) + " with " +
                           std::to_string(bgr.channels()) + " channel(s)");
  }
  return {};
}

// `passes` times: the edge pixels on the circle (c, r), within kOnCircle, and the circle through
// them (algebraic least squares: x^2 + y^2 = 2 a x + 2 b y + c). False, with c and r left
// anywhere, when fewer than six pixels are on it or no real circle fits them.
bool refine_circle(const std::vector<Eigen::Vector2d>& edge, Eigen::Vector2d& c, double& r, int passes) {
  for (int pass = 0; pass < passes; ++pass) {
    Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
    Eigen::Vector3d atb = Eigen::Vector3d::Zero();
    int on = 0;
    for (const Eigen::Vector2d& e : edge) {
      const Eigen::Vector2d d = e - c;  // about the last centre, for precision
      if (std::abs(d.norm() - r) > kOnCircle) continue;
      const Eigen::Vector3d row(2.0 * d.x(), 2.0 * d.y(), 1.0);
      ata += row * row.transpose();
      atb += row * d.squaredNorm();
      ++on;
    }
    if (on < 6) return false;
    const Eigen::Vector3d abc = ata.ldlt().solve(atb);
    const double r2 = abc.z() + abc.head<2>().squaredNorm();
    if (!abc.allFinite() || !(r2 > 1.0)) return false;
    c += abc.head<2>();
    r = std::sqrt(r2);
  }
  return true;
}

// The circle of a partly hidden marker (kPartial* above) through the edge pixels of a blob of n
// pixels, as (centre x, centre y, radius), or nothing when they do not hold one no larger than
// max_radius_px.
std::optional<Eigen::Vector3d> partial_circle(const std::vector<Eigen::Vector2d>& edge, double n, double max_radius_px) {
  if (edge.size() < 8) return std::nullopt;
  std::vector<cv::Point2f> edge_f;
  for (const Eigen::Vector2d& e : edge) edge_f.emplace_back(static_cast<float>(e.x()), static_cast<float>(e.y()));
  cv::Point2f centre;
  float radius = 0.0f;
  cv::minEnclosingCircle(edge_f, centre, radius);
  Eigen::Vector2d c(static_cast<double>(centre.x), static_cast<double>(centre.y));
  double r = static_cast<double>(radius);
  if (!refine_circle(edge, c, r, 2)) return std::nullopt;
  // The blob inside the circle (pixel centres lie half a pixel inside the edge they mark).
  if (r > max_radius_px) return std::nullopt;
  if (n < kPartialCover * std::numbers::pi * (r + 0.5) * (r + 0.5)) return std::nullopt;
  std::array<bool, 24> sector{};
  for (const Eigen::Vector2d& e : edge) {
    const double d = (e - c).norm();
    if (d > r + kOnCircle) return std::nullopt;
    if (d < r - kOnCircle) continue;
    const double a = std::atan2(e.y() - c.y(), e.x() - c.x()) + std::numbers::pi;
    sector[std::min<std::size_t>(23, static_cast<std::size_t>(a / (2.0 * std::numbers::pi) * 24.0))] = true;
  }
  // One arc, the far side from the bite: the longest run of sectors with edge pixels on the
  // circle (a one-sector gap bridged) and no more than one such sector elsewhere. Two markers
  // whose images touch show two arcs, one at each end, and are not one marker in between.
  const int n_sectors = static_cast<int>(sector.size());
  int best_run = 0, best_start = 0;
  for (int start = 0; start < n_sectors; ++start) {
    if (!sector[static_cast<std::size_t>(start)] || sector[static_cast<std::size_t>((start + n_sectors - 1) % n_sectors)]) continue;
    int end = start;  // one past the run's last sector with a pixel on the circle
    for (int k = start; k < start + n_sectors; ++k) {
      if (sector[static_cast<std::size_t>(k % n_sectors)])
        end = k + 1;
      else if (!sector[static_cast<std::size_t>((k + 1) % n_sectors)])
        break;
    }
    if (end - start > best_run) best_run = end - start, best_start = start;
  }
  if (best_run == 0) best_run = n_sectors, best_start = 0;  // on the circle all round (no bite)
  if (best_run < kPartialArc / (2.0 * std::numbers::pi) * n_sectors) return std::nullopt;
  int elsewhere = 0;
  for (int k = best_start + best_run; k < best_start + n_sectors; ++k) elsewhere += sector[static_cast<std::size_t>(k % n_sectors)] ? 1 : 0;
  if (elsewhere > 1) return std::nullopt;
  return Eigen::Vector3d(c.x(), c.y(), r);
}

}  // namespace

void ColourDetector::scan(const cv::Mat& bgr, const cv::Rect& rect) {
  const std::uint8_t* lut = table_.classes();
  std::size_t prev_begin = runs_.size(), prev_end = runs_.size();
  for (int y = rect.y; y < rect.y + rect.height; ++y) {
    const std::size_t row_begin = runs_.size();
    const std::uint8_t* p = bgr.ptr<std::uint8_t>(y) + 3 * rect.x;
    int current = 0, start = 0;
    const int x_end = rect.x + rect.width;
    for (int x = rect.x; x < x_end; ++x, p += 3) {
      const int k = lut[ColourTable::cell(p[0], p[1], p[2])];
      if (k == current) continue;
      if (current != 0) runs_.push_back({y, start, x, current, static_cast<int>(runs_.size())});
      current = k;
      start = x;
    }
    if (current != 0) runs_.push_back({y, start, x_end, current, static_cast<int>(runs_.size())});
    // Join with the previous row's runs of the same colour that touch (8-connected).
    std::size_t j = prev_begin;
    for (std::size_t i = row_begin; i < runs_.size(); ++i) {
      Run& r = runs_[i];
      while (j < prev_end && runs_[j].x1 < r.x0) ++j;  // ends more than one pixel left of r
      for (std::size_t k = j; k < prev_end && runs_[k].x0 <= r.x1; ++k) {
        if (runs_[k].klass != r.klass) continue;
        // Union: the later root points at the earlier one.
        int a = static_cast<int>(i), b = static_cast<int>(k);
        while (runs_[static_cast<std::size_t>(a)].parent != a) a = runs_[static_cast<std::size_t>(a)].parent;
        while (runs_[static_cast<std::size_t>(b)].parent != b) b = runs_[static_cast<std::size_t>(b)].parent;
        if (a != b) runs_[static_cast<std::size_t>(std::max(a, b))].parent = std::min(a, b);
      }
    }
    prev_begin = row_begin;
    prev_end = runs_.size();
  }
}

namespace {

// A blob's pixel moments, plain and weighted by the pixels' colour membership.
struct Moments {
  double n = 0, sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
  double w = 0, wx = 0, wy = 0, value = 0;
  int klass = 0;
  bool clipped = false;  // touches a region's edge inside the image: part of it may lie outside
};

// A blob's shape from its unweighted second moments.
struct Shape {
  double elongation = 1e9, fill = 0.0, angle = 0.0;
};

Shape shape_of(const Moments& m) {
  Shape sh;
  const double mx = m.sx / m.n, my = m.sy / m.n;
  // Pixel squares: each adds 1/12 to its own variance.
  const double cxx = m.sxx / m.n - mx * mx + 1.0 / 12.0, cyy = m.syy / m.n - my * my + 1.0 / 12.0, cxy = m.sxy / m.n - mx * my;
  const double half_trace = 0.5 * (cxx + cyy);
  const double root = std::sqrt(std::max(0.0, 0.25 * (cxx - cyy) * (cxx - cyy) + cxy * cxy));
  const double major = half_trace + root, minor = half_trace - root;
  if (!(minor > 0.0)) return sh;
  sh.elongation = std::sqrt(major / minor);
  sh.fill = m.n / (4.0 * std::numbers::pi * std::sqrt(major * minor));
  sh.angle = 0.5 * std::atan2(2.0 * cxy, cxx - cyy);
  return sh;
}

// The blobs of one scan, from its runs to detections. Run: ColourDetector's run of one colour
// along a row (y, x0, x1, klass, parent), after scan() joined the runs that touch.
template <typename Run>
class BlobMeasure {
 public:
  BlobMeasure(const std::vector<Run>& runs, const cv::Mat& bgr, const ColourTable& table, const ColourDetectorSettings& settings)
      : runs_(runs), bgr_(bgr), membership_(table.memberships()), model_(table.model()), settings_(settings) {}

  // Each run into its blob's moments; rect_of_run_begin: the first run of each of the rects
  // scanned, in order.
  void gather(const std::vector<cv::Rect>& rects, const std::vector<std::size_t>& rect_of_run_begin) {
    std::vector<int> parent(runs_.size());
    for (std::size_t i = 0; i < runs_.size(); ++i) parent[i] = runs_[i].parent;
    std::vector<int> slot(runs_.size(), -1);
    blob_of_run_.assign(runs_.size(), -1);
    std::size_t rect_index = 0;
    for (std::size_t i = 0; i < runs_.size(); ++i) {
      while (rect_index + 1 < rects.size() && i >= rect_of_run_begin[rect_index + 1]) ++rect_index;
      const cv::Rect& rect = rects[rect_index];
      const Run& run = runs_[i];
      const int root = find_root(parent, static_cast<int>(i));
      int& s = slot[static_cast<std::size_t>(root)];
      if (s < 0) {
        s = static_cast<int>(blobs_.size());
        blobs_.push_back({});
        blobs_.back().klass = run.klass;
      }
      blob_of_run_[i] = s;
      Moments& m = blobs_[static_cast<std::size_t>(s)];
      if ((run.x0 == rect.x && rect.x > 0) || (run.x1 == rect.x + rect.width && run.x1 < bgr_.cols) || (run.y == rect.y && rect.y > 0) ||
          (run.y == rect.y + rect.height - 1 && run.y < bgr_.rows - 1)) {
        m.clipped = true;
      }
      if (m.n > settings_.max_area_px) continue;  // refused anyway: stop measuring a wall
      add_run(m, run, [](int, int) { return true; });
    }
  }

  // The gathered blobs that pass as markers: whole, two touching, or one partly hidden.
  std::vector<Detection> detections() {
    for (std::size_t b = 0; b < blobs_.size(); ++b) {
      const Moments& m = blobs_[b];
      if (m.clipped || m.n < settings_.min_area_px || m.n > settings_.max_area_px || m.w <= 0.0) continue;
      if (m.w / m.n < settings_.min_confidence) continue;
      const Shape sh = shape_of(m);
      // Three or more discs before the cut (a chain of four can pass as two round halves and be cut
      // in two), two after it. The blob's distance transform is made once.
      std::optional<BlobPeaks> peaks;
      if ((sh.fill < kOneDiscFill || sh.elongation > kRoundAt) && m.n >= kDiscsMinArea) peaks = blob_peaks(b);
      if (peaks && peaks->peaks.size() >= 3 && several_discs(b, m, *peaks)) continue;
      if (sh.fill >= settings_.min_fill && sh.elongation > kPairFrom && sh.elongation <= kPairElongation && split(b, m, sh)) continue;
      if (peaks && peaks->peaks.size() == 2 && several_discs(b, m, *peaks)) continue;
      if (sh.fill >= settings_.min_fill && sh.elongation <= settings_.max_elongation) {
        // Round enough to be a marker; one not quite round may be a partly hidden one, whose
        // visible part's centroid leans away from the bite by up to a pixel or two.
        const auto circle = sh.elongation > kRoundAt ? circle_of(b, m.n) : std::nullopt;
        if (circle)
          emit_at(m, *circle);
        else
          emit(m);
        continue;
      }
      if (const auto circle = circle_of(b, m.n)) emit_at(m, *circle);
    }
    return std::move(out_);
  }

 private:
  // A run's pixels (those `keep` accepts) into a blob's moments.
  template <typename Keep>
  void add_run(Moments& m, const Run& run, const Keep& keep) const {
    const std::uint8_t* p = bgr_.ptr<std::uint8_t>(run.y) + 3 * run.x0;
    const double y = run.y;
    for (int x = run.x0; x < run.x1; ++x, p += 3) {
      if (!keep(x, run.y)) continue;
      const double w = membership_[ColourTable::cell(p[0], p[1], p[2])] / 255.0;
      m.n += 1.0;
      m.sx += x;
      m.sy += y;
      m.sxx += static_cast<double>(x) * x;
      m.syy += y * y;
      m.sxy += x * y;
      m.w += w;
      m.wx += w * x;
      m.wy += w * y;
      m.value += std::max({p[0], p[1], p[2]});
    }
  }

  void emit(const Moments& m) {
    Detection d;
    d.pixel = Eigen::Vector2d(m.wx / m.w, m.wy / m.w);
    d.area_px = static_cast<float>(m.n);
    d.intensity = static_cast<float>(m.value / m.n);
    d.colour = static_cast<std::int8_t>(model_.classes[static_cast<std::size_t>(m.klass - 1)].colour);
    d.confidence = static_cast<float>(m.w / m.n);
    out_.push_back(d);
  }

  // A marker at a circle's centre, measured otherwise as m.
  void emit_at(Moments m, const Eigen::Vector3d& circle) {
    m.wx = circle.x() * m.w, m.wy = circle.y() * m.w;
    emit(m);
  }

  // The circle of a partly hidden marker (kPartial* above) from blob b's n pixels, as (centre x,
  // centre y, radius), or nothing. Its edge pixels: pixels with a 4-neighbour outside it.
  std::optional<Eigen::Vector3d> circle_of(std::size_t b, double n) const {
    if (n < kPartialMinArea) return std::nullopt;
    cv::Point corner;
    return partial_circle(edge_of(mask_of(b, corner), corner), n, std::sqrt(settings_.max_area_px / std::numbers::pi) + 1.0);
  }

  // Blob b's pixels as a mask with a one-pixel border, and its top-left corner in the image.
  cv::Mat1b mask_of(std::size_t b, cv::Point& corner) const {
    int x0 = bgr_.cols, x1 = 0, y0 = bgr_.rows, y1 = 0;
    for (std::size_t i = 0; i < runs_.size(); ++i) {
      if (blob_of_run_[i] != static_cast<int>(b)) continue;
      x0 = std::min(x0, runs_[i].x0), x1 = std::max(x1, runs_[i].x1), y0 = std::min(y0, runs_[i].y), y1 = std::max(y1, runs_[i].y + 1);
    }
    cv::Mat1b mask(y1 - y0 + 2, x1 - x0 + 2, std::uint8_t{0});
    for (std::size_t i = 0; i < runs_.size(); ++i) {
      if (blob_of_run_[i] != static_cast<int>(b)) continue;
      for (int x = runs_[i].x0; x < runs_[i].x1; ++x) mask(runs_[i].y - y0 + 1, x - x0 + 1) = 1;
    }
    corner = cv::Point(x0 - 1, y0 - 1);
    return mask;
  }

  // A mask's edge pixels (those with a 4-neighbour outside it), in image pixels.
  static std::vector<Eigen::Vector2d> edge_of(const cv::Mat1b& mask, cv::Point corner) {
    std::vector<Eigen::Vector2d> edge;
    for (int y = 1; y < mask.rows - 1; ++y) {
      for (int x = 1; x < mask.cols - 1; ++x) {
        if (mask(y, x) && (!mask(y - 1, x) || !mask(y + 1, x) || !mask(y, x - 1) || !mask(y, x + 1)))
          edge.emplace_back(x + corner.x, y + corner.y);
      }
    }
    return edge;
  }

  // Blob b's mask, its distance transform and the transform's peaks (disc_peaks).
  BlobPeaks blob_peaks(std::size_t b) const {
    BlobPeaks out;
    out.mask = mask_of(b, out.corner);
    cv::distanceTransform(out.mask, out.dist, cv::DIST_L2, cv::DIST_MASK_PRECISE);
    out.peaks = disc_peaks(out.dist);
    return out;
  }

  // Several markers of one colour in blob b, one per peak (kOneDiscFill and on, above): emits each
  // and says so, or emits nothing.
  bool several_discs(std::size_t b, const Moments& m, const BlobPeaks& blob) {
    const cv::Mat1b& mask = blob.mask;
    const cv::Point corner = blob.corner;
    const std::vector<DiscPeak>& peaks = blob.peaks;
    if (peaks.size() < 2 || peaks.size() > static_cast<std::size_t>(kMaxDiscs) || !waists_between(peaks, blob.dist)) return false;
    // Two small discs alone are refused: a short stub of cable as thick is the same shape.
    if (peaks.size() == 2 && peaks.front().value < kFitFromRadius) return false;
    // Each disc: a circle through the blob's edge pixels nearest its peak, started at the peak (a
    // pixel centre on the edge lies half a pixel inside the disc's outline).
    const std::vector<Eigen::Vector2d> edge = edge_of(mask, corner);
    std::vector<Eigen::Vector3d> discs;  // centre x, y and radius in the image
    std::vector<Eigen::Vector2d> own_edge;
    for (const DiscPeak& p : peaks) {
      own_edge.clear();
      for (const Eigen::Vector2d& e : edge) {
        const Eigen::Vector2d q = e - Eigen::Vector2d(corner.x, corner.y);
        if (nearest_peak(peaks, q) == &p) own_edge.push_back(e);
      }
      const Eigen::Vector2d at(p.at.x + corner.x, p.at.y + corner.y);
      Eigen::Vector2d c = at;
      double r = p.value - 0.5;
      if (refine_circle(own_edge, c, r, 3)) {
        if ((c - at).norm() > 0.5 * p.value) return false;  // a circle that wandered off its peak: no disc
        discs.emplace_back(c.x(), c.y(), r + 0.5);
        continue;
      }
      // Too few outline pixels to hold a circle (a peak under kFitFromRadius): the centroid of its
      // own pixels, and an outline half a pixel past its peak's value (where the fits of discs
      // this small came out, 0.3-0.5 px past).
      if (p.value >= kFitFromRadius) return false;
      const Eigen::Vector2d centre = cell_centroid(mask, corner, peaks, p);
      discs.emplace_back(centre.x(), centre.y(), p.value + 0.5);
    }
    if (!discs_explain(discs, mask, corner, m.n)) return false;
    // Each marker measured over the blob's pixels nearest its centre, placed at its centre.
    for (const Eigen::Vector3d& disc : discs) {
      Moments cell;
      cell.klass = m.klass;
      for (std::size_t i = 0; i < runs_.size(); ++i) {
        if (blob_of_run_[i] != static_cast<int>(b)) continue;
        add_run(cell, runs_[i], [&](int x, int y) {
          const double own = (Eigen::Vector2d(x, y) - disc.head<2>()).squaredNorm();
          return std::all_of(discs.begin(), discs.end(),
                             [&](const Eigen::Vector3d& o) { return own <= (Eigen::Vector2d(x, y) - o.head<2>()).squaredNorm(); });
        });
      }
      if (cell.w > 0.0) emit_at(cell, disc);
    }
    return true;
  }

  // The distance transform's local maxima of at least kDiscMinRadius and kPeakOfLargest of the
  // largest, each kept when kPeakSpacing of its and the others' values from those kept (largest
  // first). Mask pixels.
  static std::vector<DiscPeak> disc_peaks(const cv::Mat1f& dist) {
    std::vector<DiscPeak> maxima;
    for (int y = 1; y < dist.rows - 1; ++y) {
      for (int x = 1; x < dist.cols - 1; ++x) {
        const float v = dist(y, x);
        if (static_cast<double>(v) < kDiscMinRadius) continue;
        bool top = true;
        for (int dy = -1; dy <= 1 && top; ++dy)
          for (int dx = -1; dx <= 1 && top; ++dx) top = dist(y + dy, x + dx) <= v;
        if (top) maxima.push_back({{x, y}, static_cast<double>(v)});
      }
    }
    // Largest first; equals in the order found (row by row), for the same peaks on every run.
    std::sort(maxima.begin(), maxima.end(), [](const DiscPeak& a, const DiscPeak& c) {
      if (a.value != c.value) return a.value > c.value;
      return a.at.y != c.at.y ? a.at.y < c.at.y : a.at.x < c.at.x;
    });
    std::vector<DiscPeak> peaks;
    for (const DiscPeak& p : maxima) {
      if (p.value < kPeakOfLargest * maxima.front().value) break;
      const bool apart = std::all_of(peaks.begin(), peaks.end(), [&](const DiscPeak& q) {
        return std::hypot(p.at.x - q.at.x, p.at.y - q.at.y) >= kPeakSpacing * std::max(p.value, q.value);
      });
      if (apart) peaks.push_back(p);
    }
    return peaks;
  }

  // The centroid (image pixels) of the mask's pixels that are p's: nearest its disc's outline,
  // so that a small disc beside a larger one does not take the larger one's rim. Never empty: p's
  // own pixel is p's.
  static Eigen::Vector2d cell_centroid(const cv::Mat1b& mask, cv::Point corner, const std::vector<DiscPeak>& peaks, const DiscPeak& p) {
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    int n = 0;
    for (int y = 0; y < mask.rows; ++y) {
      for (int x = 0; x < mask.cols; ++x) {
        if (!mask(y, x)) continue;
        const DiscPeak* owner = &p;
        double owner_d = std::hypot(x - p.at.x, y - p.at.y) - p.value;
        for (const DiscPeak& q : peaks) {
          const double d = std::hypot(x - q.at.x, y - q.at.y) - q.value;
          if (d < owner_d) owner_d = d, owner = &q;
        }
        if (owner != &p) continue;
        sum += Eigen::Vector2d(x, y);
        ++n;
      }
    }
    return sum / n + Eigen::Vector2d(corner.x, corner.y);
  }

  static const DiscPeak* nearest_peak(const std::vector<DiscPeak>& peaks, const Eigen::Vector2d& q) {
    const DiscPeak* nearest = nullptr;
    double nearest_d2 = 1e18;
    for (const DiscPeak& p : peaks) {
      const double d2 = (q - Eigen::Vector2d(p.at.x, p.at.y)).squaredNorm();
      if (d2 < nearest_d2) nearest_d2 = d2, nearest = &p;
    }
    return nearest;
  }

  // Whether each peak has a waist toward its nearest: the transform dips below kDiscWaist of the
  // smaller value on the way. Two discs are narrow where they meet; a bar or a box is not.
  static bool waists_between(const std::vector<DiscPeak>& peaks, const cv::Mat1f& dist) {
    for (const DiscPeak& p : peaks) {
      const DiscPeak* nearest = nullptr;
      double nearest_d = 1e9;
      for (const DiscPeak& q : peaks) {
        const double d = std::hypot(p.at.x - q.at.x, p.at.y - q.at.y);
        if (&q != &p && d < nearest_d) nearest_d = d, nearest = &q;
      }
      const int steps = static_cast<int>(std::ceil(nearest_d * 2.0));
      double lowest = p.value;
      for (int k = 1; k < steps; ++k) {
        const double t = static_cast<double>(k) / steps;
        const int x = static_cast<int>(std::lround(p.at.x + t * (nearest->at.x - p.at.x)));
        const int y = static_cast<int>(std::lround(p.at.y + t * (nearest->at.y - p.at.y)));
        lowest = std::min(lowest, static_cast<double>(dist(y, x)));
      }
      if (lowest > kDiscWaist * std::min(p.value, nearest->value)) return false;
    }
    return true;
  }

  // Whether the discs (centre x, y, radius) explain a blob of n pixels: kDiscsExplain of its
  // pixels inside one, and as much of the discs' pixels inside it (each to within the slack below).
  static bool discs_explain(const std::vector<Eigen::Vector3d>& discs, const cv::Mat1b& mask, cv::Point corner, double n) {
    // Over the mask and every disc's square: a disc bulging out of the blob's box counts too.
    int x0 = 0, y0 = 0, x1 = mask.cols, y1 = mask.rows;  // in mask pixels, [x0, x1) x [y0, y1)
    for (const Eigen::Vector3d& d : discs) {
      x0 = std::min(x0, static_cast<int>(std::floor(d.x() - d.z())) - corner.x - 1);
      y0 = std::min(y0, static_cast<int>(std::floor(d.y() - d.z())) - corner.y - 1);
      x1 = std::max(x1, static_cast<int>(std::ceil(d.x() + d.z())) - corner.x + 2);
      y1 = std::max(y1, static_cast<int>(std::ceil(d.y() + d.z())) - corner.y + 2);
    }
    double inside = 0.0, disc_pixels = 0.0, disc_pixels_inside = 0.0;
    for (int y = y0; y < y1; ++y) {
      for (int x = x0; x < x1; ++x) {
        const bool in_blob = x >= 0 && y >= 0 && x < mask.cols && y < mask.rows && mask(y, x);
        const Eigen::Vector2d q(x + corner.x, y + corner.y);
        double nearest = 1e9;  // to a disc's outline, negative inside
        for (const Eigen::Vector3d& d : discs) nearest = std::min(nearest, (q - d.head<2>()).norm() - d.z());
        inside += in_blob && nearest <= 0.5 ? 1.0 : 0.0;
        disc_pixels += nearest <= -0.5 ? 1.0 : 0.0;
        disc_pixels_inside += in_blob && nearest <= -0.5 ? 1.0 : 0.0;
      }
    }
    // Whichever is more: 1 - kDiscsExplain of the pixels, or kOutlineSlack per pixel of the discs'
    // outline (more for discs under 4 px in radius, most of whose pixels lie on the outline).
    double outline = 0.0;
    for (const Eigen::Vector3d& d : discs) outline += 2.0 * std::numbers::pi * d.z();
    const double slack_px = kOutlineSlack * outline;
    return n - inside <= std::max((1.0 - kDiscsExplain) * n, slack_px) &&
           disc_pixels - disc_pixels_inside <= std::max((1.0 - kDiscsExplain) * disc_pixels, slack_px);
  }

  // Two markers of one colour whose images touch: cut across the major axis at its narrowest near
  // the centroid; both halves must come out round, full and of similar size, with a waist between
  // them. Emits both.
  bool split(std::size_t b, const Moments& m, const Shape& sh) {
    const double ux = std::cos(sh.angle), uy = std::sin(sh.angle);
    // The cut: the narrowest one-pixel strip across the axis, within kCutSteps x kCutStep of the centroid (two
    // discs of different sizes, or one partly hidden, meet off their joint centroid).
    double mx = m.sx / m.n, my = m.sy / m.n;
    {
      std::array<int, 2 * kCutSteps + 1> strip{};
      for (std::size_t i = 0; i < runs_.size(); ++i) {
        if (blob_of_run_[i] != static_cast<int>(b)) continue;
        for (int x = runs_[i].x0; x < runs_[i].x1; ++x) {
          const double t = (x - mx) * ux + (runs_[i].y - my) * uy;
          for (int k = -kCutSteps; k <= kCutSteps; ++k)
            strip[static_cast<std::size_t>(k + kCutSteps)] += std::abs(t - k * kCutStep) < 0.5 ? 1 : 0;
        }
      }
      int best = 0;  // the narrowest within the blob (an empty strip lies beyond its end), the nearest the centroid among equals
      for (int k = -kCutSteps; k <= kCutSteps; ++k) {
        const int w = strip[static_cast<std::size_t>(k + kCutSteps)], w_best = strip[static_cast<std::size_t>(best + kCutSteps)];
        if (w > 0 && (w < w_best || (w == w_best && std::abs(k) < std::abs(best)))) best = k;
      }
      mx += best * kCutStep * ux, my += best * kCutStep * uy;
    }
    Moments half[2];
    half[0].klass = half[1].klass = m.klass;
    for (std::size_t i = 0; i < runs_.size(); ++i) {
      if (blob_of_run_[i] != static_cast<int>(b)) continue;
      for (int side = 0; side < 2; ++side) {
        add_run(half[side], runs_[i], [&](int x, int y) { return ((x - mx) * ux + (y - my) * uy > 0.0) == (side == 1); });
      }
    }
    if (half[0].n < settings_.min_area_px || half[1].n < settings_.min_area_px) return false;
    if (std::min(half[0].n, half[1].n) < 0.6 * std::max(half[0].n, half[1].n)) return false;
    if (half[0].w <= 0.0 || half[1].w <= 0.0) return false;
    const Shape a = shape_of(half[0]), c = shape_of(half[1]);
    if (a.elongation > kHalfElongation || c.elongation > kHalfElongation || a.fill < kHalfFill || c.fill < kHalfFill) return false;
    if (!has_waist(b, mx, my, ux, uy, half)) return false;
    emit(half[0]);
    emit(half[1]);
    return true;
  }

  // Whether blob b, cut at (mx, my) across the axis (ux, uy) into `half`, has a waist: two discs
  // are narrow where they touch; a stub of cable or the corner of a box cut in two is not. Pixels
  // in a one-pixel strip across the cut against strips through each half's centroid.
  bool has_waist(std::size_t b, double mx, double my, double ux, double uy, const Moments (&half)[2]) const {
    const auto along = [&](const Moments& h) { return (h.sx / h.n - mx) * ux + (h.sy / h.n - my) * uy; };
    const double at0 = along(half[0]), at1 = along(half[1]);
    int waist = 0, body0 = 0, body1 = 0;
    for (std::size_t i = 0; i < runs_.size(); ++i) {
      if (blob_of_run_[i] != static_cast<int>(b)) continue;
      for (int x = runs_[i].x0; x < runs_[i].x1; ++x) {
        const double t = (x - mx) * ux + (runs_[i].y - my) * uy;
        waist += std::abs(t) < 0.5 ? 1 : 0;
        body0 += std::abs(t - at0) < 0.5 ? 1 : 0;
        body1 += std::abs(t - at1) < 0.5 ? 1 : 0;
      }
    }
    return !(waist > kWaist * std::min(body0, body1));
  }

  const std::vector<Run>& runs_;
  const cv::Mat& bgr_;
  const std::uint8_t* membership_;
  const ColourModel& model_;
  const ColourDetectorSettings& settings_;
  std::vector<int> blob_of_run_;  // per run: its blob, an index into blobs_
  std::vector<Moments> blobs_;
  std::vector<Detection> out_;
};

}  // namespace

std::vector<Detection> ColourDetector::measure(const cv::Mat& bgr, const std::vector<cv::Rect>& rects) {
  runs_.clear();
  last_pixels_ = 0;
  std::vector<std::size_t> rect_of_run_begin;
  for (const cv::Rect& r : rects) {
    rect_of_run_begin.push_back(runs_.size());
    scan(bgr, r);
    last_pixels_ += static_cast<std::int64_t>(r.area());
  }
  BlobMeasure<Run> blobs(runs_, bgr, table_, settings_);
  blobs.gather(rects, rect_of_run_begin);
  std::vector<Detection> out = blobs.detections();
  if (static_cast<int>(out.size()) > settings_.max_blobs) {
    std::nth_element(out.begin(), out.begin() + settings_.max_blobs, out.end(),
                     [](const Detection& a, const Detection& b) { return a.area_px > b.area_px; });
    out.resize(static_cast<std::size_t>(settings_.max_blobs));
  }
  return out;
}

std::expected<std::vector<Detection>, std::string> ColourDetector::detect(const cv::Mat& bgr) {
  if (auto ok = check_image(bgr); !ok) return std::unexpected(ok.error());
  reset();
  size_ = bgr.size();
  last_full_ = true;
  if (settings_.white_balance) balance(bgr);
  auto out = measure(bgr, {cv::Rect(0, 0, bgr.cols, bgr.rows)});
  remember(out);
  return out;
}

void ColourDetector::balance(const cv::Mat& bgr) {
  if (!table_.model().white_reference) return;
  const auto& ref = *table_.model().white_reference;
  const auto c = median_colour(bgr);
  std::array<double, 3> gains{};
  for (std::size_t ch = 0; ch < 3; ++ch) gains[ch] = std::clamp(ref[ch] / c[ch], 0.3, 3.0);
  const auto& now = table_.gains();
  bool changed = false;
  for (std::size_t ch = 0; ch < 3; ++ch) changed = changed || std::abs(gains[ch] / now[ch] - 1.0) > 0.02;
  if (changed) table_ = ColourTable(table_.model(), gains);
}

void ColourDetector::reset() {
  tracked_.clear();
  frames_since_full_ = 0;
}

void ColourDetector::remember(const std::vector<Detection>& detections) {
  std::vector<Tracked> next;
  for (const Detection& d : detections) {
    Tracked t{d.pixel, {0, 0}, std::sqrt(static_cast<double>(d.area_px) / std::numbers::pi), d.colour};
    // Its motion: from the nearest marker of its colour last frame, if one was near.
    double best = 4.0 * t.radius_px + 2.0 * settings_.roi_margin_px;
    for (const Tracked& o : tracked_) {
      if (o.colour != d.colour) continue;
      const double dist = (o.pixel + o.velocity - d.pixel).norm();
      if (dist < best) best = dist, t.velocity = d.pixel - o.pixel;
    }
    next.push_back(t);
  }
  tracked_ = std::move(next);
}

std::expected<std::vector<Detection>, std::string> ColourDetector::track(const cv::Mat& bgr) {
  if (auto ok = check_image(bgr); !ok) return std::unexpected(ok.error());
  if (bgr.size() != size_ || tracked_.empty() || ++frames_since_full_ >= settings_.full_scan_every) return detect(bgr);
  // Regions around each marker's predicted place, merged where they overlap or touch.
  const cv::Rect image(0, 0, bgr.cols, bgr.rows);
  std::vector<cv::Rect> rects;
  for (const Tracked& t : tracked_) {
    const Eigen::Vector2d c = t.pixel + t.velocity;
    const double half = t.radius_px + settings_.roi_margin_px + t.velocity.norm();
    rects.push_back(cv::Rect(static_cast<int>(std::floor(c.x() - half)), static_cast<int>(std::floor(c.y() - half)),
                             static_cast<int>(std::ceil(2.0 * half)) + 1, static_cast<int>(std::ceil(2.0 * half)) + 1) &
                    image);
  }
  for (bool merged = true; merged;) {
    merged = false;
    for (std::size_t i = 0; i < rects.size() && !merged; ++i) {
      for (std::size_t j = i + 1; j < rects.size() && !merged; ++j) {
        const cv::Rect grown(rects[i].x - 1, rects[i].y - 1, rects[i].width + 2, rects[i].height + 2);
        if ((grown & rects[j]).area() > 0) {
          rects[i] |= rects[j];
          rects.erase(rects.begin() + static_cast<std::ptrdiff_t>(j));
          merged = true;
        }
      }
    }
  }
  rects.erase(std::remove_if(rects.begin(), rects.end(), [](const cv::Rect& r) { return r.area() <= 0; }), rects.end());
  std::sort(rects.begin(), rects.end(), [](const cv::Rect& a, const cv::Rect& b) { return a.y != b.y ? a.y < b.y : a.x < b.x; });
  auto out = measure(bgr, rects);
  // A marker lost (hidden, left its region, merged with another): search everything.
  std::array<int, kMarkerColourCount> had{}, found{};
  for (const Tracked& t : tracked_) ++had[static_cast<std::size_t>(t.colour)];
  for (const Detection& d : out) ++found[static_cast<std::size_t>(d.colour)];
  if (had != found) {
    return detect(bgr);
  }
  last_full_ = false;
  remember(out);
  return out;
}

}  // namespace rhot
