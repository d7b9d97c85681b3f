#include "tracking/media/Media.h"

#include <dlfcn.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <system_error>
#include <utility>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "tracking/media/MediaModule.h"

namespace rhot {

namespace {

struct Loaded {
  const MediaModuleApi* api = nullptr;
  std::string error;  // why not, when api is null
};

// One attempt: the handle is kept for the life of the process (never dlclose'd: OpenCV's
// back-ends keep threads and static state), a module refused for its version included.
const MediaModuleApi* try_load(const std::string& file, std::string& why) {
  void* handle = dlopen(file.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr) {
    const char* e = dlerror();
    why = e != nullptr ? e : file + ": cannot be loaded";
    return nullptr;
  }
  using Entry = const MediaModuleApi* (*)(std::uint32_t);
  auto* entry = reinterpret_cast<Entry>(dlsym(handle, kMediaModuleSymbol));
  if (entry == nullptr) {
    why = file + ": not rhot's media module (no " + kMediaModuleSymbol + ")";
    return nullptr;
  }
  const MediaModuleApi* api = entry(kMediaModuleVersion);
  if (api == nullptr) {
    why = file + ": built for another version of rhot (this program needs version " + std::to_string(kMediaModuleVersion) + ")";
    return nullptr;
  }
  return api;
}

Loaded load() {
  std::vector<std::string> candidates;
  const char* chosen = std::getenv("RHOT_MEDIA_MODULE");
  if (chosen != nullptr && *chosen != '\0') {
    candidates.emplace_back(chosen);
  } else {
    candidates.emplace_back(kMediaModuleFile);  // the run path (rhot::tracking_media sets it), LD_LIBRARY_PATH, the system's
    std::error_code ec;
    const std::filesystem::path program = std::filesystem::read_symlink("/proc/self/exe", ec);
    if (!ec) {
      candidates.push_back((program.parent_path() / kMediaModuleFile).string());
      candidates.push_back((program.parent_path() / "lib" / "rhot" / kMediaModuleFile).string());  // the build tree's tools
      candidates.push_back((program.parent_path() / ".." / "lib" / "rhot" / kMediaModuleFile).string());
    }
    // Where this build installs it, for a program whose run path was not set (an application on
    // a CMake that drops the package's link options: policy CMP0099 before 3.17).
    candidates.emplace_back(RHOT_MEDIA_INSTALL_DIR "/" + std::string(kMediaModuleFile));
  }
  Loaded loaded;
  std::string reasons;
  for (const std::string& file : candidates) {
    std::string why;
    loaded.api = try_load(file, why);
    if (loaded.api != nullptr) return loaded;
    reasons += (reasons.empty() ? "" : "; ") + why;
  }
  loaded.error = std::string("image files and video capture need rhot's media module (") + kMediaModuleFile + "): " + reasons +
                 (chosen != nullptr && *chosen != '\0' ? " (the file RHOT_MEDIA_MODULE names)" : " (set RHOT_MEDIA_MODULE to its path)");
  return loaded;
}

const Loaded& loaded() {
  static const Loaded once = load();  // thread-safe: a function-local static is initialised once
  return once;
}

// Where OpenCV said why, after the message of our own.
std::string with_reason(std::string message, const char* reason) {
  if (reason != nullptr && *reason != '\0') message += std::string(": ") + reason;
  return message;
}

}  // namespace

std::expected<void, std::string> media_module() {
  if (loaded().api == nullptr) return std::unexpected(loaded().error);
  return {};
}

std::expected<cv::Mat, std::string> read_image(const std::filesystem::path& file, ImageRead mode) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) return std::unexpected(file.string() + ": no such file");
  const MediaModuleApi* api = loaded().api;
  if (api == nullptr) return std::unexpected(file.string() + ": cannot read the image: " + loaded().error);
  const int flags = mode == ImageRead::kGrey ? cv::IMREAD_GRAYSCALE : mode == ImageRead::kColour ? cv::IMREAD_COLOR : cv::IMREAD_UNCHANGED;
  cv::Mat image;
  std::array<char, 512> error{};
  if (!api->read_image(file.c_str(), flags, &image, error.data(), error.size())) {
    return std::unexpected(with_reason(file.string() + ": cannot read the image (not a format OpenCV reads, or damaged)", error.data()));
  }
  return image;
}

std::expected<void, std::string> write_image(const std::filesystem::path& file, const cv::Mat& image, int png_compression) {
  const MediaModuleApi* api = loaded().api;
  if (api == nullptr) return std::unexpected(file.string() + ": cannot write the image: " + loaded().error);
  std::vector<int> params;
  if (png_compression >= 0) params = {cv::IMWRITE_PNG_COMPRESSION, std::min(png_compression, 9)};
  std::array<char, 512> error{};
  if (image.empty() || !api->write_image(file.c_str(), &image, params.data(), params.size(), error.data(), error.size())) {
    return std::unexpected(with_reason(file.string() + ": cannot write the image", image.empty() ? "the image is empty" : error.data()));
  }
  return {};
}

std::optional<VideoCapture> VideoCapture::open(const std::string& device, Kind kind) {
  const MediaModuleApi* api = loaded().api;
  if (api == nullptr) return std::nullopt;
  void* handle = api->open_capture(device.c_str(), static_cast<int>(kind));
  if (handle == nullptr) return std::nullopt;
  return VideoCapture(handle);
}

VideoCapture::VideoCapture(VideoCapture&& other) noexcept : handle_(std::exchange(other.handle_, nullptr)) {}

VideoCapture& VideoCapture::operator=(VideoCapture&& other) noexcept {
  if (this != &other) {
    if (handle_ != nullptr) loaded().api->close_capture(handle_);
    handle_ = std::exchange(other.handle_, nullptr);
  }
  return *this;
}

VideoCapture::~VideoCapture() {
  if (handle_ != nullptr) loaded().api->close_capture(handle_);
}

bool VideoCapture::grab() { return handle_ != nullptr && loaded().api->grab(handle_); }

bool VideoCapture::retrieve(cv::Mat& image) {
  if (handle_ == nullptr) {
    image.release();
    return false;
  }
  return loaded().api->retrieve(handle_, &image);
}

bool VideoCapture::read(cv::Mat& image) {
  if (grab()) return retrieve(image);
  image.release();
  return false;
}

}  // namespace rhot
