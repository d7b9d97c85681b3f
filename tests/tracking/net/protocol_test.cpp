// The node messages: exact round trips, every refusal with its message, and a fuzz run.

#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "tracking/net/NodeProtocol.h"

namespace rhot {
namespace {

NodeFrameMessage sample_frame(int detections) {
  NodeFrameMessage m;
  m.node = 3;
  m.camera = 7;
  m.counter = 123456789012ULL;
  m.capture_ns = -42'000'000'123LL;
  m.exposure_us = 2500;
  m.width = 1280;
  m.height = 720;
  for (int i = 0; i < detections; ++i) {
    Detection d;
    d.pixel = {10.25 + 12.5 * i, 700.75 - 3.0 * i};
    d.area_px = static_cast<float>(20 + i);
    d.intensity = 200.5f;
    m.detections.push_back(d);
  }
  return m;
}

std::string why(std::span<const std::uint8_t> bytes) {
  const auto r = decode(bytes);
  return r ? std::string("accepted") : r.error().message;
}

TEST(NodeProtocol, EveryMessageComesBackAsItWasSent) {
  const NodeFrameMessage f = sample_frame(5);
  const auto bytes = encode(f);
  EXPECT_EQ(bytes.size(), kNodeHeaderBytes + kFrameFixedBytes + 5 * kDetectionBytes);
  const auto back = decode(bytes);
  ASSERT_TRUE(back.has_value()) << back.error().message;
  const auto& g = std::get<NodeFrameMessage>(*back);
  EXPECT_EQ(g.node, 3);
  EXPECT_EQ(g.camera, 7);
  EXPECT_EQ(g.counter, 123456789012ULL);
  EXPECT_EQ(g.capture_ns, -42'000'000'123LL);
  EXPECT_EQ(g.exposure_us, 2500u);
  EXPECT_EQ(g.width, 1280);
  EXPECT_EQ(g.height, 720);
  ASSERT_EQ(g.detections.size(), 5u);
  for (std::size_t i = 0; i < 5; ++i) {
    // float32 on the wire: exact for these values, within 1e-4 px for any in a 4k image.
    EXPECT_EQ(g.detections[i].pixel, f.detections[i].pixel);
    EXPECT_EQ(g.detections[i].area_px, f.detections[i].area_px);
    EXPECT_EQ(g.detections[i].intensity, 200.5f);
    EXPECT_EQ(g.detections[i].truth_marker, -1) << "no truth travels";
  }
  const auto t = std::get<TimeReply>(*decode(encode(TimeReply{9, 1'000'000'007LL, -5})));
  EXPECT_EQ(t.sequence, 9u);
  EXPECT_EQ(t.master_send_ns, 1'000'000'007LL);
  EXPECT_EQ(t.node_ns, -5);
  EXPECT_EQ(std::get<TimeRequest>(*decode(encode(TimeRequest{4, 77}))).master_send_ns, 77);
  EXPECT_EQ(std::get<StatusRequest>(*decode(encode(StatusRequest{11}))).sequence, 11u);
  StatusReply s{5, 2, 3, 89.5f, 0.25f, 1000, 7};
  const auto sb = std::get<StatusReply>(*decode(encode(s)));
  EXPECT_EQ(sb.cameras, 3);
  EXPECT_EQ(sb.frame_rate_hz, 89.5f);
  EXPECT_EQ(sb.frames_dropped, 7u);
  // An empty frame is a frame: a camera that sees nothing says so.
  EXPECT_TRUE(std::get<NodeFrameMessage>(*decode(encode(sample_frame(0)))).detections.empty());
}

TEST(NodeProtocol, BadMessagesAreRefusedWithTheirReason) {
  auto bytes = encode(sample_frame(3));
  EXPECT_EQ(why(std::span(bytes.data(), 2)), "message of 2 bytes, shorter than the 4-byte header");
  EXPECT_EQ(why(std::span(bytes.data(), 20)), "frame: needs at least 30 bytes after the header, got 16");
  EXPECT_EQ(why(std::span(bytes.data(), bytes.size() - 1)), "frame: 3 detections need 66 bytes after the header, got 65");
  auto longer = bytes;
  longer.push_back(0);
  EXPECT_EQ(why(longer), "frame: 3 detections need 66 bytes after the header, got 67");
  EXPECT_EQ(decode(longer).error().kind, NodeDecodeError::kOversized);
  auto other = bytes;
  other[0] = 'X';
  EXPECT_EQ(why(other), "not a rhot node message (no 'RN' header)");
  auto version = bytes;
  version[2] = 2;
  EXPECT_EQ(why(version), "protocol version 2, this master speaks 1");
  auto type = bytes;
  type[3] = 99;
  EXPECT_EQ(why(type), "unknown message type 99");
  // Count field (after node, camera, counter, capture, exposure, width, height) beyond the limit.
  auto count = bytes;
  const std::uint16_t many = 5000;
  std::memcpy(count.data() + kNodeHeaderBytes + 28, &many, 2);
  EXPECT_EQ(why(count), "frame: 5000 detections, at most 4096");
  const std::vector<std::uint8_t> huge(kMaxNodeMessageBytes + 1, 0);
  EXPECT_EQ(decode(huge).error().kind, NodeDecodeError::kOversized);
  // Nonsense values.
  NodeFrameMessage f = sample_frame(2);
  f.detections[1].pixel = {std::numeric_limits<double>::quiet_NaN(), 3.0};
  EXPECT_EQ(why(encode(f)), "frame: detection 1 at (nan, 3.000000) is outside the 1280x720 image");
  f.detections[1].pixel = {1283.0, 3.0};
  EXPECT_EQ(why(encode(f)), "frame: detection 1 at (1283.000000, 3.000000) is outside the 1280x720 image");
  f.detections[1].pixel = {1280.5, -2.0};
  EXPECT_TRUE(decode(encode(f)).has_value()) << "a border blob's noisy centre within 2 px of the image is kept";
  f = sample_frame(0);
  f.width = 0;
  EXPECT_EQ(why(encode(f)), "frame: image size 0x720 has no pixels");
  StatusReply s;
  s.frame_rate_hz = std::numeric_limits<float>::infinity();
  EXPECT_EQ(why(encode(s)), "status reply: frame rate and detection time must be finite and >= 0");
  auto time = encode(TimeReply{});
  time.pop_back();
  EXPECT_EQ(why(time), "time reply: needs 20 bytes after the header, got 19");
}

// A million messages from the network's worst: valid ones with bytes flipped, cut, lengthened or
// spliced, and pure noise. Nothing may crash, read out of bounds (the sanitizers watch), or be
// accepted with a non-finite or out-of-image value.
TEST(NodeProtocol, AMillionMutatedAndRandomMessagesNeverCrashTheDecoder) {
  std::mt19937_64 rng(2026);
  std::vector<std::vector<std::uint8_t>> seeds{encode(sample_frame(0)),
                                               encode(sample_frame(1)),
                                               encode(sample_frame(40)),
                                               encode(TimeRequest{1, 2}),
                                               encode(TimeReply{1, 2, 3}),
                                               encode(StatusRequest{4}),
                                               encode(StatusReply{5, 1, 2, 90.0f, 0.1f, 10, 0})};
  // A random byte as the generator's low eight bits: this program is compiled at -O0 under the
  // sanitizers, where a distribution's call per byte and Eigen's allFinite per detection took
  // most of the test's time (perf: the decoder itself was a fifth of it).
  const auto random_byte = [&rng] { return static_cast<std::uint8_t>(rng() & 0xff); };
  long accepted = 0, refused = 0;
  const auto began = std::chrono::steady_clock::now();
  for (int i = 0; i < 1'000'000; ++i) {
    std::vector<std::uint8_t> m;
    const int how = static_cast<int>(rng() % 6);
    if (how == 5) {
      m.resize(rng() % 200);
      for (auto& b : m) b = random_byte();
      if (m.size() >= 3 && rng() % 2) m[0] = 'R', m[1] = 'N', m[2] = 1;  // past the first checks
    } else {
      m = seeds[rng() % seeds.size()];
      const int flips = 1 + static_cast<int>(rng() % 4);
      for (int k = 0; k < flips && !m.empty(); ++k) m[rng() % m.size()] = random_byte();
      if (how == 1 && !m.empty()) m.resize(rng() % m.size());
      if (how == 2) m.resize(m.size() + 1 + rng() % 64, random_byte());
      if (how == 3) {
        const auto& other = seeds[rng() % seeds.size()];
        m.insert(m.end(), other.begin() + static_cast<long>(rng() % other.size()), other.end());
      }
    }
    const auto r = decode(m);
    if (!r) {
      ++refused;
      EXPECT_FALSE(r.error().message.empty());
      continue;
    }
    ++accepted;
    if (const auto* f = std::get_if<NodeFrameMessage>(&*r)) {
      for (const Detection& d : f->detections) {
        ASSERT_TRUE(std::isfinite(d.pixel.x()) && std::isfinite(d.pixel.y()));
        ASSERT_LE(d.pixel.x(), f->width + 2.0);
        ASSERT_LE(d.pixel.y(), f->height + 2.0);
      }
    }
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
  std::printf("1e6 messages: %ld accepted, %ld refused, %.2f s\n", accepted, refused, seconds);
  EXPECT_GT(accepted, 10'000) << "mutations that keep a message valid are decoded";
  EXPECT_GT(refused, 500'000);
}

}  // namespace
}  // namespace rhot
