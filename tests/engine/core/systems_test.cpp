#include "engine/core/Systems.h"

#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "engine/core/World.h"

namespace rhot {
namespace {

SystemDesc recorder(std::string name, std::vector<std::string>* log, std::vector<std::string> after = {},
                    std::vector<std::string> before = {}) {
  return SystemDesc{name, std::move(after), std::move(before), [log, name](World&, const FrameContext&) { log->push_back(name); }};
}

TEST(Systems, RunInDeclaredOrder) {
  std::vector<std::string> log;
  Systems s;
  s.add(recorder("render", &log, {"physics"}));
  s.add(recorder("physics", &log, {"tracking"}));
  s.add(recorder("tracking", &log));
  s.add(recorder("grasp", &log, {"tracking"}, {"physics"}));
  ASSERT_TRUE(s.build().has_value());
  EXPECT_EQ(s.names(), (std::vector<std::string>{"tracking", "grasp", "physics", "render"}));

  World w;
  std::vector<double> ms(s.size());
  s.run(w, FrameContext{}, ms);
  EXPECT_EQ(log, s.names());
}

TEST(Systems, UnconstrainedSystemsKeepInsertionOrder) {
  std::vector<std::string> log;
  Systems s;
  for (const char* n : {"c", "a", "b"}) s.add(recorder(n, &log));
  ASSERT_TRUE(s.build().has_value());
  EXPECT_EQ(s.names(), (std::vector<std::string>{"c", "a", "b"}));
}

TEST(Systems, CycleIsReportedWithItsMembers) {
  std::vector<std::string> log;
  Systems s;
  s.add(recorder("first", &log));
  s.add(recorder("a", &log, {"b"}));
  s.add(recorder("b", &log, {"a"}));
  const auto r = s.build();
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error(), "dependency cycle among systems 'a', 'b'");
}

TEST(Systems, UnknownDependencyIsReported) {
  std::vector<std::string> log;
  Systems s;
  s.add(recorder("render", &log, {}, {"present"}));
  const auto r = s.build();
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error(), "system 'render' must run before unknown system 'present'");
}

TEST(Systems, EachSystemIsTimed) {
  Systems s;
  s.add({"quick", {}, {}, [](World&, const FrameContext&) {}});
  s.add({"slow", {"quick"}, {}, [](World&, const FrameContext&) { std::this_thread::sleep_for(std::chrono::milliseconds(20)); }});
  ASSERT_TRUE(s.build().has_value());
  World w;
  std::vector<double> ms(2, -1.0);
  s.run(w, FrameContext{}, ms);
  EXPECT_GE(ms[0], 0.0);
  EXPECT_LT(ms[0], 20.0);
  EXPECT_GE(ms[1], 20.0) << "sleep_for(20 ms) returns no earlier than 20 ms";
}

TEST(SystemsDeathTest, DuplicateNameIsAPreconditionFailure) {
  std::vector<std::string> log;
  Systems s;
  s.add(recorder("x", &log));
  EXPECT_DEATH(s.add(recorder("x", &log)), "a system named 'x' already exists");
}

TEST(SystemsDeathTest, RunBeforeBuildIsAPreconditionFailure) {
  std::vector<std::string> log;
  Systems s;
  s.add(recorder("x", &log));
  World w;
  std::vector<double> ms(1);
  EXPECT_DEATH(s.run(w, FrameContext{}, ms), "call build\\(\\) after adding systems");
}

}  // namespace
}  // namespace rhot
