#include "engine/sim/GraspScenarios.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <functional>
#include <optional>

#include "engine/core/Transform.h"
#include "engine/core/World.h"
#include "engine/physics/BulletMath.h"
#include "engine/physics/HandPhysics.h"
#include "engine/sim/ScriptedHands.h"
#include "engine/scene/SceneLoader.h"

namespace rhot {

namespace {

constexpr std::array<std::string_view, 7> kNames{"lift", "pinch", "throw", "push", "hand-over", "hidden-markers", "place"};

constexpr double kPedestalTop = 0.8;
constexpr float kPedestalTopF = 0.8f;

// A hand's script: the grip centre (world) and the closure at key times, linear in between.
struct Key {
  double t;
  Eigen::Vector3d centre;
  double closure;
};

std::pair<Eigen::Vector3d, double> at_time(const std::vector<Key>& keys, double t) {
  if (t <= keys.front().t) return {keys.front().centre, keys.front().closure};
  for (std::size_t i = 1; i < keys.size(); ++i) {
    if (t <= keys[i].t) {
      const double s = (t - keys[i - 1].t) / (keys[i].t - keys[i - 1].t);
      return {keys[i - 1].centre + s * (keys[i].centre - keys[i - 1].centre),
              keys[i - 1].closure + s * (keys[i].closure - keys[i - 1].closure)};
    }
  }
  return {keys.back().centre, keys.back().closure};
}

EntityDesc box_entity(const std::string& name, const glm::vec3& position, const glm::vec3& size, std::optional<PhysicsBody> body) {
  EntityDesc e;
  e.name = name;
  e.transform.position = position;
  e.mesh = Mesh{BoxShape{size}};
  e.body = body;
  return e;
}

SceneDesc make_scene(bool sphere, double size_m, bool second_pedestal, float pedestal_width_m) {
  SceneDesc scene;
  scene.settings.grasp = GraspSettings{};
  EntityDesc floor;
  floor.name = "floor";
  floor.mesh = Mesh{PlaneShape{}};
  floor.body = PhysicsBody{BodyType::kStatic, 0.0f, 0.8f, 0.0f};
  scene.entities.push_back(floor);
  const PhysicsBody fixed{BodyType::kStatic, 0.0f, 0.8f, 0.0f};
  scene.entities.push_back(
      box_entity("pedestal", {0.0f, 0.5f * kPedestalTopF, 0.0f}, {pedestal_width_m, kPedestalTopF, pedestal_width_m}, fixed));
  if (second_pedestal) {
    scene.entities.push_back(box_entity("pedestal-2", {0.3f, 0.5f * kPedestalTopF, 0.0f}, {0.12f, kPedestalTopF, 0.12f}, fixed));
    scene.entities.push_back(
        box_entity("zone", {0.3f, static_cast<float>(kPedestalTop) + 0.05f, 0.0f}, {0.12f, 0.1f, 0.12f}, std::nullopt));
  }
  EntityDesc object;
  object.name = "object";
  object.transform.position = {0.0f, static_cast<float>(kPedestalTop + 0.5 * size_m), 0.0f};
  if (sphere) {
    object.mesh = Mesh{SphereShape{static_cast<float>(0.5 * size_m)}};
  } else {
    object.mesh = Mesh{BoxShape{glm::vec3(static_cast<float>(size_m))}};
  }
  object.body = PhysicsBody{BodyType::kDynamic, 0.1f, 0.8f, 0.0f};
  object.grabbable = true;
  scene.entities.push_back(object);
  return scene;
}

// What a scenario does with the hands: each hand's keys (grip centre and closure over time) and
// how long it runs; the throw's swing velocity.
struct ScenarioScript {
  std::vector<Key> right_keys, left_keys;
  double duration = 0.0;
  Eigen::Vector3d swing_velocity = Eigen::Vector3d::Zero();
};

ScenarioScript script_for(std::string_view name, double size) {
  const Eigen::Vector3d start(0.0, kPedestalTop + 0.5 * size, 0.0);
  const Eigen::Vector3d up(0.0, 1.0, 0.0);
  const Eigen::Vector3d x_axis = Eigen::Vector3d::UnitX();
  ScenarioScript sc;
  std::vector<Key>& right_keys = sc.right_keys;
  std::vector<Key>& left_keys = sc.left_keys;
  double& duration = sc.duration;
  Eigen::Vector3d& swing_velocity = sc.swing_velocity;
  if (name == "lift" || name == "pinch" || name == "hidden-markers") {
    right_keys = {{0.0, start + 0.15 * up, 0.0},
                  {0.3, start + 0.15 * up, 0.0},
                  {0.8, start, 0.0},
                  {1.3, start, 1.0},
                  {2.3, start + 0.15 * up, 1.0},
                  {4.3, start + 0.15 * up, 1.0},
                  {4.5, start + 0.15 * up, 0.0},
                  {4.6, start + 0.25 * up, 0.0}};
    duration = 5.5;
  } else if (name == "throw") {
    swing_velocity = Eigen::Vector3d(1.5, 0.0, 0.0);
    const Eigen::Vector3d lifted = start + 0.1 * up;
    // Back 0.15 m, then accelerate over 0.2 s to 1.5 m/s (0.15 m) and swing on at that speed.
    const Eigen::Vector3d back = lifted - Eigen::Vector3d(0.3, 0.0, 0.0);
    right_keys = {{0.0, start + 0.15 * up, 0.0},
                  {0.3, start + 0.15 * up, 0.0},
                  {0.8, start, 0.0},
                  {1.3, start, 1.0},
                  {1.8, lifted, 1.0},
                  {2.3, back, 1.0},
                  {2.5, back, 1.0}};
    // Constant acceleration from rest at 2.5 s is not linear: sample it into keys.
    for (int i = 1; i <= 20; ++i) {
      const double t = 0.2 * i / 20.0;
      right_keys.push_back({2.5 + t, back + 0.5 * (1.5 / 0.2) * t * t * x_axis, 1.0});
    }
    const Eigen::Vector3d swing_start = right_keys.back().centre;
    right_keys.push_back({2.85, swing_start + 0.15 * swing_velocity, 1.0});
    right_keys.push_back({2.93, swing_start + 0.23 * swing_velocity, 0.0});
    right_keys.push_back({3.2, swing_start + 0.5 * swing_velocity, 0.0});
    duration = 3.2;
  } else if (name == "push") {
    duration = 2.0;
  } else if (name == "hand-over") {
    const Eigen::Vector3d held = start + 0.15 * up;
    right_keys = {{0.0, start + 0.15 * up, 0.0},
                  {0.3, start + 0.15 * up, 0.0},
                  {0.8, start, 0.0},
                  {1.3, start, 1.0},
                  {2.3, held, 1.0},
                  {3.8, held, 1.0},
                  {4.0, held, 0.0},
                  {4.5, held + 0.15 * up, 0.0}};
    left_keys = {{0.0, held + 0.3 * up, 0.0}, {2.5, held + 0.3 * up, 0.0}, {3.0, held, 0.0}, {3.5, held, 1.0}, {5.0, held, 1.0}};
    duration = 5.0;
  } else if (name == "place") {
    const Eigen::Vector3d target(0.3, kPedestalTop + 0.5 * size + 0.005, 0.0);
    right_keys = {{0.0, start + 0.15 * up, 0.0}, {0.3, start + 0.15 * up, 0.0}, {0.8, start, 0.0},  {1.3, start, 1.0},
                  {1.8, start + 0.1 * up, 1.0},  {2.6, target + 0.1 * up, 1.0}, {3.0, target, 1.0}, {3.2, target, 0.0},
                  {3.6, target + 0.15 * up, 0.0}};
    duration = 4.5;
  }

  return sc;
}

// The hands of a scenario at time t, from its script (and, for hidden-markers, through the hand
// solver with the fingertips hidden for 0.5 s while holding).
class ScenarioHands {
 public:
  ScenarioHands(std::string_view name, double size)
      : name_(name),
        script_(script_for(name, size)),
        right_(make_grasp(HandSide::kRight, size, 0.006, 2)),
        left_(make_grasp(HandSide::kLeft, size, 0.006, 2)),
        solver_(HandSide::kRight, right_.skeleton) {
    // Pointing forward-down at 40 degrees, the index tip 4 cm behind the cube's near face (+Z side)
    // at 1 cm above its centre; it moves along -Z.
    const HandPose pointing = pointing_hand(HandSide::kRight);
    const Eigen::Vector3d tip = pointing.position_m[static_cast<std::size_t>(HandJoint::kIndexTip)];
    push_hand_start_.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(-0.7, Eigen::Vector3d::UnitX()));
    push_hand_start_.translation =
        Eigen::Vector3d(0.0, kPedestalTop + 0.5 * size + 0.01, 0.5 * size + 0.04) - push_hand_start_.rotation * tip;
  }

