#pragma once
// What each marker colour looks like to a camera, as data (a colour file, `rhot-calib colours`
// writes one from example images):
//
//   {
//     "format": "rhot-marker-colours", "version": 1,
//     "description": "...",                        optional, free text
//     "colours": [
//       { "name": "red",                           a marker colour's name (tracking/core/MarkerColour.h)
//         "hue_deg": 356.0,                        its hue (HSV, 0-360, sRGB pixels)
//         "hue_tolerance_deg": 18.0,               a pixel within this many degrees of it may be the colour
//         "min_saturation": 0.55,                  and at least this saturated (0-1)
//         "min_value": 0.2 },                      and at least this bright (HSV value, 0-1)
//       ...
//     ],
//     "white_reference": [0.52, 0.50, 0.45]        optional: the scene's median R, G and B (0-1) where
//   }                                              the colours were learned (absent: no balancing)
//
// Hue and saturation do not change when exposure scales a pixel, and white balance turns hues by
// a few degrees only for saturated colours: a model of hue windows stays valid under both, where
// an RGB box would not. A light much warmer or cooler than the one the colours were learned under
// turns hues further, and a darker exposure drops the shaded side of a marker under min_value; the
// detector follows both by comparing the image's median R, G and B with the model's white
// reference and scaling pixels by the ratio before they are classified. Skin, wood and paper are less saturated than marker paint, which
// is what min_saturation keeps out. Colours' hue windows may not overlap, so a pixel has one colour at most.
//
// A ColourTable turns the model into a lookup table of 32 x 32 x 32 RGB cells (the top five bits of
// each channel, 32 KiB, in the first-level cache): per cell its colour and how surely (the
// membership, 0 at a window's edge to 1 well inside), so classifying a pixel is one load.

#include <array>
#include <cstdint>
#include <expected>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "base/JsonError.h"

namespace rhot {

struct ColourClass {
  int colour = 0;  // index into kMarkerColours
  double hue_deg = 0.0;
  double hue_tolerance_deg = 15.0;
  double min_saturation = 0.5;
  double min_value = 0.2;
};

struct ColourModel {
  std::string description;
  std::vector<ColourClass> classes;  // one per colour, at most one each
  // The median R, G and B (0-1) of the images the model was learned from: what the detector
  // balances a new image's medians toward. None: the detector takes pixels as they come (a model written by
  // hand, or the default one, knows nothing of the scene's colours: a wooden table is not grey).
  std::optional<std::array<double, 3>> white_reference;

  // Every value usable: "colours/<i> (<name>): <field>: <what was expected>, got <value>", or the
  // two colours whose hue windows overlap.
  [[nodiscard]] std::expected<void, std::string> check() const;
  // The class of a colour, or nullptr.
  const ColourClass* find(int colour) const;
};

// HSV of an sRGB pixel (0-255 each): hue 0-360 degrees, saturation and value 0-1.
struct Hsv {
  double hue_deg = 0.0, saturation = 0.0, value = 0.0;
};
Hsv hsv_from_rgb(double r, double g, double b);
// The smallest angle between two hues, 0-180 degrees.
double hue_distance_deg(double a, double b);

// A pixel's colour under a model: the class (index into model.classes) and membership 0-1, or
// class -1 for none.
struct PixelClass {
  int klass = -1;
  double membership = 0.0;
};
PixelClass classify(const ColourModel& model, const Hsv& hsv);

class ColourTable {
 public:
  // Precondition: model.check() passes. Each cell's pixel is multiplied by gains (R, G, B) before
  // it is classified: a white balance and exposure folded into the table.
  explicit ColourTable(const ColourModel& model, std::array<double, 3> gains = {1.0, 1.0, 1.0});
  const std::array<double, 3>& gains() const { return gains_; }
  // Per cell: 0 for no colour, else 1 + the class's index in the model.
  std::uint8_t klass(std::uint8_t b, std::uint8_t g, std::uint8_t r) const { return klass_[cell(b, g, r)]; }
  // Per cell: the membership times 255 (0 where klass is 0).
  std::uint8_t membership(std::uint8_t b, std::uint8_t g, std::uint8_t r) const { return membership_[cell(b, g, r)]; }
  static std::size_t cell(std::uint8_t b, std::uint8_t g, std::uint8_t r) {
    return (static_cast<std::size_t>(r >> 3) << 10) | (static_cast<std::size_t>(g >> 3) << 5) | static_cast<std::size_t>(b >> 3);
  }
  const ColourModel& model() const { return model_; }
  const std::uint8_t* classes() const { return klass_.data(); }
  const std::uint8_t* memberships() const { return membership_.data(); }

