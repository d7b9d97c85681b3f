// The showcase script: a scene's rules and place interactions become scripted tasks, and the
// workbench run through the demo (its physics, rules and mechanisms) with the script's hands
// makes every interaction succeed, with no press the script did not ask for.

#include <algorithm>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "engine/core/World.h"
#include "engine/interact/HandPhysics.h"
#include "engine/scene/SceneLoader.h"
#include "engine/sim/Demo.h"
#include "engine/sim/DemoScript.h"

namespace rhot {
namespace {

SceneDesc workbench() {
  auto scene = load_scene_file(RHOT_ASSET_DIR "/scenes/workbench.json");
  EXPECT_TRUE(scene.has_value()) << (scene ? "" : scene.error().to_string());
  return scene.value_or(SceneDesc{});
}

TEST(Showcase, TheWorkbenchsRulesAndInteractionsBecomeOneTaskEach) {
  const DemoScript script(workbench());
  ASSERT_EQ(script.tasks().size(), 5u);
  std::vector<std::pair<std::string, std::string>> got;
  double last_end = 0.0;
  for (const DemoScript::Task& t : script.tasks()) {
    got.emplace_back(t.kind, t.entity);
    EXPECT_GE(t.begin_s, last_end - 1e-9) << "one task after another";
    EXPECT_GT(t.end_s, t.begin_s);
    last_end = t.end_s;
  }
  EXPECT_EQ(got, (std::vector<std::pair<std::string, std::string>>{
                     {"poke", "button"}, {"hinge", "door"}, {"slider", "drawer"}, {"socket", "socket-block"}, {"place", "bar"}}));
  EXPECT_DOUBLE_EQ(script.duration_s(), last_end + 1.0);
  // It plays once: after the end both hands rest where they ended.
  const SceneTruth end = script.at(script.duration_s());
  const SceneTruth later = script.at(script.duration_s() + 7.3);
  for (std::size_t h = 0; h < 2; ++h)
    EXPECT_LT((end.hands[h].world_from_hand.translation - later.hands[h].world_from_hand.translation).norm(), 1e-12);
}

TEST(Showcase, ASceneWithoutRulesToExerciseKeepsTheDemoScript) {
  auto scene = load_scene_file(RHOT_ASSET_DIR "/scenes/default.json");
  ASSERT_TRUE(scene.has_value());
  EXPECT_FALSE(DemoScript::wants_showcase(*scene));
  const DemoScript script(*scene);
  EXPECT_TRUE(script.tasks().empty());
  EXPECT_DOUBLE_EQ(script.duration_s(), 26.0);
}

TEST(Showcase, TheWorkbenchRunHeadlessWithTheScriptsHandsSucceedsAtEveryInteraction) {
  const SceneDesc scene = workbench();
  DemoSettings settings;
  settings.asset_dir = RHOT_ASSET_DIR;
  settings.perfect_hands = true;
  auto demo = Demo::create(scene, nullptr, settings);
  ASSERT_TRUE(demo.has_value()) << (demo ? "" : demo.error());
  Runtime& runtime = (*demo)->runtime();
  const DemoScript& script = (*demo)->script();
  const double rate = scene.settings.headset.refresh_hz;
  std::map<std::string, double> successes;
  std::vector<double> presses;
  bool bar_in_both_hands = false;
  double door_max = 0.0, drawer_max = 0.0;
  const Entity bar = find_named(runtime.world(), "bar");
  for (int f = 0; f < static_cast<int>(script.duration_s() * rate); ++f) {
    const double t = f / rate;
    runtime.run_frame(t);
    for (const InteractionEvent& e : runtime.physics().events()) {
      if (e.type == InteractionEventType::kSuccess) successes.emplace(e.interaction, t);
      if (e.type == InteractionEventType::kPress) presses.push_back(t);
    }
    bar_in_both_hands = bar_in_both_hands || runtime.physics().grasp().held_by_both(bar);
    door_max = std::max(door_max, runtime.physics().mechanisms().value(find_named(runtime.world(), "door")).value_or(0.0));
    drawer_max = std::max(drawer_max, runtime.physics().mechanisms().value(find_named(runtime.world(), "drawer")).value_or(0.0));
  }
  std::vector<std::string> names;
  for (const auto& [name, t] : successes) names.push_back(name);
  EXPECT_EQ(names, (std::vector<std::string>{"bar-to-rack", "door-open", "drawer-open", "lamp-on", "peg-in"}));
  // Each success inside its task.
  const auto within = [&](const std::string& name, const std::string& entity) {
    const auto task =
        std::find_if(script.tasks().begin(), script.tasks().end(), [&](const DemoScript::Task& k) { return k.entity == entity; });
    ASSERT_NE(task, script.tasks().end());
    ASSERT_TRUE(successes.contains(name)) << name;
    EXPECT_GE(successes[name], task->begin_s) << name;
    EXPECT_LE(successes[name], task->end_s + 0.5) << name;
  };
  within("lamp-on", "button");
  within("door-open", "door");
  within("drawer-open", "drawer");
  within("peg-in", "socket-block");
  within("bar-to-rack", "bar");
  ASSERT_EQ(presses.size(), 1u) << "one press, by the poke";
  EXPECT_TRUE(bar_in_both_hands) << "the bar is carried in both hands";
  EXPECT_GT(door_max, 60.0);
  EXPECT_LE(door_max, 110.5) << "within the hinge's limit";
  EXPECT_GT(drawer_max, 0.12);
  EXPECT_LE(drawer_max, 0.2 + 1e-3) << "within the slider's limit";
}

}  // namespace
}  // namespace rhot
