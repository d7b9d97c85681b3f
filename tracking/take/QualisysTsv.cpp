#include "tracking/take/QualisysTsv.h"

#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <vector>

#include <fmt/format.h>

namespace rhot {
namespace {

std::vector<std::string> tab_fields(const std::string& line) {
  std::vector<std::string> out;
  std::size_t start = 0;
  for (;;) {
    const std::size_t tab = line.find('\t', start);
    out.push_back(line.substr(start, tab == std::string::npos ? std::string::npos : tab - start));
    if (tab == std::string::npos) break;
    start = tab + 1;
  }
  return out;
}

std::optional<double> parse_number(const std::string& field) {
  std::size_t begin = 0, end = field.size();
  while (begin < end && field[begin] == ' ') ++begin;
  while (end > begin && (field[end - 1] == ' ' || field[end - 1] == '\r')) --end;
  double v = 0.0;
  const auto [ptr, ec] = std::from_chars(field.data() + begin, field.data() + end, v);
  if (ec != std::errc() || ptr != field.data() + end || !std::isfinite(v)) return std::nullopt;
  return v;
}

bool blank(const std::string& field) { return field.find_first_not_of(" \r") == std::string::npos; }

// A gap: an empty field, or "nan" (Qualisys Track Manager writes either, by version and settings).
bool gap(const std::string& field) {
  if (blank(field)) return true;
  std::string lower;
  for (const char c : field) {
    if (c != ' ' && c != '\r') lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  return lower == "nan";
}

}  // namespace

std::expected<MarkerTake, std::string> read_qualisys_tsv(const std::filesystem::path& file) {
  const auto fail = [&](const std::string& what) { return std::unexpected(file.string() + ": " + what); };
  std::ifstream in(file);
  if (!in) return fail("cannot be opened");
  std::map<std::string, std::vector<std::string>> header;
  std::string line;
  int line_number = 0;
  std::optional<std::string> first_data;
  while (std::getline(in, line)) {
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    std::vector<std::string> fields = tab_fields(line);
    // Header keys are upper-case words; the first line that starts otherwise is the column line or data.
    const std::string key = fields.front();
    const bool is_key = !key.empty() && key.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZ_0123456789") == std::string::npos &&
                        !parse_number(key).has_value() && !gap(key);
    if (!is_key) {
      first_data = line;
      break;
    }
    fields.erase(fields.begin());
    header[key] = fields;
  }
  if (header.empty() && !first_data) return fail("empty: no TSV header");
  const auto value = [&](const std::string& key) -> std::expected<double, std::string> {
    const auto it = header.find(key);
    if (it == header.end() || it->second.empty())
      return std::unexpected("no " + key + " line in its header (a Qualisys TSV 3D export has one)");
    const auto v = parse_number(it->second.front());
    if (!v) return std::unexpected(key + " is \"" + it->second.front() + "\", not a number");
    return *v;
  };
  const auto frames = value("NO_OF_FRAMES");
  if (!frames) return fail(frames.error());
  const auto markers = value("NO_OF_MARKERS");
  if (!markers) return fail(markers.error());
  const auto rate = value("FREQUENCY");
  if (!rate) return fail(rate.error());
  if (*rate <= 0.0) return fail(fmt::format("FREQUENCY {} Hz: must be positive", *rate));
  if (*markers < 1 || *frames < 1 || *markers != std::floor(*markers) || *frames != std::floor(*frames) || *frames > 1e7 ||
      *markers > 1e4) {
    return fail(fmt::format("NO_OF_MARKERS {} and NO_OF_FRAMES {}: must be whole numbers, at least 1", *markers, *frames));
  }
  if (const auto units = header.find("UNITS"); units != header.end() && !units->second.empty() && units->second.front() != "mm") {
    return fail("UNITS is \"" + units->second.front() + "\" (rhot reads Qualisys' millimetres)");
  }
  const auto names = header.find("MARKER_NAMES");
  if (names == header.end()) return fail("no MARKER_NAMES line in its header (rhot reads labelled takes)");
  std::vector<std::string> marker_names = names->second;
  while (!marker_names.empty() && blank(marker_names.back())) marker_names.pop_back();
  const auto marker_count = static_cast<std::size_t>(*markers);
  if (marker_names.size() != marker_count) {
    return fail(fmt::format("MARKER_NAMES lists {} names for NO_OF_MARKERS {}", marker_names.size(), marker_count));
  }

  MarkerTake take;
  take.frame_rate_hz = *rate;
  take.marker_names = marker_names;
  const auto frame_count = static_cast<std::size_t>(*frames);
  std::size_t leading = 0;  // Frame and Time columns before the markers'
  bool columns_known = false;
  std::optional<std::string> pending = first_data;
  std::size_t read_frames = 0;
  for (;;) {
    if (pending) {
      line = *pending;
      pending.reset();
    } else {
      if (!std::getline(in, line)) break;
      ++line_number;
      if (!line.empty() && line.back() == '\r') line.pop_back();
    }
    if (line.empty()) continue;
    const std::vector<std::string> fields = tab_fields(line);
    if (!columns_known && fields.front() == "Frame") {
      leading = fields.size() > 1 && fields[1] == "Time" ? 2 : 1;
      columns_known = true;
      continue;
    }
    if (!columns_known) {
      leading = fields.size() >= 3 * marker_count + 2 ? 2 : 0;
      columns_known = true;
    }
    if (read_frames == frame_count) return fail(fmt::format("line {}: more frames than NO_OF_FRAMES {}", line_number, frame_count));
    std::size_t used = fields.size();
    while (used > leading + 3 * marker_count && blank(fields[used - 1])) --used;  // trailing tabs
    if (used != leading + 3 * marker_count) {
      return fail(fmt::format("line {}: {} fields, not {} ({} markers x 3{})", line_number, used, leading + 3 * marker_count, marker_count,
                              leading == 2 ? " after Frame and Time" : ""));
    }
    for (std::size_t m = 0; m < marker_count; ++m) {
      Eigen::Vector3d p = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
      const std::size_t at = leading + 3 * m;
      if (!(gap(fields[at]) || gap(fields[at + 1]) || gap(fields[at + 2]))) {
        for (std::size_t k = 0; k < 3; ++k) {
          const auto v = parse_number(fields[at + k]);
          if (!v) {
            return fail(
                fmt::format("line {}, marker \"{}\" {}: \"{}\" is not a number", line_number, marker_names[m], "XYZ"[k], fields[at + k]));
          }
          p[static_cast<Eigen::Index>(k)] = *v * 1e-3;
        }
      }
      take.positions_m.push_back(p);
    }
    ++read_frames;
  }
  if (read_frames < frame_count) return fail(fmt::format("truncated: {} of NO_OF_FRAMES {} frames", read_frames, frame_count));
  if (const std::string fault = check_take(take); !fault.empty()) return fail(fault);
  return take;
}

std::expected<void, std::string> write_qualisys_tsv(const MarkerTake& take, const std::filesystem::path& file) {
  const auto fail = [&](const std::string& what) { return std::unexpected(file.string() + ": " + what); };
  if (const std::string fault = check_take(take); !fault.empty()) return fail(fault);
  std::ofstream out(file);
  if (!out) return fail("cannot be written");
  out << fmt::format("NO_OF_FRAMES\t{}\nNO_OF_CAMERAS\t0\nNO_OF_MARKERS\t{}\nFREQUENCY\t{}\nNO_OF_ANALOG\t0\nANALOG_FREQUENCY\t0\n",
                     take.frame_count(), take.marker_count(), take.frame_rate_hz);
  out << "DESCRIPTION\t--\nDATA_INCLUDED\t3D\nMARKER_NAMES";
  for (const std::string& name : take.marker_names) out << '\t' << name;
  out << "\nFrame\tTime";
  for (const std::string& name : take.marker_names) out << fmt::format("\t{0} X\t{0} Y\t{0} Z", name);
  out << '\n';
  for (int f = 0; f < take.frame_count(); ++f) {
    out << fmt::format("{}\t{:.5f}", f + 1, take.time_s(f));
    for (int m = 0; m < take.marker_count(); ++m) {
      const Eigen::Vector3d mm = take.at(f, m) * 1e3;
      if (mm.allFinite()) {
        out << fmt::format("\t{:.3f}\t{:.3f}\t{:.3f}", mm.x(), mm.y(), mm.z());
      } else {
        out << "\t\t\t";
      }
    }
    out << '\n';
  }
  if (!out) return fail("cannot be written");
  return {};
}

}  // namespace rhot
