// The showcase script (engine/sim/DemoScript.h): tasks derived from a scene's rules and place
// interactions, played one after another by scripted hands.

#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>

#include <Eigen/Geometry>
#include <glm/gtc/quaternion.hpp>

#include "engine/core/Transform.h"
#include "engine/math/EigenGlm.h"
#include "engine/sim/DemoScript.h"

namespace rhot {

namespace {

const Eigen::Vector3d kUp = Eigen::Vector3d::UnitY();
const std::array<Eigen::Vector3d, 2> kRest{Eigen::Vector3d(-0.25, 0.95, -0.3), Eigen::Vector3d(0.25, 0.95, -0.3)};

const EntityDesc* named(const SceneDesc& scene, const std::string& name) {
  for (const EntityDesc& e : scene.entities) {
    if (e.name == name) return &e;
  }
  return nullptr;
}

// An entity's pose in the world (its parents' transforms applied), without scale.
Rigid3d world_pose(const SceneDesc& scene, const EntityDesc& e) {
  glm::mat4 m = e.transform.matrix();
  for (const EntityDesc* p = named(scene, e.parent); p; p = named(scene, p->parent)) m = p->transform.matrix() * m;
  glm::mat3 r(m);
  for (int i = 0; i < 3; ++i) r[i] = glm::normalize(r[i]);
  Rigid3d out;
  out.translation = to_eigen(glm::vec3(m[3]));
  out.rotation = to_eigen(glm::normalize(glm::quat_cast(r)));
  return out;
}

// Half the entity's shape along its own axes, scaled.
Eigen::Vector3d half_of(const EntityDesc& e) {
  const auto h = e.mesh ? shape_half_extents(e.mesh->shape) : std::nullopt;
  if (!h) return Eigen::Vector3d::Constant(0.025);
  return to_eigen(*h * e.transform.scale);
}

// The hand for a point: the left one left of the middle of the table.
int hand_for(const Eigen::Vector3d& p) { return p.x() < -0.1 ? 0 : 1; }

// How a hand closes on an entity from above, palm down: the grip point (its centre, or 2.5 cm
// below the top of a tall one), the horizontal axis across its thinnest side, and its width there.
struct Grip {
  Eigen::Vector3d point;
  Eigen::Vector3d axis;
  double width_m;
};
Grip grip_of(const SceneDesc& scene, const EntityDesc& e) {
  const Rigid3d pose = world_pose(scene, e);
  const Eigen::Vector3d half = half_of(e);
  Grip g;
  g.point = pose.translation + kUp * std::max(0.0, half.y() - 0.025);
  // The entity's x and z axes, flattened: the thinner one is the grip axis.
  const Eigen::Vector3d x = pose.rotation * Eigen::Vector3d::UnitX(), z = pose.rotation * Eigen::Vector3d::UnitZ();
  const bool across_x = half.x() <= half.z();
  Eigen::Vector3d axis = across_x ? x : z;
  axis.y() = 0.0;
  g.axis = axis.norm() > 1e-6 ? axis.normalized() : Eigen::Vector3d::UnitX();
  // The way a hand reaching forward closes: from the thumb toward the fingers away from the user
  // (-z), or across toward its own side (the left hand -x, the right +x).
  if (std::abs(g.axis.z()) > std::abs(g.axis.x())) {
    if (g.axis.z() > 0.0) g.axis = -g.axis;
  } else if ((g.axis.x() > 0.0) != (hand_for(g.point) == 1)) {
    g.axis = -g.axis;
  }
  g.width_m = 2.0 * (across_x ? half.x() : half.z());
  return g;
}

}  // namespace

bool DemoScript::wants_showcase(const SceneDesc& scene) {
  for (const RuleDesc& r : scene.rules) {
    if (r.when.event == "value_above" || r.when.event == "press" || r.when.event == "snap") return true;
  }
  return false;
}

namespace {

// The point `u` (0..1) of the way along a path through `points`, leg i ending at `ends[i]`.
Eigen::Vector3d along_path(const std::vector<Eigen::Vector3d>& points, const std::vector<double>& ends, double u) {
  double begin = 0.0;
  for (std::size_t i = 0; i + 1 < points.size(); ++i) {
    if (u <= ends[i] || i + 2 == points.size()) {
      const double f = ends[i] > begin ? std::clamp((u - begin) / (ends[i] - begin), 0.0, 1.0) : 1.0;
      return points[i] + f * (points[i + 1] - points[i]);
    }
    begin = ends[i];
  }
  return points.back();
}

}  // namespace

// Builds the showcase's keys, one task after another.
struct DemoScript::Showcase {
  using Move = std::function<std::pair<Eigen::Vector3d, Eigen::Quaterniond>(std::size_t, double)>;
  static Eigen::Quaterniond none() { return Eigen::Quaterniond::Identity(); }

