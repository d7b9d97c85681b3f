#include "tracking/calib/Detections.h"

#include <charconv>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <map>
#include <sstream>

namespace rhot {

namespace {

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r");
  if (a == std::string::npos) return "";
  const auto b = s.find_last_not_of(" \t\r");
  return s.substr(a, b - a + 1);
}

std::vector<std::string> split_trimmed(const std::string& line, char sep) {
  std::vector<std::string> out;
  std::string field;
  std::istringstream in(line);
  while (std::getline(in, field, sep)) out.push_back(trim(field));
  if (!line.empty() && line.back() == sep) out.emplace_back();
  return out;
}

bool parse_long(const std::string& s, long& out) {
  const char* end = s.data() + s.size();
  const auto r = std::from_chars(s.data(), end, out);
  return r.ec == std::errc() && r.ptr == end && !s.empty();
}

bool parse_double(const std::string& s, double& out) {
  const char* end = s.data() + s.size();
  const auto r = std::from_chars(s.data(), end, out);
  return r.ec == std::errc() && r.ptr == end && !s.empty();
}

// Whitespace-separated numbers of a text matrix file, row by row.
std::expected<std::vector<std::vector<double>>, std::string> read_matrix_file(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) return std::unexpected(file.string() + ": cannot open");
  std::vector<std::vector<double>> rows;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    std::istringstream fields(line);
    std::vector<double> row;
    std::string token;
    while (fields >> token) {
      double v = 0;
      // MATLAB writes NaN for frames a camera missed; keep them as NaN, masked by IdMat.
      if (token == "NaN" || token == "nan") {
        v = std::nan("");
      } else if (!parse_double(token, v)) {
        return std::unexpected(file.string() + ":" + std::to_string(line_no) + ": expected a number, got \"" + token + "\"");
      }
      row.push_back(v);
    }
    if (!row.empty()) rows.push_back(std::move(row));
  }
  return rows;
}

}  // namespace

std::size_t Detections::count() const {
  std::size_t n = 0;
  for (const DetectionFrame& f : frames) n += f.observations.size();
  return n;
}

std::expected<Detections, std::string> read_detections_csv(const std::filesystem::path& file) {
  const std::string name = file.string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) return std::unexpected(name + ": detections file not found");
  std::ifstream in(file);
  if (!in) return std::unexpected(name + ": cannot open");
  std::map<long, DetectionFrame> frames;
  Detections d;
  std::string line;
  int line_no = 0;
  bool first = true;
  while (std::getline(in, line)) {
    ++line_no;
    const std::string t = trim(line);
    if (t.empty() || t[0] == '#') continue;
    const std::string where = name + ":" + std::to_string(line_no) + ": ";
    if (first) {
      first = false;
      if (t.rfind("frame", 0) == 0) continue;  // the header
    }
    const std::vector<std::string> f = split_trimmed(t, ',');
    if (f.size() != 4 && f.size() != 5) {
      return std::unexpected(where + "expected 4 or 5 comma-separated fields (frame,camera,x,y[,marker]), got " + std::to_string(f.size()));
    }
    long frame = 0, camera = 0, marker = -1;
    double x = 0, y = 0;
    if (!parse_long(f[0], frame) || frame < 0)
      return std::unexpected(where + "frame: expected a non-negative integer, got \"" + f[0] + "\"");
    if (!parse_long(f[1], camera) || camera < 0 || camera >= 256) {
      return std::unexpected(where + "camera: expected a camera index 0 to 255, got \"" + f[1] + "\"");
    }
    if (!parse_double(f[2], x) || !std::isfinite(x)) return std::unexpected(where + "x: expected a finite number, got \"" + f[2] + "\"");
    if (!parse_double(f[3], y) || !std::isfinite(y)) return std::unexpected(where + "y: expected a finite number, got \"" + f[3] + "\"");
    if (std::abs(x) > 1e6 || std::abs(y) > 1e6)
      return std::unexpected(where + "x,y: expected a pixel within 1e6 of the image, got " + f[2] + "," + f[3]);
    if (f.size() == 5 && !f[4].empty() && (!parse_long(f[4], marker) || marker < -1 || marker > 1000000)) {
      return std::unexpected(where + "marker: expected -1 (unknown) or a marker id 0 to 1000000, got \"" + f[4] + "\"");
    }
    DetectionFrame& df = frames[frame];
    df.frame = frame;
    df.observations.push_back({static_cast<int>(camera), {x, y}, static_cast<int>(marker)});
    d.camera_count = std::max(d.camera_count, static_cast<int>(camera) + 1);
  }
  if (frames.empty()) return std::unexpected(name + ": no detections (expected lines frame,camera,x,y[,marker])");
  for (auto& [index, frame] : frames) d.frames.push_back(std::move(frame));
  return d;
}

std::expected<void, std::string> write_detections_csv(const Detections& detections, const std::filesystem::path& file) {
  std::ofstream out(file);
  if (!out) return std::unexpected(file.string() + ": cannot write");
  out << "frame,camera,x,y,marker\n";
  out << std::fixed << std::setprecision(4);
  for (const DetectionFrame& f : detections.frames) {
    for (const MarkerObservation& o : f.observations) {
      out << f.frame << ',' << o.camera << ',' << o.pixel.x() << ',' << o.pixel.y() << ',' << o.marker << '\n';
    }
  }
  out.flush();
  if (!out) return std::unexpected(file.string() + ": write failed");
  return {};
}

