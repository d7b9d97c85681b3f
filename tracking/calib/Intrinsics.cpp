#include "tracking/calib/Intrinsics.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <set>
#include <system_error>
#include <utility>

#include <opencv2/aruco.hpp>
#include <opencv2/aruco/charuco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "tracking/calib/CalibPictures.h"
#include "tracking/media/Media.h"

namespace rhot {

namespace {

constexpr double kDeg = 180.0 / std::numbers::pi;

struct NamedDictionary {
  const char* name;
  cv::aruco::PREDEFINED_DICTIONARY_NAME id;
  int markers;
};

constexpr NamedDictionary kDictionaries[] = {
    {"4X4_50", cv::aruco::DICT_4X4_50, 50},
    {"4X4_100", cv::aruco::DICT_4X4_100, 100},
    {"4X4_250", cv::aruco::DICT_4X4_250, 250},
    {"4X4_1000", cv::aruco::DICT_4X4_1000, 1000},
    {"5X5_50", cv::aruco::DICT_5X5_50, 50},
    {"5X5_100", cv::aruco::DICT_5X5_100, 100},
    {"5X5_250", cv::aruco::DICT_5X5_250, 250},
    {"5X5_1000", cv::aruco::DICT_5X5_1000, 1000},
    {"6X6_50", cv::aruco::DICT_6X6_50, 50},
    {"6X6_100", cv::aruco::DICT_6X6_100, 100},
    {"6X6_250", cv::aruco::DICT_6X6_250, 250},
    {"6X6_1000", cv::aruco::DICT_6X6_1000, 1000},
    {"7X7_50", cv::aruco::DICT_7X7_50, 50},
    {"7X7_100", cv::aruco::DICT_7X7_100, 100},
    {"7X7_250", cv::aruco::DICT_7X7_250, 250},
    {"7X7_1000", cv::aruco::DICT_7X7_1000, 1000},
    {"ARUCO_ORIGINAL", cv::aruco::DICT_ARUCO_ORIGINAL, 1024},
    {"APRILTAG_16h5", cv::aruco::DICT_APRILTAG_16h5, 30},
    {"APRILTAG_25h9", cv::aruco::DICT_APRILTAG_25h9, 35},
    {"APRILTAG_36h10", cv::aruco::DICT_APRILTAG_36h10, 2320},
    {"APRILTAG_36h11", cv::aruco::DICT_APRILTAG_36h11, 587},
};

std::string upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

const NamedDictionary* find_dictionary(const std::string& name) {
  std::string key = upper(name);
  if (key.starts_with("DICT_")) key = key.substr(5);
  for (const NamedDictionary& d : kDictionaries) {
    if (upper(d.name) == key) return &d;
  }
  return nullptr;
}

std::vector<std::string> split(const std::string& s, char separator) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  while (true) {
    const std::size_t end = s.find(separator, start);
    parts.push_back(s.substr(start, end == std::string::npos ? std::string::npos : end - start));
    if (end == std::string::npos) return parts;
    start = end + 1;
  }
}

std::optional<double> parse_number(const std::string& text) {
  double value = 0.0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size() || !std::isfinite(value)) return std::nullopt;
  return value;
}

std::optional<int> parse_count(const std::string& text) {
  int value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || error != std::errc() || end != text.data() + text.size()) return std::nullopt;
  return value;
}

std::string format(const char* pattern, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, pattern, value);
  return buffer;
}

std::string size_text(int width, int height) { return std::to_string(width) + "x" + std::to_string(height); }

std::string usage(BoardKind kind) {
  switch (kind) {
    case BoardKind::chess:
      return "chess:COLSxROWS:SQUARE_MM (e.g. chess:9x6:25)";
    case BoardKind::circles:
      return "circles:COLSxROWS:SPACING_MM (e.g. circles:7x6:20)";
    case BoardKind::asymmetric_circles:
      return "acircles:COLSxROWS:SPACING_MM (e.g. acircles:4x11:20)";
    case BoardKind::charuco:
      return "charuco:COLSxROWS:SQUARE_MM:MARKER_MM[:DICT] (e.g. charuco:11x8:20:15:4X4_50)";
  }
  return "";
}

// How a kind's COLSxROWS counts, for messages.
std::string counting(BoardKind kind) {
  switch (kind) {
    case BoardKind::chess:
      return "chess COLSxROWS counts inner corners (a board of 10 x 7 squares is chess:9x6)";
    case BoardKind::circles:
    case BoardKind::asymmetric_circles:
      return "circle grids' COLSxROWS counts circles per row and rows, as OpenCV's findCirclesGrid";
    case BoardKind::charuco:
      return "charuco COLSxROWS counts squares, and DICT must be the printed markers' dictionary";
  }
  return "";
}

// The board as OpenCV's ArUco module describes it (ChArUco only). In OpenCV 4.6, square (0, 0) is
// black, markers fill the white squares row by row, and inner corner id i (i = r (COLS - 1) + c)
// lies at ((c + 1) SQUARE, (r + 1) SQUARE), as board_points_m says.
cv::Ptr<cv::aruco::CharucoBoard> charuco_board(const BoardSpec& board) {
  const NamedDictionary* d = find_dictionary(board.dictionary);
  const cv::Ptr<cv::aruco::Dictionary> dictionary = cv::aruco::getPredefinedDictionary(d != nullptr ? d->id : cv::aruco::DICT_4X4_50);
  return cv::aruco::CharucoBoard::create(board.cols, board.rows, static_cast<float>(board.square_mm / 1000.0),
                                         static_cast<float>(board.marker_mm / 1000.0), dictionary);
}

