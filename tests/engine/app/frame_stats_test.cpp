#include "engine/app/FrameStats.h"

#include <nlohmann/json.hpp>
#include <gtest/gtest.h>

namespace rhot {
namespace {

TEST(Percentile, NearestRank) {
  std::vector<double> v;
  for (int i = 1; i <= 100; ++i) v.push_back(static_cast<double>(101 - i));  // 100 .. 1, unsorted
  EXPECT_EQ(percentile(v, 0.50), 50.0);
  EXPECT_EQ(percentile(v, 0.99), 99.0);
  EXPECT_EQ(percentile(v, 1.00), 100.0);
  EXPECT_EQ(percentile(v, 0.0), 1.0);
  EXPECT_EQ(percentile({7.0}, 0.99), 7.0);
  EXPECT_EQ(percentile({}, 0.5), 0.0);
  EXPECT_EQ(percentile({1, 2, 3, 4}, 0.5), 2.0);
}

TEST(FrameStats, SummariesAndBudgetMisses) {
  FrameStats s({"tracking", "render"}, 10.0);
  // 1000 frames: frame i takes i/100 ms for tracking and 5 ms for render, so the frame takes
  // 5 + i/100 ms; frames with i > 500 exceed the 10 ms budget.
  for (int i = 1; i <= 1000; ++i) {
    const double t = i / 100.0;
    s.record(5.0 + t, {t, 5.0});
  }
  EXPECT_EQ(s.frames(), 1000u);
  EXPECT_EQ(s.frames_over_budget(), 500u);
  const TimingSummary whole = s.frame_summary();
  EXPECT_DOUBLE_EQ(whole.p50_ms, 10.0);
  EXPECT_DOUBLE_EQ(whole.p99_ms, 14.9);
  EXPECT_DOUBLE_EQ(whole.max_ms, 15.0);
  EXPECT_NEAR(whole.mean_ms, 10.005, 1e-9);
  EXPECT_DOUBLE_EQ(s.stage_summary(0).p99_ms, 9.9);
  EXPECT_DOUBLE_EQ(s.stage_summary(1).p50_ms, 5.0);

  const nlohmann::json j = s.to_json();
  EXPECT_EQ(j["frames"], 1000);
  EXPECT_DOUBLE_EQ(j["budget_miss_fraction"].get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(j["p99_ms"].get<double>(), 14.9);
  EXPECT_DOUBLE_EQ(j["stages"]["tracking"]["p50_ms"].get<double>(), 5.0);
  EXPECT_DOUBLE_EQ(j["stages"]["render"]["max_ms"].get<double>(), 5.0);
}

TEST(FrameStats, PercentilesCoverTheWindowAndMaxTheWholeRun) {
  FrameStats s({}, 11.1, 10);
  s.record(50.0, {});  // one slow frame, then it leaves the window
  for (int i = 0; i < 10; ++i) s.record(1.0, {});
  EXPECT_DOUBLE_EQ(s.frame_summary().p99_ms, 1.0);
  EXPECT_DOUBLE_EQ(s.frame_summary().max_ms, 50.0);
  EXPECT_EQ(s.frames_over_budget(), 1u);
  EXPECT_EQ(s.to_json()["window_frames"], 10);
}

TEST(FrameStats, RecentFramesOldestFirstAndLastStageTimes) {
  FrameStats s({"a", "b"}, 11.1, 4);
  EXPECT_TRUE(s.recent_frame_ms(10).empty());
  EXPECT_EQ(s.last_stage_ms(1), 0.0);
  for (int i = 1; i <= 6; ++i) s.record(i, {0.5 * i, 0.25 * i});
  EXPECT_EQ(s.recent_frame_ms(2), (std::vector<double>{5.0, 6.0}));
  EXPECT_EQ(s.recent_frame_ms(100), (std::vector<double>{3.0, 4.0, 5.0, 6.0}));  // the window holds 4
  EXPECT_EQ(s.last_stage_ms(0), 3.0);
  EXPECT_EQ(s.last_stage_ms(1), 1.5);
}

TEST(FrameStatsDeathTest, RejectsNonFiniteTimes) {
  FrameStats s({"a"}, 11.1);
  EXPECT_DEATH(s.record(1.0, {std::numeric_limits<double>::quiet_NaN()}), "times must be finite and >= 0");
  EXPECT_DEATH(s.record(1.0, {}), "one time per stage");
}

}  // namespace
}  // namespace rhot
