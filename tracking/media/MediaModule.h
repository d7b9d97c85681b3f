#pragma once
// The interface between rhot_tracking_media (Media.h) and the module it loads, librhot_media.so
// (MediaModule.cpp), which holds every call into OpenCV's imgcodecs and videoio. The module exports
// one C function, rhot_media_module_api(version), which returns its table of functions when it was
// built for that version of the table, else nullptr: a module left over from an older build is
// refused instead of called with the wrong layout. Raise kMediaModuleVersion with any change here.
//
// Both sides link the same libopencv_core, so cv::Mat crosses by pointer. No exception crosses:
// the module catches OpenCV's and reports them through `error`.

#include <cstddef>
#include <cstdint>

#include <opencv2/core/mat.hpp>

namespace rhot {

inline constexpr std::uint32_t kMediaModuleVersion = 1;
inline constexpr const char* kMediaModuleFile = "librhot_media.so";
inline constexpr const char* kMediaModuleSymbol = "rhot_media_module_api";

struct MediaModuleApi {
  std::uint32_t version;
  // imread_flags: OpenCV's cv::IMREAD_*. False on failure, with why in `error` (NUL-terminated,
  // possibly empty) where OpenCV said.
  bool (*read_image)(const char* file, int imread_flags, cv::Mat* image, char* error, std::size_t error_size);
  // params: OpenCV's cv::IMWRITE_* pairs.
  bool (*write_image)(const char* file, const cv::Mat* image, const int* params, std::size_t param_count, char* error,
                      std::size_t error_size);
  // kind: VideoCapture::Kind's value. nullptr when it cannot be opened.
  void* (*open_capture)(const char* device, int kind);
  void (*close_capture)(void* capture);
  bool (*grab)(void* capture);
  bool (*retrieve)(void* capture, cv::Mat* image);
};

}  // namespace rhot

extern "C" const rhot::MediaModuleApi* rhot_media_module_api(std::uint32_t version);