// Dark round blobs, as candidates for findCirclesGrid: Otsu's threshold finds them, and each centre
// is the centroid of darkness (white level minus grey) over the blob and a 2-pixel rim, which
// follows an anti-aliased edge to a small fraction of a pixel where the binary centroids of OpenCV's
// SimpleBlobDetector move in whole-pixel steps (and it lives in features2d, which this library
// does not link).
std::vector<cv::Point2f> dark_blobs(const cv::Mat& grey) {
  cv::Mat dark;
  cv::threshold(grey, dark, 0, 255, cv::THRESH_BINARY_INV | cv::THRESH_OTSU);
  // The two classes' mean levels set the weights' scale.
  const cv::Scalar dark_mean = cv::mean(grey, dark);
  cv::Mat light_mask;
  cv::bitwise_not(dark, light_mask);
  const cv::Scalar light_mean = cv::mean(grey, light_mask);
  const double span = std::max(1.0, light_mean[0] - dark_mean[0]);
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(dark, contours, cv::RETR_LIST, cv::CHAIN_APPROX_NONE);
  std::vector<cv::Point2f> centres;
  const double max_area = 0.25 * static_cast<double>(grey.total());
  for (const std::vector<cv::Point>& contour : contours) {
    const double area = cv::contourArea(contour);
    if (area < 6.0 || area > max_area) continue;
    const double perimeter = cv::arcLength(contour, true);
    if (perimeter <= 0.0 || 4.0 * std::numbers::pi * area / (perimeter * perimeter) < 0.6) continue;  // round-ish
    std::vector<cv::Point> hull;
    cv::convexHull(contour, hull);
    if (area < 0.85 * cv::contourArea(hull)) continue;  // convex
    const cv::Rect box = cv::boundingRect(contour) + cv::Size(4, 4) - cv::Point(2, 2);
    const cv::Rect roi = box & cv::Rect(0, 0, grey.cols, grey.rows);
    cv::Mat mask = cv::Mat::zeros(roi.size(), CV_8UC1);
    cv::drawContours(mask, std::vector<std::vector<cv::Point>>{contour}, 0, cv::Scalar(255), cv::FILLED, cv::LINE_8, cv::noArray(), 0,
                     -roi.tl());
    cv::dilate(mask, mask, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(5, 5)));
    double sw = 0.0, sx = 0.0, sy = 0.0;
    for (int y = 0; y < roi.height; ++y) {
      const auto* g = grey.ptr<std::uint8_t>(roi.y + y) + roi.x;
      const auto* m = mask.ptr<std::uint8_t>(y);
      for (int x = 0; x < roi.width; ++x) {
        if (m[x] == 0) continue;
        const double weight = std::clamp((light_mean[0] - g[x]) / span, 0.0, 1.0);
        sw += weight;
        sx += weight * (roi.x + x);
        sy += weight * (roi.y + y);
      }
    }
    if (sw > 0.0) centres.emplace_back(static_cast<float>(sx / sw), static_cast<float>(sy / sw));
  }
  return centres;
}

// Sub-pixel chessboard corners (X-junctions), given each corner's point id and how many ids make a
// row of the grid. First cornerSubPix, then Förstner's operator: the point that minimises the
// gradient-weighted distance to the lines along every edge pixel in a window, computed on the
// picture's own pixel grid (gradients of the picture smoothed with a 1-pixel Gaussian).
// cornerSubPix solves the same equations on a window resampled bilinearly around its estimate,
// which leaves errors of 0.03-0.05 px on rendered corners; on the same corners Förstner's are
// 0.015 px. The window reaches 0.35 of the closest spacing between grid neighbours (2 to 12
// pixels), clear of the next corner; `markers_nearby` (ChArUco) discounts edges that do not pass
// through the corner.
void refine_corners(const cv::Mat& grey, const std::vector<int>& ids, int ids_per_row, bool markers_nearby,
                    std::vector<cv::Point2f>& corners) {
  std::map<int, std::size_t> index_of;
  for (std::size_t i = 0; i < ids.size(); ++i) index_of[ids[i]] = i;
  double spacing = 1e300;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    for (const int neighbour : {ids[i] % ids_per_row + 1 < ids_per_row ? ids[i] + 1 : -1, ids[i] + ids_per_row}) {
      const auto it = index_of.find(neighbour);
      if (it != index_of.end()) spacing = std::min(spacing, cv::norm(corners[it->second] - corners[i]));
    }
  }
  if (spacing > 1e299) return;
  const int half = static_cast<int>(std::clamp(std::floor(0.35 * spacing), 2.0, 12.0));
  const cv::TermCriteria criteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-4);
  cv::cornerSubPix(grey, corners, cv::Size(half, half), cv::Size(-1, -1), criteria);

  cv::Mat smooth, gx, gy;
  grey.convertTo(smooth, CV_32F);
  cv::GaussianBlur(smooth, smooth, cv::Size(0, 0), 1.0);
  cv::Sobel(smooth, gx, CV_32F, 1, 0, 3);
  cv::Sobel(smooth, gy, CV_32F, 0, 1, 3);
  const double sigma = half / 2.0;
  // On plain doubles: the sums run over every pixel of every window, and so stay quick in the
  // sanitizer builds too.
  for (cv::Point2f& corner : corners) {
    const double start_x = static_cast<double>(corner.x), start_y = static_cast<double>(corner.y);
    double qx = start_x, qy = start_y;
    bool ok = true;
    for (int iteration = 0; iteration < 20; ++iteration) {
      double a00 = 0.0, a01 = 0.0, a11 = 0.0, b0 = 0.0, b1 = 0.0;
      const int x0 = static_cast<int>(std::lround(qx)), y0 = static_cast<int>(std::lround(qy));
      for (int y = std::max(0, y0 - half); y <= std::min(grey.rows - 1, y0 + half); ++y) {
        const auto* row_x = gx.ptr<float>(y);
        const auto* row_y = gy.ptr<float>(y);
        for (int x = std::max(0, x0 - half); x <= std::min(grey.cols - 1, x0 + half); ++x) {
          const double g0 = static_cast<double>(row_x[x]), g1 = static_cast<double>(row_y[x]);
          const double g2 = g0 * g0 + g1 * g1;
          if (g2 <= 0.0) continue;
          const double px = x - qx, py = y - qy;
          double weight = std::exp(-(px * px + py * py) / (2.0 * sigma * sigma));
          if (markers_nearby) {
            // How far the edge line through this pixel passes from q, in pixels: the X-junction's
            // edges pass through it, a marker's edge does not and is down-weighted (Cauchy, 1 pixel).
            // Only where there are markers: on a plain chessboard it costs accuracy.
            weight /= 1.0 + (g0 * px + g1 * py) * (g0 * px + g1 * py) / g2;
          }
          const double m00 = weight * g0 * g0, m01 = weight * g0 * g1, m11 = weight * g1 * g1;
          a00 += m00;
          a01 += m01;
          a11 += m11;
          b0 += m00 * x + m01 * y;
          b1 += m01 * x + m11 * y;
        }
      }
      const double det = a00 * a11 - a01 * a01;
      if (!(det > 1e-12 * (a00 * a00 + 2.0 * a01 * a01 + a11 * a11))) {
        ok = false;
        break;
      }
      const double next_x = (a11 * b0 - a01 * b1) / det, next_y = (a00 * b1 - a01 * b0) / det;
      const double step = std::hypot(next_x - qx, next_y - qy);
      qx = next_x;
      qy = next_y;
      if (!std::isfinite(qx) || !std::isfinite(qy) || std::hypot(qx - start_x, qy - start_y) > 0.5 * half) {
        ok = false;
        break;
      }
      if (step < 1e-5) break;
    }
    if (ok) corner = cv::Point2f(static_cast<float>(qx), static_cast<float>(qy));
  }
}

