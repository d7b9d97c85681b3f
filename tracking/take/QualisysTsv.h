#pragma once
// Qualisys Track Manager's TSV 3D export: a header of `KEY<TAB>value...` lines (NO_OF_FRAMES,
// NO_OF_MARKERS, FREQUENCY and MARKER_NAMES are needed; others are read past), then, with or
// without a `Frame<TAB>Time<TAB>name X<TAB>...` column line, one line per frame: optionally the frame
// number and time, then X, Y, Z per marker in millimetres. A marker with an empty or "nan" field is
// in a gap (Qualisys Track Manager writes either, by version and export settings).

#include <expected>
#include <filesystem>
#include <string>

#include "tracking/take/MarkerTake.h"

namespace rhot {

[[nodiscard]] std::expected<MarkerTake, std::string> read_qualisys_tsv(const std::filesystem::path& file);

// Writes a take in the same form (with the Frame and Time columns), gaps as empty fields.
[[nodiscard]] std::expected<void, std::string> write_qualisys_tsv(const MarkerTake& take, const std::filesystem::path& file);

}  // namespace rhot
