#include "tracking/plan/JoinGraph.h"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <functional>
#include <limits>
#include <map>
#include <queue>

namespace rhot {

std::expected<std::vector<GroupError>, std::string> propagate_join_errors(std::span<const CameraGroup> groups,
                                                                          std::span<const GroupJoin> joins, const std::string& reference) {
  std::map<std::string, std::size_t> index;
  for (std::size_t g = 0; g < groups.size(); ++g) {
    if (!index.emplace(groups[g].name, g).second) return std::unexpected(fmt::format("groups: \"{}\" is named twice", groups[g].name));
    if (!(groups[g].own_error_mm >= 0.0) || !std::isfinite(groups[g].own_error_mm)) {
      return std::unexpected(fmt::format("groups: \"{}\": its error must be 0 or more and finite", groups[g].name));
    }
  }
  const auto root = index.find(reference);
  if (root == index.end()) return std::unexpected(fmt::format("reference: \"{}\" is not a group", reference));
  std::vector<std::vector<std::pair<std::size_t, double>>> next(groups.size());
  for (std::size_t j = 0; j < joins.size(); ++j) {
    const GroupJoin& join = joins[j];
    const auto a = index.find(join.a), b = index.find(join.b);
    if (a == index.end() || b == index.end()) {
      return std::unexpected(fmt::format("joins[{}]: \"{}\" is not a group", j, a == index.end() ? join.a : join.b));
    }
    if (!(join.error_mm >= 0.0) || !std::isfinite(join.error_mm)) {
      return std::unexpected(fmt::format("joins[{}]: its error must be 0 or more and finite", j));
    }
    next[a->second].emplace_back(b->second, join.error_mm);
    next[b->second].emplace_back(a->second, join.error_mm);
  }
  // Dijkstra from the reference.
  std::vector<double> cost(groups.size(), std::numeric_limits<double>::infinity());
  std::vector<std::size_t> via(groups.size(), groups.size());
  using Entry = std::pair<double, std::size_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> open;
  cost[root->second] = 0.0;
  open.emplace(0.0, root->second);
  while (!open.empty()) {
    const auto [c, g] = open.top();
    open.pop();
    if (c > cost[g]) continue;
    for (const auto& [h, w] : next[g]) {
      if (c + w < cost[h]) {
        cost[h] = c + w;
        via[h] = g;
        open.emplace(cost[h], h);
      }
    }
  }
  std::vector<GroupError> out;
  for (std::size_t g = 0; g < groups.size(); ++g) {
    GroupError e;
    e.group = groups[g].name;
    e.error_mm = groups[g].own_error_mm + cost[g];
    if (std::isfinite(cost[g])) {
      for (std::size_t at = g; at != groups.size(); at = via[at]) e.chain.push_back(groups[at].name);
      std::reverse(e.chain.begin(), e.chain.end());
    }
    out.push_back(std::move(e));
  }
  return out;
}

}  // namespace rhot
