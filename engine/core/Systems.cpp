#include "engine/core/Systems.h"

#include <algorithm>
#include <unordered_map>

#include "engine/core/World.h"
#include "base/Check.h"

namespace rhot {

void Systems::add(SystemDesc system) {
  RHOT_PRECONDITION(!system.name.empty(), "Systems::add: a system needs a name");
  RHOT_PRECONDITION(static_cast<bool>(system.run), "Systems::add: system '" + system.name + "' has no function");
  for (const SystemDesc& s : systems_) {
    RHOT_PRECONDITION(s.name != system.name, "Systems::add: a system named '" + system.name + "' already exists");
  }
  systems_.push_back(std::move(system));
  built_ = false;
}

std::expected<void, std::string> Systems::build() {
  const std::size_t n = systems_.size();
  std::unordered_map<std::string, std::size_t> index;
  for (std::size_t i = 0; i < n; ++i) index.emplace(systems_[i].name, i);

  // Edges first -> then, from both 'after' and 'before'.
  std::vector<std::vector<std::size_t>> successors(n);
  std::vector<std::size_t> indegree(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    auto link = [&](const std::string& other, bool other_first) -> std::expected<void, std::string> {
      const auto it = index.find(other);
      if (it == index.end()) {
        return std::unexpected("system '" + systems_[i].name + "' must run " + (other_first ? "after" : "before") + " unknown system '" +
                               other + "'");
      }
      const std::size_t first = other_first ? it->second : i;
      const std::size_t then = other_first ? i : it->second;
      successors[first].push_back(then);
      ++indegree[then];
      return {};
    };
    for (const std::string& a : systems_[i].after) {
      if (auto r = link(a, true); !r) return r;
    }
    for (const std::string& b : systems_[i].before) {
      if (auto r = link(b, false); !r) return r;
    }
  }

  // Kahn's algorithm, always taking the earliest-added ready system, so unconstrained systems
  // keep the order they were added in.
  std::vector<std::size_t> order;
  order.reserve(n);
  std::vector<bool> done(n, false);
  while (order.size() < n) {
    std::size_t next = n;
    for (std::size_t i = 0; i < n; ++i) {
      if (!done[i] && indegree[i] == 0) {
        next = i;
        break;
      }
    }
    if (next == n) {
      std::string cycle;
      for (std::size_t i = 0; i < n; ++i) {
        if (!done[i]) cycle += (cycle.empty() ? "'" : ", '") + systems_[i].name + "'";
      }
      return std::unexpected("dependency cycle among systems " + cycle);
    }
    done[next] = true;
    order.push_back(next);
    for (const std::size_t s : successors[next]) --indegree[s];
  }

  order_ = std::move(order);
  ordered_names_.clear();
  for (const std::size_t i : order_) ordered_names_.push_back(systems_[i].name);
  built_ = true;
  return {};
}

void Systems::run(World& world, const FrameContext& frame, std::span<double> durations_ms) {
  RHOT_PRECONDITION(built_, "Systems::run: call build() after adding systems");
  RHOT_PRECONDITION(durations_ms.size() == order_.size(), "Systems::run: one duration slot per system");
  using Clock = std::chrono::steady_clock;
  for (std::size_t k = 0; k < order_.size(); ++k) {
    const auto start = Clock::now();
    systems_[order_[k]].run(world, frame);
    durations_ms[k] = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  }
}

}  // namespace rhot