std::expected<void, std::string> same_size(const BoardView& first, const BoardView& view) {
  if (view.width_px == first.width_px && view.height_px == first.height_px) return {};
  return std::unexpected(view.name + ": the image is " + size_text(view.width_px, view.height_px) + " but " + first.name + " is " +
                         size_text(first.width_px, first.height_px) + "; every image must come from one camera at one resolution");
}

// The printed board for board_picture: grey 0 (black) to 1 (white) at a board point (metres).
class BoardColour {
 public:
  explicit BoardColour(const BoardSpec& board) : board_(board), s_(board.square_mm / 1000.0) {
    if (board.kind != BoardKind::charuco) return;
    const cv::Ptr<cv::aruco::CharucoBoard> cb = charuco_board(board);
    marker_in_square_.assign(static_cast<std::size_t>(board.cols * board.rows), -1);
    for (std::size_t m = 0; m < cb->objPoints.size(); ++m) {
      const cv::Point3f& top_left = cb->objPoints[m][0];
      const double x = static_cast<double>(top_left.x), y = static_cast<double>(top_left.y);
      const int c = static_cast<int>(std::floor(x / s_)), r = static_cast<int>(std::floor(y / s_));
      if (c >= 0 && c < board.cols && r >= 0 && r < board.rows) {
        marker_in_square_[static_cast<std::size_t>(r * board.cols + c)] = static_cast<int>(m);
      }
      cv::Mat bits = cv::aruco::Dictionary::getBitsFromByteList(cb->dictionary->bytesList.rowRange(cb->ids[m], cb->ids[m] + 1),
                                                                cb->dictionary->markerSize);
      marker_bits_.push_back(bits);
      marker_corner_.emplace_back(x, y);
    }
    marker_m_ = board.marker_mm / 1000.0;
    marker_cells_ = cb->dictionary->markerSize + 2;  // a one-bit black border
  }

  // The board's outline: pattern plus a margin of one square.
  std::pair<Eigen::Vector2d, Eigen::Vector2d> extent() const {
    switch (board_.kind) {
      case BoardKind::chess:
        return {{-2 * s_, -2 * s_}, {(board_.cols + 1) * s_, (board_.rows + 1) * s_}};
      case BoardKind::circles:
        return {{-1.25 * s_, -1.25 * s_}, {(board_.cols - 1 + 1.25) * s_, (board_.rows - 1 + 1.25) * s_}};
      case BoardKind::asymmetric_circles:
        return {{-1.25 * s_, -1.25 * s_}, {(2.0 * (board_.cols - 1) + 1 + 1.25) * s_, (board_.rows - 1 + 1.25) * s_}};
      case BoardKind::charuco:
        return {{-s_, -s_}, {(board_.cols + 1) * s_, (board_.rows + 1) * s_}};
    }
    return {};
  }

  double operator()(double u, double v) const {
    switch (board_.kind) {
      case BoardKind::chess: {
        const int c = static_cast<int>(std::floor(u / s_)), r = static_cast<int>(std::floor(v / s_));
        if (c < -1 || c > board_.cols - 1 || r < -1 || r > board_.rows - 1) return 1.0;
        return (c + r) % 2 == 0 ? 0.0 : 1.0;
      }
      case BoardKind::circles:
      case BoardKind::asymmetric_circles: {
        const double radius = 0.25 * s_;  // diameter half the spacing
        for (int r = 0; r < board_.rows; ++r) {
          if (std::abs(v - r * s_) > radius) continue;
          for (int c = 0; c < board_.cols; ++c) {
            const double x = board_.kind == BoardKind::circles ? c * s_ : (2.0 * c + r % 2) * s_;
            if (std::hypot(u - x, v - r * s_) < radius) return 0.0;
          }
        }
        return 1.0;
      }
      case BoardKind::charuco: {
        const int c = static_cast<int>(std::floor(u / s_)), r = static_cast<int>(std::floor(v / s_));
        if (c < 0 || c >= board_.cols || r < 0 || r >= board_.rows) return 1.0;
        if ((c + r) % 2 == 0) return 0.0;
        const int m = marker_in_square_[static_cast<std::size_t>(r * board_.cols + c)];
        if (m < 0) return 1.0;
        const Eigen::Vector2d local = (Eigen::Vector2d(u, v) - marker_corner_[static_cast<std::size_t>(m)]) / marker_m_;
        if (local.x() < 0 || local.y() < 0 || local.x() >= 1 || local.y() >= 1) return 1.0;
        const int bx = static_cast<int>(local.x() * marker_cells_), by = static_cast<int>(local.y() * marker_cells_);
        if (bx == 0 || by == 0 || bx == marker_cells_ - 1 || by == marker_cells_ - 1) return 0.0;
        return marker_bits_[static_cast<std::size_t>(m)].at<std::uint8_t>(by - 1, bx - 1) != 0 ? 1.0 : 0.0;
      }
    }
    return 1.0;
  }