  DemoScript& script;
  const SceneDesc& scene;
  std::array<std::vector<ShowKey>, 2> keys;
  double t = 0.5;  // both hands rest until then

  Showcase(DemoScript& s, const SceneDesc& sc) : script(s), scene(sc) {
    for (std::size_t h = 0; h < 2; ++h) {
      const Eigen::Vector3d axis = h == 0 ? Eigen::Vector3d(-1.0, 0.0, 0.0) : Eigen::Vector3d(1.0, 0.0, 0.0);
      keys[h].push_back({0.0, kRest[h], 0.0, 0.05, axis, none(), false});
    }
  }

  void add(int h, double at, const Eigen::Vector3d& c, double closure, const Grip& g, const Eigen::Quaterniond& turn,
           bool pointing = false) {
    keys[static_cast<std::size_t>(h)].push_back({at, c, closure, g.width_m, g.axis, turn, pointing});
  }
  // The hand stays as it is until `at` (its shape then changes on the way to the next key).
  void hold(int h, double at) {
    ShowKey k = keys[static_cast<std::size_t>(h)].back();
    k.t = at;
    keys[static_cast<std::size_t>(h)].push_back(k);
  }
  void task(const char* kind, const std::string& entity, double begin_s) { script.tasks_.push_back({kind, entity, begin_s, t}); }

  // Reach over a grip, down, close; `move(k, u)` (u 0..1) takes hand k's grip point and turn
  // through the task; open, lift off, back to rest. Several hands at once for a two-handed carry.
  void grasp_task(const std::vector<int>& hands, const std::vector<Grip>& grips, double move_s, const Move& move) {
    for (std::size_t k = 0; k < hands.size(); ++k) {
      const int h = hands[k];
      const Grip& g = grips[k];
      hold(h, t);
      add(h, t + 1.0, g.point + 0.15 * kUp, 0.0, g, none());
      add(h, t + 1.7, g.point, 0.0, g, none());
      add(h, t + 2.3, g.point, 1.0, g, none());
      constexpr int kSteps = 12;
      for (int i = 1; i <= kSteps; ++i) {
        const double u = static_cast<double>(i) / kSteps;
        const auto [p, turn] = move(k, u);
        add(h, t + 2.3 + move_s * u, p, 1.0, g, turn);
      }
      const auto [end, turn] = move(k, 1.0);
      add(h, t + 2.5 + move_s, end, 1.0, g, turn);
      add(h, t + 2.9 + move_s, end, 0.0, g, turn);
      add(h, t + 3.5 + move_s, end + 0.1 * kUp, 0.0, g, turn);
      add(h, t + 4.4 + move_s, kRest[static_cast<std::size_t>(h)], 0.0, g, none());
    }
    t += 4.6 + move_s;
  }

  // value_above on a hinge or slider: its handle (a grabbable entity fixed to it, or it) swung or
  // pulled past the threshold.
  void joint_task(const RuleDesc& rule, const EntityDesc& e) {
    const EntityDesc* handle = e.grabbable ? &e : nullptr;
    for (const EntityDesc& c : scene.entities) {
      if (!handle && c.grabbable && c.joint && c.joint->type == JointType::kFixed && c.joint->connected_to == e.name) handle = &c;
    }
    if (!handle) return;
    const Grip g = grip_of(scene, *handle);
    const Rigid3d pose = world_pose(scene, e);
    const Eigen::Vector3d axis = (pose.rotation * to_eigen(e.joint->axis)).normalized();
    const double begin_s = t;
    if (e.joint->type == JointType::kHinge) {
      const double upper = e.joint->limits ? (*e.joint->limits)[1] : 180.0;
      const double target = std::min(rule.when.value + 15.0, upper - 5.0) * std::numbers::pi / 180.0;
      const Eigen::Vector3d pivot = pose * to_eigen(e.joint->anchor_m);
      grasp_task({hand_for(g.point)}, {g}, 2.0, [&](std::size_t, double u) {
        const Eigen::Quaterniond turn(Eigen::AngleAxisd(target * u, axis));
        return std::make_pair(Eigen::Vector3d(pivot + turn * (g.point - pivot)), turn);
      });
      task("hinge", e.name, begin_s);
    } else {
      const double upper = e.joint->limits ? (*e.joint->limits)[1] : 1.0;
      const double target = std::min(rule.when.value + 0.04, upper - 0.01);
      grasp_task({hand_for(g.point)}, {g}, 1.5,
                 [&](std::size_t, double u) { return std::make_pair(Eigen::Vector3d(g.point + target * u * axis), none()); });
      task("slider", e.name, begin_s);
    }
  }

