#pragma once
// A labelled marker take: what an optical motion-capture system (Vicon, Qualisys, OptiTrack,
// Motion Analysis) exports after labelling, every named marker's 3D position in every frame, with
// gaps where a marker was not seen. rhot reads them to drive the simulated world with real motion
// and to measure the hand tracker against recorded positions (docs/tracking.md, "Real takes").
//
// Formats (the file's extension picks the reader):
//   .c3d  C3D (tracking/take/C3d.h): Intel, DEC and MIPS processor types, integer and float storage
//   .tsv  Qualisys' TSV 3D export (tracking/take/QualisysTsv.h)
//
// Positions are in metres in the capture system's world frame (files in millimetres or
// centimetres are converted); a gap is a position that is not finite (NaN).

#include <expected>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace rhot {

struct MarkerTake {
  double frame_rate_hz = 0.0;
  std::vector<std::string> marker_names;
  // Frame-major: positions_m[frame * marker_count() + marker]; NaN in a gap.
  std::vector<Eigen::Vector3d> positions_m;

  int marker_count() const { return static_cast<int>(marker_names.size()); }
  int frame_count() const { return marker_names.empty() ? 0 : static_cast<int>(positions_m.size() / marker_names.size()); }
  // Seconds from the first frame.
  double time_s(int f) const { return f / frame_rate_hz; }

  // Frame f's marker m.
  const Eigen::Vector3d& at(int f, int m) const {
    return positions_m[static_cast<std::size_t>(f) * marker_names.size() + static_cast<std::size_t>(m)];
  }
  Eigen::Vector3d& at(int f, int m) { return positions_m[static_cast<std::size_t>(f) * marker_names.size() + static_cast<std::size_t>(m)]; }
  bool seen(int f, int m) const { return at(f, m).allFinite(); }
  // Frame f's positions, in marker_names' order.
  std::span<const Eigen::Vector3d> frame(int f) const {
    return std::span(positions_m).subspan(static_cast<std::size_t>(f) * marker_names.size(), marker_names.size());
  }
  // The index of a marker by name; nothing when the take has none of that name.
  std::optional<int> marker(const std::string& name) const;
  // Share of the frames in which a marker was seen.
  double seen_fraction(int m) const;
};

// What a take reader checks of every take before handing it out: a positive, finite frame rate,
// at least one marker and one frame, marker names that are non-empty and distinct, and positions
// that are finite or NaN (a gap; never infinite). An empty string when it is sound, else the first
// fault, naming it.
std::string check_take(const MarkerTake& take);

// Reads a take, the reader chosen by the file's extension (.c3d, .tsv; either case). Errors name the
// file and what was wrong ("take.c3d: truncated: the data holds 120 of 300 frames").
[[nodiscard]] std::expected<MarkerTake, std::string> read_marker_take(const std::filesystem::path& file);

}  // namespace rhot