 private:
  ColourModel model_;
  std::array<double, 3> gains_;
  std::vector<std::uint8_t> klass_, membership_;
};

// Reading and writing colour files. Errors: "<file>: <json path>: <what was wrong>", as every
// JSON loader of rhot (base/Json.h); a model that fails check() is refused naming the colour.
[[nodiscard]] std::expected<ColourModel, JsonError> load_colour_model(const std::filesystem::path& file);
[[nodiscard]] std::expected<ColourModel, JsonError> parse_colour_model(std::string_view text, std::string_view file);
std::string colour_model_json(const ColourModel& model);
[[nodiscard]] std::expected<void, std::string> save_colour_model(const ColourModel& model, const std::filesystem::path& file);

// The six colours of rhot's colour markers (red, yellow, green, cyan, blue, magenta: hues 60
// degrees apart) with windows wide enough for white balances from 3000 K to 8000 K: what the
// shipped colour layouts and the simulated colour cameras use before a model is learned.
ColourModel default_colour_model();

// Learning a model from example images (BGR, CV_8UC3) in which the user holds the markers up.
struct ColourLearnSettings {
  std::vector<int> expected;         // the colours to find (empty: whichever are found)
  double min_saturation = 0.4;       // pixels less saturated than this are never marker paint
  double min_blob_saturation = 0.7;  // nor blobs less saturated on average (skin under a warm light reaches 0.6)
  double min_value = 0.15;
  int min_area_px = 12;     // a marker's blob: at least this many pixels ...
  int max_area_px = 2500;   // ... and at most this many (a painted wall is not a marker)
  double min_fill = 0.6;    // and round: elongation at most 2, its pixels over its moments' ellipse at least this
  double min_share = 0.02;  // a hue peak must hold at least this share of the blobs' pixels
};
struct ColourLearnReport {
  ColourModel model;
  std::vector<int> pixels_per_class;  // samples behind each class
  int blobs = 0;                      // compact saturated blobs the samples came from
};
// Finds compact, strongly saturated blobs in the images (optionally only where `masks` are non-zero: one
// CV_8UC1 per image or none), clusters their pixels' hues into peaks, names each peak by the
// nearest colour of the vocabulary (leaving out peaks nearest a colour not expected, such as skin's
// nearest orange) and fits its window: hue at the peak's circular mean, tolerance
// 3 standard deviations plus 6 degrees (at most halfway to the next peak, at most 30), minimum
// saturation 80 % of its 10th percentile (at least 0.55), value half its 5th. Fails naming an image that is not
// BGR, a mask of another size, no blobs, an expected colour not found, or two peaks with one name.
[[nodiscard]] std::expected<ColourLearnReport, std::string> learn_colour_model(const std::vector<cv::Mat>& images,
                                                                               const std::vector<cv::Mat>& masks,
                                                                               const ColourLearnSettings& settings = {});

// An image's median R, G and B (0-1) over a sparse grid (every 8th pixel of every 8th row),
// leaving out clipped pixels: its white balance and exposure, as ColourModel::white_reference.
// (0.5, 0.5, 0.5) when no pixel counts.
std::array<double, 3> median_colour(const cv::Mat& bgr);

// A picture of what a model classifies: every pixel of a colour painted that colour's display
// colour at full strength (dimmed by its membership), everything else a dark grey copy of the
// image, so a user sees a bad model (skin taken for red, a marker half missing) before tracking.
cv::Mat classification_picture(const ColourTable& table, const cv::Mat& bgr);

}  // namespace rhot
