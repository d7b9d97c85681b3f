#include "tracking/detect/ColourModel.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "base/Json.h"
#include "tracking/core/MarkerColour.h"

namespace rhot {

namespace {

std::string number_text(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%g", v);
  return buffer;
}

// Membership ramps: a hue in the inner half of its window, a saturation 0.15 above the minimum and
// a value 0.1 above it count fully.
constexpr double kSaturationRamp = 0.15;
constexpr double kValueRamp = 0.10;

}  // namespace

Hsv hsv_from_rgb(double r, double g, double b) {
  const double mx = std::max({r, g, b});
  const double mn = std::min({r, g, b});
  Hsv out;
  out.value = mx / 255.0;
  if (mx <= 0.0) return out;
  const double chroma = mx - mn;
  out.saturation = chroma / mx;
  if (chroma <= 0.0) return out;
  double h;
  if (mx == r) {
    h = (g - b) / chroma;
  } else if (mx == g) {
    h = 2.0 + (b - r) / chroma;
  } else {
    h = 4.0 + (r - g) / chroma;
  }
  h *= 60.0;
  if (h < 0.0) h += 360.0;
  out.hue_deg = h;
  return out;
}

double hue_distance_deg(double a, double b) {
  const double d = std::fmod(std::abs(a - b), 360.0);
  return d > 180.0 ? 360.0 - d : d;
}

PixelClass classify(const ColourModel& model, const Hsv& hsv) {
  PixelClass best;
  double best_rel = 2.0;
  for (std::size_t k = 0; k < model.classes.size(); ++k) {
    const ColourClass& c = model.classes[k];
    if (hsv.saturation < c.min_saturation || hsv.value < c.min_value) continue;
    const double d = hue_distance_deg(hsv.hue_deg, c.hue_deg);
    if (d > c.hue_tolerance_deg) continue;
    const double rel = d / c.hue_tolerance_deg;
    if (rel >= best_rel) continue;
    best_rel = rel;
    best.klass = static_cast<int>(k);
    const double m_hue = 2.0 * (1.0 - rel);
    const double m_sat = (hsv.saturation - c.min_saturation) / kSaturationRamp;
    const double m_val = (hsv.value - c.min_value) / kValueRamp;
    best.membership = std::clamp(std::min({m_hue, m_sat, m_val}), 0.0, 1.0);
  }
  return best;
}

std::expected<void, std::string> ColourModel::check() const {
  if (classes.empty()) return std::unexpected("colours: expected at least one colour, got none");
  for (std::size_t i = 0; i < classes.size(); ++i) {
    const ColourClass& c = classes[i];
    const std::string where = "colours/" + std::to_string(i) + " (" + std::string(marker_colour_name(c.colour)) + "): ";
    if (c.colour < 0 || c.colour >= kMarkerColourCount) {
      return std::unexpected("colours/" + std::to_string(i) + ": name: expected one of " + marker_colour_list());
    }
    const auto bad = [&](const char* field, const char* expected, double v) {
      return std::unexpected(where + field + ": expected " + expected + ", got " + number_text(v));
    };
    if (!(c.hue_deg >= 0.0 && c.hue_deg < 360.0)) return bad("hue_deg", "a hue from 0 to 360 (not 360)", c.hue_deg);
    if (!(c.hue_tolerance_deg >= 1.0 && c.hue_tolerance_deg <= 60.0)) {
      return bad("hue_tolerance_deg", "1 to 60 degrees", c.hue_tolerance_deg);
    }
    if (!(c.min_saturation >= 0.05 && c.min_saturation <= 1.0)) return bad("min_saturation", "0.05 to 1", c.min_saturation);
    if (!(c.min_value >= 0.0 && c.min_value <= 1.0)) return bad("min_value", "0 to 1", c.min_value);
    for (std::size_t j = 0; j < i; ++j) {
      const ColourClass& o = classes[j];
      if (o.colour == c.colour) return std::unexpected(where + "name: the colour is listed twice (also colours/" + std::to_string(j) + ")");
      if (hue_distance_deg(o.hue_deg, c.hue_deg) < o.hue_tolerance_deg + c.hue_tolerance_deg) {
        return std::unexpected(where + "hue window " + number_text(c.hue_deg) + " +- " + number_text(c.hue_tolerance_deg) +
                               " overlaps colours/" + std::to_string(j) + " (" + std::string(marker_colour_name(o.colour)) + ") " +
                               number_text(o.hue_deg) + " +- " + number_text(o.hue_tolerance_deg));
      }
    }
  }
  return {};
}

const ColourClass* ColourModel::find(int colour) const {
  for (const ColourClass& c : classes) {
    if (c.colour == colour) return &c;
  }
  return nullptr;
}

ColourTable::ColourTable(const ColourModel& model, std::array<double, 3> gains)
    : model_(model), gains_(gains), klass_(32768, 0), membership_(32768, 0) {
  for (int r = 0; r < 32; ++r) {
    for (int g = 0; g < 32; ++g) {
      for (int b = 0; b < 32; ++b) {
        const PixelClass p = classify(model_, hsv_from_rgb(std::min(255.0, (r * 8 + 4) * gains[0]), std::min(255.0, (g * 8 + 4) * gains[1]),
                                                           std::min(255.0, (b * 8 + 4) * gains[2])));
        if (p.klass < 0) continue;
        const std::size_t i = (static_cast<std::size_t>(r) << 10) | (static_cast<std::size_t>(g) << 5) | static_cast<std::size_t>(b);
        klass_[i] = static_cast<std::uint8_t>(p.klass + 1);
        membership_[i] = static_cast<std::uint8_t>(std::clamp(std::lround(255.0 * p.membership), 1L, 255L));
      }
    }
  }
}

namespace {

ColourModel read_model(const JsonNode& root) {
  root.expect_object({"format", "version", "description", "colours", "white_reference"});
  const JsonNode format = root["format"];
  if (format.string() != "rhot-marker-colours") format.fail("expected \"rhot-marker-colours\", got " + describe_json(format.raw()));
  root["version"].integer_in(1, 1);
  ColourModel model;
  if (auto d = root.optional("description")) model.description = d->string();
  const JsonNode list = root["colours"];
  for (const JsonNode& e : list.elements()) {
    e.expect_object({"name", "hue_deg", "hue_tolerance_deg", "min_saturation", "min_value"});
    ColourClass c;
    const JsonNode name = e["name"];
    const auto colour = marker_colour_from_name(name.string());
    if (!colour) name.fail("expected a marker colour (" + marker_colour_list() + "), got " + describe_json(name.raw()));
    c.colour = *colour;
    c.hue_deg = e["hue_deg"].number_in(0.0, 359.999999, "a hue from 0 to 360 (not 360)");
    c.hue_tolerance_deg = e["hue_tolerance_deg"].number_in(1.0, 60.0, "1 to 60 degrees");
    c.min_saturation = e["min_saturation"].number_in(0.05, 1.0, "0.05 to 1");
    c.min_value = e["min_value"].number_in(0.0, 1.0, "0 to 1");
    model.classes.push_back(c);
  }
  if (const auto ok = model.check(); !ok) list.fail(ok.error());
  if (auto w = root.optional("white_reference")) {
    const auto v = w->numbers(3);
    if (!std::all_of(v.begin(), v.end(), [](double x) { return x >= 0.01 && x <= 1.0; })) w->fail("expected R, G and B from 0.01 to 1");
    model.white_reference = std::array<double, 3>{v[0], v[1], v[2]};
  }
  return model;
}

}  // namespace

std::expected<ColourModel, JsonError> load_colour_model(const std::filesystem::path& file) {
  return read_json_file<ColourModel>(file, "colour", read_model);
}

std::expected<ColourModel, JsonError> parse_colour_model(std::string_view text, std::string_view file) {
  return parse_json<ColourModel>(text, file, read_model);
}

std::string colour_model_json(const ColourModel& model) {
  const auto round3 = [](double v) { return std::round(v * 1000.0) / 1000.0; };
  nlohmann::ordered_json j;
  j["format"] = "rhot-marker-colours";
  j["version"] = 1;
  if (!model.description.empty()) j["description"] = model.description;
  j["colours"] = nlohmann::ordered_json::array();
  for (const ColourClass& c : model.classes) {
    nlohmann::ordered_json e;
    e["name"] = std::string(marker_colour_name(c.colour));
    e["hue_deg"] = round3(c.hue_deg);
    e["hue_tolerance_deg"] = round3(c.hue_tolerance_deg);
    e["min_saturation"] = round3(c.min_saturation);
    e["min_value"] = round3(c.min_value);
    j["colours"].push_back(e);
  }
  if (model.white_reference) {
    const auto& w = *model.white_reference;
    j["white_reference"] = {round3(w[0]), round3(w[1]), round3(w[2])};
  }
  return j.dump(2) + "\n";
}

std::expected<void, std::string> save_colour_model(const ColourModel& model, const std::filesystem::path& file) {
  if (const auto ok = model.check(); !ok) return std::unexpected(file.string() + ": " + ok.error());
  const std::filesystem::path tmp = file.string() + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) return std::unexpected(file.string() + ": cannot write");
    out << colour_model_json(model);
    if (!out.flush()) return std::unexpected(file.string() + ": cannot write");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, file, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    return std::unexpected(file.string() + ": cannot write");
  }
  return {};
}