  // press on a button: a pointing index finger from 5 cm above the cap down to the button's stop
  // (its whole travel past the top), and back up, as a user presses a switch until it stops: a
  // press that stopped just past press_at would fail on a fingertip tracked a millimetre high.
  void poke_task(const EntityDesc& e) {
    const Rigid3d pose = world_pose(scene, e);
    const Eigen::Vector3d push = (pose.rotation * to_eigen(e.button->axis)).normalized();
    const Eigen::Vector3d half = half_of(e), local = to_eigen(e.button->axis).normalized();
    const double depth = std::abs(local.x()) * half.x() + std::abs(local.y()) * half.y() + std::abs(local.z()) * half.z();
    const Eigen::Vector3d top = pose.translation - depth * push;
    const Eigen::Vector3d above = top - 0.05 * push, pressed = top + e.button->travel_m * push;
    const int h = hand_for(top);
    const Grip g{top, Eigen::Vector3d::UnitX(), 0.05};
    const double begin_s = t;
    hold(h, t);
    add(h, t + 1.0, above, 0.0, g, none(), true);
    add(h, t + 1.6, above, 0.0, g, none(), true);
    add(h, t + 2.1, pressed, 0.0, g, none(), true);
    add(h, t + 2.3, pressed, 0.0, g, none(), true);
    add(h, t + 2.8, above, 0.0, g, none(), true);
    add(h, t + 3.6, kRest[static_cast<std::size_t>(h)], 0.0, g, none(), true);
    t += 3.8;
    task("poke", e.name, begin_s);
  }

  // snap on a socket: the rule's object (or the first the socket accepts) carried up, over the
  // attach pose and down, a third of the time each, and let go.
  void socket_task(const RuleDesc& rule, const EntityDesc& e) {
    const EntityDesc* object = rule.when.object.empty() ? nullptr : named(scene, rule.when.object);
    const auto& acc = e.socket->accepts;
    const auto accepted = [&](const std::string& n) { return std::find(acc.begin(), acc.end(), n) != acc.end(); };
    for (const EntityDesc& c : scene.entities) {
      if (!object && c.grabbable && (acc.empty() || accepted(c.name) || std::any_of(c.tags.begin(), c.tags.end(), accepted))) object = &c;
    }
    if (!object) return;
    const Grip g = grip_of(scene, *object);
    const Eigen::Vector3d offset = g.point - world_pose(scene, *object).translation;
    const Eigen::Vector3d attach = world_pose(scene, e) * to_eigen(e.socket->attach_position) + offset + 0.01 * kUp;
    const Eigen::Vector3d lifted = g.point + 0.12 * kUp;
    const Eigen::Vector3d over(attach.x(), std::max(lifted.y(), attach.y() + 0.08), attach.z());
    const double begin_s = t;
    grasp_task({hand_for(g.point)}, {g}, 2.0, [&](std::size_t, double u) {
      return std::make_pair(along_path({g.point, lifted, over, attach}, {1.0 / 3.0, 2.0 / 3.0, 1.0}, u), none());
    });
    task("socket", e.name, begin_s);
  }

  // place: the object carried into its zone (up 10 cm, over, down) and put down; with both hands,
  // 37 % of its length out from the middle, when it is 30 cm or longer.
  void place_task(const InteractionDesc& in) {
    const EntityDesc* object = named(scene, in.object);
    const EntityDesc* zone = named(scene, in.zone);
    if (!object || !zone || !object->grabbable) return;
    const Rigid3d pose = world_pose(scene, *object);
    const Eigen::Vector3d half = half_of(*object);
    const Eigen::Vector3d goal = world_pose(scene, *zone).translation;
    const Eigen::Vector3d shift = Eigen::Vector3d(goal.x(), pose.translation.y() + 0.003, goal.z()) - pose.translation;
    std::vector<int> hands;
    std::vector<Grip> grips;
    const double length = 2.0 * std::max(half.x(), half.z());
    if (length >= 0.3) {
      Eigen::Vector3d along = pose.rotation * (half.x() >= half.z() ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitZ());
      along.y() = 0.0;
      along.normalize();
      if (along.x() < 0.0) along = -along;
      const Eigen::Vector3d across = kUp.cross(along).normalized();
      const double width = 2.0 * std::min(half.x(), half.z());
      for (int h = 0; h < 2; ++h) {
        hands.push_back(h);
        grips.push_back({pose.translation + (h == 0 ? -0.37 : 0.37) * length * along, across, width});
      }
    } else {
      grips.push_back(grip_of(scene, *object));
      hands.push_back(hand_for(grips.back().point));
    }
    const double begin_s = t;
    grasp_task(hands, grips, 2.5, [&](std::size_t k, double u) {
      const Eigen::Vector3d from = grips[k].point, to = from + shift;
      return std::make_pair(along_path({from, from + 0.1 * kUp, to + 0.1 * kUp, to}, {0.25, 0.75, 1.0}, u), none());
    });
    task("place", object->name, begin_s);
  }

