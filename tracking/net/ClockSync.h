#pragma once
// A node's clock against the master's, from request/reply round trips (the NTP idea, with drift).
//
// Each round trip gives the master's send and receive times and the node's time in between. The
// node's time is assumed to be at the midpoint, so a sample's error is at most half its round
// trip; a delayed sample (a busy scheduler, a queue) has a long round trip and is given no say.
// The fit is node_ns = offset + (1 + drift) * master_ns over the window's fastest samples (per
// quarter second, those within rtt_margin of that stretch's fastest, in stretches whose fastest is
// itself within rtt_margin of the typical stretch's), so a node whose crystal runs 100 ppm fast is
// followed over minutes, not just shifted. residual_us is the RMS of the chosen samples about
// the fit: what the estimate is worth.

#include <cstdint>
#include <deque>
#include <optional>

namespace rhot {

struct ClockSyncSettings {
  std::int64_t window_ns = 10'000'000'000;  // samples older than this are forgotten
  std::int64_t rtt_margin_ns = 50'000;      // samples this much slower than the fastest still count
  std::int64_t stretch_ns = 250'000'000;    // the fastest are chosen per stretch of this length
  std::size_t max_samples = 512;
};

class ClockSync {
 public:
  explicit ClockSync(ClockSyncSettings settings = {}) : settings_(settings) {}

  // One round trip: the master sent at master_send_ns, the node stamped node_ns, the reply came
  // back at master_recv_ns. A reply before its request (impossible) is ignored.
  void add(std::int64_t master_send_ns, std::int64_t node_ns, std::int64_t master_recv_ns);

  bool synchronised() const { return fit_.has_value(); }
  // The master's time of a node time. Precondition: synchronised().
  std::int64_t to_master(std::int64_t node_ns) const;
  // The node's clock ahead of the master's at master_ns (positive: the node is ahead).
  double offset_ns_at(std::int64_t master_ns) const;
  double drift_ppm() const { return fit_ ? fit_->drift * 1e6 : 0.0; }
  double residual_us() const { return fit_ ? fit_->residual_ns / 1e3 : 0.0; }
  double min_rtt_us() const;
  // The slowest round trip among the samples the fit uses (0 before any): each of them is off by at
  // most half its round trip, so the fit is off by at most half this.
  double fit_rtt_us() const { return fit_ ? static_cast<double>(fit_->max_rtt_ns) / 1e3 : 0.0; }
  std::size_t samples() const { return samples_.size(); }
  void reset() {
    samples_.clear();
    fit_.reset();
  }

 private:
  struct Sample {
    std::int64_t master_ns;  // the round trip's midpoint
    std::int64_t node_ns;
    std::int64_t rtt_ns;
  };
  struct Fit {
    std::int64_t master_ref_ns;  // times are taken relative to this for precision
    double offset_ns;            // node - master at master_ref_ns
    double drift;                // d(node - master) / d(master)
    double residual_ns;
    std::int64_t max_rtt_ns;  // the slowest round trip among the samples fitted
  };
  void refit();

  ClockSyncSettings settings_;
  std::deque<Sample> samples_;
  std::optional<Fit> fit_;
};

}  // namespace rhot
