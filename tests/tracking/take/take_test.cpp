// Labelled marker takes: C3D in every processor type and storage, and Qualisys TSV, written by
// rhot and read back exactly (gaps included); truncated and malformed files refused with their
// exact message.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/support/TempDir.h"
#include "tracking/take/C3d.h"
#include "tracking/take/MarkerTake.h"
#include "tracking/take/QualisysTsv.h"

namespace rhot {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Five markers moving on circles of different radii about a point 1 m up, 40 frames at 120 Hz;
// marker 2 is hidden in frames 10-14 and marker 4 in the last frame.
MarkerTake moving_take() {
  MarkerTake take;
  take.frame_rate_hz = 120.0;
  take.marker_names = {"hand_top", "hand_left", "index_tip", "thumb_tip", "pillow_top"};
  for (int f = 0; f < 40; ++f) {
    for (int m = 0; m < 5; ++m) {
      const double a = 0.1 * f + m;
      Eigen::Vector3d p{0.3 + 0.05 * (m + 1) * std::cos(a), -0.2 + 0.04 * (m + 1) * std::sin(a), 1.0 + 0.01 * m - 0.002 * f};
      if ((m == 2 && f >= 10 && f < 15) || (m == 4 && f == 39)) p.setConstant(kNaN);
      take.positions_m.push_back(p);
    }
  }
  return take;
}

void expect_same_take(const MarkerTake& a, const MarkerTake& b, double tolerance_m) {
  ASSERT_EQ(a.marker_names, b.marker_names);
  ASSERT_EQ(a.frame_count(), b.frame_count());
  EXPECT_NEAR(a.frame_rate_hz, b.frame_rate_hz, 1e-9);
  for (int f = 0; f < a.frame_count(); ++f) {
    for (int m = 0; m < a.marker_count(); ++m) {
      ASSERT_EQ(a.seen(f, m), b.seen(f, m)) << "frame " << f << ", marker " << m;
      if (a.seen(f, m)) {
        EXPECT_LT((a.at(f, m) - b.at(f, m)).cwiseAbs().maxCoeff(), tolerance_m) << "frame " << f << ", marker " << m;
      }
    }
  }
}

std::vector<char> bytes_of(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_bytes(const std::filesystem::path& file, const std::vector<char>& bytes) {
  std::ofstream out(file, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

TEST(C3d, EveryProcessorTypeAndStorageReadsBackWhatWasWritten) {
  const auto dir = test::fresh_test_dir("c3d_round_trip");
  const MarkerTake take = moving_take();
  for (const C3dProcessor processor : {C3dProcessor::kIntel, C3dProcessor::kDec, C3dProcessor::kMips}) {
    for (const bool float_storage : {true, false}) {
      SCOPED_TRACE(testing::Message() << "processor " << static_cast<int>(processor) << (float_storage ? ", float" : ", integer"));
      const auto file = dir / "take.c3d";
      // Two analog channels in the integer files: the reader must step over their samples.
      ASSERT_TRUE(
          write_c3d(take, file, {.processor = processor, .float_storage = float_storage, .analog_channels = float_storage ? 0 : 2}));
      // The header's frame rate (bytes 20-23), 120.0 as each processor stores it: IEEE little- and
      // big-endian, and VAX F (the IEEE bits of 4 x 120 with their 16-bit halves swapped).
      const std::vector<char> bytes = bytes_of(file);
      const std::vector<unsigned char> rate(bytes.begin() + 20, bytes.begin() + 24);
      const std::vector<unsigned char> expected_rate =
          processor == C3dProcessor::kIntel  ? std::vector<unsigned char>{0x00, 0x00, 0xf0, 0x42}
          : processor == C3dProcessor::kMips ? std::vector<unsigned char>{0x42, 0xf0, 0x00, 0x00}
                                             : std::vector<unsigned char>{0xf0, 0x43, 0x00, 0x00};
      EXPECT_EQ(rate, expected_rate);
      const auto read = read_marker_take(file);
      ASSERT_TRUE(read.has_value()) << read.error();
      // Floats keep about 0.1 um at 1 m; integers round to the scale (1,040 mm / 32,000: 0.033 mm).
      expect_same_take(take, *read, float_storage ? 1e-6 : 0.5 * 1.04 / 32000.0 + 1e-9);
      EXPECT_DOUBLE_EQ(read->seen_fraction(2), 35.0 / 40.0);
    }
  }
}

TEST(C3d, TruncatedAndMalformedFilesAreRefusedWithTheReason) {
  const auto dir = test::fresh_test_dir("c3d_bad");
  const auto file = dir / "take.c3d";
  ASSERT_TRUE(write_c3d(moving_take(), file));
  const std::vector<char> good = bytes_of(file);
  const auto refused = [&](std::vector<char> bytes) {
    write_bytes(file, bytes);
    const auto r = read_c3d(file);
    return r.has_value() ? std::string("read") : r.error();
  };
  const std::string name = file.string() + ": ";
  // One frame is 5 points x 4 floats (80 bytes): 30 bytes short leaves 39 whole frames.
  EXPECT_EQ(refused({good.begin(), good.end() - 30}), name + "truncated: the data holds 39 of 40 frames");
  EXPECT_EQ(refused({good.begin(), good.begin() + 600}), name + "the parameter section is cut short");
  EXPECT_EQ(refused({good.begin(), good.begin() + 100}), name + "not a C3D file: 100 bytes, shorter than its 512-byte header");
  std::vector<char> not_c3d = good;
  not_c3d[1] = 0x12;
  EXPECT_EQ(refused(not_c3d), name + "not a C3D file (its second byte is 0x12, not 0x50)");
  std::vector<char> processor = good;
  processor[512 + 3] = 90;
  EXPECT_EQ(refused(processor), name + "processor type 90 is not one C3D defines (84 Intel, 85 DEC, 86 MIPS)");
  // POINT:UNITS' two characters follow its name, the offset, the type and one dimension.
  std::vector<char> units = good;
  const std::string key = "UNITS";
  const auto at = std::search(units.begin(), units.end(), key.begin(), key.end()) - units.begin();
  units[static_cast<std::size_t>(at) + 5 + 2 + 1 + 1 + 1] = 'i';
  units[static_cast<std::size_t>(at) + 5 + 2 + 1 + 1 + 1 + 1] = 'n';
  EXPECT_EQ(refused(units), name + "POINT:UNITS is \"in\", not a length (mm, cm or m)");
  EXPECT_EQ(refused(good), "read");

  MarkerTake long_names = moving_take();
  long_names.marker_names[0] = std::string(300, 'x');
  EXPECT_EQ(write_c3d(long_names, file).error(),
            name + "marker names too long for C3D's POINT:LABELS (255 characters each, 32,000 in all)");
}

TEST(QualisysTsv, ATakeWrittenAndReadBackIsTheSameWithItsGaps) {
  const auto dir = test::fresh_test_dir("tsv_round_trip");
  const MarkerTake take = moving_take();
  ASSERT_TRUE(write_qualisys_tsv(take, dir / "take.tsv"));
  const auto read = read_marker_take(dir / "take.tsv");
  ASSERT_TRUE(read.has_value()) << read.error();
  expect_same_take(take, *read, 0.51e-6);  // three decimals of a millimetre
}

// As Qualisys Track Manager writes it: header keys with several values, a column line or none.
TEST(QualisysTsv, TheExportsHeaderWithAndWithoutTheFrameAndTimeColumns) {
  const auto dir = test::fresh_test_dir("tsv_export");
  const std::string header =
      "NO_OF_FRAMES\t2\nNO_OF_CAMERAS\t7\nNO_OF_MARKERS\t2\nFREQUENCY\t100\nNO_OF_ANALOG\t0\nANALOG_FREQUENCY\t0\nDESCRIPTION\t--\n"
      "TIME_STAMP\t2021-08-26, 15:19:24.317\t1483034.68525310\nDATA_INCLUDED\t3D\nMARKER_NAMES\thand_top\tindex_tip\n"
      "TRAJECTORY_TYPES\tMeasured\tMixed\n";
  {
    std::ofstream(dir / "columns.tsv")
        << header << "Frame\tTime\thand_top X\thand_top Y\thand_top Z\tindex_tip X\tindex_tip Y\tindex_tip Z\n"
        << "1\t0.00000\t110.406\t135.075\t460.584\tnan\tnan\tnan\n2\t0.01000\t110.763\t135.349\t460.458\t141.316\t248.687\t391.455\n";
  }
  {
    std::ofstream(dir / "bare.tsv") << header << "110.406\t135.075\t460.584\t\t\t\n110.763\t135.349\t460.458\t141.316\t248.687\t391.455\n";
  }
  for (const char* file : {"columns.tsv", "bare.tsv"}) {
    SCOPED_TRACE(file);
    const auto take = read_qualisys_tsv(dir / file);
    ASSERT_TRUE(take.has_value()) << take.error();
    EXPECT_EQ(take->frame_rate_hz, 100.0);
    EXPECT_EQ(take->marker_names, (std::vector<std::string>{"hand_top", "index_tip"}));
    ASSERT_EQ(take->frame_count(), 2);
    EXPECT_FALSE(take->seen(0, 1));
    EXPECT_TRUE(take->at(1, 1).isApprox(Eigen::Vector3d(0.141316, 0.248687, 0.391455), 1e-12));
    EXPECT_TRUE(take->at(0, 0).isApprox(Eigen::Vector3d(0.110406, 0.135075, 0.460584), 1e-12));
  }
}

TEST(QualisysTsv, TruncatedAndMalformedFilesAreRefusedWithTheReason) {
  const auto dir = test::fresh_test_dir("tsv_bad");
  const auto file = dir / "take.tsv";
  ASSERT_TRUE(write_qualisys_tsv(moving_take(), file));
  std::string good;
  {
    std::ifstream in(file);
    good.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  const auto refused = [&](const std::string& text) {
    std::ofstream(file) << text;
    const auto r = read_qualisys_tsv(file);
    return r.has_value() ? std::string("read") : r.error();
  };
  const std::string name = file.string() + ": ";
  const std::string without_last = good.substr(0, good.rfind('\n', good.size() - 2) + 1);
  EXPECT_EQ(refused(without_last), name + "truncated: 39 of NO_OF_FRAMES 40 frames");
  // Nine header lines and the column line: frame 1 is line 11.
  std::string not_a_number = good;
  const auto first_data = not_a_number.find("\n1\t") + 1;
  const auto third_field = not_a_number.find('\t', not_a_number.find('\t', first_data) + 1) + 1;
  not_a_number.replace(third_field, not_a_number.find('\t', third_field) - third_field, "12,5");
  EXPECT_EQ(refused(not_a_number), name + "line 11, marker \"hand_top\" X: \"12,5\" is not a number");
  std::string short_line = good;
  short_line.replace(short_line.find("\n2\t"), 1, "\n2\t1\n");
  EXPECT_EQ(refused(short_line), name + "line 12: 2 fields, not 17 (5 markers x 3 after Frame and Time)");
  std::string no_rate = good;
  no_rate.replace(no_rate.find("FREQUENCY\t120"), 13, "FREQ\t120");
  EXPECT_EQ(refused(no_rate), name + "no FREQUENCY line in its header (a Qualisys TSV 3D export has one)");
  std::string names = good;
  names.replace(names.find("\tpillow_top\n"), 12, "\n");
  EXPECT_EQ(refused(names), name + "MARKER_NAMES lists 4 names for NO_OF_MARKERS 5");
  EXPECT_EQ(refused(good), "read");
}

TEST(MarkerTakes, AnUnknownFormatIsNamed) {
  const auto r = read_marker_take("session.trc");
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error(), "session.trc: unknown take format \".trc\" (rhot reads .c3d and Qualisys .tsv)");
}

}  // namespace
}  // namespace rhot