 private:
  const BoardSpec& board_;
  double s_;
  std::vector<int> marker_in_square_;
  std::vector<cv::Mat> marker_bits_;
  std::vector<Eigen::Vector2d> marker_corner_;
  double marker_m_ = 0.0;
  int marker_cells_ = 0;
};

}  // namespace

std::string BoardSpec::to_string() const {
  const auto mm = [](double v) { return format("%g", v); };
  const std::string size = std::to_string(cols) + "x" + std::to_string(rows);
  switch (kind) {
    case BoardKind::chess:
      return "chess:" + size + ":" + mm(square_mm);
    case BoardKind::circles:
      return "circles:" + size + ":" + mm(square_mm);
    case BoardKind::asymmetric_circles:
      return "acircles:" + size + ":" + mm(square_mm);
    case BoardKind::charuco:
      return "charuco:" + size + ":" + mm(square_mm) + ":" + mm(marker_mm) + ":" + dictionary;
  }
  return "";
}

int BoardSpec::point_count() const { return kind == BoardKind::charuco ? (cols - 1) * (rows - 1) : cols * rows; }

std::expected<BoardSpec, std::string> parse_board_spec(const std::string& spec) {
  const std::string quoted = "board \"" + spec + "\": ";
  const std::vector<std::string> parts = split(spec, ':');
  BoardSpec board;
  const std::string kind = parts[0];
  if (kind == "chess") {
    board.kind = BoardKind::chess;
  } else if (kind == "circles") {
    board.kind = BoardKind::circles;
  } else if (kind == "acircles") {
    board.kind = BoardKind::asymmetric_circles;
  } else if (kind == "charuco") {
    board.kind = BoardKind::charuco;
  } else {
    return std::unexpected(quoted + "expected " + usage(BoardKind::chess) + ", " + usage(BoardKind::circles) + ", " +
                           usage(BoardKind::asymmetric_circles) + " or " + usage(BoardKind::charuco));
  }
  const bool charuco = board.kind == BoardKind::charuco;
  const std::size_t want = charuco ? 4 : 3;
  if (parts.size() != want && !(charuco && parts.size() == 5)) return std::unexpected(quoted + "expected " + usage(board.kind));

  const std::vector<std::string> counts = split(parts[1], 'x');
  const std::optional<int> cols = counts.size() == 2 ? parse_count(counts[0]) : std::nullopt;
  const std::optional<int> rows = counts.size() == 2 ? parse_count(counts[1]) : std::nullopt;
  if (!cols || !rows) {
    return std::unexpected(quoted + "COLSxROWS must be two whole numbers joined by 'x' (e.g. 9x6), got \"" + parts[1] + "\"");
  }
  const int minimum = board.kind == BoardKind::chess ? 2 : 3;
  if (*cols < minimum || *rows < minimum || *cols > 100 || *rows > 100) {
    return std::unexpected(quoted + "COLS and ROWS must each be " + std::to_string(minimum) + " to 100, got " + parts[1] + "; " +
                           counting(board.kind));
  }
  board.cols = *cols;
  board.rows = *rows;

  const char* square_name = (board.kind == BoardKind::chess || charuco) ? "SQUARE_MM" : "SPACING_MM";
  const std::optional<double> square = parse_number(parts[2]);
  if (!square || *square <= 0.0) {
    return std::unexpected(quoted + square_name + " must be a positive number of millimetres, got \"" + parts[2] + "\"");
  }
  board.square_mm = *square;
  if (!charuco) return board;

  const std::optional<double> marker = parse_number(parts[3]);
  if (!marker || *marker <= 0.0 || *marker >= board.square_mm) {
    return std::unexpected(quoted + "MARKER_MM must be a positive number of millimetres less than SQUARE_MM (" + parts[2] + "), got \"" +
                           parts[3] + "\"");
  }
  board.marker_mm = *marker;
  if (parts.size() == 5) {
    const NamedDictionary* d = find_dictionary(parts[4]);
    if (d == nullptr) {
      std::string names;
      for (const NamedDictionary& n : kDictionaries) names += std::string(names.empty() ? "" : ", ") + n.name;
      return std::unexpected(quoted + "unknown dictionary \"" + parts[4] + "\"; expected one of " + names);
    }
    board.dictionary = d->name;
  }
  const int markers = board.cols * board.rows / 2;
  const NamedDictionary* d = find_dictionary(board.dictionary);
  if (markers > d->markers) {
    // Suggest the smallest dictionary with enough markers, of the same marker size where one has.
    const auto family = [](const NamedDictionary& n) { return std::string(n.name).substr(0, 4); };
    const NamedDictionary* suggestion = nullptr;
    for (const NamedDictionary& n : kDictionaries) {
      if (n.markers < markers) continue;
      const auto rank = [&](const NamedDictionary& m) { return std::pair{family(m) != family(*d), m.markers}; };
      if (suggestion == nullptr || rank(n) < rank(*suggestion)) suggestion = &n;
    }
    return std::unexpected(
        quoted + std::to_string(board.cols) + "x" + std::to_string(board.rows) + " squares hold " + std::to_string(markers) +
        " markers but dictionary " + d->name + " has " + std::to_string(d->markers) +
        (suggestion != nullptr ? std::string("; name a larger one, e.g. ") + suggestion->name : std::string("; use fewer squares")));
  }
  return board;
}

std::vector<Eigen::Vector3d> board_points_m(const BoardSpec& board) {
  std::vector<Eigen::Vector3d> points;
  const double s = board.square_mm / 1000.0;
  switch (board.kind) {
    case BoardKind::chess:
    case BoardKind::circles:
      for (int r = 0; r < board.rows; ++r) {
        for (int c = 0; c < board.cols; ++c) points.emplace_back(c * s, r * s, 0.0);
      }
      break;
    case BoardKind::asymmetric_circles:
      for (int r = 0; r < board.rows; ++r) {
        for (int c = 0; c < board.cols; ++c) points.emplace_back((2.0 * c + r % 2) * s, r * s, 0.0);
      }
      break;
    case BoardKind::charuco:
      for (int r = 1; r < board.rows; ++r) {
        for (int c = 1; c < board.cols; ++c) points.emplace_back(c * s, r * s, 0.0);
      }
      break;
  }
  return points;
}

