#include "tracking/net/NodeProtocol.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <type_traits>

namespace rhot {

namespace {

static_assert(std::endian::native == std::endian::little, "the wire format is little-endian; add byte swapping for this machine");

constexpr std::size_t kTimeRequestBytes = 12;
constexpr std::size_t kTimeReplyBytes = 20;
constexpr std::size_t kStatusRequestBytes = 4;
constexpr std::size_t kStatusReplyBytes = 32;

class Writer {
 public:
  explicit Writer(NodeMessageType type, std::size_t body) {
    bytes_.reserve(kNodeHeaderBytes + body);
    bytes_.push_back('R');
    bytes_.push_back('N');
    bytes_.push_back(kNodeProtocolVersion);
    bytes_.push_back(static_cast<std::uint8_t>(type));
  }
  template <typename T>
  void put(T value) {
    static_assert(std::is_arithmetic_v<T>);
    std::uint8_t raw[sizeof(T)];
    std::memcpy(raw, &value, sizeof(T));
    bytes_.insert(bytes_.end(), raw, raw + sizeof(T));
  }
  std::vector<std::uint8_t> take() { return std::move(bytes_); }

 private:
  std::vector<std::uint8_t> bytes_;
};

// Reads a body whose length was checked beforehand.
class Reader {
 public:
  explicit Reader(std::span<const std::uint8_t> body) : body_(body) {}
  template <typename T>
  T get() {
    T value;
    std::memcpy(&value, body_.data() + at_, sizeof(T));
    at_ += sizeof(T);
    return value;
  }

 private:
  std::span<const std::uint8_t> body_;
  std::size_t at_ = 0;
};

NodeDecodeFailure fail(NodeDecodeError kind, std::string message) { return {kind, std::move(message)}; }

std::expected<void, NodeDecodeFailure> exact_size(const char* what, std::size_t body, std::size_t expected) {
  if (body < expected)
    return std::unexpected(fail(NodeDecodeError::kTruncated, std::string(what) + ": needs " + std::to_string(expected) +
                                                                 " bytes after the header, got " + std::to_string(body)));
  if (body > expected)
    return std::unexpected(fail(NodeDecodeError::kOversized, std::string(what) + ": needs " + std::to_string(expected) +
                                                                 " bytes after the header, got " + std::to_string(body)));
  return {};
}

std::uint16_t saturate16(double v) { return static_cast<std::uint16_t>(std::clamp(std::round(v), 0.0, 65535.0)); }

void write_frame(Writer& w, const NodeFrameMessage& m, std::size_t count) {
  w.put(m.node);
  w.put(m.camera);
  w.put(m.counter);
  w.put(m.capture_ns);
  w.put(m.exposure_us);
  w.put(m.width);
  w.put(m.height);
  w.put(static_cast<std::uint16_t>(count));
  for (std::size_t i = 0; i < count; ++i) {
    const Detection& d = m.detections[i];
    w.put(static_cast<float>(d.pixel.x()));
    w.put(static_cast<float>(d.pixel.y()));
    w.put(saturate16(static_cast<double>(d.area_px)));
    w.put(saturate16(static_cast<double>(d.intensity) * 256.0));
  }
}

std::expected<NodeMessage, NodeDecodeFailure> read_frame(std::span<const std::uint8_t> body) {
  if (body.size() < kFrameFixedBytes)
    return std::unexpected(fail(NodeDecodeError::kTruncated, "frame: needs at least " + std::to_string(kFrameFixedBytes) +
                                                                 " bytes after the header, got " + std::to_string(body.size())));
  Reader r(body);
  NodeFrameMessage m;
  m.node = r.get<std::uint16_t>();
  m.camera = r.get<std::uint16_t>();
  m.counter = r.get<std::uint64_t>();
  m.capture_ns = r.get<std::int64_t>();
  m.exposure_us = r.get<std::uint32_t>();
  m.width = r.get<std::uint16_t>();
  m.height = r.get<std::uint16_t>();
  const std::size_t count = r.get<std::uint16_t>();
  if (count > kMaxDetectionsPerFrame)
    return std::unexpected(fail(NodeDecodeError::kOversized,
                                "frame: " + std::to_string(count) + " detections, at most " + std::to_string(kMaxDetectionsPerFrame)));
  if (const auto size = exact_size("frame", body.size(), kFrameFixedBytes + count * kDetectionBytes); !size) {
    NodeDecodeFailure f = size.error();
    f.message = "frame: " + std::to_string(count) + " detections need " + std::to_string(kFrameFixedBytes + count * kDetectionBytes) +
                " bytes after the header, got " + std::to_string(body.size());
    return std::unexpected(f);
  }
  if (m.width == 0 || m.height == 0)
    return std::unexpected(fail(NodeDecodeError::kBadValue,
                                "frame: image size " + std::to_string(m.width) + "x" + std::to_string(m.height) + " has no pixels"));
  m.detections.resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    const float x = r.get<float>(), y = r.get<float>();
    // The image spans -0.5 to size - 0.5; a noisy centroid of a blob on the border may lie a
    // little beyond it, anything further is nonsense.
    constexpr float margin = kDetectionMarginPx;
    if (!std::isfinite(x) || !std::isfinite(y) || x < -0.5f - margin || y < -0.5f - margin ||
        x > static_cast<float>(m.width) - 0.5f + margin || y > static_cast<float>(m.height) - 0.5f + margin)
      return std::unexpected(fail(NodeDecodeError::kBadValue, "frame: detection " + std::to_string(i) + " at (" + std::to_string(x) + ", " +
                                                                  std::to_string(y) + ") is outside the " + std::to_string(m.width) + "x" +
                                                                  std::to_string(m.height) + " image"));
    Detection& d = m.detections[i];
    d.pixel = {x, y};
    d.area_px = static_cast<float>(r.get<std::uint16_t>());
    d.intensity = static_cast<float>(r.get<std::uint16_t>()) / 256.0f;
  }
  return m;
}

}  // namespace

