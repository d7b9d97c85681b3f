#include "engine/render/Image.h"

#include <algorithm>
#include <array>
#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <system_error>

#include "base/Check.h"

// Debian's libstb-dev ships stb compiled (libstb.so, found through pkg-config `stb`), so only the
// declarations are included here: no STB_*_IMPLEMENTATION macros.
#include <stb_image.h>
#include <stb_image_write.h>

namespace rhot {

namespace {

std::size_t expected_bytes(const Image& im) { return static_cast<std::size_t>(im.width) * static_cast<std::size_t>(im.height) * 4; }

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

bool well_formed(const Image& im) { return im.width >= 0 && im.height >= 0 && im.rgba.size() == expected_bytes(im); }

std::string describe(const Image& im) {
  std::string s = std::to_string(im.width) + "x" + std::to_string(im.height);
  if (!well_formed(im)) {
    s += " with " + std::to_string(im.rgba.size()) + " bytes of RGBA";
    if (im.width >= 0 && im.height >= 0) s += " (" + std::to_string(expected_bytes(im)) + " expected)";
  }
  return s;
}

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

}  // namespace rhot