ColourModel default_colour_model() {
  ColourModel model;
  model.description = "rhot's six marker colours, hues 60 degrees apart, before a model is learned from the cameras";
  for (const char* name : {"red", "yellow", "green", "cyan", "blue", "magenta"}) {
    ColourClass c;
    c.colour = *marker_colour_from_name(name);
    c.hue_deg = kMarkerColours[static_cast<std::size_t>(c.colour)].hue_deg;
    if (c.hue_deg == 310.0) c.hue_deg = 300.0;  // magenta at its place among six
    c.hue_tolerance_deg = 22.0;
    c.min_saturation = 0.7;  // paint: skin and wood stay under 0.7 (below 0.5 in daylight)
    c.min_value = 0.12;
    model.classes.push_back(c);
  }
  return model;
}

namespace {

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  const auto k = static_cast<std::size_t>(std::clamp(p, 0.0, 1.0) * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

struct Sample {
  double hue, saturation, value;
};

// A learned colour's saturation threshold never goes below this: small markers' samples are
// mostly edge pixels mixed with the background, and skin and wood reach 0.5 under daylight.
constexpr double kLearnedSaturationFloor = 0.55;

// An image's pixels as hue, saturation and value (CV_32FC3) into `hsv`; returned: 255 where a pixel
// is saturated and bright enough to be paint (and the mask, if any, is non-zero), else 0.
cv::Mat candidate_pixels(const cv::Mat& image, const cv::Mat* mask, const ColourLearnSettings& settings, cv::Mat& hsv) {
  cv::Mat candidate(image.size(), CV_8UC1, cv::Scalar(0));
  hsv.create(image.size(), CV_32FC3);
  for (int y = 0; y < image.rows; ++y) {
    const auto* p = image.ptr<cv::Vec3b>(y);
    auto* h = hsv.ptr<cv::Vec3f>(y);
    auto* c = candidate.ptr<std::uint8_t>(y);
    const auto* m = mask ? mask->ptr<std::uint8_t>(y) : nullptr;
    for (int x = 0; x < image.cols; ++x) {
      const Hsv v = hsv_from_rgb(p[x][2], p[x][1], p[x][0]);
      h[x] = cv::Vec3f(static_cast<float>(v.hue_deg), static_cast<float>(v.saturation), static_cast<float>(v.value));
      c[x] = (v.saturation >= settings.min_saturation && v.value >= settings.min_value && (!m || m[x] != 0)) ? 255 : 0;
    }
  }
  return candidate;
}

// A connected component's pixel moments and summed saturation.
struct BlobStats {
  double n = 0, sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0, saturation = 0;
};

std::vector<BlobStats> blob_stats(const cv::Mat& labels, int count, const cv::Mat& hsv) {
  std::vector<BlobStats> stat(static_cast<std::size_t>(count));
  for (int y = 0; y < labels.rows; ++y) {
    const auto* lab = labels.ptr<int>(y);
    const auto* h = hsv.ptr<cv::Vec3f>(y);
    for (int x = 0; x < labels.cols; ++x) {
      BlobStats& s = stat[static_cast<std::size_t>(lab[x])];
      s.n += 1.0;
      s.sx += x;
      s.sy += y;
      s.sxx += static_cast<double>(x) * x;
      s.syy += static_cast<double>(y) * y;
      s.sxy += static_cast<double>(x) * y;
      s.saturation += static_cast<double>(h[x][1]);
    }
  }
  return stat;
}

// Whether a component could be a marker: its size, its mean saturation (paint is more saturated
// than skin under any light) and its shape (a marker is round: a wood grain's stripe or a cable is
// not).
bool is_marker_blob(const BlobStats& s, const ColourLearnSettings& settings) {
  if (s.n < settings.min_area_px || s.n > settings.max_area_px || s.saturation / s.n < settings.min_blob_saturation) return false;
  const double mx = s.sx / s.n, my = s.sy / s.n;
  const double cxx = s.sxx / s.n - mx * mx + 1.0 / 12.0, cyy = s.syy / s.n - my * my + 1.0 / 12.0, cxy = s.sxy / s.n - mx * my;
  const double det = cxx * cyy - cxy * cxy;
  const double half_trace = 0.5 * (cxx + cyy), root = std::sqrt(std::max(0.0, half_trace * half_trace - det));
  if (!(det > 0.0) || (half_trace + root) > 4.0 * (half_trace - root)) return false;  // elongation over 2
  return !(s.n / (4.0 * std::numbers::pi * std::sqrt(det)) < settings.min_fill);
}

// The pixels of an image's compact saturated blobs appended to `samples`; `blobs` counts the blobs.
void add_blob_samples(const cv::Mat& image, const cv::Mat* mask, const ColourLearnSettings& settings, std::vector<Sample>& samples,
                      int& blobs) {
  cv::Mat hsv;
  const cv::Mat candidate = candidate_pixels(image, mask, settings, hsv);
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(candidate, labels, stats, centroids, 8, CV_32S);
  const std::vector<BlobStats> stat = blob_stats(labels, n, hsv);
  std::vector<char> keep(static_cast<std::size_t>(n), 0);
  for (int l = 1; l < n; ++l) {
    if (!is_marker_blob(stat[static_cast<std::size_t>(l)], settings)) continue;
    keep[static_cast<std::size_t>(l)] = 1;
    ++blobs;
  }
  for (int y = 0; y < image.rows; ++y) {
    const auto* lab = labels.ptr<int>(y);
    const auto* h = hsv.ptr<cv::Vec3f>(y);
    for (int x = 0; x < image.cols; ++x) {
      if (keep[static_cast<std::size_t>(lab[x])])
        samples.push_back({static_cast<double>(h[x][0]), static_cast<double>(h[x][1]), static_cast<double>(h[x][2])});
    }
  }
}

// The hue histogram's peaks (1 degree bins, smoothed over +-5 degrees), at least 20 degrees apart
// and holding at least min_share of the samples.
std::vector<int> hue_peaks(const std::vector<Sample>& samples, const ColourLearnSettings& settings) {
  std::array<double, 360> hist{}, smooth{};
  for (const Sample& s : samples) hist[static_cast<std::size_t>(std::min(359.0, s.hue))] += 1.0;
  for (int i = 0; i < 360; ++i) {
    for (int d = -5; d <= 5; ++d) smooth[static_cast<std::size_t>(i)] += hist[static_cast<std::size_t>((i + d + 360) % 360)];
  }
  std::vector<int> peaks;
  const double floor_count = settings.min_share * static_cast<double>(samples.size());
  for (int i = 0; i < 360; ++i) {
    const double v = smooth[static_cast<std::size_t>(i)];
    if (v < floor_count) continue;
    bool is_max = true;
    for (int d = -20; d <= 20 && is_max; ++d) {
      const double o = smooth[static_cast<std::size_t>((i + d + 360) % 360)];
      if (o > v || (o == v && d < 0)) is_max = d == 0;
    }
    if (is_max) peaks.push_back(i);
  }
  return peaks;
}

struct Peak {
  double hue;
  double half_gap;
  std::vector<Sample> samples;
  int colour = -1;
};

// Each peak's samples: within half the distance to its nearest neighbouring peak (at most 30).
// Its hue: their circular mean. Left out: a peak with too few samples, and one whose nearest colour
// of the vocabulary is not one of those expected (skin, a table, a colour not asked for).
std::vector<Peak> named_peaks(const std::vector<int>& peaks, const std::vector<Sample>& samples, const ColourLearnSettings& settings) {
  std::vector<Peak> found;
  for (const int p : peaks) {
    double gap = 360.0;
    for (const int q : peaks) {
      if (q != p) gap = std::min(gap, hue_distance_deg(p, q));
    }
    Peak peak{static_cast<double>(p), std::min(30.0, gap / 2.0), {}, -1};
    for (const Sample& s : samples) {
      if (hue_distance_deg(s.hue, p) <= peak.half_gap) peak.samples.push_back(s);
    }
    if (static_cast<double>(peak.samples.size()) < settings.min_share * static_cast<double>(samples.size())) continue;
    double sx = 0.0, sy = 0.0;
    for (const Sample& s : peak.samples) {
      sx += std::cos(s.hue * std::numbers::pi / 180.0);
      sy += std::sin(s.hue * std::numbers::pi / 180.0);
    }
    peak.hue = std::fmod(std::atan2(sy, sx) * 180.0 / std::numbers::pi + 360.0, 360.0);
    double best = 1e9;
    for (int c = 0; c < kMarkerColourCount; ++c) {
      const double d = hue_distance_deg(peak.hue, kMarkerColours[static_cast<std::size_t>(c)].hue_deg);
      if (d < best) best = d, peak.colour = c;
    }
    if (!settings.expected.empty() &&
        std::find(settings.expected.begin(), settings.expected.end(), peak.colour) == settings.expected.end()) {
      continue;
    }
    found.push_back(std::move(peak));
  }
  return found;
}

// Fails when two peaks have one name, an expected colour has no peak, or there is no peak at all.
std::expected<void, std::string> check_peaks(const std::vector<Peak>& found, const ColourLearnSettings& settings) {
  for (std::size_t i = 0; i < found.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      if (found[i].colour == found[j].colour) {
        return std::unexpected("two hue peaks (" + number_text(std::round(found[j].hue)) + " and " + number_text(std::round(found[i].hue)) +
                               " degrees) are both nearest " + std::string(marker_colour_name(found[i].colour)) +
                               ": mask the images or name the colours expected");
      }
    }
  }
  for (const int c : settings.expected) {
    if (std::none_of(found.begin(), found.end(), [&](const Peak& p) { return p.colour == c; })) {
      return std::unexpected("no blobs of " + std::string(marker_colour_name(c)) + " found: is the marker in view and lit?");
    }
  }
  if (found.empty()) return std::unexpected("no hue holds enough of the blobs' pixels to be a marker colour");
  return {};
}

// A peak's window: tolerance 3 standard deviations plus 6 degrees (at most halfway to the next of
// `found`, at most 30), minimum saturation 80 % of its 10th percentile, value half its 5th.
ColourClass learned_class(const Peak& p, const std::vector<Peak>& found) {
  double var = 0.0;
  std::vector<double> sat, val;
  for (const Sample& s : p.samples) {
    const double d = hue_distance_deg(s.hue, p.hue);
    var += d * d;
    sat.push_back(s.saturation);
    val.push_back(s.value);
  }
  const double sd = std::sqrt(var / static_cast<double>(p.samples.size()));
  double half_gap = 30.0;
  for (const Peak& q : found) {
    if (&q != &p) half_gap = std::min(half_gap, hue_distance_deg(p.hue, q.hue) / 2.0 - 0.5);
  }
  ColourClass c;
  c.colour = p.colour;
  c.hue_deg = p.hue >= 359.9995 ? 0.0 : p.hue;
  c.hue_tolerance_deg = std::clamp(3.0 * sd + 6.0, 1.0, std::max(1.0, half_gap));
  c.min_saturation = std::clamp(0.8 * percentile(sat, 0.1), kLearnedSaturationFloor, 1.0);
  c.min_value = std::clamp(0.5 * percentile(val, 0.05), 0.0, 1.0);
  return c;
}

// The images' median colours, channel by channel.
std::array<double, 3> median_white_reference(const std::vector<cv::Mat>& images) {
  std::array<std::vector<double>, 3> medians;
  for (const cv::Mat& image : images) {
    const auto c = median_colour(image);
    for (std::size_t ch = 0; ch < 3; ++ch) medians[ch].push_back(c[ch]);
  }
  return {percentile(medians[0], 0.5), percentile(medians[1], 0.5), percentile(medians[2], 0.5)};
}

}  // namespace