const char* to_string(NodeDecodeError e) {
  switch (e) {
    case NodeDecodeError::kTruncated:
      return "truncated";
    case NodeDecodeError::kOversized:
      return "oversized";
    case NodeDecodeError::kNotRhot:
      return "not a rhot node message";
    case NodeDecodeError::kVersion:
      return "wrong version";
    case NodeDecodeError::kUnknownType:
      return "unknown type";
    case NodeDecodeError::kBadValue:
      return "bad value";
  }
  return "?";
}

std::vector<std::uint8_t> encode(const NodeMessage& message) {
  return std::visit(
      [](const auto& m) {
        using T = std::decay_t<decltype(m)>;
        if constexpr (std::is_same_v<T, NodeFrameMessage>) {
          const std::size_t count = std::min(m.detections.size(), kMaxDetectionsPerFrame);
          Writer w(NodeMessageType::kFrame, kFrameFixedBytes + count * kDetectionBytes);
          write_frame(w, m, count);
          return w.take();
        } else if constexpr (std::is_same_v<T, TimeRequest>) {
          Writer w(NodeMessageType::kTimeRequest, kTimeRequestBytes);
          w.put(m.sequence);
          w.put(m.master_send_ns);
          return w.take();
        } else if constexpr (std::is_same_v<T, TimeReply>) {
          Writer w(NodeMessageType::kTimeReply, kTimeReplyBytes);
          w.put(m.sequence);
          w.put(m.master_send_ns);
          w.put(m.node_ns);
          return w.take();
        } else if constexpr (std::is_same_v<T, StatusRequest>) {
          Writer w(NodeMessageType::kStatusRequest, kStatusRequestBytes);
          w.put(m.sequence);
          return w.take();
        } else {
          Writer w(NodeMessageType::kStatusReply, kStatusReplyBytes);
          w.put(m.sequence);
          w.put(m.node);
          w.put(m.cameras);
          w.put(m.frame_rate_hz);
          w.put(m.detect_mean_ms);
          w.put(m.frames_published);
          w.put(m.frames_dropped);
          return w.take();
        }
      },
      message);
}

std::expected<NodeMessage, NodeDecodeFailure> decode(std::span<const std::uint8_t> bytes) {
  if (bytes.size() > kMaxNodeMessageBytes)
    return std::unexpected(fail(NodeDecodeError::kOversized,
                                "message of " + std::to_string(bytes.size()) + " bytes, at most " + std::to_string(kMaxNodeMessageBytes)));
  if (bytes.size() < kNodeHeaderBytes)
    return std::unexpected(fail(NodeDecodeError::kTruncated, "message of " + std::to_string(bytes.size()) + " bytes, shorter than the " +
                                                                 std::to_string(kNodeHeaderBytes) + "-byte header"));
  if (bytes[0] != 'R' || bytes[1] != 'N')
    return std::unexpected(fail(NodeDecodeError::kNotRhot, "not a rhot node message (no 'RN' header)"));
  if (bytes[2] != kNodeProtocolVersion)
    return std::unexpected(fail(NodeDecodeError::kVersion, "protocol version " + std::to_string(bytes[2]) + ", this master speaks " +
                                                               std::to_string(kNodeProtocolVersion)));
  const std::span<const std::uint8_t> body = bytes.subspan(kNodeHeaderBytes);
  switch (static_cast<NodeMessageType>(bytes[3])) {
    case NodeMessageType::kFrame:
      return read_frame(body);
    case NodeMessageType::kTimeRequest: {
      if (auto s = exact_size("time request", body.size(), kTimeRequestBytes); !s) return std::unexpected(s.error());
      Reader r(body);
      TimeRequest m;
      m.sequence = r.get<std::uint32_t>();
      m.master_send_ns = r.get<std::int64_t>();
      return m;
    }
    case NodeMessageType::kTimeReply: {
      if (auto s = exact_size("time reply", body.size(), kTimeReplyBytes); !s) return std::unexpected(s.error());
      Reader r(body);
      TimeReply m;
      m.sequence = r.get<std::uint32_t>();
      m.master_send_ns = r.get<std::int64_t>();
      m.node_ns = r.get<std::int64_t>();
      return m;
    }
    case NodeMessageType::kStatusRequest: {
      if (auto s = exact_size("status request", body.size(), kStatusRequestBytes); !s) return std::unexpected(s.error());
      Reader r(body);
      return StatusRequest{r.get<std::uint32_t>()};
    }
    case NodeMessageType::kStatusReply: {
      if (auto s = exact_size("status reply", body.size(), kStatusReplyBytes); !s) return std::unexpected(s.error());
      Reader r(body);
      StatusReply m;
      m.sequence = r.get<std::uint32_t>();
      m.node = r.get<std::uint16_t>();
      m.cameras = r.get<std::uint16_t>();
      m.frame_rate_hz = r.get<float>();
      m.detect_mean_ms = r.get<float>();
      m.frames_published = r.get<std::uint64_t>();
      m.frames_dropped = r.get<std::uint64_t>();
      if (!std::isfinite(m.frame_rate_hz) || !std::isfinite(m.detect_mean_ms) || m.frame_rate_hz < 0.0f || m.detect_mean_ms < 0.0f)
        return std::unexpected(fail(NodeDecodeError::kBadValue, "status reply: frame rate and detection time must be finite and >= 0"));
      return m;
    }
  }
  return std::unexpected(fail(NodeDecodeError::kUnknownType, "unknown message type " + std::to_string(bytes[3])));
}

}  // namespace rhot
