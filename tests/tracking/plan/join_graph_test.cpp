#include "tracking/plan/JoinGraph.h"

#include <cmath>
#include <limits>
#include <string>

#include <gtest/gtest.h>

namespace rhot {
namespace {

// Seed 000's grids of vision systems: nx along X by ny along Y, numbered row by row from 1, each
// joined to its neighbours along X (8.5 mm) and Y (9.5 mm), each with 1 mm of its own.
void seed_grid(int nx, int ny, std::vector<CameraGroup>& groups, std::vector<GroupJoin>& joins) {
  const auto name = [&](int x, int y) { return std::to_string(y * nx + x + 1); };
  for (int y = 0; y < ny; ++y) {
    for (int x = 0; x < nx; ++x) {
      groups.push_back({name(x, y), 1.0});
      if (x + 1 < nx) joins.push_back({name(x, y), name(x + 1, y), 8.5});
      if (y + 1 < ny) joins.push_back({name(x, y), name(x, y + 1), 9.5});
    }
  }
}

TEST(JoinGraph, TheSeedsFourSystemsCarryAtMostNineteenMillimetres) {
  std::vector<CameraGroup> groups;
  std::vector<GroupJoin> joins;
  seed_grid(2, 2, groups, joins);
  const auto e = propagate_join_errors(groups, joins, "1");
  ASSERT_TRUE(e.has_value()) << e.error();
  EXPECT_DOUBLE_EQ((*e)[0].error_mm, 1.0);
  EXPECT_DOUBLE_EQ((*e)[1].error_mm, 9.5);
  EXPECT_DOUBLE_EQ((*e)[2].error_mm, 10.5);
  EXPECT_DOUBLE_EQ((*e)[3].error_mm, 19.0);  // the seed: "maximum system measurement error = 20 mm"
  EXPECT_EQ((*e)[3].chain.size(), 3u);
}

TEST(JoinGraph, TheFarthestOfTwentyFourSystemsIsReachedByTheCheapestChain) {
  std::vector<CameraGroup> groups;
  std::vector<GroupJoin> joins;
  seed_grid(4, 6, groups, joins);
  // A measured join cheaper than the grid's: 2 -> 6 at 1 mm makes every chain through it cheaper.
  joins.push_back({"2", "6", 1.0});
  const auto e = propagate_join_errors(groups, joins, "1");
  ASSERT_TRUE(e.has_value()) << e.error();
  const GroupError& far = e->back();
  EXPECT_EQ(far.group, "24");
  // 1 -> 2 (8.5), 2 -> 6 (1), then 2 steps along X and 4 along Y: 8.5 + 1 + 17 + 38 + 1 own.
  EXPECT_DOUBLE_EQ(far.error_mm, 65.5);
  ASSERT_GE(far.chain.size(), 3u);
  EXPECT_EQ(far.chain[0], "1");
  EXPECT_EQ(far.chain[1], "2");
  EXPECT_EQ(far.chain[2], "6");
  EXPECT_EQ(far.chain.back(), "24");
}

TEST(JoinGraph, AGroupNoChainReachesHasNoBound) {
  const std::vector<CameraGroup> groups = {{"a", 0.5}, {"b", 0.5}, {"island", 0.5}};
  const std::vector<GroupJoin> joins = {{"a", "b", 3.0}};
  const auto e = propagate_join_errors(groups, joins, "a");
  ASSERT_TRUE(e.has_value());
  EXPECT_DOUBLE_EQ((*e)[1].error_mm, 3.5);
  EXPECT_TRUE(std::isinf((*e)[2].error_mm));
  EXPECT_TRUE((*e)[2].chain.empty());
}

TEST(JoinGraph, BadInputIsRefusedWithTheReason) {
  const std::vector<CameraGroup> groups = {{"a", 0.0}, {"b", 0.0}};
  EXPECT_EQ(propagate_join_errors(groups, std::vector<GroupJoin>{}, "c").error(), "reference: \"c\" is not a group");
  EXPECT_EQ(propagate_join_errors(groups, std::vector<GroupJoin>{{"a", "z", 1.0}}, "a").error(), "joins[0]: \"z\" is not a group");
  EXPECT_EQ(propagate_join_errors(groups, std::vector<GroupJoin>{{"a", "b", -1.0}}, "a").error(),
            "joins[0]: its error must be 0 or more and finite");
  EXPECT_EQ(propagate_join_errors(groups, std::vector<GroupJoin>{{"a", "b", std::numeric_limits<double>::quiet_NaN()}}, "a").error(),
            "joins[0]: its error must be 0 or more and finite");
  const std::vector<CameraGroup> twice = {{"a", 0.0}, {"a", 0.0}};
  EXPECT_EQ(propagate_join_errors(twice, std::vector<GroupJoin>{}, "a").error(), "groups: \"a\" is named twice");
}

}  // namespace
}  // namespace rhot
