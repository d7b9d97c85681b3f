#pragma once
// Image files and video capture: OpenCV's imgcodecs and videoio, loaded when first used.
//
// Those two OpenCV modules bring GDAL, GStreamer, FFmpeg and their dependencies: about 240 shared
// libraries, which a program linking them maps at every start (0.4 s; 0.5 s under the sanitizers)
// whether it ever reads an image or not. rhot keeps every call into them in one small module,
// `librhot_media.so` (MediaModule.h), opened with dlopen the first time a program reads or writes
// an image file or opens a capture. A program that never does (the tracker on simulated cameras,
// camera nodes on a recording, most of rhot-eval) starts with the thirty-odd libraries it uses.
//
// Where the module is looked for, in order: the file named by the environment variable
// RHOT_MEDIA_MODULE (and only there, when it is set); then by name, through the program's run path,
// which linking rhot::tracking_media sets (the build tree's lib/rhot, or the installed package's
// PREFIX/lib/rhot); then beside the program, in lib/rhot and ../lib/rhot from it, and where this
// build installs it. When it cannot be loaded,
// media_module() says why and every call below fails with that reason; nothing aborts.
//
// Thread safety: the module is loaded once, under a lock; the functions may be called from any
// thread. One VideoCapture is used by one thread at a time.

#include <expected>
#include <filesystem>
#include <optional>
#include <string>

#include <opencv2/core/mat.hpp>

namespace rhot {

// Loads the module if it is not yet loaded. The error says which files were tried and why each
// failed: "image files and video capture need rhot's media module (librhot_media.so): ...".
std::expected<void, std::string> media_module();

enum class ImageRead {
  kGrey,       // 8-bit, one channel
  kColour,     // 8-bit BGR
  kUnchanged,  // as stored: depth and channels (a 16-bit PNG stays 16-bit)
};

// Reads an image file in any format OpenCV reads. The error names the file:
// "<file>: cannot read the image (not a format OpenCV reads, or damaged)", "<file>: no such file",
// or "<file>: cannot read the image: <the module's error>".
std::expected<cv::Mat, std::string> read_image(const std::filesystem::path& file, ImageRead mode);

// Writes an image in the format its extension names (PNG, JPEG, ...). png_compression: 0 (fastest)
// to 9 (smallest), or -1 for OpenCV's default. The error names the file:
// "<file>: cannot write the image" (a folder that does not exist, an extension or pixel type the
// format has no encoder for), followed by OpenCV's or the module's reason where there is one.
std::expected<void, std::string> write_image(const std::filesystem::path& file, const cv::Mat& image, int png_compression = -1);

// One camera, video file or image sequence, as OpenCV's VideoCapture reads it.
class VideoCapture {
 public:
  enum class Kind {
    kDevice,         // a capture device's index, "0", "1", ...
    kImageSequence,  // a printf pattern of numbered images, "cam0_%04d.png" (OpenCV's CAP_IMAGES)
    kVideoFile,      // a video file, through FFmpeg, else GStreamer (not the camera back-ends)
    kAny,            // whatever OpenCV's CAP_ANY makes of it
  };

  // nullopt when the device or file cannot be opened, or the module cannot be loaded (media_module()
  // says why).
  static std::optional<VideoCapture> open(const std::string& device, Kind kind);

  VideoCapture(VideoCapture&& other) noexcept;
  VideoCapture& operator=(VideoCapture&& other) noexcept;
  VideoCapture(const VideoCapture&) = delete;
  VideoCapture& operator=(const VideoCapture&) = delete;
  ~VideoCapture();

  // grab() takes the next frame from the device without decoding it; retrieve() decodes the one
  // grabbed. read() is both. Each is false (and the image empty) when there is no frame.
  bool grab();
  bool retrieve(cv::Mat& image);
  bool read(cv::Mat& image);

 private:
  explicit VideoCapture(void* handle) : handle_(handle) {}
  void* handle_ = nullptr;
};

}  // namespace rhot
