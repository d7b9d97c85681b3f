#include "tools/eval/Chaos.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <string>
#include <thread>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <malloc.h>
#include <spdlog/spdlog.h>
#include <zmq.hpp>

// Built with AddressSanitizer (GCC says so with __SANITIZE_ADDRESS__, Clang with __has_feature).
#if defined(__SANITIZE_ADDRESS__)
#define RHOT_CHAOS_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define RHOT_CHAOS_ASAN 1
#endif
#endif
#ifdef RHOT_CHAOS_ASAN
#include <sanitizer/allocator_interface.h>
#endif

#include "tools/eval/Eval.h"
#include "tracking/net/CurveKeys.h"
#include "tracking/net/NodeProtocol.h"

namespace rhot::eval {

namespace {

int port_of(const std::string& endpoint) { return std::stoi(endpoint.substr(endpoint.rfind(':') + 1)); }

// Raw bytes to a TCP port, then the connection closed: what a port scanner or a broken client sends.
void send_raw(int port, const std::vector<std::uint8_t>& bytes) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return;
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0) (void)::send(fd, bytes.data(), bytes.size(), MSG_NOSIGNAL);
  ::close(fd);
}

// Whether a loopback TCP port can be bound now.
bool port_free(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return false;
  const int on = 1;
  ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &on, sizeof on);  // as ZeroMQ binds
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  const bool ok = ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
  ::close(fd);
  return ok;
}

}  // namespace

// The attacker's thread: junk at every node's ports all along and, while a node is down, an
// impostor bound at its endpoint.
struct Chaos::Attacker {
  std::vector<ChaosNode> nodes;
  bool secure = true;
  std::mt19937_64 rng;
  zmq::context_t context{1};
  std::atomic<int> target{-1};    // the node to impersonate (-1: none)
  std::atomic<int> bound{-1};     // the node whose endpoint the impostor holds now
  std::atomic<bool> busy{false};  // closing or binding: `bound` is about to change
  std::atomic<bool> stop{false};
  std::atomic<std::uint64_t> false_frames{0}, junk{0}, oversized{0};
  std::thread thread;

  Attacker(std::vector<ChaosNode> n, bool s, unsigned seed) : nodes(std::move(n)), secure(s), rng(seed * 7919u + 17u) {
    thread = std::thread([this] { run(); });
  }
  ~Attacker() {
    stop = true;
    thread.join();
  }

  std::vector<std::uint8_t> random_bytes(std::size_t n) {
    std::vector<std::uint8_t> out(n);
    for (auto& b : out) b = static_cast<std::uint8_t>(rng());
    return out;
  }

  // A frame of false markers for the node's first camera, well formed.
  std::vector<std::uint8_t> false_frame(int node, std::uint64_t counter) {
    NodeFrameMessage f;
    f.node = static_cast<std::uint16_t>(node);
    f.camera = static_cast<std::uint16_t>(nodes[static_cast<std::size_t>(node)].cameras.front());
    f.counter = counter;
    f.capture_ns = steady_now_ns();
    f.width = 1280;
    f.height = 720;
    std::uniform_real_distribution<double> x(10.0, 1270.0), y(10.0, 710.0);
    for (int i = 0; i < 20; ++i) {
      const double px = x(rng);
      const double py = y(rng);
      f.detections.push_back({Eigen::Vector2d(px, py), -1});
    }
    return encode(f);
  }