std::expected<BoardPicture, std::string> board_picture(const BoardSpec& board, int pixels_per_square) {
  if (pixels_per_square < 4 || pixels_per_square > 1000) {
    return std::unexpected("board picture: expected 4 to 1000 pixels per square, got " + std::to_string(pixels_per_square));
  }
  const BoardColour colour(board);
  const auto [lo, hi] = colour.extent();
  BoardPicture picture;
  picture.pixel_m = board.square_mm / 1000.0 / pixels_per_square;
  // The outline rounded outwards to whole pixels, so square edges fall on pixel edges.
  const double first_x = std::floor(lo.x() / picture.pixel_m + 1e-9), first_y = std::floor(lo.y() / picture.pixel_m + 1e-9);
  picture.corner_board_m = Eigen::Vector2d(first_x, first_y) * picture.pixel_m;
  picture.width_px = static_cast<int>(std::ceil(hi.x() / picture.pixel_m - 1e-9) - first_x);
  picture.height_px = static_cast<int>(std::ceil(hi.y() / picture.pixel_m - 1e-9) - first_y);
  if (static_cast<double>(picture.width_px) * picture.height_px > 2.5e8) {
    return std::unexpected("board picture: " + size_text(picture.width_px, picture.height_px) +
                           " pixels is too large; use fewer pixels per square");
  }
  picture.grey.resize(static_cast<std::size_t>(picture.width_px) * picture.height_px);
  constexpr int kSub = 4;  // sub-samples per pixel side, for anti-aliased circles and marker edges off the pixel grid
  for (int y = 0; y < picture.height_px; ++y) {
    for (int x = 0; x < picture.width_px; ++x) {
      double sum = 0.0;
      for (int b = 0; b < kSub; ++b) {
        for (int a = 0; a < kSub; ++a) {
          sum += colour(picture.corner_board_m.x() + (x + (a + 0.5) / kSub) * picture.pixel_m,
                        picture.corner_board_m.y() + (y + (b + 0.5) / kSub) * picture.pixel_m);
        }
      }
      picture.grey[static_cast<std::size_t>(y) * picture.width_px + x] =
          static_cast<std::uint8_t>(std::lround(255.0 * sum / (kSub * kSub)));
    }
  }
  return picture;
}

std::expected<BoardView, std::string> detect_board(const std::filesystem::path& image, const BoardSpec& board) {
  auto read = read_image(image, ImageRead::kGrey);
  if (!read) return std::unexpected(read.error());
  cv::Mat grey = std::move(*read);
  BoardView view;
  view.name = image.filename().string();
  view.width_px = grey.cols;
  view.height_px = grey.rows;
  std::vector<cv::Point2f> corners;
  std::vector<int> ids;
  try {
    switch (board.kind) {
      case BoardKind::chess: {
        // The classic detector first (milliseconds), the sector-based one where it fails (robust to
        // blur, tilt, distortion and uneven light, but near a second a picture); then
        // refine_corners, which on rendered pictures places corners 5 times closer to the truth
        // than the sector-based detector's own refinement. The classic detector runs without
        // CALIB_CB_ADAPTIVE_THRESH: on a picture of a board with other counts of corners it then
        // searched for 20 to 40 s (its quad linking explodes), and on every rendered picture it
        // found nothing the plain one did not.
        const cv::Size pattern(board.cols, board.rows);
        bool found = cv::findChessboardCorners(grey, pattern, corners, cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_FAST_CHECK);
        if (!found) found = cv::findChessboardCornersSB(grey, pattern, corners, cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_EXHAUSTIVE);
        if (found) {
          std::vector<int> grid_ids(corners.size());
          for (std::size_t i = 0; i < grid_ids.size(); ++i) grid_ids[i] = static_cast<int>(i);
          refine_corners(grey, grid_ids, board.cols, false, corners);
        } else {
          corners.clear();
        }
        break;
      }
      case BoardKind::circles:
      case BoardKind::asymmetric_circles: {
        const std::vector<cv::Point2f> candidates = dark_blobs(grey);
        const int flags = board.kind == BoardKind::circles ? cv::CALIB_CB_SYMMETRIC_GRID : cv::CALIB_CB_ASYMMETRIC_GRID;
        // A null detector tells OpenCV the "image" is already the candidate centres.
        if (candidates.size() < static_cast<std::size_t>(board.cols * board.rows) ||
            !cv::findCirclesGrid(candidates, cv::Size(board.cols, board.rows), corners, flags, cv::Ptr<cv::FeatureDetector>(),
                                 cv::CirclesGridFinderParameters())) {
          corners.clear();
        }
        break;
      }
      case BoardKind::charuco: {
        const cv::Ptr<cv::aruco::CharucoBoard> cb = charuco_board(board);
        std::vector<std::vector<cv::Point2f>> marker_corners;
        std::vector<int> marker_ids;
        cv::aruco::detectMarkers(grey, cb->dictionary, marker_corners, marker_ids);
        if (!marker_ids.empty()) cv::aruco::interpolateCornersCharuco(marker_corners, marker_ids, grey, cb, corners, ids);
        std::set<int> rows, cols;
        for (const int id : ids) {
          rows.insert(id / (board.cols - 1));
          cols.insert(id % (board.cols - 1));
        }
        if (corners.size() < 6 || rows.size() < 2 || cols.size() < 2) {  // too few, or all on one line
          corners.clear();
          ids.clear();
        } else {
          refine_corners(grey, ids, board.cols - 1, true, corners);
        }
        break;
      }
    }
  } catch (const cv::Exception&) {
    corners.clear();  // OpenCV gave up on this picture: the board was not found in it
    ids.clear();
  }
  if (corners.empty()) return view;
  if (board.kind != BoardKind::charuco) {
    ids.resize(corners.size());
    for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = static_cast<int>(i);
  }
  const std::vector<Eigen::Vector3d> points = board_points_m(board);
  for (std::size_t i = 0; i < corners.size(); ++i) {
    if (!std::isfinite(corners[i].x) || !std::isfinite(corners[i].y) || ids[i] < 0 || ids[i] >= static_cast<int>(points.size())) continue;
    view.corners_px.emplace_back(static_cast<double>(corners[i].x), static_cast<double>(corners[i].y));
    view.point_ids.push_back(ids[i]);
    view.points_board_m.push_back(points[static_cast<std::size_t>(ids[i])]);
  }
  return view;
}

