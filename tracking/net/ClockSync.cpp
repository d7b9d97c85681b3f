#include "tracking/net/ClockSync.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace rhot {

void ClockSync::add(std::int64_t master_send_ns, std::int64_t node_ns, std::int64_t master_recv_ns) {
  if (master_recv_ns < master_send_ns) return;
  samples_.push_back({master_send_ns + (master_recv_ns - master_send_ns) / 2, node_ns, master_recv_ns - master_send_ns});
  while (!samples_.empty() &&
         (samples_.size() > settings_.max_samples || samples_.back().master_ns - samples_.front().master_ns > settings_.window_ns))
    samples_.pop_front();
  refit();
}

double ClockSync::min_rtt_us() const {
  std::int64_t best = std::numeric_limits<std::int64_t>::max();
  for (const Sample& s : samples_) best = std::min(best, s.rtt_ns);
  return samples_.empty() ? 0.0 : static_cast<double>(best) / 1e3;
}

void ClockSync::refit() {
  if (samples_.empty()) {
    fit_.reset();
    return;
  }
  // The fastest round trips of each stretch of the window, not of the whole window: one lucky
  // sample far faster than the rest would otherwise leave it alone in the fit, and a fit of one
  // moment has no drift. A stretch whose fastest round trip is itself slow (everything held up)
  // is left out.
  const std::int64_t start_ns = samples_.front().master_ns;
  const auto stretch = [&](const Sample& s) { return (s.master_ns - start_ns) / std::max<std::int64_t>(1, settings_.stretch_ns); };
  std::vector<std::int64_t> fastest(static_cast<std::size_t>(stretch(samples_.back()) + 1), std::numeric_limits<std::int64_t>::max());
  for (const Sample& s : samples_) {
    std::int64_t& f = fastest[static_cast<std::size_t>(stretch(s))];
    f = std::min(f, s.rtt_ns);
  }
  std::vector<std::int64_t> present;
  for (const std::int64_t f : fastest)
    if (f != std::numeric_limits<std::int64_t>::max()) present.push_back(f);
  // The typical stretch is the lower median: of two stretches, the faster. A stalled master reads
  // one reply late (its round trip the stall's length, its midpoint the stall's middle, so its
  // offset off by half the stall); alone in its stretch beside one other, the upper median would
  // make it typical and pull the fit milliseconds off, frames an exposure off in time.
  const auto middle = present.begin() + static_cast<std::ptrdiff_t>((present.size() - 1) / 2);
  std::nth_element(present.begin(), middle, present.end());
  const std::int64_t typical = *middle;
  std::vector<const Sample*> chosen;
  for (const Sample& s : samples_) {
    const std::int64_t f = fastest[static_cast<std::size_t>(stretch(s))];
    if (f <= typical + settings_.rtt_margin_ns && s.rtt_ns <= f + settings_.rtt_margin_ns) chosen.push_back(&s);
  }
  Fit fit;
  fit.master_ref_ns = samples_.back().master_ns;
  // Least squares of (node - master) against master time, relative to the reference; the drift
  // only once the chosen samples span a second (before that it would be noise).
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (const Sample* s : chosen) {
    const double x = static_cast<double>(s->master_ns - fit.master_ref_ns);
    const double y = static_cast<double>(s->node_ns - s->master_ns);
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
  }
  const double n = static_cast<double>(chosen.size());
  const double span_ns = static_cast<double>(chosen.back()->master_ns - chosen.front()->master_ns);
  const double var = sxx - sx * sx / n;
  fit.drift = chosen.size() >= 3 && span_ns >= 1e9 && var > 0.0 ? (sxy - sx * sy / n) / var : 0.0;
  fit.offset_ns = (sy - fit.drift * sx) / n;
  double sq = 0.0;
  for (const Sample* s : chosen) {
    const double x = static_cast<double>(s->master_ns - fit.master_ref_ns);
    const double e = static_cast<double>(s->node_ns - s->master_ns) - (fit.offset_ns + fit.drift * x);
    sq += e * e;
  }
  fit.residual_ns = std::sqrt(sq / n);
  fit.max_rtt_ns = 0;
  for (const Sample* s : chosen) fit.max_rtt_ns = std::max(fit.max_rtt_ns, s->rtt_ns);
  fit_ = fit;
}

double ClockSync::offset_ns_at(std::int64_t master_ns) const {
  if (!fit_) return 0.0;
  return fit_->offset_ns + fit_->drift * static_cast<double>(master_ns - fit_->master_ref_ns);
}

std::int64_t ClockSync::to_master(std::int64_t node_ns) const {
  // node = master + offset + drift * (master - ref)  =>  master = (node - offset + drift * ref) / (1 + drift)
  const double rel_node = static_cast<double>(node_ns - fit_->master_ref_ns);
  const double rel_master = (rel_node - fit_->offset_ns) / (1.0 + fit_->drift);
  return fit_->master_ref_ns + static_cast<std::int64_t>(std::llround(rel_master));
}

}  // namespace rhot
