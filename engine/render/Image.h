#pragma once
// 8-bit RGBA images on the CPU: captured frames, PNG files, and the golden-image comparison the
// frame-capture tests use.

#include <cstdint>
#include <expected>
#include <filesystem>
#include <string>
#include <vector>

namespace rhot {

// Row-major, top row first, 4 bytes per pixel (R, G, B, A), sRGB-encoded colour.
struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgba;

  Image() = default;
  Image(int w, int h) : width(w), height(h), rgba(static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 4, 0) {}
  std::uint8_t* pixel(int x, int y) { return rgba.data() + (static_cast<std::size_t>(y) * width + x) * 4; }
  const std::uint8_t* pixel(int x, int y) const { return rgba.data() + (static_cast<std::size_t>(y) * width + x) * 4; }
};

[[nodiscard]] std::expected<void, std::string> write_png(const Image& image, const std::filesystem::path& file);
[[nodiscard]] std::expected<Image, std::string> read_png(const std::filesystem::path& file);

// Places images side by side, left to right. Precondition: equal heights.
Image side_by_side(const Image& left, const Image& right);

// Tolerance for comparing a rendered frame with its golden image. Rasterisers differ a little at
// edges (coverage, rounding), so a pixel counts as matching when some pixel of the other image
// within `search_radius_px` has every channel within `channel_tolerance`. The check runs both
// ways (actual against expected and expected against actual) so a missing thin line is caught as
// surely as an extra one. The images match when at most `max_differing_fraction` of the pixels
// differ.
struct ImageCompareSettings {
  int channel_tolerance = 8;
  int search_radius_px = 1;
  double max_differing_fraction = 0.001;
};

struct ImageCompareResult {
  bool matches = false;
  int differing_pixels = 0;
  double differing_fraction = 0.0;
  int max_channel_difference = 0;  // largest plain per-pixel difference, no search
  Image diff;                      // differing pixels in red over a dimmed grey copy of expected
  std::string summary;             // one line for a test failure message
};

// Precondition-free: images of different sizes simply do not match (summary says so).
ImageCompareResult compare_images(const Image& actual, const Image& expected,
                                  const ImageCompareSettings& settings = {});

}  // namespace rhot