std::expected<std::vector<BoardView>, std::string> detect_boards(const std::vector<std::filesystem::path>& images, const BoardSpec& board,
                                                                 const DetectProgress& progress) {
  if (images.empty()) return std::unexpected("no images: give the pictures of the board (files, or folders of them)");
  for (const std::filesystem::path& image : images) {  // a mistyped name fails before minutes of detection
    std::error_code error;
    if (!std::filesystem::is_regular_file(image, error)) return std::unexpected(image.string() + ": no such file");
  }
  std::vector<BoardView> views;
  int found = 0;
  for (std::size_t i = 0; i < images.size(); ++i) {
    if (progress) progress(static_cast<int>(i + 1), static_cast<int>(images.size()), images[i].filename().string());
    auto view = detect_board(images[i], board);
    if (!view) return std::unexpected(view.error());
    if (!views.empty()) {
      if (auto ok = same_size(views.front(), *view); !ok) return std::unexpected(ok.error());
    }
    found += view->found() ? 1 : 0;
    views.push_back(std::move(*view));
    // A board in none of the first pictures is most often a spec that counts differently from the
    // printed board: said now, not after every picture has been searched in vain.
    if (found == 0 && views.size() == static_cast<std::size_t>(kBoardSearchGiveUpViews) && images.size() > views.size()) {
      return std::unexpected("board " + board.to_string() + " not found in any of the first " + std::to_string(views.size()) + " of " +
                             std::to_string(images.size()) + " images, so the others were not searched; is the board's size right? " +
                             counting(board.kind));
    }
  }
  if (found == 0) {
    return std::unexpected("board " + board.to_string() + " not found in any of the " + std::to_string(images.size()) + " images; " +
                           counting(board.kind));
  }
  return views;
}

std::expected<void, std::string> IntrinsicsSettings::check() const {
  if (worst_view_count < 0) return std::unexpected("worst_view_count: expected 0 or more, got " + std::to_string(worst_view_count));
  if (!std::isfinite(min_coverage) || min_coverage < 0.0 || min_coverage > 1.0) {
    return std::unexpected("min_coverage: expected a fraction from 0 to 1, got " + std::to_string(min_coverage));
  }
  if (!std::isfinite(min_orientation_spread_deg) || min_orientation_spread_deg < 0.0 || min_orientation_spread_deg > 180.0) {
    return std::unexpected("min_orientation_spread_deg: expected 0 to 180 degrees, got " + std::to_string(min_orientation_spread_deg));
  }
  if (recommended_views < 0) return std::unexpected("recommended_views: expected 0 or more, got " + std::to_string(recommended_views));
  if (!std::isfinite(outlier_view_factor) || outlier_view_factor < 1.0) {
    return std::unexpected("outlier_view_factor: expected 1 or more, got " + std::to_string(outlier_view_factor));
  }
  return {};
}

namespace {

struct CvViews {
  std::vector<std::vector<cv::Point3f>> object;
  std::vector<std::vector<cv::Point2f>> image;
};

CvViews to_cv(const std::vector<const BoardView*>& views) {
  CvViews out;
  for (const BoardView* v : views) {
    std::vector<cv::Point3f> object;
    std::vector<cv::Point2f> image;
    for (std::size_t i = 0; i < v->corners_px.size(); ++i) {
      const Eigen::Vector3d& p = v->points_board_m[i];
      object.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
      image.emplace_back(static_cast<float>(v->corners_px[i].x()), static_cast<float>(v->corners_px[i].y()));
    }
    out.object.push_back(std::move(object));
    out.image.push_back(std::move(image));
  }
  return out;
}

// Observed - predicted for each point of one view, and their RMS length.
std::vector<Eigen::Vector2d> residuals(const std::vector<cv::Point3f>& object, const std::vector<cv::Point2f>& image, const cv::Mat& rvec,
                                       const cv::Mat& tvec, const cv::Mat& k, const cv::Mat& dist, double& rms_px) {
  std::vector<cv::Point2f> predicted;
  cv::projectPoints(object, rvec, tvec, k, dist, predicted);
  std::vector<Eigen::Vector2d> out;
  double sum = 0.0;
  for (std::size_t i = 0; i < image.size(); ++i) {
    out.emplace_back(static_cast<double>(image[i].x) - static_cast<double>(predicted[i].x),
                     static_cast<double>(image[i].y) - static_cast<double>(predicted[i].y));
    sum += out.back().squaredNorm();
  }
  rms_px = image.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(image.size()));
  return out;
}

const cv::TermCriteria kCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 200, 1e-12);

// The views calibration uses (the board found, with at least 4 points), in input order; the others'
// names go to report.skipped. Errors: views of different sizes, fewer than 3 usable views.
std::expected<std::vector<const BoardView*>, std::string> usable_views(const std::vector<BoardView>& views, IntrinsicsReport& report) {
  std::vector<const BoardView*> used;
  for (const BoardView& v : views) {
    if (auto ok = same_size(views.front(), v); !ok) return std::unexpected(ok.error());
    if (v.found() && v.corners_px.size() == v.points_board_m.size() && v.corners_px.size() >= 4) {
      used.push_back(&v);
    } else {
      report.skipped.push_back(v.name);
    }
  }
  if (used.size() < 3) {
    return std::unexpected("the board was found in only " + std::to_string(used.size()) + " of " + std::to_string(views.size()) +
                           " images; Zhang's method needs at least 3 views, and 10 to 20 with the board tilted differently give intrinsics "
                           "worth trusting");
  }
  return used;
}

// Zhang's method over every used view, as OpenCV solves it: the camera matrix, the distortion and
// each view's pose (rvec, tvec), for the leave-one-out and per-view phases to start from.
struct ZhangFit {
  cv::Size size;
  int flags = 0;
  cv::Mat k, dist;
  std::vector<cv::Mat> rvecs, tvecs;
};

