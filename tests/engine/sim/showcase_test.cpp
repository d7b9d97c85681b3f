// The showcase script: a scene's rules and place interactions become scripted tasks, and the
// workbench run through the demo (its physics, rules and mechanisms) with the script's hands
// makes every interaction succeed, with no press the script did not ask for.

#include <algorithm>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "engine/core/Transform.h"
#include "engine/core/World.h"
#include "engine/interact/HandPhysics.h"
#include "engine/math/EigenGlm.h"
#include "engine/scene/SceneLoader.h"
#include "engine/sim/Demo.h"
#include "engine/sim/DemoScript.h"

namespace rhot {
namespace {

SceneDesc showcase_scene(const std::string& name) {
  auto scene = load_scene_file(RHOT_ASSET_DIR "/scenes/" + name);
  EXPECT_TRUE(scene.has_value()) << (scene ? "" : scene.error().to_string());
  return scene.value_or(SceneDesc{});
}
SceneDesc workbench() { return showcase_scene("workbench.json"); }

// The script's tasks as (kind, entity), checked to follow one another.
std::vector<std::pair<std::string, std::string>> task_list(const DemoScript& script) {
  std::vector<std::pair<std::string, std::string>> got;
  double last_end = 0.0;
  for (const DemoScript::Task& t : script.tasks()) {
    got.emplace_back(t.kind, t.entity);
    EXPECT_GE(t.begin_s, last_end - 1e-9) << "one task after another";
    EXPECT_GT(t.end_s, t.begin_s);
    last_end = t.end_s;
  }
  EXPECT_DOUBLE_EQ(script.duration_s(), last_end + 1.0);
  return got;
}

// The showcase run headless with the script's own hands: when each interaction first succeeded,
// and each press.
struct ShowcaseEvents {
  std::map<std::string, double> successes;
  std::vector<double> presses;
  std::vector<InteractionEvent> releases;
};

TEST(Showcase, TheWorkbenchsRulesAndInteractionsBecomeOneTaskEach) {
  const DemoScript script(workbench());
  EXPECT_EQ(task_list(script),
            (std::vector<std::pair<std::string, std::string>>{
                {"poke", "button"}, {"hinge", "door"}, {"slider", "drawer"}, {"socket", "socket-block"}, {"place", "bar"}}));
  // It plays once: after the end both hands rest where they ended.
  const SceneTruth end = script.at(script.duration_s());
  const SceneTruth later = script.at(script.duration_s() + 7.3);
  for (std::size_t h = 0; h < 2; ++h)
    EXPECT_LT((end.hands[h].world_from_hand.translation - later.hands[h].world_from_hand.translation).norm(), 1e-12);
}

// The second showcase, made only of scene data: a lever, a dial, a lid and a tool handed over.
TEST(Showcase, TheWorkshopsHingesAndHandOverBecomeOneTaskEach) {
  const DemoScript script(showcase_scene("workshop.json"));
  EXPECT_EQ(task_list(script), (std::vector<std::pair<std::string, std::string>>{
                                   {"hinge", "lever"}, {"hinge", "dial"}, {"hinge", "lid"}, {"hand_over", "tool"}}));
}

TEST(Showcase, ASceneWithoutRulesToExerciseKeepsTheDemoScript) {
  auto scene = load_scene_file(RHOT_ASSET_DIR "/scenes/default.json");
  ASSERT_TRUE(scene.has_value());
  EXPECT_FALSE(DemoScript::wants_showcase(*scene));
  const DemoScript script(*scene);
  EXPECT_TRUE(script.tasks().empty());
  EXPECT_DOUBLE_EQ(script.duration_s(), 26.0);
}

// Runs a scene's showcase headless with the script's own hands; `each_frame` sees the runtime
// after every frame.
ShowcaseEvents run_with_script_hands(const SceneDesc& scene, const std::function<void(Runtime&)>& each_frame) {
  ShowcaseEvents out;
  DemoSettings settings;
  settings.asset_dir = RHOT_ASSET_DIR;
  settings.perfect_hands = true;
  auto demo = Demo::create(scene, nullptr, settings);
  EXPECT_TRUE(demo.has_value()) << (demo ? "" : demo.error());
  if (!demo) return out;
  Runtime& runtime = (*demo)->runtime();
  const double rate = scene.settings.headset.refresh_hz;
  for (int f = 0; f < static_cast<int>((*demo)->script().duration_s() * rate); ++f) {
    const double t = f / rate;
    runtime.run_frame(t);
    for (const InteractionEvent& e : runtime.physics().events()) {
      if (e.type == InteractionEventType::kSuccess) out.successes.emplace(e.interaction, t);
      if (e.type == InteractionEventType::kPress) out.presses.push_back(t);
      if (e.type == InteractionEventType::kRelease) out.releases.push_back(e);
    }
    each_frame(runtime);
  }
  return out;
}

// Each interaction's first success inside its task (or within half a second after it).
void expect_within_tasks(const DemoScript& script, const std::map<std::string, double>& successes,
                         const std::vector<std::pair<std::string, std::string>>& interaction_and_entity) {
  std::vector<std::string> names, expected;
  for (const auto& [name, t] : successes) names.push_back(name);
  for (const auto& [name, entity] : interaction_and_entity) expected.push_back(name);
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(names, expected);
  for (const auto& [name, entity] : interaction_and_entity) {
    const auto task =
        std::find_if(script.tasks().begin(), script.tasks().end(), [&](const DemoScript::Task& k) { return k.entity == entity; });
    ASSERT_NE(task, script.tasks().end()) << entity;
    const auto it = successes.find(name);
    ASSERT_NE(it, successes.end()) << name;
    EXPECT_GE(it->second, task->begin_s) << name;
    EXPECT_LE(it->second, task->end_s + 0.5) << name;
  }
}

TEST(Showcase, TheWorkbenchRunHeadlessWithTheScriptsHandsSucceedsAtEveryInteraction) {
  const SceneDesc scene = workbench();
  bool bar_in_both_hands = false;
  double door_max = 0.0, drawer_max = 0.0, button_max = 0.0;
  const ShowcaseEvents run = run_with_script_hands(scene, [&](Runtime& runtime) {
    button_max = std::max(button_max, runtime.physics().mechanisms().value(find_named(runtime.world(), "button")).value_or(0.0));
    bar_in_both_hands = bar_in_both_hands || runtime.physics().grasp().held_by_both(find_named(runtime.world(), "bar"));
    door_max = std::max(door_max, runtime.physics().mechanisms().value(find_named(runtime.world(), "door")).value_or(0.0));
    drawer_max = std::max(drawer_max, runtime.physics().mechanisms().value(find_named(runtime.world(), "drawer")).value_or(0.0));
  });
  expect_within_tasks(
      DemoScript(scene), run.successes,
      {{"lamp-on", "button"}, {"door-open", "door"}, {"drawer-open", "drawer"}, {"peg-in", "socket-block"}, {"bar-to-rack", "bar"}});
  ASSERT_EQ(run.presses.size(), 1u) << "one press, by the poke";
  // The poke goes to the button's stop (10 mm), well past where it counts (6 mm): a poke that
  // stopped at 7 mm left a fingertip tracked a millimetre high short of a press (lamp-on failed so
  // through tracked hands on seed 224).
  EXPECT_GT(button_max, 0.009);
  EXPECT_TRUE(bar_in_both_hands) << "the bar is carried in both hands";
  EXPECT_GT(door_max, 60.0);
  EXPECT_LE(door_max, 110.5) << "within the hinge's limit";
  EXPECT_GT(drawer_max, 0.12);
  EXPECT_LE(drawer_max, 0.2 + 1e-3) << "within the slider's limit";
}

// The second showcase: the lever pulled toward the user, the dial turned from above, the lid
// lifted by its handle, and the tool taken by the right hand, passed to the left and put down on
// the left of the table.
TEST(Showcase, TheWorkshopRunHeadlessWithTheScriptsHandsSucceedsAtEveryInteraction) {
  const SceneDesc scene = showcase_scene("workshop.json");
  std::map<std::string, double> most;
  bool tool_in_both_hands = false;
  Eigen::Vector3d tool_at = Eigen::Vector3d::Zero();
  const ShowcaseEvents run = run_with_script_hands(scene, [&](Runtime& runtime) {
    // While held (the hand leaving the lever afterwards may push it against its stop, which gives
    // a few degrees: Bullet's limits are soft against a hand's bones).
    for (const auto& [name, handle] : {std::pair{"lever", "lever-grip"}, {"dial", "dial"}, {"lid", "lid-handle"}}) {
      if (!runtime.physics().grasp().held_by(find_named(runtime.world(), handle))) continue;
      most[name] = std::max(most[name], runtime.physics().mechanisms().value(find_named(runtime.world(), name)).value_or(0.0));
    }
    const Entity tool = find_named(runtime.world(), "tool");
    tool_in_both_hands = tool_in_both_hands || runtime.physics().grasp().held_by_both(tool);
    tool_at = to_eigen(runtime.world().get<Transform>(tool).position);
  });
  const DemoScript script(scene);
  expect_within_tasks(script, run.successes,
                      {{"lever-pulled", "lever"}, {"dial-turned", "dial"}, {"lid-open", "lid"}, {"tool-handed-over", "tool"}});
  EXPECT_TRUE(run.presses.empty());
  EXPECT_GT(most["lever"], 40.0);
  EXPECT_LE(most["lever"], 75.5) << "within the hinge's limit";
  EXPECT_GT(most["dial"], 60.0);
  EXPECT_LE(most["dial"], 120.5);
  EXPECT_GT(most["lid"], 60.0);
  EXPECT_LE(most["lid"], 110.5);
  EXPECT_TRUE(tool_in_both_hands);
  // The right hand let go while the left held it (a hand-over), and the left put it down lying on
  // the table, on the left (the script mirrors its start, x 0.22 -> -0.22).
  ASSERT_EQ(run.releases.size(), 5u) << "lever, dial, lid, and the tool twice";
  EXPECT_TRUE(run.releases[3].handed_over);
  EXPECT_EQ(run.releases[3].hand, HandSide::kRight);
  EXPECT_FALSE(run.releases[4].handed_over);
  EXPECT_EQ(run.releases[4].hand, HandSide::kLeft);
  EXPECT_NEAR(tool_at.x(), -0.22, 0.05);
  EXPECT_NEAR(tool_at.y(), 0.7625, 0.005) << "lying on the table";
  EXPECT_NEAR(tool_at.z(), -0.28, 0.05);  // measured 4 cm nearer the user: the taker's grip, taken in the air
}

}  // namespace
}  // namespace rhot