std::expected<Detections, std::string> read_multicamselfcal(const std::filesystem::path& folder) {
  const std::filesystem::path points_file = folder / "points.dat";
  const std::filesystem::path ids_file = folder / "IdMat.dat";
  std::error_code ec;
  if (!std::filesystem::is_regular_file(points_file, ec))
    return std::unexpected(folder.string() + ": no points.dat (not a MultiCamSelfCal folder)");
  if (!std::filesystem::is_regular_file(ids_file, ec))
    return std::unexpected(folder.string() + ": no IdMat.dat (not a MultiCamSelfCal folder)");
  const auto points = read_matrix_file(points_file);
  if (!points) return std::unexpected(points.error());
  const auto ids = read_matrix_file(ids_file);
  if (!ids) return std::unexpected(ids.error());
  const std::size_t cameras = ids->size();
  if (cameras < 2) return std::unexpected(ids_file.string() + ": expected one row per camera, at least 2, got " + std::to_string(cameras));
  if (points->size() != 3 * cameras) {
    return std::unexpected(points_file.string() + ": expected 3 rows per camera (x, y, 1) for the " + std::to_string(cameras) +
                           " cameras of IdMat.dat, got " + std::to_string(points->size()) + " rows");
  }
  const std::size_t frame_count = (*ids)[0].size();
  for (std::size_t r = 0; r < cameras; ++r) {
    if ((*ids)[r].size() != frame_count) {
      return std::unexpected(ids_file.string() + ": row " + std::to_string(r + 1) + " has " + std::to_string((*ids)[r].size()) +
                             " frames, row 1 has " + std::to_string(frame_count));
    }
  }
  for (std::size_t r = 0; r < points->size(); ++r) {
    if ((*points)[r].size() != frame_count) {
      return std::unexpected(points_file.string() + ": row " + std::to_string(r + 1) + " has " + std::to_string((*points)[r].size()) +
                             " frames, IdMat.dat has " + std::to_string(frame_count));
    }
  }
  Detections d;
  d.camera_count = static_cast<int>(cameras);
  for (std::size_t f = 0; f < frame_count; ++f) {
    DetectionFrame df;
    df.frame = static_cast<long>(f);
    for (std::size_t c = 0; c < cameras; ++c) {
      if ((*ids)[c][f] == 0.0) continue;
      const double x = (*points)[3 * c][f] - 1.0;
      const double y = (*points)[3 * c + 1][f] - 1.0;
      if (!std::isfinite(x) || !std::isfinite(y)) {
        return std::unexpected(points_file.string() + ": camera " + std::to_string(c) + " frame " + std::to_string(f) +
                               ": IdMat.dat marks it seen but its pixel is not finite");
      }
      df.observations.push_back({static_cast<int>(c), {x, y}, -1});
    }
    if (!df.observations.empty()) d.frames.push_back(std::move(df));
  }
  const std::filesystem::path res_file = folder / "Res.dat";
  if (std::filesystem::is_regular_file(res_file, ec)) {
    const auto res = read_matrix_file(res_file);
    if (!res) return std::unexpected(res.error());
    if (res->size() != cameras) {
      return std::unexpected(res_file.string() + ": expected one row (width height) per camera, " + std::to_string(cameras) + ", got " +
                             std::to_string(res->size()));
    }
    for (std::size_t c = 0; c < cameras; ++c) {
      const auto& row = (*res)[c];
      if (row.size() != 2 || !(row[0] >= 1 && row[0] <= 65536) || !(row[1] >= 1 && row[1] <= 65536)) {
        return std::unexpected(res_file.string() + ":" + std::to_string(c + 1) + ": expected an image width and height in pixels");
      }
      d.image_sizes_px.emplace_back(static_cast<int>(row[0]), static_cast<int>(row[1]));
    }
  }
  if (d.frames.empty()) return std::unexpected(folder.string() + ": IdMat.dat marks no detection");
  return d;
}

std::expected<Detections, std::string> read_detections(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return read_multicamselfcal(path);
  return read_detections_csv(path);
}

TrackSplit split_tracks(const Detections& detections) {
  TrackSplit out;
  for (const DetectionFrame& f : detections.frames) {
    // Per camera: its blobs of each marker id (-1: unlabelled).
    std::map<int, std::map<int, std::vector<Eigen::Vector2d>>> by_marker;
    bool any_labelled = false;
    for (const MarkerObservation& o : f.observations) {
      by_marker[o.marker][o.camera].push_back(o.pixel);
      any_labelled = any_labelled || o.marker >= 0;
    }
    for (const auto& [marker, cameras] : by_marker) {
      // In a frame with labelled markers, unlabelled blobs are strays: they cannot be matched.
      if (marker < 0 && any_labelled) {
        for (const auto& [camera, pixels] : cameras) out.ambiguous += pixels.size();
        continue;
      }
      PointTrack t;
      t.frame = f.frame;
      t.marker = marker;
      for (const auto& [camera, pixels] : cameras) {
        if (pixels.size() == 1) {
          t.views.emplace_back(camera, pixels[0]);
        } else {
          out.ambiguous += pixels.size();  // which of them is the marker cannot be told
        }
      }
      if (t.views.size() >= 2) out.tracks.push_back(std::move(t));
    }
  }
  return out;
}

}  // namespace rhot
