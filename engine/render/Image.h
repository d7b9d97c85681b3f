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

// Writes `image` as an 8-bit RGBA PNG, replacing `file` and creating its missing parent folders.
// Refuses an empty image (no pixels) or one whose `rgba` is not width * height * 4 bytes. Errors
// name the file and the reason, e.g. "<file>: cannot write PNG: Permission denied". A failed write
// leaves no partial file and keeps an existing one. Cost: stb's zlib encoder, about 0.2 s for a
// 2160x1200 rendered frame (up to 1 s for noise), far beyond a 90 Hz frame budget.
[[nodiscard]] std::expected<void, std::string> write_png(const Image& image, const std::filesystem::path& file);

// Reads a PNG of any colour type and bit depth as 8-bit RGBA (grey is copied to R, G and B; a
// missing alpha becomes 255; 16-bit channels keep their high byte). Colour is not converted: the
// bytes are taken as sRGB whatever gAMA/iCCP chunks say. Other formats are refused even where stb
// could decode them. Errors: "<file>: file not found", "<file>: not a PNG image: <reason>".
[[nodiscard]] std::expected<Image, std::string> read_png(const std::filesystem::path& file);

// Whether the pixel buffer holds width * height RGBA pixels (and the sizes are not negative).
bool well_formed(const Image& image);
// "64x32", or "64x32 with 100 bytes of RGBA (8192 expected)" for a malformed image: for messages.
std::string describe(const Image& image);

// Places images side by side, left to right: `left` at x = 0, `right` at x = left.width.
// Precondition: equal heights and well-formed images (rgba of width * height * 4 bytes).
Image side_by_side(const Image& left, const Image& right);

}  // namespace rhot
