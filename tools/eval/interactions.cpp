// rhot-eval interactions: a scene's showcase script (engine/sim/DemoScript.h) run through the whole
// demo, tracked hands and physics, once per seed: per interaction its success fraction, time to
// success and the events it raised; overall the success fraction and presses no poke asked for.

#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <nlohmann/json.hpp>

#include "engine/scene/SceneLoader.h"
#include "engine/sim/Demo.h"

#include "tools/eval/Eval.h"

namespace rhot::eval {

namespace {

// What each interaction is about: its name and the entities whose events count toward it.
struct Watched {
  std::string name;
  std::set<std::string> entities;
};

std::vector<Watched> watched_interactions(const SceneDesc& scene) {
  std::vector<Watched> out;
  // Entities fixed to one of these (a door's handle) count with it.
  const auto with_fixed = [&](std::set<std::string> names) {
    for (const EntityDesc& e : scene.entities) {
      if (e.joint && e.joint->type == JointType::kFixed && names.contains(e.joint->connected_to)) names.insert(e.name);
    }
    return names;
  };
  for (const RuleDesc& r : scene.rules) {
    for (const RuleAction& a : r.actions) {
      if (a.action != "succeed") continue;
      std::set<std::string> names;
      if (!r.when.entity.empty()) names.insert(r.when.entity);
      if (!r.when.object.empty()) names.insert(r.when.object);
      out.push_back({a.name, with_fixed(names)});
    }
  }
  for (const InteractionDesc& i : scene.interactions) out.push_back({i.name, with_fixed({i.object, i.zone})});
  return out;
}

bool counted(InteractionEventType type) {
  return type != InteractionEventType::kHoverBegin && type != InteractionEventType::kHoverEnd &&
         type != InteractionEventType::kContactBegin && type != InteractionEventType::kContactEnd;
}

}  // namespace

int interactions(const InteractionsArgs& args) {
  spdlog::set_default_logger(spdlog::stderr_color_mt("rhot-eval"));
  spdlog::set_level(spdlog::level::warn);
  const auto world = world_settings(args.world);
  if (!world) {
    std::cerr << "rhot-eval: " << world.error() << "\n";
    return 1;
  }
  const auto scene = load_scene_file(args.scene_file);
  if (!scene) {
    std::cerr << "rhot-eval: " << scene.error().to_string() << "\n";
    return 1;
  }
  if (!DemoScript::wants_showcase(*scene)) {
    std::cerr << "rhot-eval: " << args.scene_file
              << ": nothing for the showcase script to exercise (no value_above, press or snap rules; docs/scene-format.md)\n";
    return 1;
  }
  const std::vector<Watched> watched = watched_interactions(*scene);
  DemoSettings settings;
  settings.asset_dir = RHOT_ASSET_DIR;
  settings.world = *world;
  settings.sigma_px = world->sigma_px;
  settings.perfect_hands = args.hands == "perfect";

  std::map<std::string, std::vector<double>> times;          // per interaction: time to success, per seed that succeeded
  std::map<std::string, std::map<std::string, int>> events;  // per interaction: events by type, over all seeds
  int false_presses = 0;
  nlohmann::json runs = nlohmann::json::array();
  double duration_s = 0.0;
  for (int k = 0; k < args.seeds; ++k) {
    settings.seed = args.seed + static_cast<unsigned>(k);
    auto created = Demo::create(*scene, nullptr, settings);
    if (!created) {
      std::cerr << "rhot-eval: " << created.error() << "\n";
      return 1;
    }
    Demo& demo = **created;
    const DemoScript& script = demo.script();
    duration_s = script.duration_s();
    const double rate_hz = scene->settings.headset.refresh_hz;
    const int frames = static_cast<int>(std::ceil(duration_s * rate_hz));
    std::map<std::string, double> succeeded;
    int run_false = 0;
    nlohmann::json fired = nlohmann::json::array();
    for (int f = 0; f < frames; ++f) {
      const double t = f / rate_hz;
      demo.runtime().run_frame(t);
      for (const InteractionEvent& e : demo.runtime().physics().events()) {
        if (!counted(e.type)) continue;
        const Name* object = demo.world().find<Name>(e.object);
        const Name* subject = demo.world().find<Name>(e.subject);
        if (e.type == InteractionEventType::kSuccess && !succeeded.contains(e.interaction)) succeeded[e.interaction] = t;
        nlohmann::json ev = {{"t_s", t}, {"type", event_name(e.type)}};
        if (object) ev["object"] = object->value;
        if (subject) ev["subject"] = subject->value;
        if (e.hand) ev["hand"] = *e.hand == HandSide::kLeft ? "left" : "right";
        if (!e.interaction.empty()) ev["interaction"] = e.interaction;
        fired.push_back(ev);
        for (const Watched& w : watched) {
          if ((object && w.entities.contains(object->value)) || (subject && w.entities.contains(subject->value))) {
            ++events[w.name][event_name(e.type)];
          }
        }
        if (e.type == InteractionEventType::kPress) {
          // A press no poke of this button asked for (0.5 s of slack after the poke).
          const bool asked = std::any_of(script.tasks().begin(), script.tasks().end(), [&](const DemoScript::Task& task) {
            return task.kind == "poke" && subject && task.entity == subject->value && t >= task.begin_s && t <= task.end_s + 0.5;
          });
          run_false += asked ? 0 : 1;
        }
      }
    }
    false_presses += run_false;
    nlohmann::json run = {{"seed", settings.seed}, {"false_presses", run_false}, {"events", fired}};
    std::string summary;
    for (const Watched& w : watched) {
      const auto it = succeeded.find(w.name);
      run["succeeded"][w.name] = it != succeeded.end();
      if (it != succeeded.end()) times[w.name].push_back(it->second);
      summary += " " + w.name + (it != succeeded.end() ? " yes" : " NO");
    }
    runs.push_back(run);
    std::cerr << "rhot-eval: seed " << settings.seed << " (" << (k + 1) << " of " << args.seeds << "):" << summary << "\n";
  }

  nlohmann::json j;
  j["scene"] = args.scene_file;
  j["world"] = world_json(*world, args.world.world);
  j["hands"] = args.hands;
  j["seeds"] = args.seeds;
  j["first_seed"] = args.seed;
  j["script_s"] = duration_s;
  std::size_t total = 0;
  for (const Watched& w : watched) {
    std::vector<double>& ts = times[w.name];
    nlohmann::json one;
    one["success_fraction"] = static_cast<double>(ts.size()) / args.seeds;
    if (!ts.empty()) {
      one["time_to_success_s"] = {{"median", percentile(ts, 0.5)}, {"max", *std::max_element(ts.begin(), ts.end())}};
    }
    one["events"] = events[w.name];
    j["interactions"][w.name] = one;
    total += ts.size();
  }
  j["success_fraction"] =
      watched.empty() ? 0.0 : static_cast<double>(total) / static_cast<double>(watched.size() * static_cast<std::size_t>(args.seeds));
  j["false_press_count"] = false_presses;
  j["runs"] = runs;
  std::cout << j.dump(2) << "\n";
  return 0;
}

}  // namespace rhot::eval
