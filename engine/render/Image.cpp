#include "engine/render/Image.h"

#include <algorithm>
#include <array>
#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <system_error>

#include "tracking/core/Check.h"

// Debian's libstb-dev ships stb compiled (libstb.so, found through pkg-config `stb`), so only the
// declarations are included here: no STB_*_IMPLEMENTATION macros.
#include <stb_image.h>
#include <stb_image_write.h>

namespace rhot {

namespace {

std::size_t expected_bytes(const Image& im) { return static_cast<std::size_t>(im.width) * static_cast<std::size_t>(im.height) * 4; }

bool well_formed(const Image& im) { return im.width >= 0 && im.height >= 0 && im.rgba.size() == expected_bytes(im); }

// "64x32" or "64x32 with 100 bytes of RGBA (8192 expected)" when the pixel buffer does not fit.
std::string describe(const Image& im) {
  std::string s = std::to_string(im.width) + "x" + std::to_string(im.height);
  if (!well_formed(im)) {
    s += " with " + std::to_string(im.rgba.size()) + " bytes of RGBA";
    if (im.width >= 0 && im.height >= 0) s += " (" + std::to_string(expected_bytes(im)) + " expected)";
  }
  return s;
}

std::string errno_text(int err) { return std::error_code(err, std::generic_category()).message(); }

// Reads a whole file; the error is the reason only (the caller names the file).
std::expected<std::vector<std::uint8_t>, std::string> read_file(const std::filesystem::path& file) {
  std::FILE* f = std::fopen(file.c_str(), "rb");
  if (f == nullptr) return std::unexpected(errno_text(errno));
  std::vector<std::uint8_t> bytes;
  std::array<std::uint8_t, 1 << 16> chunk{};
  for (;;) {
    const std::size_t n = std::fread(chunk.data(), 1, chunk.size(), f);
    bytes.insert(bytes.end(), chunk.begin(), chunk.begin() + static_cast<std::ptrdiff_t>(n));
    if (n < chunk.size()) break;
  }
  const bool failed = std::ferror(f) != 0;
  const int err = errno;
  std::fclose(f);
  if (failed) return std::unexpected(errno_text(err));
  return bytes;
}

// Writes `bytes` to `file` through a temporary file beside it that is renamed over `file`, so a
// failure (disk full, a folder in the way) leaves neither a partial file nor a damaged old one.
std::expected<void, std::string> write_file_atomically(const std::vector<std::uint8_t>& bytes, const std::filesystem::path& file) {
  std::filesystem::path partial = file;
  partial += ".partial";
  std::FILE* f = std::fopen(partial.c_str(), "wb");
  if (f == nullptr) return std::unexpected(errno_text(errno));
  const bool written = std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
  const int write_err = errno;
  const bool closed = std::fclose(f) == 0;
  const int close_err = errno;
  std::error_code ec;
  if (!written || !closed) {
    std::filesystem::remove(partial, ec);
    return std::unexpected(errno_text(!written ? write_err : close_err));
  }
  std::filesystem::rename(partial, file, ec);
  if (ec) {
    std::error_code ignored;
    std::filesystem::remove(partial, ignored);
    return std::unexpected(ec.message());
  }
  return {};
}

}  // namespace

std::expected<void, std::string> write_png(const Image& image, const std::filesystem::path& file) {
  const std::string name = file.string();
  if (!well_formed(image) || image.rgba.empty()) {
    const char* what = well_formed(image) ? "empty" : "malformed";
    return std::unexpected(name + ": cannot write PNG: the image is " + what + " (" + describe(image) + ")");
  }
  if (image.width > INT_MAX / 4) {
    return std::unexpected(name + ": cannot write PNG: the image is too wide (" + describe(image) + ")");
  }
  if (file.has_parent_path()) {
    std::error_code ec;
    std::filesystem::create_directories(file.parent_path(), ec);
    if (ec) {
      return std::unexpected(name + ": cannot write PNG: cannot create folder " + file.parent_path().string() + ": " + ec.message());
    }
  }
  std::vector<std::uint8_t> encoded;
  const auto append = [](void* context, void* data, int size) {
    auto* out = static_cast<std::vector<std::uint8_t>*>(context);
    const auto* bytes = static_cast<const std::uint8_t*>(data);
    out->insert(out->end(), bytes, bytes + size);
  };
  if (stbi_write_png_to_func(append, &encoded, image.width, image.height, 4, image.rgba.data(), image.width * 4) == 0) {
    return std::unexpected(name + ": cannot write PNG: encoding failed (" + describe(image) + ")");
  }
  if (auto written = write_file_atomically(encoded, file); !written) {
    return std::unexpected(name + ": cannot write PNG: " + written.error());
  }
  return {};
}

std::expected<Image, std::string> read_png(const std::filesystem::path& file) {
  const std::string name = file.string();
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(file, ec);
  if (status.type() == std::filesystem::file_type::not_found) return std::unexpected(name + ": file not found");
  if (ec) return std::unexpected(name + ": cannot read: " + ec.message());  // e.g. a folder on the way is unreadable
  if (std::filesystem::is_directory(status)) return std::unexpected(name + ": is a folder, not a PNG image");
  auto bytes = read_file(file);
  if (!bytes) return std::unexpected(name + ": cannot read: " + bytes.error());

  // stb also decodes JPEG, BMP, GIF...; a golden or capture in those formats is a mistake.
  static constexpr std::array<std::uint8_t, 8> kSignature{0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (bytes->size() < kSignature.size() || !std::equal(kSignature.begin(), kSignature.end(), bytes->begin())) {
    return std::unexpected(name + ": not a PNG image: no PNG signature");
  }
  if (bytes->size() > static_cast<std::size_t>(INT_MAX)) {
    return std::unexpected(name + ": not a PNG image: file too large (" + std::to_string(bytes->size()) + " bytes)");
  }

  int w = 0;
  int h = 0;
  int channels_in_file = 0;
  stbi_uc* data = stbi_load_from_memory(bytes->data(), static_cast<int>(bytes->size()), &w, &h, &channels_in_file, 4);
  if (data == nullptr) {
    const char* stb_reason = stbi_failure_reason();
    std::string reason = stb_reason != nullptr ? stb_reason : "cannot decode";
    // stb reports a cut-off file as whatever it read in place of the next chunk's name (e.g.
    // "IDA"); say what happened instead.
    static constexpr std::array<std::uint8_t, 8> kIend{0, 0, 0, 0, 'I', 'E', 'N', 'D'};
    if (std::search(bytes->begin(), bytes->end(), kIend.begin(), kIend.end()) == bytes->end()) {
      reason = "file truncated (no IEND chunk; stb says \"" + reason + "\")";
    }
    return std::unexpected(name + ": not a PNG image: " + reason);
  }
  Image im;
  if (w > 0 && h > 0) {
    im = Image(w, h);
    std::memcpy(im.rgba.data(), data, im.rgba.size());
  }
  stbi_image_free(data);
  if (im.rgba.empty()) return std::unexpected(name + ": not a PNG image: no pixels");
  return im;
}

Image side_by_side(const Image& left, const Image& right) {
  RHOT_PRECONDITION(well_formed(left) && well_formed(right),
                    "side_by_side: malformed image (left " + describe(left) + ", right " + describe(right) + ")");
  RHOT_PRECONDITION(left.height == right.height,
                    "side_by_side: heights differ (left " + describe(left) + ", right " + describe(right) + ")");
  Image out(left.width + right.width, left.height);
  const std::size_t left_row = static_cast<std::size_t>(left.width) * 4;
  const std::size_t right_row = static_cast<std::size_t>(right.width) * 4;
  for (int y = 0; y < out.height; ++y) {
    std::uint8_t* row = out.pixel(0, y);
    if (left_row > 0) std::memcpy(row, left.pixel(0, y), left_row);
    if (right_row > 0) std::memcpy(row + left_row, right.pixel(0, y), right_row);
  }
  return out;
}

namespace {

// Largest absolute difference over the four channels of two RGBA pixels.
inline int channel_difference(const std::uint8_t* p, const std::uint8_t* q) {
  const int d0 = std::abs(p[0] - q[0]);
  const int d1 = std::abs(p[1] - q[1]);
  const int d2 = std::abs(p[2] - q[2]);
  const int d3 = std::abs(p[3] - q[3]);
  const int d01 = d0 > d1 ? d0 : d1;
  const int d23 = d2 > d3 ? d2 : d3;
  return d01 > d23 ? d01 : d23;
}

// channel_difference(p, q) <= tolerance for 0 <= tolerance <= 255, without branches: the search
// runs this up to 2 (2r+1)^2 times per pixel, and on noisy content unpredictable branches made a
// debug build four times slower (1.1 s instead of 0.25 s for 2160x1200, every pixel differing).
inline bool within(const std::uint8_t* p, const std::uint8_t* q, unsigned tolerance) {
  const unsigned span = 2 * tolerance;
  return (static_cast<unsigned>(p[0] - q[0] + static_cast<int>(tolerance)) <= span) &
         (static_cast<unsigned>(p[1] - q[1] + static_cast<int>(tolerance)) <= span) &
         (static_cast<unsigned>(p[2] - q[2] + static_cast<int>(tolerance)) <= span) &
         (static_cast<unsigned>(p[3] - q[3] + static_cast<int>(tolerance)) <= span);
}

// True when some pixel of `other` in the window [x0, x1] x [y0, y1] (already clipped to it) has
// every channel within `tolerance` of the pixel `p`.
bool has_match_in(const std::uint8_t* p, const Image& other, int x0, int x1, int y0, int y1, unsigned tolerance) {
  for (int y = y0; y <= y1; ++y) {
    const std::uint8_t* q = other.pixel(x0, y);
    for (int x = x0; x <= x1; ++x, q += 4) {
      if (within(p, q, tolerance)) return true;
    }
  }
  return false;
}

std::string percent(double fraction) {
  const double pc = 100.0 * fraction;
  if (pc > 0.0 && pc < 0.0005) return "<0.001%";
  std::array<char, 64> text{};
  std::snprintf(text.data(), text.size(), "%.3f%%", pc);
  return text.data();
}

}  // namespace

ImageCompareResult compare_images(const Image& actual, const Image& expected, const ImageCompareSettings& settings) {
  ImageCompareResult r;
  if (!well_formed(actual) || !well_formed(expected)) {
    r.summary = std::string(!well_formed(actual) ? "actual" : "expected") +
                " image is malformed: " + describe(!well_formed(actual) ? actual : expected);
    return r;
  }
  if (actual.width != expected.width || actual.height != expected.height) {
    r.summary = "size " + describe(actual) + " differs from expected " + describe(expected);
    return r;
  }
  if (expected.rgba.empty()) {
    r.summary = "both images are empty (" + describe(expected) + ")";
    return r;
  }

  // A tolerance of 255 or more accepts every pixel; clamping keeps within()'s arithmetic exact.
  const int tolerance = std::clamp(settings.channel_tolerance, 0, 255);
  const int radius = std::max(settings.search_radius_px, 0);
  const int w = expected.width;
  const int h = expected.height;
  r.diff = Image(w, h);
  for (int y = 0; y < h; ++y) {
    const int y0 = std::max(y - radius, 0);
    const int y1 = std::min(y + radius, h - 1);
    const std::uint8_t* a = actual.pixel(0, y);
    const std::uint8_t* e = expected.pixel(0, y);
    std::uint8_t* d = r.diff.pixel(0, y);
    for (int x = 0; x < w; ++x, a += 4, e += 4, d += 4) {
      const int plain = channel_difference(a, e);
      r.max_channel_difference = std::max(r.max_channel_difference, plain);
      bool differs = false;
      if (plain > tolerance) {
        const int x0 = std::max(x - radius, 0);
        const int x1 = std::min(x + radius, w - 1);
        const auto tol = static_cast<unsigned>(tolerance);
        differs = !has_match_in(a, expected, x0, x1, y0, y1, tol) || !has_match_in(e, actual, x0, x1, y0, y1, tol);
      }
      if (differs) {
        ++r.differing_pixels;
        d[0] = 255;
        d[1] = 0;
        d[2] = 0;
      } else {
        // Rec. 601 luma in 8-bit fixed point (weights sum to 256), then a third of it.
        const int luma = (77 * e[0] + 150 * e[1] + 29 * e[2]) >> 8;
        d[0] = d[1] = d[2] = static_cast<std::uint8_t>(luma / 3);
      }
      d[3] = 255;
    }
  }

  const long long total = static_cast<long long>(w) * h;
  r.differing_fraction = static_cast<double>(r.differing_pixels) / static_cast<double>(total);
  r.matches = r.differing_fraction <= settings.max_differing_fraction;
  r.summary = std::to_string(r.differing_pixels) + " of " + std::to_string(total) + " pixels differ (" + percent(r.differing_fraction) +
              ", allowed " + percent(settings.max_differing_fraction) + "); largest channel difference " +
              std::to_string(r.max_channel_difference);
  return r;
}

}  // namespace rhot