// The fit, its intrinsics and their uncertainties into the report. Errors: OpenCV fails, or gives
// non-finite values, focal lengths that are not positive or a principal point off the image.
std::expected<ZhangFit, std::string> fit_intrinsics(const CvViews& cv_views, cv::Size size, const IntrinsicsSettings& settings,
                                                    IntrinsicsReport& report) {
  ZhangFit fit;
  fit.size = size;
  fit.flags = settings.fix_k3 ? cv::CALIB_FIX_K3 : 0;
  fit.k = cv::Mat::eye(3, 3, CV_64F);
  fit.dist = cv::Mat::zeros(5, 1, CV_64F);
  cv::Mat sigma_intrinsics, sigma_extrinsics, per_view;
  try {
    cv::calibrateCamera(cv_views.object, cv_views.image, size, fit.k, fit.dist, fit.rvecs, fit.tvecs, sigma_intrinsics, sigma_extrinsics,
                        per_view, fit.flags, kCriteria);
  } catch (const cv::Exception& e) {
    return std::unexpected("calibration failed (OpenCV: " + e.msg + "); check the board spec and the pictures");
  }
  CameraIntrinsics& intr = report.intrinsics;
  intr.width_px = size.width;
  intr.height_px = size.height;
  intr.fx = fit.k.at<double>(0, 0);
  intr.fy = fit.k.at<double>(1, 1);
  intr.cx = fit.k.at<double>(0, 2);
  intr.cy = fit.k.at<double>(1, 2);
  for (int i = 0; i < 5; ++i) intr.distortion[static_cast<std::size_t>(i)] = fit.dist.at<double>(i);
  const bool finite = std::isfinite(intr.fx) && std::isfinite(intr.fy) && std::isfinite(intr.cx) && std::isfinite(intr.cy) &&
                      std::all_of(intr.distortion.begin(), intr.distortion.end(), [](double d) { return std::isfinite(d); });
  if (!finite) return std::unexpected("calibration failed: it gave non-finite values; check the board spec and the pictures");
  if (!(intr.fx > 0.0) || !(intr.fy > 0.0)) {
    return std::unexpected("calibration failed: focal length " + format("%.6g", intr.fx) + " x " + format("%.6g", intr.fy) +
                           " px is not positive; check the board spec and the pictures");
  }
  if (intr.cx < 0.0 || intr.cx >= size.width || intr.cy < 0.0 || intr.cy >= size.height) {
    return std::unexpected("calibration failed: principal point (" + format("%.1f", intr.cx) + ", " + format("%.1f", intr.cy) +
                           ") px lies outside the " + size_text(size.width, size.height) +
                           " image; the views do not constrain it: add tilted views");
  }
  if (sigma_intrinsics.total() >= 9) {
    const auto sigma = [&](int i) {
      const double s = sigma_intrinsics.at<double>(i);
      return std::isfinite(s) ? s : 0.0;
    };
    report.fx_sigma = sigma(0);
    report.fy_sigma = sigma(1);
    report.cx_sigma = sigma(2);
    report.cy_sigma = sigma(3);
    for (int i = 0; i < 5; ++i) report.distortion_sigma[static_cast<std::size_t>(i)] = sigma(4 + i);
  }
  return fit;
}

// Per view its residuals, pose and tilt; over all of them the RMS, the image's coverage, the range
// of tilts and the spread of the board's orientations. Error: a reprojection error that is not finite.
std::expected<void, std::string> measure_views(const std::vector<const BoardView*>& used, const CvViews& cv_views, const ZhangFit& fit,
                                               IntrinsicsReport& report) {
  double sum_sq = 0.0;
  std::size_t points = 0;
  std::vector<Eigen::Vector3d> normals;
  std::vector<Eigen::Vector2d> all_corners;
  for (std::size_t v = 0; v < used.size(); ++v) {
    ViewResult result;
    result.name = used[v]->name;
    result.corners_px = used[v]->corners_px;
    result.residuals_px = residuals(cv_views.object[v], cv_views.image[v], fit.rvecs[v], fit.tvecs[v], fit.k, fit.dist, result.rms_px);
    for (const Eigen::Vector2d& r : result.residuals_px) sum_sq += r.squaredNorm();
    points += result.residuals_px.size();
    cv::Mat rotation;
    cv::Rodrigues(fit.rvecs[v], rotation);
    Eigen::Matrix3d r;
    for (int i = 0; i < 9; ++i) r(i / 3, i % 3) = rotation.at<double>(i / 3, i % 3);
    result.camera_from_board.rotation = Eigen::Quaterniond(r).normalized();
    result.camera_from_board.translation =
        Eigen::Vector3d(fit.tvecs[v].at<double>(0), fit.tvecs[v].at<double>(1), fit.tvecs[v].at<double>(2));
    Eigen::Vector3d normal = r.col(2);
    if (normal.z() < 0) normal = -normal;  // a plane's orientation, whichever side faces the camera
    normals.push_back(normal);
    result.tilt_deg = std::acos(std::clamp(normal.z(), -1.0, 1.0)) * kDeg;
    all_corners.insert(all_corners.end(), used[v]->corners_px.begin(), used[v]->corners_px.end());
    report.views.push_back(std::move(result));
  }
  report.rms_px = std::sqrt(sum_sq / static_cast<double>(std::max<std::size_t>(points, 1)));
  if (!std::isfinite(report.rms_px)) return std::unexpected("calibration failed: the reprojection error is not finite");
  report.coverage = image_coverage(fit.size.width, fit.size.height, all_corners);
  report.tilt_min_deg = 180.0;
  for (std::size_t a = 0; a < normals.size(); ++a) {
    report.tilt_min_deg = std::min(report.tilt_min_deg, report.views[a].tilt_deg);
    report.tilt_max_deg = std::max(report.tilt_max_deg, report.views[a].tilt_deg);
    for (std::size_t b = a + 1; b < normals.size(); ++b) {
      report.orientation_spread_deg =
          std::max(report.orientation_spread_deg, std::acos(std::clamp(normals[a].dot(normals[b]), -1.0, 1.0)) * kDeg);
    }
  }
  return {};
}

