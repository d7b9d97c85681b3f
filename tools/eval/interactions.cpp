// rhot-eval interactions: a scene's showcase script (engine/sim/DemoScript.h) run through the whole
// demo, tracked hands and physics, once per seed: per interaction its success fraction, time to
// success (and over the perfect hands' time), fingertip error while hidden and while seen, and
// the events it raised; overall the success fraction, presses no poke asked for, and the grasps
// against the perfect hands' of the same seed (missed, unintended releases and grasps).

#include <algorithm>
#include <cmath>
#include <expected>
#include <iostream>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <nlohmann/json.hpp>

#include "base/Jobs.h"
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

// Fingertip error against the truth, split by whether the tip was measured.
struct TipError {
  double hidden_sum_m = 0.0, seen_sum_m = 0.0;
  long hidden = 0, seen = 0;
  void add(double error_m, bool measured) {
    (measured ? seen_sum_m : hidden_sum_m) += error_m;
    (measured ? seen : hidden) += 1;
  }
  void add(const TipError& o) {
    hidden_sum_m += o.hidden_sum_m;
    seen_sum_m += o.seen_sum_m;
    hidden += o.hidden;
    seen += o.seen;
  }
  nlohmann::json json() const {
    nlohmann::json j;
    j["fingertip_error_hidden_mm"] = hidden > 0 ? 1000.0 * hidden_sum_m / static_cast<double>(hidden) : 0.0;
    j["fingertip_error_seen_mm"] = seen > 0 ? 1000.0 * seen_sum_m / static_cast<double>(seen) : 0.0;
    j["fingertip_hidden_fraction"] = hidden + seen > 0 ? static_cast<double>(hidden) / static_cast<double>(hidden + seen) : 0.0;
    return j;
  }
};

// One run of the showcase script through the demo.
struct ShowcaseRun {
  std::map<std::string, double> succeeded;  // per interaction: when it first succeeded
  std::vector<InteractionEvent> grasp_events;
  std::map<std::string, TipError> tips;  // per interaction whose task was under way
  int false_presses = 0;
  nlohmann::json fired = nlohmann::json::array();
  std::map<std::string, std::map<std::string, int>> events;  // per interaction: events by type
};

constexpr double kConfident = 0.95;  // a tip measured this frame (GraspSettings::confident)