  const ScenarioScript& script() const { return script_; }

  std::array<HandInput, 2> at(double t) {
    std::array<HandInput, 2> inputs;
    const Eigen::Vector3d x_axis = Eigen::Vector3d::UnitX();
    if (!script_.right_keys.empty()) {
      const auto [centre, closure] = at_time(script_.right_keys, t);
      const Rigid3d world_from_hand = right_.place(centre, x_axis);
      if (name_ == "hidden-markers") {
        const HandPose truth = right_.pose(closure);
        std::array<std::optional<Eigen::Vector3d>, kFingerCount> tips;
        const bool hidden = t >= 2.8 && t < 3.3;
        for (int k = 0; k < kFingerCount; ++k) {
          if (!hidden)
            tips[static_cast<std::size_t>(k)] = truth.position_m[static_cast<std::size_t>(chain_joints(static_cast<Finger>(k))[3])];
        }
        const HandState& s = solver_.update(t, tips);
        inputs[1] = hand_input(world_from_hand, s.pose);
        inputs[1].confidence = s.confidence;
      } else {
        inputs[1] = hand_input(world_from_hand, right_.pose(closure));
      }
    }
    if (name_ == "push") {
      Rigid3d r = push_hand_start_;
      const double travel = std::clamp((t - 0.3) / 1.2, 0.0, 1.0) * 0.10;  // 4 cm to the face, then 6 cm of push
      r.translation.z() -= travel;
      inputs[1] = hand_input(r, pointing_hand(HandSide::kRight));
    }
    if (!script_.left_keys.empty()) {
      const auto [centre, closure] = at_time(script_.left_keys, t);
      inputs[0] = hand_input(left_.place(centre, Eigen::Vector3d::UnitZ()), left_.pose(closure));
    }
    return inputs;
  }

