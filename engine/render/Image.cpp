#include "engine/render/Image.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>

// Debian's libstb ships the compiled implementation (libstb.so); only the declarations here.
#include <stb_image.h>
#include <stb_image_write.h>

namespace rhot {

namespace {

bool well_formed(const Image& im) {
  return im.width > 0 && im.height > 0 &&
         im.rgba.size() == static_cast<std::size_t>(im.width) * static_cast<std::size_t>(im.height) * 4;
}

}  // namespace

std::expected<void, std::string> write_png(const Image& image, const std::filesystem::path& file) {
  if (!well_formed(image)) {
    return std::unexpected(file.string() + ": cannot write an empty or malformed image (" + std::to_string(image.width) +
                           "x" + std::to_string(image.height) + ", " + std::to_string(image.rgba.size()) + " bytes)");
  }
  std::error_code ec;
  if (file.has_parent_path()) std::filesystem::create_directories(file.parent_path(), ec);
  if (ec) return std::unexpected(file.string() + ": cannot create its folder: " + ec.message());
  if (stbi_write_png(file.c_str(), image.width, image.height, 4, image.rgba.data(), image.width * 4) == 0) {
    return std::unexpected(file.string() + ": cannot write PNG");
  }
  return {};
}

std::expected<Image, std::string> read_png(const std::filesystem::path& file) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) return std::unexpected(file.string() + ": file not found");
  int w = 0;
  int h = 0;
  int channels = 0;
  stbi_uc* data = stbi_load(file.c_str(), &w, &h, &channels, 4);
  if (data == nullptr) return std::unexpected(file.string() + ": not a PNG image: " + stbi_failure_reason());
  Image im(w, h);
  std::copy(data, data + im.rgba.size(), im.rgba.begin());
  stbi_image_free(data);
  return im;
}

Image side_by_side(const Image& left, const Image& right) {
  Image out(left.width + right.width, std::max(left.height, right.height));
  for (int y = 0; y < out.height; ++y) {
    if (y < left.height) std::copy_n(left.pixel(0, y), left.width * 4, out.pixel(0, y));
    if (y < right.height) std::copy_n(right.pixel(0, y), right.width * 4, out.pixel(left.width, y));
  }
  return out;
}

namespace {

// True where some pixel of `other` within `radius` of (x, y) has every channel within tolerance
// of `a`'s pixel at (x, y).
bool has_match(const Image& a, const Image& other, int x, int y, int radius, int tolerance) {
  const std::uint8_t* p = a.pixel(x, y);
  for (int dy = -radius; dy <= radius; ++dy) {
    const int yy = y + dy;
    if (yy < 0 || yy >= other.height) continue;
    for (int dx = -radius; dx <= radius; ++dx) {
      const int xx = x + dx;
      if (xx < 0 || xx >= other.width) continue;
      const std::uint8_t* q = other.pixel(xx, yy);
      if (std::abs(p[0] - q[0]) <= tolerance && std::abs(p[1] - q[1]) <= tolerance && std::abs(p[2] - q[2]) <= tolerance &&
          std::abs(p[3] - q[3]) <= tolerance) {
        return true;
      }
    }
  }
  return false;
}

}  // namespace

ImageCompareResult compare_images(const Image& actual, const Image& expected, const ImageCompareSettings& settings) {
  ImageCompareResult r;
  if (actual.width != expected.width || actual.height != expected.height || !well_formed(actual) || !well_formed(expected)) {
    r.summary = "size " + std::to_string(actual.width) + "x" + std::to_string(actual.height) + " differs from expected " +
                std::to_string(expected.width) + "x" + std::to_string(expected.height);
    return r;
  }
  r.diff = Image(expected.width, expected.height);
  for (int y = 0; y < expected.height; ++y) {
    for (int x = 0; x < expected.width; ++x) {
      const std::uint8_t* a = actual.pixel(x, y);
      const std::uint8_t* e = expected.pixel(x, y);
      int plain = 0;
      for (int c = 0; c < 4; ++c) plain = std::max(plain, std::abs(a[c] - e[c]));
      r.max_channel_difference = std::max(r.max_channel_difference, plain);
      const bool differs = plain > settings.channel_tolerance &&
                           (!has_match(actual, expected, x, y, settings.search_radius_px, settings.channel_tolerance) ||
                            !has_match(expected, actual, x, y, settings.search_radius_px, settings.channel_tolerance));
      std::uint8_t* d = r.diff.pixel(x, y);
      if (differs) {
        ++r.differing_pixels;
        d[0] = 255;
        d[1] = 0;
        d[2] = 0;
      } else {
        const auto grey = static_cast<std::uint8_t>((e[0] * 77 + e[1] * 150 + e[2] * 29) / 256 / 3);
        d[0] = d[1] = d[2] = grey;
      }
      d[3] = 255;
    }
  }
  const double total = static_cast<double>(expected.width) * expected.height;
  r.differing_fraction = r.differing_pixels / total;
  r.matches = r.differing_fraction <= settings.max_differing_fraction;
  char line[160];
  std::snprintf(line, sizeof(line), "%d of %.0f pixels differ (%.3f%%, allowed %.3f%%); largest channel difference %d",
                r.differing_pixels, total, 100.0 * r.differing_fraction, 100.0 * settings.max_differing_fraction,
                r.max_channel_difference);
  r.summary = line;
  return r;
}

}  // namespace rhot
