#include "tracking/source/VideoSource.h"

#include "base/Jobs.h"

#include <algorithm>
#include <cctype>
#include <cmath>

#include <opencv2/core.hpp>

#include "tracking/media/Media.h"

namespace rhot {

namespace {

using Clock = std::chrono::steady_clock;

bool is_device_index(const std::string& device) {
  return !device.empty() && device.size() <= 6 &&
         std::all_of(device.begin(), device.end(), [](unsigned char c) { return std::isdigit(c) != 0; });
}

std::string size_text(int width, int height) { return std::to_string(width) + "x" + std::to_string(height); }

std::string camera_text(const CameraRig& rig, std::size_t c) {
  return "camera " + std::to_string(c) + (rig.cameras[c].name.empty() ? "" : " (" + rig.cameras[c].name + ")");
}

}  // namespace

struct VideoSource::Impl {
  CameraRig rig;
  std::vector<std::string> devices;
  VideoSourceSettings settings;
  std::vector<VideoCapture> captures;
  std::vector<bool> live;
  std::vector<cv::Mat> pending;  // the first frames, read by open() to check their size
  std::vector<VideoCameraStats> stats;
  std::vector<ColourDetector> colour_detectors;  // per camera, with coloured markers
  std::vector<VideoCameraStats> told;            // the counts last told by take_warnings()
  Clock::time_point opened = Clock::now();
  std::uint64_t index = 0;
  bool ended = false;
  std::shared_ptr<JobPool> jobs;  // the cameras' detection side by side; none with one thread or camera
};

std::expected<std::vector<std::string>, std::string> parse_video_devices(const std::string& list) {
  std::vector<std::string> devices;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = list.find(',', start);
    devices.push_back(list.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    if (devices.back().empty()) {
      return std::unexpected("video source: empty device in \"" + list +
                             "\" (expected DEV[,DEV...], one per camera: an index such as 0, or a file)");
    }
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return devices;
}

VideoSource::VideoSource(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
VideoSource::VideoSource(VideoSource&&) noexcept = default;
VideoSource& VideoSource::operator=(VideoSource&&) noexcept = default;
VideoSource::~VideoSource() = default;

std::expected<VideoSource, std::string> VideoSource::open(const CameraRig& rig, const std::vector<std::string>& devices,
                                                          VideoSourceSettings settings) {
  if (devices.size() != rig.cameras.size()) {
    return std::unexpected("video source: " + std::to_string(devices.size()) + (devices.size() == 1 ? " device" : " devices") +
                           " for a rig of " + std::to_string(rig.cameras.size()) + (rig.cameras.size() == 1 ? " camera" : " cameras") +
                           " (one per camera, in rig order)");
  }
  if (auto ok = check(settings.detector); !ok) return std::unexpected("video source: " + ok.error());
  if (settings.colours) {
    if (auto ok = settings.colours->check(); !ok) return std::unexpected("video source: colours: " + ok.error());
    if (auto ok = settings.colour_detector.check(); !ok) return std::unexpected("video source: colour detector: " + ok.error());
  }
  if (!(settings.rate_hz > 0.0) || !std::isfinite(settings.rate_hz))
    return std::unexpected(std::string("video source: rate_hz must be a positive number"));
  if (settings.threads < 0 || settings.threads > kMaxThreads)
    return std::unexpected("video source: threads: " + std::to_string(settings.threads) +
                           " is not a thread count (0: every core, at most " + std::to_string(kMaxThreads) + ")");
  auto impl = std::make_unique<Impl>();
  if (settings.jobs) {
    impl->jobs = settings.jobs;
  } else if (const int threads = std::min(threads_or_all(settings.threads), static_cast<int>(devices.size())); threads > 1) {
    impl->jobs = std::make_shared<JobPool>(threads);
  }
  impl->rig = rig;
  impl->devices = devices;
  impl->settings = settings;
  impl->stats.resize(devices.size());
  if (settings.colours) impl->colour_detectors.assign(devices.size(), ColourDetector(*settings.colours, settings.colour_detector));
  for (std::size_t c = 0; c < devices.size(); ++c) {
    const std::string& device = devices[c];
    const bool live = is_device_index(device);
    const VideoCapture::Kind kind = live                                    ? VideoCapture::Kind::kDevice
                                    : device.find('%') != std::string::npos ? VideoCapture::Kind::kImageSequence
                                                                            : VideoCapture::Kind::kVideoFile;
    std::optional<VideoCapture> capture = VideoCapture::open(device, kind);
    if (!capture) {
      if (auto module = media_module(); !module) return std::unexpected("video source: " + module.error());
      return std::unexpected("video source: " + camera_text(rig, c) + ": cannot open " +
                             (live ? "capture device " + device : "\"" + device + "\""));
    }
    cv::Mat first;
    if (!capture->read(first) || first.empty()) {
      return std::unexpected("video source: " + camera_text(rig, c) + ": \"" + device + "\" gives no image");
    }
    const CameraIntrinsics& k = rig.cameras[c].intrinsics;
    if (first.cols != k.width_px || first.rows != k.height_px) {
      return std::unexpected("video source: " + camera_text(rig, c) + ": \"" + device + "\" gives " + size_text(first.cols, first.rows) +
                             " images, the rig calibrates it at " + size_text(k.width_px, k.height_px));
    }
    impl->captures.push_back(std::move(*capture));
    impl->live.push_back(live);
    impl->pending.push_back(std::move(first));
  }
  impl->opened = Clock::now();
  return VideoSource(std::move(impl));
}

std::optional<RigFrame> VideoSource::next() {
  Impl& s = *impl_;
  if (s.ended) return std::nullopt;
  const std::size_t n = s.captures.size();
  // Grab every camera first, decode after: the exposures stay as close together as the devices allow.
  std::vector<bool> grabbed(n, false);
  std::vector<double> grab_time_s(n, 0.0);
  for (std::size_t c = 0; c < n; ++c) {
    grabbed[c] = !s.pending[c].empty() || s.captures[c].grab();
    grab_time_s[c] = std::chrono::duration<double>(Clock::now() - s.opened).count();
  }
  std::vector<cv::Mat> images(n);
  bool any = false;
  for (std::size_t c = 0; c < n; ++c) {
    if (!s.pending[c].empty()) {
      images[c] = std::move(s.pending[c]);
      s.pending[c] = cv::Mat();
    } else if (grabbed[c]) {
      s.captures[c].retrieve(images[c]);
    }
    any = any || !images[c].empty();
  }
  if (!any) {
    s.ended = true;
    return std::nullopt;
  }

  RigFrame frame;
  frame.index = s.index++;
  frame.time_s = static_cast<double>(frame.index) / s.settings.rate_hz;
  // Devices: when their frames were grabbed (OpenCV tells no exposure time), on the steady clock.
  double grabbed_sum_s = 0.0;
  int live = 0;
  for (std::size_t c = 0; c < n; ++c) {
    if (!s.live[c] || !grabbed[c]) continue;
    grabbed_sum_s += grab_time_s[c];
    ++live;
  }
  if (live > 0) {
    frame.capture_steady_s = std::chrono::duration<double>(s.opened.time_since_epoch()).count() + grabbed_sum_s / static_cast<double>(live);
  }
  frame.cameras.resize(n);
  // Each camera's image detected on its own (its frame, its stats, its colour detector): on the
  // job pool where there is one, the same detections whatever the thread count.
  const auto detect = [&](std::size_t c) {
    CameraFrame& cf = frame.cameras[c];
    cf.camera = static_cast<int>(c);
    cf.timestamp_s = s.live[c] ? grab_time_s[c] : frame.time_s;
    VideoCameraStats& st = s.stats[c];
    const cv::Mat& image = images[c];
    if (image.empty()) {
      ++st.failed_reads;
      st.last_problem = "frame " + std::to_string(frame.index) + ": no image from \"" + s.devices[c] + "\"";
      cf.delivered = false;
      return;
    }
    const CameraIntrinsics& k = s.rig.cameras[c].intrinsics;
    if (image.cols != k.width_px || image.rows != k.height_px) {
      ++st.bad_images;
      st.last_problem = "frame " + std::to_string(frame.index) + ": \"" + s.devices[c] + "\" gave a " + size_text(image.cols, image.rows) +
                        " image, the rig calibrates it at " + size_text(k.width_px, k.height_px);
      cf.delivered = false;
      return;
    }
    auto detections = s.colour_detectors.empty() ? detect_blobs(image, s.settings.detector) : s.colour_detectors[c].track(image);
    if (!detections) {
      ++st.bad_images;
      st.last_problem = "frame " + std::to_string(frame.index) + ": \"" + s.devices[c] + "\": " + detections.error();
      cf.delivered = false;
      return;
    }
    ++st.frames;
    cf.detections = std::move(*detections);
  };
  if (s.jobs) {
    s.jobs->for_each(n, detect);
  } else {
    for (std::size_t c = 0; c < n; ++c) detect(c);
  }
  return frame;
}

bool VideoSource::ended() const { return impl_->ended; }
const CameraRig& VideoSource::rig() const { return impl_->rig; }

std::vector<std::string> VideoSource::take_warnings() {
  // True when a power of ten lies in (before, now].
  const auto milestone = [](std::uint64_t before, std::uint64_t now) {
    for (std::uint64_t m = 1; m <= now; m *= 10) {
      if (m > before) return true;
    }
    return false;
  };
  Impl& s = *impl_;
  s.told.resize(s.stats.size());
  std::vector<std::string> out;
  for (std::size_t c = 0; c < s.stats.size(); ++c) {
    const VideoCameraStats& now = s.stats[c];
    VideoCameraStats& told = s.told[c];
    if (milestone(told.bad_images, now.bad_images) || milestone(told.failed_reads, now.failed_reads)) {
      out.push_back("video: camera " + std::to_string(c) + " (" + s.rig.cameras[c].name + "): " + std::to_string(now.bad_images) +
                    " bad image(s), " + std::to_string(now.failed_reads) + " failed read(s) so far; last: " + now.last_problem);
      told = now;
    }
  }
  return out;
}

std::vector<std::string> VideoSource::summary() const {
  std::vector<std::string> out;
  for (std::size_t c = 0; c < impl_->stats.size(); ++c) {
    const VideoCameraStats& s = impl_->stats[c];
    out.push_back("video camera " + std::to_string(c) + " (" + impl_->devices[c] + "): " + std::to_string(s.frames) + " frames, " +
                  std::to_string(s.bad_images) + " bad images, " + std::to_string(s.failed_reads) + " failed reads");
  }
  return out;
}
const std::vector<VideoCameraStats>& VideoSource::stats() const { return impl_->stats; }
const std::vector<std::string>& VideoSource::devices() const { return impl_->devices; }

}  // namespace rhot