 private:
  std::string_view name_;
  ScenarioScript script_;
  GraspPose right_, left_;
  HandSolver solver_;  // for hidden-markers: fingertips in, a hand out
  Rigid3d push_hand_start_;
};

// What a scenario measures, step by step.
class ScenarioMeasure {
 public:
  ScenarioMeasure(std::string_view name, const btRigidBody* body, Entity object, Eigen::Vector3d swing_velocity)
      : body_(body), object_(object), swing_velocity_(std::move(swing_velocity)), throwing_(name == "throw") {
    result_.name = std::string(name);
    object_start_ = to_eigen(body->getWorldTransform().getOrigin());
  }

  // After the physics step at time t with these hands.
  void observe(double t, double dt, const HandPhysics& physics, const std::array<HandInput, 2>& inputs) {
    ++result_.frames;
    const Eigen::Vector3d p = to_eigen(body_->getWorldTransform().getOrigin());
    if (measure_throw_ && released_at_ && t > *released_at_) {
      // The step after the release: the object flies on its own.
      result_.hand_speed_mps = swing_velocity_.norm();
      result_.throw_velocity_error = (to_eigen(body_->getLinearVelocity()) - swing_velocity_).norm() / swing_velocity_.norm();
      measure_throw_ = false;
    }
    for (const InteractionEvent& e : physics.events()) {
      result_.events.push_back(e);
      if (e.object != object_) continue;
      if (e.type == InteractionEventType::kGrasp) {
        result_.grasped = true;
        have_offset_ = false;
      }
      if (e.type == InteractionEventType::kRelease && e.handed_over) result_.handed_over = true;
      if (e.type == InteractionEventType::kRelease && !e.handed_over) {
        result_.released = true;
        released_at_ = t;
        height_at_release_ = p.y();
        lowest_after_release_ = p.y();
        measure_throw_ = throwing_;
      }
      if (e.type == InteractionEventType::kSuccess) result_.successes.push_back(e.interaction);
    }
    result_.lift_m = std::max(result_.lift_m, p.y() - object_start_.y());
    if (const auto side = physics.grasp().held_by(object_)) {
      const HandInput& in = inputs[*side == HandSide::kLeft ? 0 : 1];
      const Eigen::Vector3d in_hand = in.world_from_hand.inverse() * p;
      if (!have_offset_) held_offset_ = in_hand;
      have_offset_ = true;
      result_.max_slip_m = std::max(result_.max_slip_m, (in_hand - held_offset_).norm());
      result_.held_s += dt;
    }
    if (released_at_) lowest_after_release_ = std::min(lowest_after_release_, p.y());
  }

