#pragma once
// The messages between camera nodes (rhot-node) and the master, version 1 (docs/camera-nodes.md).
//
// Every message is one ZeroMQ frame: a 4-byte header (the bytes 'R' 'N', the version, the type)
// and a body of fixed layout, little-endian, with no padding. A node publishes one kFrame per
// camera per exposure on its PUB socket and answers kTimeRequest and kStatusRequest on its REP
// socket. decode() takes bytes from the network: anything truncated, oversized, of another
// version, of an unknown type, or with a value that makes no sense (non-finite numbers, a pixel
// outside the image, a size that disagrees with the count) is refused with its reason, and
// nothing else is ever read from it.

#include <cstddef>
#include <cstdint>
#include <expected>
#include <span>
#include <string>
#include <variant>
#include <vector>

#include "tracking/core/Frames.h"

namespace rhot {

inline constexpr std::uint8_t kNodeProtocolVersion = 1;

// Whether the n-th occurrence of something on the network is told: the 1st, 10th, 100th ... (a
// flood of bad messages or refused peers is counted, not logged line by line).
inline bool worth_telling(std::uint64_t n) {
  while (n >= 10 && n % 10 == 0) n /= 10;
  return n == 1;
}
inline constexpr std::size_t kNodeHeaderBytes = 4;
// A frame's fixed part after the header, and each detection's bytes.
inline constexpr std::size_t kFrameFixedBytes = 30;
inline constexpr std::size_t kDetectionBytes = 12;
inline constexpr std::size_t kMaxDetectionsPerFrame = 4096;
// How far beyond the image's edge a detection's centre may lie (noise on a border blob).
inline constexpr float kDetectionMarginPx = 2.0f;
inline constexpr std::size_t kMaxNodeMessageBytes = kNodeHeaderBytes + kFrameFixedBytes + kMaxDetectionsPerFrame * kDetectionBytes;

enum class NodeMessageType : std::uint8_t {
  kFrame = 1,
  kTimeRequest = 2,
  kTimeReply = 3,
  kStatusRequest = 4,
  kStatusReply = 5,
};

// One camera's detections of one exposure. On the wire a detection's centre is two float32 pixel
// coordinates, its area a uint16 (pixels, saturated) and its peak intensity a uint16 (grey
// levels times 256).
struct NodeFrameMessage {
  std::uint16_t node = 0;
  std::uint16_t camera = 0;       // the node's own camera number
  std::uint64_t counter = 0;      // frames of this camera since the node started, from 0
  std::int64_t capture_ns = 0;    // mid-exposure on the node's clock
  std::uint32_t exposure_us = 0;  // 0: unknown
  std::uint16_t width = 0;        // image size in pixels
  std::uint16_t height = 0;
  std::vector<Detection> detections;  // pixel, area_px, intensity (no truth on the wire)
};

struct TimeRequest {
  std::uint32_t sequence = 0;
  std::int64_t master_send_ns = 0;  // the master's clock when it sent this (echoed back)
};

struct TimeReply {
  std::uint32_t sequence = 0;
  std::int64_t master_send_ns = 0;
  std::int64_t node_ns = 0;  // the node's clock when it answered
};

struct StatusRequest {
  std::uint32_t sequence = 0;
};

struct StatusReply {
  std::uint32_t sequence = 0;
  std::uint16_t node = 0;
  std::uint16_t cameras = 0;
  float frame_rate_hz = 0.0f;   // frames per camera per second, measured over the last second
  float detect_mean_ms = 0.0f;  // detection time per camera frame, mean over the last second
  std::uint64_t frames_published = 0;
  std::uint64_t frames_dropped = 0;  // exposures the node could not detect and send in time
};

using NodeMessage = std::variant<NodeFrameMessage, TimeRequest, TimeReply, StatusRequest, StatusReply>;

// Why a message was refused, by kind (for counting), with the message in words.
enum class NodeDecodeError : std::uint8_t { kTruncated, kOversized, kNotRhot, kVersion, kUnknownType, kBadValue };
inline constexpr std::size_t kNodeDecodeErrorKinds = 6;
const char* to_string(NodeDecodeError e);

struct NodeDecodeFailure {
  NodeDecodeError kind;
  std::string message;  // for example "frame: 3 detections need 70 bytes, got 64"
};

std::vector<std::uint8_t> encode(const NodeMessage& message);
[[nodiscard]] std::expected<NodeMessage, NodeDecodeFailure> decode(std::span<const std::uint8_t> bytes);

}  // namespace rhot