  void run() {
    std::optional<zmq::socket_t> pub, rep;
    std::optional<KeyRing> own;  // the impostor's key (not the node's; no ZAP handler: it would admit any master)
    if (secure) {
      auto pair = make_key_pair("impostor");
      if (pair) own = KeyRing{"", *pair, {}};
    }
    std::uint64_t counter = 0;
    std::int64_t next_junk = 0, next_oversized = 0;
    while (!stop) {
      const std::int64_t now = steady_now_ns();
      if (target != bound) {
        busy = true;
        pub.reset();
        rep.reset();
        bound = -1;
        const int t = target;
        if (t >= 0) {
          try {
            pub.emplace(context, zmq::socket_type::pub);
            rep.emplace(context, zmq::socket_type::rep);
            for (zmq::socket_t* s : {&*pub, &*rep}) {
              s->set(zmq::sockopt::linger, 0);
              if (own) {
                const int on = 1;
                zmq_setsockopt(s->handle(), ZMQ_CURVE_SERVER, &on, sizeof on);
                zmq_setsockopt(s->handle(), ZMQ_CURVE_SECRETKEY, own->own.secret_key->bytes.data(), 32);
              }
            }
            const std::string& e = nodes[static_cast<std::size_t>(t)].endpoint;
            pub->bind(e);
            rep->bind(control_endpoint_for(e));
            bound = t;
          } catch (const zmq::error_t&) {
            pub.reset();  // the port is not free yet: again at the next turn
            rep.reset();
            bound = -1;
          }
        }
        busy = false;
      }
      if (pub && bound >= 0) {
        // Frames of false markers, junk and, twice a second, one message over any limit.
        (void)pub->send(zmq::buffer(false_frame(bound, counter++)), zmq::send_flags::dontwait);
        (void)pub->send(zmq::buffer(random_bytes(1 + rng() % 64)), zmq::send_flags::dontwait);
        ++false_frames;
        if (now >= next_oversized) {
          (void)pub->send(zmq::buffer(random_bytes(kMaxNodeMessageBytes + 4096)), zmq::send_flags::dontwait);
          ++oversized;
          next_oversized = now + 500'000'000;
        }
        zmq::message_t request;
        while (rep->recv(request, zmq::recv_flags::dontwait)) {
          const auto d = decode(std::span(static_cast<const std::uint8_t*>(request.data()), request.size()));
          const TimeRequest q = d && std::holds_alternative<TimeRequest>(*d) ? std::get<TimeRequest>(*d) : TimeRequest{};
          (void)rep->send(zmq::buffer(encode(TimeReply{q.sequence, q.master_send_ns, steady_now_ns()})), zmq::send_flags::dontwait);
        }
      }
      if (now >= next_junk) {
        // Junk at every live node's ports: raw bytes at the handshake, and oversized.
        for (std::size_t n = 0; n < nodes.size(); ++n) {
          if (static_cast<int>(n) == bound) continue;
          const int port = port_of(nodes[n].endpoint);
          send_raw(port + static_cast<int>(rng() % 2), random_bytes(1 + rng() % 512));
          ++junk;
          if (rng() % 8 == 0) {
            send_raw(port + 1, random_bytes(kMaxNodeMessageBytes + 4096));
            ++oversized;
          }
        }
        next_junk = now + 100'000'000;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
};

#ifdef RHOT_CHAOS_ASAN
long heap_in_use_kb() { return static_cast<long>(__sanitizer_get_current_allocated_bytes() / 1024); }
#else
long heap_in_use_kb() { return static_cast<long>(mallinfo2().uordblks / 1024); }
#endif

long resident_kb() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::atol(line.c_str() + 6);
  return 0;
}

Chaos::Chaos(unsigned seed, double seconds, std::vector<ChaosNode> nodes, std::vector<ChildProcess>& children, std::filesystem::path log,
             NodeSource& source, bool secure)
    : rng_(seed),
      seconds_(seconds),
      nodes_(std::move(nodes)),
      children_(children),
      log_(std::move(log)),
      source_(source),
      secure_(secure),
      attacker_(std::make_unique<Attacker>(nodes_, secure, seed)) {}

Chaos::~Chaos() = default;

std::vector<std::string> Chaos::new_clock_argv(const ChaosNode& node) {
  std::vector<std::string> argv;
  for (std::size_t i = 0; i < node.argv.size(); ++i) {
    const std::string& a = node.argv[i];
    if (a == "--clock-offset-ms" || a == "--clock-drift-ppm" || a == "--delay-ms") {
      ++i;  // and its value
      continue;
    }
    argv.push_back(a);
  }
  std::uniform_real_distribution<double> offset(-50.0, 50.0), drift(-200.0, 200.0), delay(0.0, 3.0);
  argv.insert(argv.end(), {"--clock-offset-ms", std::to_string(offset(rng_)), "--clock-drift-ppm", std::to_string(drift(rng_)),
                           "--delay-ms", std::to_string(delay(rng_))});
  return argv;
}

void Chaos::kill_one(double t_s) {
  Down d;
  d.node = static_cast<int>(rng_() % nodes_.size());
  d.killed_s = t_s;
  d.restart_s = t_s + std::uniform_real_distribution<double>(0.3, 2.0)(rng_);
  children_[static_cast<std::size_t>(d.node)].kill();
  attacker_->target = d.node;  // an impostor takes its endpoint while it is down
  spdlog::info("chaos: node {} killed at {:.2f} s", d.node, t_s);
  downs_.push_back(d);
}

void Chaos::restart(Down& d, double t_s) {
  // The impostor gives the endpoint back first, and the ports are free (ZeroMQ closes its sockets
  // in the background) before the node binds them: within a second.
  attacker_->target = -1;
  const int port = port_of(nodes_[static_cast<std::size_t>(d.node)].endpoint);
  for (int i = 0; i < 100 && (attacker_->busy || attacker_->bound != -1 || !port_free(port) || !port_free(port + 1)); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  auto child = ChildProcess::spawn(new_clock_argv(nodes_[static_cast<std::size_t>(d.node)]), log_);
  if (child) children_[static_cast<std::size_t>(d.node)] = std::move(*child);
  d.restarted_s = t_s;
  spdlog::info("chaos: node {} started again at {:.2f} s", d.node, t_s);
}

void Chaos::step(double t_s) {
  for (Down& d : downs_) {
    if (!d.restarted_s && t_s >= d.restart_s) restart(d, t_s);
    // A node that could not start (its port still held) is started again, as an operator would.
    if (d.restarted_s && !d.rejoined_s && !children_[static_cast<std::size_t>(d.node)].running()) {
      spdlog::warn("chaos: node {} exited after its restart; starting it again", d.node);
      restart(d, *d.restarted_s);
    }
  }
  for (Down& d : downs_) {
    if (d.stall_s && t_s >= *d.stall_s) {
      d.stall_s.reset();
      stall(0.2, 0.3);
    }
  }
  if (t_s < next_event_s_ || t_s > seconds_ - 2.5) return;
  next_event_s_ = t_s + std::uniform_real_distribution<double>(1.0, 3.0)(rng_);
  const bool one_down = std::any_of(downs_.begin(), downs_.end(), [](const Down& d) { return !d.rejoined_s; });
  if (!one_down && rng_() % 5 < 3) {
    kill_one(t_s);
  } else {
    stall(0.05, 0.3);
  }
}

void Chaos::stall(double min_s, double max_s) {
  const double seconds = std::uniform_real_distribution<double>(min_s, max_s)(rng_);
  source_.stall_receiver(seconds);
  ++stalls_;
  stalled_s_ += seconds;
}

void Chaos::on_frame(const AssembledFrame& frame, double t_s) {
  for (Down& d : downs_) {
    if (!d.restarted_s || d.rejoined_s) continue;
    for (const int c : nodes_[static_cast<std::size_t>(d.node)].cameras)
      if (static_cast<std::size_t>(c) < frame.cameras.size() && frame.cameras[static_cast<std::size_t>(c)] && !d.rejoined_s) {
        d.rejoined_s = t_s;
        // Its clock was measured anew a moment ago: a stall 0.1-0.2 s from now falls while its fit
        // has two quarter seconds of samples or fewer.
        d.stall_s = t_s + std::uniform_real_distribution<double>(0.1, 0.2)(rng_);
      }
  }
}

bool Chaos::all_up(double t_s) const {
  return std::none_of(downs_.begin(), downs_.end(),
                      [&](const Down& d) { return t_s >= d.killed_s && (!d.rejoined_s || t_s <= *d.rejoined_s); });
}

void Chaos::report(nlohmann::json& j) const {
  std::vector<double> rejoin;
  int never = 0;
  for (const Down& d : downs_) {
    if (d.rejoined_s && d.restarted_s)
      rejoin.push_back(*d.rejoined_s - *d.restarted_s);
    else if (d.restarted_s)
      ++never;
  }
  j["kills"] = downs_.size();
  j["never_rejoined"] = never;
  j["rejoin_p50_s"] = percentile(rejoin, 0.5);
  j["rejoin_p99_s"] = percentile(rejoin, 0.99);
  j["stalls"] = stalls_;
  j["stalled_s"] = stalled_s_;
  j["impostor_frames_sent"] = attacker_->false_frames.load();
  j["junk_sent"] = attacker_->junk.load();
  j["oversized_sent"] = attacker_->oversized.load();
}

}  // namespace rhot::eval
