#include "tracking/take/MarkerTake.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <set>

#include "tracking/take/C3d.h"
#include "tracking/take/QualisysTsv.h"

namespace rhot {

std::optional<int> MarkerTake::marker(const std::string& name) const {
  const auto it = std::ranges::find(marker_names, name);
  if (it == marker_names.end()) return std::nullopt;
  return static_cast<int>(it - marker_names.begin());
}

double MarkerTake::seen_fraction(int m) const {
  const int frames = frame_count();
  if (frames == 0) return 0.0;
  int seen_frames = 0;
  for (int f = 0; f < frames; ++f) seen_frames += seen(f, m) ? 1 : 0;
  return static_cast<double>(seen_frames) / frames;
}

std::string check_take(const MarkerTake& take) {
  if (!std::isfinite(take.frame_rate_hz) || take.frame_rate_hz <= 0.0) {
    return "frame rate " + std::to_string(take.frame_rate_hz) + " Hz: must be positive";
  }
  if (take.marker_names.empty()) return "no markers";
  std::set<std::string> names;
  for (std::size_t m = 0; m < take.marker_names.size(); ++m) {
    const std::string& name = take.marker_names[m];
    if (name.empty()) return "marker " + std::to_string(m + 1) + " has no name";
    if (!names.insert(name).second) return "marker name \"" + name + "\" appears twice";
  }
  if (take.positions_m.size() % take.marker_names.size() != 0) return "positions are not whole frames";
  if (take.frame_count() == 0) return "no frames";
  for (std::size_t i = 0; i < take.positions_m.size(); ++i) {
    const Eigen::Vector3d& p = take.positions_m[i];
    if (p.array().isInf().any()) {
      return "frame " + std::to_string(i / take.marker_names.size() + 1) + ", marker \"" + take.marker_names[i % take.marker_names.size()] +
             "\": an infinite coordinate";
    }
  }
  return {};
}

std::expected<MarkerTake, std::string> read_marker_take(const std::filesystem::path& file) {
  std::string extension = file.extension().string();
  std::ranges::transform(extension, extension.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (extension == ".c3d") return read_c3d(file);
  if (extension == ".tsv") return read_qualisys_tsv(file);
  return std::unexpected(file.string() + ": unknown take format \"" + extension + "\" (rhot reads .c3d and Qualisys .tsv)");
}

}  // namespace rhot
