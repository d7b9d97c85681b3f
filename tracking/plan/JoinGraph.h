#pragma once
// Rigs calibrated in parts and joined (seed 000, chapter 8: "vision systems" of a few cameras
// each, every one calibrated to its neighbours): the error a group's cameras carry with respect to
// the reference group. Each join between two groups has a measured error; a group's position is
// known through a chain of joins from the reference, and errors along a chain add up (the seed's
// model: about 8.5 mm a join along X, 9.5 mm along Y). The chain with the smallest sum is found by
// Dijkstra's algorithm over the join graph; a group's total adds its own error (its calibration's,
// about 1 mm in the seed).

#include <expected>
#include <span>
#include <string>
#include <vector>

namespace rhot {

struct CameraGroup {
  std::string name;
  double own_error_mm = 0.0;
};

struct GroupJoin {
  std::string a, b;  // group names; a join works both ways
  double error_mm = 0.0;
};

struct GroupError {
  std::string group;
  double error_mm = 0.0;           // own error + the chain's; infinite when no chain reaches it
  std::vector<std::string> chain;  // from the reference to this group; empty when unreachable
};

// Per group (in the order given): its error and chain. Errors name what is wrong: a reference or
// join naming no group, a group named twice, an error that is negative or not finite.
[[nodiscard]] std::expected<std::vector<GroupError>, std::string> propagate_join_errors(std::span<const CameraGroup> groups,
                                                                                        std::span<const GroupJoin> joins,
                                                                                        const std::string& reference);

}  // namespace rhot