  // hand_over: one hand (the one on the object's side of the table's middle) takes the object at
  // its own end, lifts it between the hands, the other hand takes the other end, the first lets go
  // and leaves, and the second puts it down on its own side, mirrored across the middle of the
  // table. An object shorter than 16 cm has no room for two hands: no task.
  void hand_over_task(const InteractionDesc& in) {
    const EntityDesc* object = named(scene, in.object);
    if (!object || !object->grabbable) return;
    const Rigid3d pose = world_pose(scene, *object);
    const Eigen::Vector3d half = half_of(*object);
    Eigen::Vector3d along = pose.rotation * (half.x() >= half.z() ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitZ());
    along.y() = 0.0;
    along = along.norm() > 1e-6 ? along.normalized() : Eigen::Vector3d::UnitX();
    if (along.x() < 0.0) along = -along;
    const double length = 2.0 * std::max(half.x(), half.z()), width = 2.0 * std::min(half.x(), half.z());
    if (length < 0.16) return;
    const Eigen::Vector3d across = kUp.cross(along).normalized();
    const int giver = pose.translation.x() < 0.0 ? 0 : 1, taker = 1 - giver;
    // Each hand at its own end, 35 % of the length out from the middle (left hand to -along).
    const auto end_of = [&](int h, const Eigen::Vector3d& centre) {
      return Grip{centre + (h == 0 ? -0.35 : 0.35) * length * along, across, width};
    };
    const Eigen::Vector3d middle(0.0, pose.translation.y() + 0.2, pose.translation.z() - 0.05);
    const Eigen::Vector3d put(-pose.translation.x(), pose.translation.y() + 0.003, pose.translation.z());
    const Grip give_at = end_of(giver, pose.translation), give_over = end_of(giver, middle), take_at = end_of(taker, middle),
               put_at = end_of(taker, put);
    const double begin_s = t;
    // The giver: reach, take, lift to the middle, hold until the taker has closed, open, leave.
    hold(giver, t);
    add(giver, t + 1.0, give_at.point + 0.15 * kUp, 0.0, give_at, none());
    add(giver, t + 1.7, give_at.point, 0.0, give_at, none());
    add(giver, t + 2.3, give_at.point, 1.0, give_at, none());
    add(giver, t + 2.8, give_at.point + 0.1 * kUp, 1.0, give_at, none());
    add(giver, t + 4.0, give_over.point, 1.0, give_at, none());
    const double taken = t + 6.2;  // the taker closed
    hold(giver, taken + 0.3);
    add(giver, taken + 0.8, give_over.point, 0.0, give_at, none());
    add(giver, taken + 1.4, give_over.point + 0.1 * kUp, 0.0, give_at, none());
    add(giver, taken + 2.4, kRest[static_cast<std::size_t>(giver)], 0.0, give_at, none());
    // The taker: over its end while the object comes, down, close; after the giver let go, carry
    // it to its side (up, over, down), open, lift off, rest.
    hold(taker, t + 3.0);
    add(taker, t + 4.2, take_at.point + 0.12 * kUp, 0.0, take_at, none());
    add(taker, t + 5.4, take_at.point, 0.0, take_at, none());
    add(taker, taken, take_at.point, 1.0, take_at, none());
    hold(taker, taken + 1.6);
    const Eigen::Vector3d carried = put_at.point + 0.1 * kUp;
    add(taker, taken + 2.8, Eigen::Vector3d(carried.x(), std::max(carried.y(), take_at.point.y()), carried.z()), 1.0, take_at, none());
    add(taker, taken + 3.6, put_at.point, 1.0, take_at, none());
    add(taker, taken + 4.0, put_at.point, 0.0, take_at, none());
    add(taker, taken + 4.6, put_at.point + 0.1 * kUp, 0.0, take_at, none());
    add(taker, taken + 5.5, kRest[static_cast<std::size_t>(taker)], 0.0, take_at, none());
    t = taken + 5.7;
    task("hand_over", object->name, begin_s);
  }

