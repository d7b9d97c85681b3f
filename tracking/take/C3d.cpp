#include "tracking/take/C3d.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <optional>
#include <vector>

#include <fmt/format.h>

namespace rhot {
namespace {

constexpr std::size_t kBlock = 512;
constexpr std::uint8_t kKey = 0x50;

// Numbers in a C3D file's byte order and float format.
class C3dNumbers {
 public:
  explicit C3dNumbers(C3dProcessor processor) : processor_(processor) {}

  std::uint16_t u16(const std::uint8_t* b) const {
    return processor_ == C3dProcessor::kMips ? static_cast<std::uint16_t>(b[0] << 8 | b[1]) : static_cast<std::uint16_t>(b[1] << 8 | b[0]);
  }
  std::int16_t i16(const std::uint8_t* b) const { return static_cast<std::int16_t>(u16(b)); }
  float f32(const std::uint8_t* b) const {
    std::array<std::uint8_t, 4> ieee{};  // little-endian IEEE
    switch (processor_) {
      case C3dProcessor::kIntel:
        ieee = {b[0], b[1], b[2], b[3]};
        break;
      case C3dProcessor::kMips:
        ieee = {b[3], b[2], b[1], b[0]};
        break;
      // VAX F: the two 16-bit halves swapped against IEEE, and an exponent bias of 128 with the
      // hidden bit at 0.5 (four times IEEE's value for the same bits).
      case C3dProcessor::kDec:
        ieee = {b[2], b[3], b[0], b[1]};
        break;
    }
    const float v = std::bit_cast<float>(ieee);
    return processor_ == C3dProcessor::kDec ? v / 4.0f : v;
  }

  void put_u16(std::vector<std::uint8_t>& out, std::size_t at, std::uint16_t v) const {
    const auto hi = static_cast<std::uint8_t>(v >> 8), lo = static_cast<std::uint8_t>(v & 0xff);
    out[at] = processor_ == C3dProcessor::kMips ? hi : lo;
    out[at + 1] = processor_ == C3dProcessor::kMips ? lo : hi;
  }
  void put_i16(std::vector<std::uint8_t>& out, std::size_t at, std::int16_t v) const { put_u16(out, at, static_cast<std::uint16_t>(v)); }
  void put_f32(std::vector<std::uint8_t>& out, std::size_t at, float v) const {
    // VAX F has no negative zero or denormals (the sign with a zero exponent is a reserved operand).
    if (processor_ == C3dProcessor::kDec && std::fabs(v * 4.0f) < std::numeric_limits<float>::min()) v = 0.0f;
    const auto ieee = std::bit_cast<std::array<std::uint8_t, 4>>(processor_ == C3dProcessor::kDec ? v * 4.0f : v);
    std::array<std::uint8_t, 4> b{};
    switch (processor_) {
      case C3dProcessor::kIntel:
        b = ieee;
        break;
      case C3dProcessor::kMips:
        b = {ieee[3], ieee[2], ieee[1], ieee[0]};
        break;
      case C3dProcessor::kDec:
        b = {ieee[2], ieee[3], ieee[0], ieee[1]};
        break;
    }
    std::ranges::copy(b, out.begin() + static_cast<std::ptrdiff_t>(at));
  }