std::expected<ColourLearnReport, std::string> learn_colour_model(const std::vector<cv::Mat>& images, const std::vector<cv::Mat>& masks,
                                                                 const ColourLearnSettings& settings) {
  if (images.empty()) return std::unexpected("no images to learn colours from");
  if (!masks.empty() && masks.size() != images.size()) {
    return std::unexpected("expected one mask per image (" + std::to_string(images.size()) + "), got " + std::to_string(masks.size()));
  }
  std::vector<Sample> samples;
  ColourLearnReport report;
  for (std::size_t i = 0; i < images.size(); ++i) {
    const cv::Mat& image = images[i];
    if (image.empty() || image.type() != CV_8UC3) return std::unexpected("image " + std::to_string(i) + ": expected an 8-bit BGR image");
    const cv::Mat* mask = masks.empty() ? nullptr : &masks[i];
    if (mask && (mask->type() != CV_8UC1 || mask->size() != image.size())) {
      return std::unexpected("mask " + std::to_string(i) + ": expected an 8-bit single-channel image of the image's size");
    }
    add_blob_samples(image, mask, settings, samples, report.blobs);
  }
  if (samples.empty()) {
    return std::unexpected("no compact saturated blobs in the images: hold the markers up to the camera, nearer or in better light");
  }
  std::vector<Peak> found = named_peaks(hue_peaks(samples, settings), samples, settings);
  std::sort(found.begin(), found.end(), [](const Peak& a, const Peak& b) { return a.samples.size() > b.samples.size(); });
  if (const auto ok = check_peaks(found, settings); !ok) return std::unexpected(ok.error());
  for (const Peak& p : found) {
    report.model.classes.push_back(learned_class(p, found));
    report.pixels_per_class.push_back(static_cast<int>(p.samples.size()));
  }
  report.model.white_reference = median_white_reference(images);
  report.model.description = "learned from " + std::to_string(images.size()) + " image(s), " + std::to_string(report.blobs) + " blobs";
  if (const auto ok = report.model.check(); !ok) return std::unexpected("the learned model is not usable: " + ok.error());
  return report;
}