  GraspScenarioResult& result() { return result_; }

  GraspScenarioResult finish() {
    result_.fell_after_release = released_at_ && height_at_release_ - lowest_after_release_ >= 0.05;
    result_.pushed_m = (to_eigen(body_->getWorldTransform().getOrigin()) - object_start_).norm();
    return result_;
  }

 private:
  const btRigidBody* body_;
  Entity object_;
  Eigen::Vector3d swing_velocity_;
  bool throwing_;
  GraspScenarioResult result_;
  Eigen::Vector3d object_start_ = Eigen::Vector3d::Zero();
  bool have_offset_ = false;  // object in the holding hand's frame, at the grasp
  Eigen::Vector3d held_offset_ = Eigen::Vector3d::Zero();
  std::optional<double> released_at_;
  bool measure_throw_ = false;
  double lowest_after_release_ = 1e9;
  double height_at_release_ = 0.0;
};

}  // namespace

std::span<const std::string_view> grasp_scenario_names() { return kNames; }

std::expected<GraspScenarioResult, std::string> run_grasp_scenario(std::string_view name, const SceneDesc* given) {
  if (std::find(kNames.begin(), kNames.end(), name) == kNames.end())
    return std::unexpected("no grasp scenario \"" + std::string(name) + "\"");
  const bool sphere = name == "pinch";
  const double size = sphere ? 0.03 : 0.05;
  SceneDesc scene;
  if (given) {
    scene = *given;
  } else {
    scene = make_scene(sphere, size, name == "place", name == "push" ? 0.3f : 0.12f);
    if (name == "place") scene.interactions.push_back({"cube-in-zone", InteractionType::kPlace, "object", "zone", 0.25});
    if (name == "hand-over") scene.interactions.push_back({"pass-the-cube", InteractionType::kHandOver, "object", "", 0.0});
  }
  World world;
  const std::vector<Entity> entities = instantiate(scene, world);
  Entity object;
  for (std::size_t i = 0; i < scene.entities.size(); ++i) {
    if (scene.entities[i].name == "object") object = entities[i];
  }
  if (object.is_null()) return std::unexpected("the scene has no entity named \"object\"");
  auto created = HandPhysics::create(world, scene);
  if (!created) return std::unexpected(created.error());
  HandPhysics& physics = **created;

  ScenarioHands hands(name, size);
  ScenarioMeasure measure(name, physics.physics().body(object), object, hands.script().swing_velocity);
  const double dt = physics.physics().step_s();
  const long frames = static_cast<long>(std::lround(hands.script().duration / dt));
  for (long f = 0; f < frames; ++f) {
    const double t = static_cast<double>(f) * dt;
    const std::array<HandInput, 2> inputs = hands.at(t);
    const auto begin = std::chrono::steady_clock::now();
    physics.step(world, inputs);
    measure.result().step_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count());
    measure.observe(t, dt, physics, inputs);
  }
  return measure.finish();
}

}  // namespace rhot