  // Both hands hold still at the end of their keys; the script ends a second later.
  void finish() {
    script.duration_s_ = t + 1.0;
    for (std::size_t h = 0; h < 2; ++h) {
      const ShowKey& last = keys[h].back();
      keys[h].push_back({script.duration_s_, kRest[h], 0.0, last.width_m, last.axis, none(), last.pointing});
      script.scripts_[h].show = std::move(keys[h]);
    }
  }
};

void DemoScript::build_showcase(const SceneDesc& scene) {
  once_ = true;
  Showcase showcase(*this, scene);
  for (const RuleDesc& rule : scene.rules) {
    const EntityDesc* e = named(scene, rule.when.entity);
    if (!e) continue;
    const std::string& ev = rule.when.event;
    if (ev == "value_above" && e->joint && (e->joint->type == JointType::kHinge || e->joint->type == JointType::kSlider)) {
      showcase.joint_task(rule, *e);
    } else if (ev == "press" && e->button) {
      showcase.poke_task(*e);
    } else if (ev == "snap" && e->socket) {
      showcase.socket_task(rule, *e);
    }
  }
  for (const InteractionDesc& in : scene.interactions) {
    if (in.type == InteractionType::kPlace) showcase.place_task(in);
    if (in.type == InteractionType::kHandOver) showcase.hand_over_task(in);
  }
  showcase.finish();
}

HandTruth DemoScript::show_hand_at(const HandScript& s, double t) const {
  // The segment t is in, smoothed at both ends; the pose (width, axis, pointing) of its end key.
  std::size_t i = 0;
  while (i + 1 < s.show.size() && t > s.show[i].t) ++i;
  const ShowKey& b = s.show[i];
  const ShowKey& a = s.show[i > 0 ? i - 1 : 0];
  double u = b.t > a.t ? std::clamp((t - a.t) / (b.t - a.t), 0.0, 1.0) : 1.0;
  u = u * u * (3.0 - 2.0 * u);
  const Eigen::Vector3d centre = a.centre + u * (b.centre - a.centre);
  const double closure = a.closure + u * (b.closure - a.closure);
  const Eigen::Quaterniond turn = a.turn.slerp(u, b.turn);
  const HandTruth to = show_pose(s.side, b, centre, closure, turn);
  if (a.pointing == b.pointing && a.width_m == b.width_m && a.axis == b.axis) return to;
  // A change of hand shape (pointing or grasping, another width or way round): the joints and the
  // hand's frame blend from the one to the other through the segment, as a real hand's would.
  const HandTruth from = show_pose(s.side, a, centre, closure, turn);
  HandTruth out = to;
  out.world_from_hand.rotation = from.world_from_hand.rotation.slerp(u, to.world_from_hand.rotation);
  out.world_from_hand.translation =
      from.world_from_hand.translation + u * (to.world_from_hand.translation - from.world_from_hand.translation);
  for (std::size_t j = 0; j < out.pose.position_m.size(); ++j) {
    out.pose.position_m[j] = from.pose.position_m[j] + u * (to.pose.position_m[j] - from.pose.position_m[j]);
    out.pose.radius_m[j] = from.pose.radius_m[j] + u * (to.pose.radius_m[j] - from.pose.radius_m[j]);
  }
  return out;
}

HandTruth DemoScript::show_pose(HandSide side, const ShowKey& k, const Eigen::Vector3d& centre, double closure,
                                const Eigen::Quaterniond& turn) const {
  if (k.pointing) {
    // The hand frame's pointing hand points its index along -z with the palm down: tilted 50
    // degrees down about x, the back of the hand stays toward the cameras above.
    const HandPose pose = pointing_hand(side);
    const Eigen::Vector3d tip = pose.position_m[static_cast<std::size_t>(HandJoint::kIndexTip)];
    const Eigen::Quaterniond q = turn * Eigen::Quaterniond(Eigen::AngleAxisd(-50.0 * std::numbers::pi / 180.0, Eigen::Vector3d::UnitX()));
    return {Rigid3d{q, centre - q * tip}, pose};
  }
  const auto key = std::make_pair(static_cast<int>(side), std::lround(k.width_m * 1e5));
  auto it = grasps_.find(key);
  if (it == grasps_.end()) it = grasps_.emplace(key, make_grasp(side, k.width_m)).first;
  // Turned about the grip point.
  Rigid3d hand = it->second.place(centre, k.axis);
  hand.rotation = turn * hand.rotation;
  hand.translation = centre + turn * (hand.translation - centre);
  return {hand, it->second.pose(closure)};
}

}  // namespace rhot