std::array<double, 3> median_colour(const cv::Mat& bgr) {
  std::array<std::vector<double>, 3> channels;
  for (int y = 4; y < bgr.rows; y += 8) {
    const auto* p = bgr.ptr<cv::Vec3b>(y);
    for (int x = 4; x < bgr.cols; x += 8) {
      if (std::max({p[x][0], p[x][1], p[x][2]}) >= 255) continue;
      for (std::size_t ch = 0; ch < 3; ++ch) channels[ch].push_back(p[x][static_cast<int>(2 - ch)] / 255.0);
    }
  }
  if (channels[0].empty()) return {0.5, 0.5, 0.5};
  return {std::max(0.01, percentile(channels[0], 0.5)), std::max(0.01, percentile(channels[1], 0.5)),
          std::max(0.01, percentile(channels[2], 0.5))};
}

cv::Mat classification_picture(const ColourTable& table, const cv::Mat& bgr) {
  cv::Mat out(bgr.size(), CV_8UC3);
  for (int y = 0; y < bgr.rows; ++y) {
    const auto* p = bgr.ptr<cv::Vec3b>(y);
    auto* o = out.ptr<cv::Vec3b>(y);
    for (int x = 0; x < bgr.cols; ++x) {
      const std::uint8_t k = table.klass(p[x][0], p[x][1], p[x][2]);
      if (k == 0) {
        const auto grey = static_cast<std::uint8_t>((p[x][0] + 2 * p[x][1] + p[x][2]) / 12);
        o[x] = cv::Vec3b(grey, grey, grey);
        continue;
      }
      const double m = 0.35 + 0.65 * table.membership(p[x][0], p[x][1], p[x][2]) / 255.0;
      const auto& d = kMarkerColours[static_cast<std::size_t>(table.model().classes[k - 1u].colour)].display_srgb;
      o[x] = cv::Vec3b(static_cast<std::uint8_t>(255.0 * m * d[2]), static_cast<std::uint8_t>(255.0 * m * d[1]),
                       static_cast<std::uint8_t>(255.0 * m * d[0]));
    }
  }
  return out;
}

}  // namespace rhot