std::expected<ShowcaseRun, std::string> run_showcase(const SceneDesc& scene, const DemoSettings& settings,
                                                     const std::vector<Watched>& watched, double& duration_s) {
  auto created = Demo::create(scene, nullptr, settings);
  if (!created) return std::unexpected(created.error());
  Demo& demo = **created;
  const DemoScript& script = demo.script();
  duration_s = script.duration_s();
  const double rate_hz = scene.settings.headset.refresh_hz;
  const int frames = static_cast<int>(std::ceil(duration_s * rate_hz));
  ShowcaseRun run;
  for (int f = 0; f < frames; ++f) {
    const double t = f / rate_hz;
    demo.runtime().run_frame(t);
    for (const InteractionEvent& e : demo.runtime().physics().events()) {
      if (!counted(e.type)) continue;
      const Name* object = demo.world().find<Name>(e.object);
      const Name* subject = demo.world().find<Name>(e.subject);
      if (e.type == InteractionEventType::kSuccess && !run.succeeded.contains(e.interaction)) run.succeeded[e.interaction] = t;
      nlohmann::json ev = {{"t_s", t}, {"type", event_name(e.type)}};
      if (object) ev["object"] = object->value;
      if (subject) ev["subject"] = subject->value;
      if (e.hand) ev["hand"] = *e.hand == HandSide::kLeft ? "left" : "right";
      if (!e.interaction.empty()) ev["interaction"] = e.interaction;
      if (!e.reason.empty()) ev["reason"] = e.reason;
      run.fired.push_back(ev);
      for (const Watched& w : watched) {
        if ((object && w.entities.contains(object->value)) || (subject && w.entities.contains(subject->value))) {
          ++run.events[w.name][event_name(e.type)];
        }
      }
      if (e.type == InteractionEventType::kGrasp || e.type == InteractionEventType::kRelease) run.grasp_events.push_back(e);
      if (e.type == InteractionEventType::kPress) {
        // A press no poke of this button asked for (0.5 s of slack after the poke).
        const bool asked = std::any_of(script.tasks().begin(), script.tasks().end(), [&](const DemoScript::Task& task) {
          return task.kind == "poke" && subject && task.entity == subject->value && t >= task.begin_s && t <= task.end_s + 0.5;
        });
        run.false_presses += asked ? 0 : 1;
      }
    }
    // Fingertips against the truth, counted for the interaction whose task is under way.
    const DemoWorld* sim = demo.simulated();
    if (!sim || !sim->truth()) continue;
    const SceneTruth& truth = *sim->truth();
    for (const DemoScript::Task& task : script.tasks()) {
      if (t < task.begin_s || t > task.end_s) continue;
      for (const Watched& w : watched) {
        if (!w.entities.contains(task.entity)) continue;
        TipError& tips = run.tips[w.name];
        for (std::size_t h = 0; h < 2; ++h) {
          const HandInput& hand = demo.runtime().tracking().results().hands[h];
          if (!hand.seen) continue;
          for (const HandJoint tip :
               {HandJoint::kThumbTip, HandJoint::kIndexTip, HandJoint::kMiddleTip, HandJoint::kRingTip, HandJoint::kLittleTip}) {
            const auto j = static_cast<std::size_t>(tip);
            const Eigen::Vector3d true_tip = truth.hands[h].world_from_hand * truth.hands[h].pose.position_m[j];
            tips.add((hand.joints_world[j] - true_tip).norm(), hand.confidence[j] >= kConfident);
          }
        }
      }
    }
  }
  return run;
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
  settings.threads = args.threads;
  DemoSettings perfect = settings;
  perfect.perfect_hands = true;

  std::map<std::string, std::vector<double>> times;          // per interaction: time to success, per seed that succeeded
  std::map<std::string, std::vector<double>> time_ratios;    // ... over the perfect hands' time, where both succeeded
  std::map<std::string, std::map<std::string, int>> events;  // per interaction: events by type, over all seeds
  std::map<std::string, TipError> tips;
  TipError all_tips;
  GraspComparison grasps;
  int false_presses = 0;
  nlohmann::json runs = nlohmann::json::array();
  double duration_s = 0.0;
  for (int k = 0; k < args.seeds; ++k) {
    settings.seed = perfect.seed = args.seed + static_cast<unsigned>(k);
    auto run = run_showcase(*scene, settings, watched, duration_s);
    std::optional<ShowcaseRun> reference;
    if (run && !settings.perfect_hands) {
      auto r = run_showcase(*scene, perfect, watched, duration_s);
      if (!r)
        run = std::unexpected(r.error());
      else
        reference = std::move(*r);
    }
    if (!run) {
      std::cerr << "rhot-eval: " << run.error() << "\n";
      return 1;
    }
    false_presses += run->false_presses;
    nlohmann::json one = {{"seed", settings.seed}, {"false_presses", run->false_presses}, {"events", run->fired}};
    if (reference) {
      const GraspComparison c =
          compare_grasps(grasp_spans(run->grasp_events, duration_s), grasp_spans(reference->grasp_events, duration_s));
      grasps.add(c);
      c.put(one);
    }
    std::string summary;
    for (const Watched& w : watched) {
      for (const auto& [type, n] : run->events[w.name]) events[w.name][type] += n;
      tips[w.name].add(run->tips[w.name]);
      all_tips.add(run->tips[w.name]);
      const auto it = run->succeeded.find(w.name);
      one["succeeded"][w.name] = it != run->succeeded.end();
      if (it != run->succeeded.end()) times[w.name].push_back(it->second);
      if (reference && it != run->succeeded.end()) {
        const auto ref = reference->succeeded.find(w.name);
        if (ref != reference->succeeded.end() && ref->second > 0.0) time_ratios[w.name].push_back(it->second / ref->second);
      }
      summary += " " + w.name + (it != run->succeeded.end() ? " yes" : " NO");
    }
    runs.push_back(one);
    std::cerr << "rhot-eval: seed " << settings.seed << " (" << (k + 1) << " of " << args.seeds << "):" << summary << "\n";
  }

  nlohmann::json j;
  j["scene"] = args.scene_file;
  j["threads"] = threads_or_all(args.threads);
  j["world"] = world_json(*world, args.world.world);
  j["hands"] = args.hands;
  j["seeds"] = args.seeds;
  j["first_seed"] = args.seed;
  j["script_s"] = duration_s;
  std::size_t total = 0;
  for (const Watched& w : watched) {
    std::vector<double>& ts = times[w.name];
    nlohmann::json one = tips[w.name].json();
    one["success_fraction"] = static_cast<double>(ts.size()) / args.seeds;
    if (!ts.empty()) {
      one["time_to_success_s"] = {{"median", percentile(ts, 0.5)}, {"max", *std::max_element(ts.begin(), ts.end())}};
    }
    if (!time_ratios[w.name].empty()) one["time_over_perfect_median"] = percentile(time_ratios[w.name], 0.5);
    one["events"] = events[w.name];
    j["interactions"][w.name] = one;
    total += ts.size();
  }
  j["success_fraction"] =
      watched.empty() ? 0.0 : static_cast<double>(total) / static_cast<double>(watched.size() * static_cast<std::size_t>(args.seeds));
  j["false_press_count"] = false_presses;
  j.update(all_tips.json());
  if (!settings.perfect_hands) grasps.put(j);
  j["runs"] = runs;
  std::cout << j.dump(2) << "\n";
  return 0;
}

}  // namespace rhot::eval