// Leave one out: calibrate without view v (from the full answer, so it converges quickly), solve
// v's pose with those intrinsics, and measure v's error. A view whose calibration or pose fails
// stays without a held-out error.
void leave_one_out(const CvViews& cv_views, const ZhangFit& fit, IntrinsicsReport& report) {
  const std::size_t count = cv_views.object.size();
  double held_sum_sq = 0.0;
  std::size_t held_points = 0;
  for (std::size_t v = 0; v < count; ++v) {
    CvViews rest;
    for (std::size_t o = 0; o < count; ++o) {
      if (o == v) continue;
      rest.object.push_back(cv_views.object[o]);
      rest.image.push_back(cv_views.image[o]);
    }
    cv::Mat k_rest = fit.k.clone(), dist_rest = fit.dist.clone();
    try {
      std::vector<cv::Mat> r_rest, t_rest;
      cv::calibrateCamera(rest.object, rest.image, fit.size, k_rest, dist_rest, r_rest, t_rest, fit.flags | cv::CALIB_USE_INTRINSIC_GUESS,
                          kCriteria);
      cv::Mat rvec = fit.rvecs[v].clone(), tvec = fit.tvecs[v].clone();
      if (!cv::solvePnP(cv_views.object[v], cv_views.image[v], k_rest, dist_rest, rvec, tvec, true, cv::SOLVEPNP_ITERATIVE)) continue;
      double rms = 0.0;
      const std::vector<Eigen::Vector2d> r = residuals(cv_views.object[v], cv_views.image[v], rvec, tvec, k_rest, dist_rest, rms);
      if (!std::isfinite(rms)) continue;
      report.views[v].held_out_rms_px = rms;
      for (const Eigen::Vector2d& e : r) held_sum_sq += e.squaredNorm();
      held_points += r.size();
    } catch (const cv::Exception&) {
      continue;  // this view stays without a held-out error
    }
  }
  if (held_points > 0) report.leave_one_out_rms_px = std::sqrt(held_sum_sq / static_cast<double>(held_points));
}

// The worst views, highest RMS first, and the warnings: what to fix before trusting the result.
void add_worst_views_and_warnings(std::size_t image_count, const IntrinsicsSettings& settings, IntrinsicsReport& report) {
  std::vector<std::size_t> order(report.views.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return report.views[a].rms_px > report.views[b].rms_px; });
  for (std::size_t i = 0; i < order.size() && static_cast<int>(i) < settings.worst_view_count; ++i) {
    report.worst_views.push_back(report.views[order[i]].name);
  }
  const std::string views_text = std::to_string(report.views.size());
  if (!report.skipped.empty()) {
    std::string names;
    for (std::size_t i = 0; i < report.skipped.size() && i < 5; ++i) names += (i == 0 ? "" : ", ") + report.skipped[i];
    if (report.skipped.size() > 5) names += ", ...";
    report.warnings.push_back("the board was not found in " + std::to_string(report.skipped.size()) + " of " + std::to_string(image_count) +
                              " images (" + names + "); they were left out");
  }
  if (static_cast<int>(report.views.size()) < settings.recommended_views) {
    report.warnings.push_back("only " + views_text + " views found the board; " + std::to_string(settings.recommended_views) +
                              " or more (10 to 20), the board tilted differently in each, give intrinsics worth trusting");
  }
  if (report.coverage < settings.min_coverage) {
    report.warnings.push_back("the corners cover only " + format("%.0f", 100.0 * report.coverage) +
                              " % of the image (cells of a 16 x 16 grid); the distortion is extrapolated where they did not reach: add "
                              "views with the board near the image's edges and corners (see the picture)");
  }
  if (report.orientation_spread_deg < settings.min_orientation_spread_deg) {
    report.warnings.push_back("the board's orientations span only " + format("%.0f", report.orientation_spread_deg) +
                              " deg; focal length and principal point are poorly determined: tilt the board 20 to 45 deg towards and "
                              "away from the camera, about different axes");
  }
  std::vector<double> rms;
  for (const ViewResult& v : report.views) rms.push_back(v.rms_px);
  std::nth_element(rms.begin(), rms.begin() + static_cast<std::ptrdiff_t>(rms.size() / 2), rms.end());
  const double median = rms[rms.size() / 2];
  for (const ViewResult& v : report.views) {
    if (v.rms_px > settings.outlier_view_factor * median && v.rms_px > 0.5) {
      report.warnings.push_back("view " + v.name + " has an RMS of " + format("%.2f", v.rms_px) + " px, " +
                                format("%.1f", v.rms_px / median) +
                                " times the median: blurred, or the board misdetected? Drop it and calibrate again");
    }
  }
  if (report.leave_one_out_rms_px && *report.leave_one_out_rms_px > 3.0 * report.rms_px && *report.leave_one_out_rms_px > 0.5) {
    report.warnings.push_back("the leave-one-out RMS (" + format("%.2f", *report.leave_one_out_rms_px) + " px) is many times the fit's (" +
                              format("%.2f", report.rms_px) + " px): the intrinsics follow these views too closely; add views" +
                              (settings.fix_k3 ? "" : ", or fix k3"));
  }
}

}  // namespace

std::expected<IntrinsicsReport, std::string> calibrate_intrinsics(const std::vector<BoardView>& views, const IntrinsicsSettings& settings) {
  if (auto ok = settings.check(); !ok) return std::unexpected("intrinsics settings: " + ok.error());
  if (views.empty()) return std::unexpected("no images: give the pictures of the board (files, or folders of them)");
  IntrinsicsReport report;
  report.k3_fixed = settings.fix_k3;
  const auto used = usable_views(views, report);
  if (!used) return std::unexpected(used.error());
  const CvViews cv_views = to_cv(*used);
  const auto fit = fit_intrinsics(cv_views, cv::Size(views.front().width_px, views.front().height_px), settings, report);
  if (!fit) return std::unexpected(fit.error());
  if (auto measured = measure_views(*used, cv_views, *fit, report); !measured) return std::unexpected(measured.error());
  if (settings.leave_one_out && used->size() >= 4) leave_one_out(cv_views, *fit, report);
  add_worst_views_and_warnings(views.size(), settings, report);
  return report;
}

}  // namespace rhot
