#pragma once
// The names of marker colours: the vocabulary colour files (tracking/detect/ColourModel.h), hand
// layouts and detections share, as OpenXR's joint names are for joints. A detection's `colour` is
// an index into kMarkerColours (-1: no colour, an infrared blob), whatever order a colour file
// lists its colours in, so a layout naming "red" and a file learning "red" always agree.

#include <array>
#include <optional>
#include <string>
#include <string_view>

namespace rhot {

struct MarkerColourName {
  std::string_view name;
  double hue_deg;                      // nominal hue (HSV, 0-360): where a learned colour is named from
  std::array<double, 3> display_srgb;  // how it is drawn in pictures and simulated markers, sRGB 0-1
};

inline constexpr std::array<MarkerColourName, 8> kMarkerColours{{
    {"red", 0.0, {0.86, 0.06, 0.08}},
    {"orange", 30.0, {0.95, 0.45, 0.05}},
    {"yellow", 60.0, {0.92, 0.85, 0.06}},
    {"green", 120.0, {0.08, 0.75, 0.15}},
    {"cyan", 180.0, {0.05, 0.75, 0.85}},
    {"blue", 240.0, {0.10, 0.18, 0.90}},
    {"purple", 275.0, {0.50, 0.12, 0.80}},
    {"magenta", 310.0, {0.90, 0.10, 0.75}},
}};

inline constexpr int kMarkerColourCount = static_cast<int>(kMarkerColours.size());

// The colour's index, or nothing for a name not in the vocabulary.
inline std::optional<int> marker_colour_from_name(std::string_view name) {
  for (int i = 0; i < kMarkerColourCount; ++i) {
    if (kMarkerColours[static_cast<std::size_t>(i)].name == name) return i;
  }
  return std::nullopt;
}

// "red", ...; "none" for -1 and anything out of range.
inline std::string_view marker_colour_name(int colour) {
  return colour >= 0 && colour < kMarkerColourCount ? kMarkerColours[static_cast<std::size_t>(colour)].name : std::string_view("none");
}

// "red, orange, ..., magenta": for messages.
inline std::string marker_colour_list() {
  std::string out;
  for (const auto& c : kMarkerColours) out += (out.empty() ? "" : ", ") + std::string(c.name);
  return out;
}

}  // namespace rhot
