#include "engine/sim/GraspScenarios.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <functional>
#include <memory>
#include <numbers>
#include <optional>

#include "engine/core/Transform.h"
#include "engine/core/World.h"
#include "engine/math/EigenGlm.h"
#include "engine/physics/BulletMath.h"
#include "engine/interact/HandPhysics.h"
#include "engine/sim/DemoScript.h"
#include "engine/sim/ScriptedHands.h"
#include "engine/tracked/LiveTracking.h"
#include "tracking/sim/SimulatedRig.h"
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
  object.grabbable = Grabbable{};
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

  // The script's true hands at time t (left, right): nothing for a hand the scenario leaves out.
  std::array<std::optional<HandTruth>, 2> truth(double t) const {
    std::array<std::optional<HandTruth>, 2> hands;
    if (!script_.right_keys.empty()) {
      const auto [centre, closure] = at_time(script_.right_keys, t);
      hands[1] = HandTruth{right_.place(centre, Eigen::Vector3d::UnitX()), right_.pose(closure)};
    }
    if (name_ == "push") {
      Rigid3d r = push_hand_start_;
      const double travel = std::clamp((t - 0.3) / 1.2, 0.0, 1.0) * 0.10;  // 4 cm to the face, then 6 cm of push
      r.translation.z() -= travel;
      hands[1] = HandTruth{r, pointing_hand(HandSide::kRight)};
    }
    if (!script_.left_keys.empty()) {
      const auto [centre, closure] = at_time(script_.left_keys, t);
      hands[0] = HandTruth{left_.place(centre, Eigen::Vector3d::UnitZ()), left_.pose(closure)};
    }
    return hands;
  }

  // Whether the fingertip markers are hidden at t (hidden-markers, while holding).
  bool tips_hidden(double t) const { return name_ == "hidden-markers" && t >= 2.8 && t < 3.3; }

  // The hands the physics gets without cameras: the truth, except in hidden-markers, where the
  // right hand goes through the hand solver with its fingertips hidden.
  std::array<HandInput, 2> at(double t) {
    std::array<HandInput, 2> inputs;
    const auto hands = truth(t);
    for (std::size_t h = 0; h < 2; ++h) {
      if (hands[h]) inputs[h] = hand_input(hands[h]->world_from_hand, hands[h]->pose);
    }
    if (name_ == "hidden-markers" && hands[1]) {
      std::array<std::optional<Eigen::Vector3d>, kFingerCount> tips;
      for (int k = 0; k < kFingerCount; ++k) {
        if (!tips_hidden(t))
          tips[static_cast<std::size_t>(k)] = hands[1]->pose.position_m[static_cast<std::size_t>(chain_joints(static_cast<Finger>(k))[3])];
      }
      const HandState& s = solver_.update(t, tips);
      inputs[1] = hand_input(hands[1]->world_from_hand, s.pose);
      inputs[1].confidence = s.confidence;
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

// The rig moved so that its tracking volume (else where its optical axes meet) is centred at `centre`.
CameraRig moved_rig(CameraRig rig, const Eigen::Vector3d& centre) {
  const Eigen::Vector3d from = rig.volume ? rig.volume->centre_m : axes_meeting_point(rig);
  const Eigen::Vector3d d = centre - from;
  for (Camera& c : rig.cameras) c.cam_from_world.translation -= c.cam_from_world.rotation * d;
  if (rig.volume) rig.volume->centre_m = centre;
  return rig;
}

// The hands the cameras see at t: the script's, or with independent_seed (not 0) each a user's
// own hand (independent_hand; the left another user's than the right), as the demo's world has them.
std::array<std::optional<HandTruth>, 2> users_hands(const ScenarioHands& hands, double t, unsigned independent_seed) {
  auto truth = hands.truth(t);
  for (std::size_t h = 0; h < 2; ++h) {
    if (truth[h] && independent_seed != 0) truth[h]->pose = independent_hand(truth[h]->pose, independent_seed + static_cast<unsigned>(h));
  }
  return truth;
}

// What the moved rig photographs: the scenario's hands' markers, their bones (and, with
// occluding_bodies, the pedestals and the object) hiding them; in hidden-markers a cover over each
// fingertip marker while holding.
class ScenarioWorld final : public SimulatedWorld {
 public:
  // independent_seed: users_hands' (0: the script's hands), the one the truth is taken with.
  ScenarioWorld(const ScenarioHands& hands, unsigned independent_seed, const std::array<HandLayout, 2>& layouts,
                std::vector<Occluder> fixed, const btRigidBody* object, const SceneDesc& scene, bool occluding_bodies)
      : hands_(hands),
        independent_seed_(independent_seed),
        layouts_(layouts),
        fixed_(std::move(fixed)),
        object_(object),
        occluding_bodies_(occluding_bodies) {
    for (const EntityDesc& e : scene.entities) {
      if (e.name != "object" || !e.mesh) continue;
      if (const auto* box = std::get_if<BoxShape>(&e.mesh->shape)) object_half_ = 0.5 * to_eigen(box->size_m);
      if (const auto* sphere = std::get_if<SphereShape>(&e.mesh->shape)) object_radius_ = static_cast<double>(sphere->radius_m);
    }
  }

  WorldSnapshot at(double t_s) override {
    WorldSnapshot out;
    const auto truth = users_hands(hands_, t_s, independent_seed_);
    for (std::size_t h = 0; h < 2; ++h) {
      if (!truth[h]) continue;
      for (const Occluder& o : hand_bone_occluders(truth[h]->world_from_hand, truth[h]->pose)) out.occluders.push_back(o);
      const auto markers = layout_markers(layouts_[h], truth[h]->world_from_hand, truth[h]->pose);
      const std::size_t star = layouts_[h].hand_frame_markers;
      for (std::size_t m = 0; m < markers.size(); ++m) {
        const bool tip = m >= star && m < star + marked_tips(layouts_[h]);
        if (tip && hands_.tips_hidden(t_s)) out.occluders.push_back({markers[m], markers[m], 0.006});
        out.markers_m.push_back(markers[m]);
      }
    }
    if (occluding_bodies_) {
      out.occluders.insert(out.occluders.end(), fixed_.begin(), fixed_.end());
      const btTransform& x = object_->getWorldTransform();
      const Eigen::Vector3d centre = to_eigen(x.getOrigin());
      if (object_radius_ > 0.0) out.occluders.push_back({centre, centre, object_radius_});
      if (object_half_.x() > 0.0) out.occluders.push_back(Occluder::box(centre, to_eigen(x.getRotation()), object_half_));
    }
    return out;
  }

 private:
  static std::size_t marked_tips(const HandLayout& layout) {
    return static_cast<std::size_t>(std::ranges::count_if(layout.fingertip_marker, [](int m) { return m >= 0; }));
  }

  const ScenarioHands& hands_;
  unsigned independent_seed_ = 0;
  std::array<HandLayout, 2> layouts_;
  std::vector<Occluder> fixed_;
  const btRigidBody* object_;
  bool occluding_bodies_;
  Eigen::Vector3d object_half_ = Eigen::Vector3d::Zero();
  double object_radius_ = 0.0;
};

// The hands through the cameras: the scenario's world photographed by the moved rig and tracked
// as the demo tracks (LiveTracking), each reported hand compared with the truth.
class CameraHands {
 public:
  CameraHands(const ScenarioCameras& cameras, const ScenarioHands& hands, const SceneDesc& scene, const btRigidBody* object, double rate_hz)
      : hands_(hands), independent_seed_(cameras.world.independent_hands ? cameras.seed : 0U) {
    const CameraRig rig = moved_rig(cameras.rig, Eigen::Vector3d(0.0, kPedestalTop + 0.15, 0.0));
    // The static boxes (pedestals) as occluders.
    std::vector<Occluder> fixed;
    for (const EntityDesc& e : scene.entities) {
      if (!e.mesh || !e.body || e.body->type != BodyType::kStatic) continue;
      if (const auto* box = std::get_if<BoxShape>(&e.mesh->shape)) {
        fixed.push_back(Occluder::box(to_eigen(e.transform.position), to_eigen(e.transform.rotation), 0.5 * to_eigen(box->size_m)));
      }
    }
    auto source = std::make_unique<SimulatedRig>(rig, std::vector<Trajectory>{}, cameras.world.rig_settings(cameras.seed, rate_hz));
    source->set_world(std::make_shared<ScenarioWorld>(hands, independent_seed_, cameras.layouts, std::move(fixed), object, scene,
                                                      cameras.world.occluding_bodies));
    LiveTrackingSettings settings;
    settings.threads = cameras.threads;
    if (cameras.world.calib_error_px > 0.0) settings.tracker_rig = perturbed_rig(rig, cameras.world.calib_error_px, cameras.seed);
    live_ = std::make_unique<LiveTracking>(std::move(source), TrackedObjects{}, cameras.layouts, settings);
  }

  std::array<HandInput, 2> at(double t, GraspScenarioResult& result) {
    live_->read_source(t);
    live_->match();
    live_->track_stars(t);
    live_->track_hands(t);
    const auto truth = users_hands(hands_, t, independent_seed_);
    std::array<HandInput, 2> inputs;
    std::array<Eigen::Vector3d, 2> wrist;
    for (std::size_t h = 0; h < 2; ++h) {
      if (truth[h]) wrist[h] = truth[h]->world_from_hand * truth[h]->pose.position_m[static_cast<std::size_t>(HandJoint::kWrist)];
    }
    bool confused = false;
    for (std::size_t h = 0; h < 2; ++h) {
      if (!truth[h]) continue;  // a hand the scenario leaves out is never seen
      const TrackedHand& tracked = live_->tracked_hand(h == 0 ? HandSide::kLeft : HandSide::kRight);
      inputs[h] = hand_input(tracked);
      if (!tracked.hand_seen) continue;
      ++result.hand_frames_seen;
      const Eigen::Vector3d reported = tracked.joints_world[static_cast<std::size_t>(HandJoint::kWrist)];
      const double turn = Eigen::AngleAxisd(tracked.world_from_hand.rotation * truth[h]->world_from_hand.rotation.conjugate()).angle();
      if ((reported - wrist[h]).norm() > 0.010 || turn > 5.0 * std::numbers::pi / 180.0) ++result.reported_wrong_frames;
      if (truth[1 - h] && hand_confused(reported, wrist[h], wrist[1 - h])) confused = true;
      for (int k = 0; k < kFingerCount; ++k) {
        const auto tip = static_cast<std::size_t>(chain_joints(static_cast<Finger>(k))[3]);
        tip_sum_m_ += (tracked.joints_world[tip] - truth[h]->world_from_hand * truth[h]->pose.position_m[tip]).norm();
        ++tips_;
      }
    }
    if (confused) ++result.hand_confusion_frames;
    return inputs;
  }

  // The seen hands' fingertip joints against the truth, mean over every frame so far (mm).
  double fingertip_mean_mm() const { return tips_ > 0 ? 1000.0 * tip_sum_m_ / static_cast<double>(tips_) : 0.0; }

 private:
  const ScenarioHands& hands_;
  unsigned independent_seed_;
  std::unique_ptr<LiveTracking> live_;
  double tip_sum_m_ = 0.0;
  long tips_ = 0;
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

std::expected<GraspScenarioResult, std::string> run_grasp_scenario(std::string_view name, const SceneDesc* given,
                                                                   const ScenarioCameras* cameras) {
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
  std::optional<CameraHands> camera_hands;
  if (cameras) {
    if (auto ok = cameras->world.check(); !ok) return std::unexpected("world: " + ok.error());
    camera_hands.emplace(*cameras, hands, scene, physics.physics().body(object), 1.0 / dt);
  }
  const long frames = static_cast<long>(std::lround(hands.script().duration / dt));
  for (long f = 0; f < frames; ++f) {
    const double t = static_cast<double>(f) * dt;
    const std::array<HandInput, 2> inputs = camera_hands ? camera_hands->at(t, measure.result()) : hands.at(t);
    const auto begin = std::chrono::steady_clock::now();
    physics.step(world, inputs);
    measure.result().step_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count());
    measure.observe(t, dt, physics, inputs);
  }
  GraspScenarioResult out = measure.finish();
  if (camera_hands) out.fingertip_mean_mm = camera_hands->fingertip_mean_mm();
  return out;
}

}  // namespace rhot
