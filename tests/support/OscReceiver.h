#pragma once

// liblo's own OSC server on a loopback port the kernel picks, collecting every message it is sent:
// the independent receiver of the streaming tests. Datagrams queue in its socket until read.
//
// liblo hands each argument as a `lo_arg*` into the message, where OSC aligns arguments to 4
// bytes; the union `lo_arg` holds 8-byte members, so reading a member through that pointer is a
// misaligned access (UBSan says so). The arguments are copied out byte by byte instead.

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <lo/lo.h>
#include <string>
#include <utility>
#include <vector>

namespace rhot::test {

struct OscReceived {
  std::string path;
  std::string types;
  std::vector<std::string> strings;
  std::vector<double> numbers;  // ints and floats, in order
};

class OscReceiver {
 public:
  OscReceiver() {
    server_ = lo_server_new_with_proto(nullptr, LO_UDP, nullptr);
    lo_server_add_method(server_, nullptr, nullptr, &OscReceiver::handle, this);
  }
  ~OscReceiver() { lo_server_free(server_); }
  OscReceiver(const OscReceiver&) = delete;
  OscReceiver& operator=(const OscReceiver&) = delete;

  int port() const { return lo_server_get_port(server_); }
  // Reads until `count` messages are in or `quiet_ms` pass without one.
  const std::vector<OscReceived>& receive(std::size_t count, int quiet_ms = 1000) {
    while (messages_.size() < count && lo_server_recv_noblock(server_, quiet_ms) > 0) {
    }
    return messages_;
  }
  // Reads everything queued, until `quiet_ms` pass without a message.
  const std::vector<OscReceived>& drain(int quiet_ms = 300) {
    while (lo_server_recv_noblock(server_, quiet_ms) > 0) {
    }
    return messages_;
  }

 private:
  static int handle(const char* path, const char* types, lo_arg** argv, int argc, lo_message, void* self) {
    OscReceived r{path, types, {}, {}};
    for (int i = 0; i < argc; ++i) {
      const auto* bytes = reinterpret_cast<const char*>(argv[i]);
      if (types[i] == 's') r.strings.emplace_back(bytes);
      if (types[i] == 'f') {
        float f = 0.0F;
        std::memcpy(&f, bytes, sizeof f);
        r.numbers.push_back(static_cast<double>(f));
      }
      if (types[i] == 'i') {
        std::int32_t n = 0;
        std::memcpy(&n, bytes, sizeof n);
        r.numbers.push_back(n);
      }
    }
    static_cast<OscReceiver*>(self)->messages_.push_back(std::move(r));
    return 0;
  }
  lo_server server_ = nullptr;
  std::vector<OscReceived> messages_;
};

}  // namespace rhot::test
