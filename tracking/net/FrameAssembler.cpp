#include "tracking/net/FrameAssembler.h"

#include <algorithm>

namespace rhot {

int AssembledFrame::cameras_present() const {
  return static_cast<int>(std::count_if(cameras.begin(), cameras.end(), [](const auto& c) { return c.has_value(); }));
}

FrameAssembler::FrameAssembler(int cameras, AssemblySettings settings)
    : cameras_(std::max(cameras, 0)),
      settings_(settings),
      recent_(static_cast<std::size_t>(cameras_)),
      last_capture_ns_(static_cast<std::size_t>(cameras_)) {}

bool FrameAssembler::add(CameraMessage m) {
  ++counts_.messages;
  if (m.camera < 0 || m.camera >= cameras_) return false;
  const auto c = static_cast<std::size_t>(m.camera);
  std::deque<std::uint64_t>& recent = recent_[c];
  if (!recent.empty()) {
    const std::uint64_t last = recent.back();
    if (m.counter <= last) {
      if (std::find(recent.begin(), recent.end(), m.counter) != recent.end() &&
          m.capture_ns <= *last_capture_ns_[c] + settings_.tolerance_ns) {
        ++counts_.duplicates;
        return false;
      }
      if (m.capture_ns <= *last_capture_ns_[c] + settings_.tolerance_ns) {
        ++counts_.out_of_order;
        return false;
      }
      // A lower counter with a newer capture time: the camera's node started again.
      ++counts_.restarts;
      recent.clear();
    }
  }
  if (closed_until_ns_ && m.capture_ns <= *closed_until_ns_) {
    ++counts_.late;
    recent.push_back(m.counter);  // seen, so a second copy counts as a duplicate
    if (recent.size() > kRecentCounters) recent.pop_front();
    last_capture_ns_[c] = std::max(last_capture_ns_[c].value_or(m.capture_ns), m.capture_ns);
    return false;
  }
  recent.push_back(m.counter);
  if (recent.size() > kRecentCounters) recent.pop_front();
  last_capture_ns_[c] = std::max(last_capture_ns_[c].value_or(m.capture_ns), m.capture_ns);
  const auto at = std::upper_bound(pending_.begin(), pending_.end(), m.capture_ns,
                                   [](std::int64_t t, const CameraMessage& p) { return t < p.capture_ns; });
  pending_.insert(at, std::move(m));
  return true;
}

std::vector<AssembledFrame> FrameAssembler::close(std::int64_t now_ns, const std::vector<bool>& waited_for) {
  std::vector<AssembledFrame> out;
  const auto waited = [&](std::size_t c) { return c < waited_for.size() ? static_cast<bool>(waited_for[c]) : true; };
  while (!pending_.empty()) {
    const std::int64_t t0 = pending_.front().capture_ns;
    const std::int64_t window_end = t0 + settings_.tolerance_ns;
    std::vector<int> member(static_cast<std::size_t>(cameras_), -1);  // per camera: index into pending_
    std::vector<bool> past(static_cast<std::size_t>(cameras_), false);
    for (std::size_t i = 0; i < pending_.size(); ++i) {
      const auto c = static_cast<std::size_t>(pending_[i].camera);
      if (pending_[i].capture_ns <= window_end) {
        if (member[c] < 0) member[c] = static_cast<int>(i);
      } else {
        past[c] = true;
      }
    }
    bool complete = true;
    for (std::size_t c = 0; c < member.size(); ++c)
      if (waited(c) && member[c] < 0 && !past[c]) complete = false;
    const bool deadline = now_ns >= t0 + settings_.deadline_ns;
    if (!complete && !deadline) break;
    AssembledFrame f;
    f.capture_ns = t0;
    f.closed_ns = now_ns;
    f.cameras.resize(static_cast<std::size_t>(cameras_));
    bool all = true;
    for (std::size_t c = 0; c < member.size(); ++c) {
      if (member[c] >= 0)
        f.cameras[c] = std::move(pending_[static_cast<std::size_t>(member[c])]);
      else if (waited(c))
        all = false;
    }
    // Remove the members (their slots were moved from), newest index first.
    std::vector<int> taken;
    for (const int i : member)
      if (i >= 0) taken.push_back(i);
    std::sort(taken.rbegin(), taken.rend());
    for (const int i : taken) pending_.erase(pending_.begin() + i);
    closed_until_ns_ = window_end;
    // Messages left inside the closed window (a camera's second one) can no longer join a group.
    while (!pending_.empty() && pending_.front().capture_ns <= window_end) {
      ++counts_.late;
      pending_.pop_front();
    }
    ++counts_.frames;
    counts_.complete_frames += all ? 1 : 0;
    counts_.deadline_frames += complete ? 0 : 1;
    out.push_back(std::move(f));
  }
  return out;
}

std::optional<std::int64_t> FrameAssembler::next_deadline() const {
  if (pending_.empty()) return std::nullopt;
  return pending_.front().capture_ns + settings_.deadline_ns;
}

void FrameAssembler::restart_camera(int camera) {
  if (camera < 0 || camera >= cameras_) return;
  recent_[static_cast<std::size_t>(camera)].clear();
  last_capture_ns_[static_cast<std::size_t>(camera)].reset();
}

}  // namespace rhot
