// librhot_media.so: every call rhot makes into OpenCV's imgcodecs and videoio (MediaModule.h says
// why they live in a module of their own). Loaded by tracking/media/Media.cpp.

#include "tracking/media/MediaModule.h"

#include <algorithm>
#include <cstring>
#include <exception>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "tracking/media/Media.h"

namespace rhot {
namespace {

void tell(std::string_view what, char* error, std::size_t error_size) {
  if (error == nullptr || error_size == 0) return;
  const std::size_t n = std::min(what.size(), error_size - 1);
  std::memcpy(error, what.data(), n);
  error[n] = '\0';
}

bool read_image(const char* file, int imread_flags, cv::Mat* image, char* error, std::size_t error_size) {
  tell("", error, error_size);
  try {
    *image = cv::imread(file, imread_flags);
  } catch (const cv::Exception& e) {
    image->release();
    tell(e.msg, error, error_size);
  } catch (const std::exception& e) {
    image->release();
    tell(e.what(), error, error_size);
  } catch (...) {
    image->release();
    tell("an exception that is not a std::exception", error, error_size);
  }
  return !image->empty();
}

bool write_image(const char* file, const cv::Mat* image, const int* params, std::size_t param_count, char* error, std::size_t error_size) {
  tell("", error, error_size);
  try {
    return cv::imwrite(file, *image, std::vector<int>(params, params + param_count));
  } catch (const cv::Exception& e) {
    tell(e.msg, error, error_size);
  } catch (const std::exception& e) {
    tell(e.what(), error, error_size);
  } catch (...) {
    tell("an exception that is not a std::exception", error, error_size);
  }
  return false;
}

bool open(cv::VideoCapture& capture, const char* device, VideoCapture::Kind kind) {
  switch (kind) {
    case VideoCapture::Kind::kDevice:
      return capture.open(std::stoi(device));
    case VideoCapture::Kind::kImageSequence:
      return capture.open(device, cv::CAP_IMAGES);
    case VideoCapture::Kind::kVideoFile:
      // The back-ends that read files, not CAP_ANY: its probe also wakes camera plug-ins (USB
      // enumeration and the like), which a file has no use for.
      return capture.open(device, cv::CAP_FFMPEG) || capture.open(device, cv::CAP_GSTREAMER);
    case VideoCapture::Kind::kAny:
      return capture.open(device);
  }
  return false;
}

void* open_capture(const char* device, int kind) {
  try {
    auto capture = std::make_unique<cv::VideoCapture>();
    if (!open(*capture, device, static_cast<VideoCapture::Kind>(kind)) || !capture->isOpened()) return nullptr;
    return capture.release();
  } catch (...) {
    return nullptr;  // OpenCV's exceptions, or stoi's on a device that is not a number
  }
}

void close_capture(void* capture) { delete static_cast<cv::VideoCapture*>(capture); }

bool grab(void* capture) {
  try {
    return static_cast<cv::VideoCapture*>(capture)->grab();
  } catch (...) {
    return false;
  }
}

bool retrieve(void* capture, cv::Mat* image) {
  try {
    if (static_cast<cv::VideoCapture*>(capture)->retrieve(*image)) return !image->empty();
  } catch (...) {
  }
  image->release();
  return false;
}

constexpr MediaModuleApi kApi{kMediaModuleVersion, read_image, write_image, open_capture, close_capture, grab, retrieve};

}  // namespace
}  // namespace rhot

extern "C" __attribute__((visibility("default"))) const rhot::MediaModuleApi* rhot_media_module_api(std::uint32_t version) {
  return version == rhot::kMediaModuleVersion ? &rhot::kApi : nullptr;
}