 private:
  C3dProcessor processor_;
};

// One parameter: its type (-1 char, 1 byte, 2 int16, 4 float), dimensions, and where its data is.
struct C3dParameter {
  int type = 0;
  std::vector<int> dims;
  std::size_t data = 0;   // offset into the file
  std::size_t items = 1;  // the product of the dimensions (checked against the section's size)
  std::size_t count() const { return items; }
};

std::string upper(std::string s) {
  std::ranges::transform(s, s.begin(), [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  return s;
}

std::string trimmed(std::string s) {
  while (!s.empty() && (s.back() == ' ' || s.back() == '\0')) s.pop_back();
  std::size_t start = 0;
  while (start < s.size() && s[start] == ' ') ++start;
  return s.substr(start);
}

class C3dReader {
 public:
  C3dReader(std::string name, std::vector<std::uint8_t> bytes) : name_(std::move(name)), bytes_(std::move(bytes)) {}

  std::expected<MarkerTake, std::string> read() {
    if (bytes_.size() < kBlock) return fail(fmt::format("not a C3D file: {} bytes, shorter than its 512-byte header", bytes_.size()));
    if (bytes_[1] != kKey) return fail(fmt::format("not a C3D file (its second byte is 0x{:02x}, not 0x50)", bytes_[1]));
    const std::size_t parameters = (static_cast<std::size_t>(bytes_[0]) - 1) * kBlock;
    if (bytes_[0] == 0 || parameters + 4 > bytes_.size())
      return fail(fmt::format("the parameter section (block {}) is past the end of the file", bytes_[0]));
    const int processor = bytes_[parameters + 3];
    if (processor < 84 || processor > 86) {
      return fail(fmt::format("processor type {} is not one C3D defines (84 Intel, 85 DEC, 86 MIPS)", processor));
    }
    numbers_.emplace(static_cast<C3dProcessor>(processor));
    const std::size_t parameter_end = std::min(bytes_.size(), parameters + std::max<std::size_t>(bytes_[parameters + 2], 1) * kBlock);
    if (auto error = read_parameters(parameters + 4, parameter_end); !error.empty()) return fail(error);
    return read_points();
  }

 private:
  std::unexpected<std::string> fail(const std::string& what) const { return std::unexpected(name_ + ": " + what); }

  // The group and parameter records from `at` to `end`: each is a name's length (negative: locked),
  // a group id (negative: a group's own record), the name, the offset to the next record, then a
  // group's description or a parameter's type, dimensions, data and description.
  std::string read_parameters(std::size_t at, std::size_t end) {
    std::map<int, std::string> groups;
    std::vector<std::pair<int, std::pair<std::string, C3dParameter>>> entries;
    const auto cut = [&] { return std::string("the parameter section is cut short"); };
    while (at + 2 <= end) {
      const int name_length = std::abs(static_cast<std::int8_t>(bytes_[at]));
      const int group = static_cast<std::int8_t>(bytes_[at + 1]);
      if (name_length == 0 || group == 0) break;
      const std::size_t next_field = at + 2 + static_cast<std::size_t>(name_length);
      if (next_field + 2 > end) return cut();
      const std::string name = upper(
          std::string(bytes_.begin() + static_cast<std::ptrdiff_t>(at + 2), bytes_.begin() + static_cast<std::ptrdiff_t>(next_field)));
      const int next = numbers_->i16(&bytes_[next_field]);
      if (group < 0) {
        groups[-group] = name;
      } else {
        if (next_field + 4 > end) return cut();
        C3dParameter p;
        p.type = static_cast<std::int8_t>(bytes_[next_field + 2]);
        if (p.type != -1 && p.type != 1 && p.type != 2 && p.type != 4) {
          return fmt::format("parameter {} has type {}, not one C3D defines (-1 char, 1 byte, 2 integer, 4 float)", name, p.type);
        }
        const std::size_t dimensions = bytes_[next_field + 3];
        if (next_field + 4 + dimensions > end) return cut();
        p.data = next_field + 4 + dimensions;
        // The product of up to 255 dimensions of up to 255 each: checked against what is left of the
        // section at every step, so that it cannot wrap.
        const std::size_t left = end - p.data;
        for (std::size_t d = 0; d < dimensions; ++d) {
          p.dims.push_back(bytes_[next_field + 4 + d]);
          p.items *= static_cast<std::size_t>(p.dims.back());
          if (p.items > left) return cut();
        }
        if (p.items * static_cast<std::size_t>(std::abs(p.type)) > left) return cut();
        entries.push_back({group, {name, p}});
      }
      if (next <= 0) break;
      at = next_field + static_cast<std::size_t>(next);
    }
    for (const auto& [group, entry] : entries) {
      const auto g = groups.find(group);
      parameters_[(g == groups.end() ? std::to_string(group) : g->second) + ":" + entry.first] = entry.second;
    }
    return {};
  }

  const C3dParameter* parameter(const std::string& key) const {
    const auto it = parameters_.find(key);
    return it == parameters_.end() ? nullptr : &it->second;
  }
  std::optional<double> number(const std::string& key) const {
    const C3dParameter* p = parameter(key);
    if (p == nullptr || p->count() == 0) return std::nullopt;
    switch (p->type) {
      case 1:
        return static_cast<double>(bytes_[p->data]);
      case 2:
        return static_cast<double>(numbers_->u16(&bytes_[p->data]));  // counts beyond 32,767 are stored unsigned
      case 4:
        return static_cast<double>(numbers_->f32(&bytes_[p->data]));
      default:
        return std::nullopt;
    }
  }
  // A char parameter's strings: the first dimension is each string's length.
  std::vector<std::string> strings(const std::string& key) const {
    const C3dParameter* p = parameter(key);
    if (p == nullptr || p->type != -1) return {};
    const std::size_t length = p->dims.empty() ? 1 : static_cast<std::size_t>(p->dims[0]);
    const std::size_t n = length == 0 ? 0 : p->count() / length;
    std::vector<std::string> out;
    for (std::size_t i = 0; i < n; ++i) {
      const auto* begin = &bytes_[p->data + i * length];
      out.push_back(trimmed(std::string(begin, begin + length)));
    }
    return out;
  }

  std::expected<MarkerTake, std::string> read_points() {
    const C3dNumbers& n = *numbers_;
    const double used = number("POINT:USED").value_or(n.u16(&bytes_[2]));
    if (used == 0.0) return fail("no 3D points (POINT:USED is 0)");
    if (!(used >= 1.0 && used <= 65535.0 && used == std::floor(used)))
      return fail(fmt::format("POINT:USED is {}, not a count of points", used));
    const int points = static_cast<int>(used);
    std::vector<std::string> labels = strings("POINT:LABELS");
    for (int k = 2; static_cast<int>(labels.size()) < points; ++k) {
      const std::vector<std::string> more = strings("POINT:LABELS" + std::to_string(k));
      if (more.empty()) break;
      labels.insert(labels.end(), more.begin(), more.end());
    }
    if (labels.empty()) return fail("no POINT:LABELS (rhot reads labelled takes)");
    if (static_cast<int>(labels.size()) < points)
      return fail(fmt::format("POINT:LABELS holds {} labels for {} points", labels.size(), points));
    labels.resize(static_cast<std::size_t>(points));

    double metres_per_unit = 1e-3;
    if (const std::vector<std::string> units = strings("POINT:UNITS"); !units.empty()) {
      const std::string u = units.front();
      if (u == "mm")
        metres_per_unit = 1e-3;
      else if (u == "cm")
        metres_per_unit = 1e-2;
      else if (u == "m")
        metres_per_unit = 1.0;
      else
        return fail("POINT:UNITS is \"" + u + "\", not a length (mm, cm or m)");
    }
    const double rate = number("POINT:RATE").value_or(static_cast<double>(n.f32(&bytes_[20])));
    const double scale = number("POINT:SCALE").value_or(static_cast<double>(n.f32(&bytes_[12])));
    if (!std::isfinite(rate) || rate <= 0.0) return fail(fmt::format("frame rate {} Hz: must be positive", rate));
    if (!std::isfinite(scale) || scale == 0.0) return fail(fmt::format("POINT:SCALE {}: must be a non-zero number", scale));
    const bool float_storage = scale < 0.0;
    const double start = number("POINT:DATA_START").value_or(n.u16(&bytes_[16]));
    if (!(start >= 0.0 && start <= static_cast<double>(bytes_.size() / kBlock + 1) && start == std::floor(start))) {
      return fail(fmt::format("the data's first block ({}) is past the end of the file", start));
    }
    const auto start_block = static_cast<std::size_t>(start);
    const int first = n.u16(&bytes_[6]), last = n.u16(&bytes_[8]);
    if (start_block == 0 || last < first)
      return fail(fmt::format("its header's frames {} to {} or data block {} make no take", first, last, start_block));
    const std::size_t frames = static_cast<std::size_t>(last - first + 1);
    const std::size_t word = float_storage ? 4 : 2;
    const std::size_t analog_words = n.u16(&bytes_[4]);
    const std::size_t frame_bytes = (static_cast<std::size_t>(points) * 4 + analog_words) * word;
    const std::size_t data = (start_block - 1) * kBlock;
    const std::size_t whole = data > bytes_.size() ? 0 : (bytes_.size() - data) / frame_bytes;
    if (whole < frames) return fail(fmt::format("truncated: the data holds {} of {} frames", whole, frames));

    MarkerTake take;
    take.frame_rate_hz = rate;
    take.marker_names = labels;
    take.positions_m.resize(frames * static_cast<std::size_t>(points));
    const double unit = float_storage ? metres_per_unit : metres_per_unit * scale;
    for (std::size_t f = 0; f < frames; ++f) {
      const std::uint8_t* frame = &bytes_[data + f * frame_bytes];
      for (int p = 0; p < points; ++p) {
        const std::uint8_t* point = frame + static_cast<std::size_t>(p) * 4 * word;
        const auto value = [&](int k) {
          return float_storage ? static_cast<double>(n.f32(point + k * 4)) : static_cast<double>(n.i16(point + k * 2));
        };
        Eigen::Vector3d& out = take.positions_m[f * static_cast<std::size_t>(points) + static_cast<std::size_t>(p)];
        if (value(3) < 0.0) {
          out.setConstant(std::numeric_limits<double>::quiet_NaN());
          continue;
        }
        out = Eigen::Vector3d{value(0), value(1), value(2)} * unit;
        if (!out.allFinite())
          return fail(
              fmt::format("frame {}, point \"{}\": a coordinate that is not a finite number", f + 1, labels[static_cast<std::size_t>(p)]));
      }
    }
    if (const std::string fault = check_take(take); !fault.empty()) return fail(fault);
    return take;
  }

  std::string name_;
  std::vector<std::uint8_t> bytes_;
  std::optional<C3dNumbers> numbers_;
  std::map<std::string, C3dParameter> parameters_;
};

// The parameter section's records, as C3dNumbers writes them.
class C3dParameterWriter {
 public:
  explicit C3dParameterWriter(const C3dNumbers& numbers) : n_(numbers) {}

  void group(int id, const std::string& name) {
    std::vector<std::uint8_t> body{0};  // no description
    record(-id, name, body);
  }
  void integer(int group, const std::string& name, int value) {
    std::vector<std::uint8_t> body{2, 0, 0, 0};
    n_.put_i16(body, 2, static_cast<std::int16_t>(value));
    body.push_back(0);
    record(group, name, body);
  }
  void real(int group, const std::string& name, float value) {
    std::vector<std::uint8_t> body{4, 0, 0, 0, 0, 0};
    n_.put_f32(body, 2, value);
    body.push_back(0);
    record(group, name, body);
  }
  void text(int group, const std::string& name, const std::vector<std::string>& values, bool array) {
    std::size_t length = 1;
    for (const std::string& v : values) length = std::max(length, v.size());
    std::vector<std::uint8_t> body{static_cast<std::uint8_t>(0xff)};  // type -1: char
    if (array) {
      body.insert(body.end(), {2, static_cast<std::uint8_t>(length), static_cast<std::uint8_t>(values.size())});
    } else {
      body.insert(body.end(), {1, static_cast<std::uint8_t>(length)});
    }
    for (const std::string& v : values) {
      std::string padded = v;
      padded.resize(length, ' ');
      body.insert(body.end(), padded.begin(), padded.end());
    }
    body.push_back(0);
    record(group, name, body);
  }
  std::vector<std::uint8_t> finish() {
    out_.insert(out_.end(), {0, 0});  // a zero-length name ends the records
    return out_;
  }

 private:
  void record(int group, const std::string& name, const std::vector<std::uint8_t>& body) {
    out_.push_back(static_cast<std::uint8_t>(name.size()));
    out_.push_back(static_cast<std::uint8_t>(static_cast<std::int8_t>(group)));
    out_.insert(out_.end(), name.begin(), name.end());
    const std::size_t at = out_.size();
    out_.insert(out_.end(), {0, 0});
    n_.put_i16(out_, at, static_cast<std::int16_t>(body.size() + 2));
    out_.insert(out_.end(), body.begin(), body.end());
  }

  const C3dNumbers& n_;
  std::vector<std::uint8_t> out_;
};

}  // namespace

std::expected<MarkerTake, std::string> read_c3d(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return std::unexpected(file.string() + ": cannot be opened");
  std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return C3dReader(file.string(), std::move(bytes)).read();
}

std::expected<void, std::string> write_c3d(const MarkerTake& take, const std::filesystem::path& file, const C3dWriteOptions& options) {
  const auto fail = [&](const std::string& what) { return std::unexpected(file.string() + ": " + what); };
  if (const std::string fault = check_take(take); !fault.empty()) return fail(fault);
  if (take.frame_count() > 65535) return fail(fmt::format("{} frames: a C3D header holds at most 65,535", take.frame_count()));
  if (take.marker_count() > 255) return fail(fmt::format("{} markers: rhot writes at most 255 to C3D", take.marker_count()));
  if (options.analog_channels < 0 || options.analog_channels > 255) return fail("analog channels must be 0 to 255");
  std::size_t longest = 1;
  for (const std::string& name : take.marker_names) longest = std::max(longest, name.size());
  // POINT:LABELS is one parameter: its dimensions are bytes, its size must fit the record's offset.
  if (longest > 255 || longest * take.marker_names.size() > 32000)
    return fail("marker names too long for C3D's POINT:LABELS (255 characters each, 32,000 in all)");
  const C3dNumbers n(options.processor);
  double scale_mm = -1.0;
  if (!options.float_storage) {
    double largest_mm = 0.0;
    for (const Eigen::Vector3d& p : take.positions_m) {
      if (p.allFinite()) largest_mm = std::max(largest_mm, 1e3 * p.cwiseAbs().maxCoeff());
    }
    // As the file stores it (a float), so that the values are rounded to the scale a reader uses.
    scale_mm = static_cast<double>(
        static_cast<float>(options.integer_scale_mm > 0.0 ? options.integer_scale_mm : std::max(largest_mm / 32000.0, 1e-3)));
    if (largest_mm / scale_mm > 32767.0)
      return fail(fmt::format("a coordinate of {} mm does not fit 16 bits at {} mm a unit", largest_mm, scale_mm));
  }

  const int points = take.marker_count(), frames = take.frame_count();
  // The records hold the data's first block, which does not change their size.
  const auto records_with = [&](int data_start) {
    C3dParameterWriter parameters(n);
    parameters.group(1, "POINT");
    parameters.integer(1, "USED", points);
    parameters.real(1, "SCALE", static_cast<float>(scale_mm));
    parameters.real(1, "RATE", static_cast<float>(take.frame_rate_hz));
    parameters.integer(1, "FRAMES", frames);
    parameters.integer(1, "DATA_START", data_start);
    parameters.text(1, "UNITS", {"mm"}, false);
    parameters.text(1, "LABELS", take.marker_names, true);
    parameters.group(2, "ANALOG");
    parameters.integer(2, "USED", options.analog_channels);
    parameters.real(2, "RATE", static_cast<float>(take.frame_rate_hz));
    return parameters.finish();
  };
  const std::size_t parameter_blocks = (4 + records_with(0).size() + kBlock - 1) / kBlock;
  const std::size_t data_block = 2 + parameter_blocks;  // 1-based: the header, the parameters, the data
  const std::vector<std::uint8_t> records = records_with(static_cast<int>(data_block));

  const std::size_t word = options.float_storage ? 4 : 2;
  const std::size_t analog_words = static_cast<std::size_t>(options.analog_channels);
  const std::size_t frame_bytes = (static_cast<std::size_t>(points) * 4 + analog_words) * word;
  std::vector<std::uint8_t> out((data_block - 1) * kBlock + static_cast<std::size_t>(frames) * frame_bytes, 0);
  out[0] = 2;
  out[1] = kKey;
  n.put_u16(out, 2, static_cast<std::uint16_t>(points));
  n.put_u16(out, 4, static_cast<std::uint16_t>(analog_words));
  n.put_u16(out, 6, 1);
  n.put_u16(out, 8, static_cast<std::uint16_t>(frames));
  n.put_f32(out, 12, static_cast<float>(scale_mm));
  n.put_u16(out, 16, static_cast<std::uint16_t>(data_block));
  n.put_u16(out, 18, static_cast<std::uint16_t>(analog_words > 0 ? 1 : 0));
  n.put_f32(out, 20, static_cast<float>(take.frame_rate_hz));
  const std::size_t section = kBlock;
  out[section + 0] = 1;
  out[section + 1] = kKey;
  out[section + 2] = static_cast<std::uint8_t>(parameter_blocks);
  out[section + 3] = static_cast<std::uint8_t>(options.processor);
  std::ranges::copy(records, out.begin() + static_cast<std::ptrdiff_t>(section + 4));

  for (int f = 0; f < frames; ++f) {
    const std::size_t frame = (data_block - 1) * kBlock + static_cast<std::size_t>(f) * frame_bytes;
    for (int p = 0; p < points; ++p) {
      const std::size_t at = frame + static_cast<std::size_t>(p) * 4 * word;
      const Eigen::Vector3d mm = take.at(f, p) * 1e3;
      const bool seen = mm.allFinite();
      // X, Y, Z, then the residual word: 0 for a point seen, -1 for a gap.
      for (int k = 0; k < 4; ++k) {
        const double v = k == 3 ? (seen ? 0.0 : -1.0) : (seen ? mm[k] : 0.0);
        if (options.float_storage) {
          n.put_f32(out, at + static_cast<std::size_t>(k) * 4, static_cast<float>(v));
        } else {
          const double stored = k == 3 ? v : std::round(v / scale_mm);
          n.put_i16(out, at + static_cast<std::size_t>(k) * 2, static_cast<std::int16_t>(stored));
        }
      }
    }
  }
  std::ofstream stream(file, std::ios::binary);
  stream.write(reinterpret_cast<const char*>(out.data()), static_cast<std::streamsize>(out.size()));
  if (!stream) return fail("cannot be written");
  return {};
}

}  // namespace rhot
