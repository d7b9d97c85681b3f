#pragma once
// C3D (www.c3d.org), the file format motion-capture systems export labelled takes in.
//
// A file is 512-byte blocks: a header block, the parameter section (groups such as POINT and ANALOG,
// each holding typed, named parameters), then the data, frame after frame: per 3D point X, Y, Z and a
// fourth word (residual and camera mask; negative: the point was not seen in that frame), then the
// frame's analog samples. Numbers are stored as the processor type in the parameter section says:
// 84 Intel (little-endian, IEEE floats), 85 DEC (little-endian words, VAX floats), 86 MIPS
// (big-endian, IEEE floats). A negative POINT:SCALE means float storage; a positive one, 16-bit
// integers to be multiplied by it.
//
// Read: every processor type and both storages; POINT:LABELS (and LABELS2 beyond 255 points),
// POINT:UNITS (mm, cm, m), POINT:RATE or the header's rate, the header's frame range (at most
// 65,535 frames; longer takes, which keep their count elsewhere, are not read yet); the analog
// samples are skipped. Refused with a message naming the fault: a file that is not C3D,
// an unknown processor type or parameter type, a parameter section or data cut short, labels that
// do not match the point count, units that are not a length.

#include <expected>
#include <filesystem>
#include <string>

#include "tracking/take/MarkerTake.h"

namespace rhot {

enum class C3dProcessor { kIntel = 84, kDec = 85, kMips = 86 };

struct C3dWriteOptions {
  C3dProcessor processor = C3dProcessor::kIntel;
  bool float_storage = true;
  // Integer storage only: millimetres per stored unit (POINT:SCALE); 0 picks the finest scale at
  // which the take's largest coordinate fits in 16 bits.
  double integer_scale_mm = 0.0;
  int analog_channels = 0;  // zero-valued analog channels (one sample a frame), to exercise readers
};

[[nodiscard]] std::expected<MarkerTake, std::string> read_c3d(const std::filesystem::path& file);

// Writes a take as C3D in millimetres (what other tools expect), gaps as invalid points.
[[nodiscard]] std::expected<void, std::string> write_c3d(const MarkerTake& take, const std::filesystem::path& file,
                                                         const C3dWriteOptions& options = {});

}  // namespace rhot
