#include "engine/interact/GraspSystem.h"

#include <algorithm>
#include <cmath>

#include <LinearMath/btAabbUtil2.h>

#include "engine/core/World.h"
#include "engine/interact/FingerContact.h"
#include "engine/physics/BulletMath.h"
#include "engine/scene/Components.h"
#include "tracking/hand/HandSolver.h"

namespace rhot {

namespace {

HandSide side_of(int hand) { return hand == 0 ? HandSide::kLeft : HandSide::kRight; }

// A bone group's name in events' reasons.
const char* digit_name(int group) {
  static constexpr std::array<const char*, 6> kNames{"thumb", "index", "middle", "ring", "little", "palm"};
  return kNames[static_cast<std::size_t>(std::clamp(group, 0, 5))];
}

std::string millimetres(double m) { return std::to_string(static_cast<int>(std::lround(1000.0 * m))) + " mm"; }

// Distance from a point to an axis-aligned box (0 inside).
double box_distance(const btVector3& p, const btVector3& lo, const btVector3& hi) {
  btVector3 d(0, 0, 0);
  for (int i = 0; i < 3; ++i) d[i] = std::max({lo[i] - p[i], btScalar(0), p[i] - hi[i]});
  return static_cast<double>(d.length());
}

// The object's normal at a contact point (world) as a finger pad of radius `pad_m` feels it. A pad
// is not a point: within its radius of a box's edge it presses on both faces, so the normal is that
// of the box rounded by the pad, from the nearest point of the box shrunk by `pad_m` to the
// contact, and turns smoothly across the edge where the contact's own normal jumps by 90 degrees.
// Other shapes (spheres and capsules are round; hulls) keep the contact's normal.
btVector3 pad_normal(const btRigidBody& body, const btVector3& point, const btVector3& normal, double pad_m) {
  const btCollisionShape* shape = body.getCollisionShape();
  if (!(pad_m > 0.0) || shape->getShapeType() != BOX_SHAPE_PROXYTYPE) return normal;
  const btTransform& world_from_body = body.getWorldTransform();
  const btVector3 q = world_from_body.invXform(point);
  const btVector3 half = static_cast<const btBoxShape*>(shape)->getHalfExtentsWithMargin();
  btVector3 core;
  for (int i = 0; i < 3; ++i) {
    const btScalar e = std::max(btScalar(0), half[i] - static_cast<btScalar>(pad_m));
    core[i] = std::clamp(q[i], -e, e);
  }
  const btVector3 out = q - core;
  return out.length2() > btScalar(1e-12) ? world_from_body.getBasis() * out.normalized() : normal;
}

}  // namespace

const char* event_name(InteractionEventType type) {
  switch (type) {
    case InteractionEventType::kHoverBegin:
      return "hover_begin";
    case InteractionEventType::kHoverEnd:
      return "hover_end";
    case InteractionEventType::kContactBegin:
      return "contact_begin";
    case InteractionEventType::kContactEnd:
      return "contact_end";
    case InteractionEventType::kGrasp:
      return "grasp";
    case InteractionEventType::kRelease:
      return "release";
    case InteractionEventType::kSuccess:
      return "success";
    case InteractionEventType::kPress:
      return "press";
    case InteractionEventType::kUnpress:
      return "unpress";
    case InteractionEventType::kSnap:
      return "snap";
    case InteractionEventType::kUnsnap:
      return "unsnap";
    case InteractionEventType::kValueAbove:
      return "value_above";
    case InteractionEventType::kValueBelow:
      return "value_below";
    case InteractionEventType::kPoke:
      return "poke";
    case InteractionEventType::kEnter:
      return "enter";
    case InteractionEventType::kExit:
      return "exit";
  }
  return "?";
}

GraspSystem::GraspSystem(PhysicsWorld& physics, std::array<HandColliders*, 2> hands, GraspSettings settings)
    : physics_(physics), hands_(hands), settings_(settings) {}

std::optional<HandSide> GraspSystem::held_by(Entity object) const {
  const auto it = held_.find(object);
  if (it == held_.end()) return std::nullopt;
  return side_of(it->second.first());
}

bool GraspSystem::held_by_both(Entity object) const {
  const auto it = held_.find(object);
  return it != held_.end() && it->second.both();
}

std::optional<Entity> GraspSystem::holding(HandSide hand) const {
  const std::size_t h = hand == HandSide::kLeft ? 0 : 1;
  for (const auto& [e, held] : held_) {
    if (held.by[h]) return e;
  }
  return std::nullopt;
}

btVector3 GraspSystem::grip_centre(const Held& held, int hand) const {
  return to_bt(hands_[static_cast<std::size_t>(hand)]->input().world_from_hand) * held.by[static_cast<std::size_t>(hand)]->centre;
}

// The frame two hands span: origin midway between their grips, x from the left grip toward the
// right one, y the pair's first y turned by the mean of the hands' turns since and made
// perpendicular to x.
btTransform GraspSystem::pair_frame(const Held& held) const {
  const btVector3 left = grip_centre(held, 0), right = grip_centre(held, 1);
  btVector3 x = right - left;
  x = x.length() > btScalar(1e-6) ? x.normalized() : btVector3(1, 0, 0);
  const auto turn = [&](int hand) {
    const btQuaternion now = to_bt(hands_[static_cast<std::size_t>(hand)]->input().world_from_hand).getRotation();
    return now * held.by[static_cast<std::size_t>(hand)]->rotation_paired.inverse();
  };
  btVector3 y = quatRotate(turn(0).slerp(turn(1), btScalar(0.5)), held.pair_up);
  y -= x * x.dot(y);
  if (y.length() < btScalar(0.1)) {  // the hands rolled the first y onto the line: fall back on it
    y = held.pair_up - x * x.dot(held.pair_up);
    if (y.length() < btScalar(0.1)) {
      btVector3 a, b;
      btPlaneSpace1(x, a, b);  // any unit vector perpendicular to x
      y = a;
    }
  }
  y.normalize();
  const btVector3 z = x.cross(y);
  const btMatrix3x3 basis(x.x(), y.x(), z.x(), x.y(), y.y(), z.y(), x.z(), y.z(), z.z());
  return btTransform(basis, (left + right) * btScalar(0.5));
}

double GraspSystem::pair_scale(const Held& held) const {
  if (!held.options.scale_with_hands || held.span_m <= 1e-6) return held.scale_paired;
  const double span = static_cast<double>((grip_centre(held, 1) - grip_centre(held, 0)).length());
  return std::clamp(held.scale_paired * span / held.span_m, static_cast<double>(held.options.min_scale),
                    static_cast<double>(held.options.max_scale));
}

btTransform GraspSystem::target_of(const Held& held) const {
  if (held.both()) {
    btTransform pair_from_object = held.pair_from_object;
    pair_from_object.setOrigin(pair_from_object.getOrigin() * static_cast<btScalar>(pair_scale(held) / held.scale_paired));
    return pair_frame(held) * pair_from_object;
  }
  const int hand = held.first();
  return to_bt(hands_[static_cast<std::size_t>(hand)]->input().world_from_hand) * held.by[static_cast<std::size_t>(hand)]->hand_from_object;
}

std::optional<btTransform> GraspSystem::grip_target(Entity object) const {
  const auto it = held_.find(object);
  if (it == held_.end()) return std::nullopt;
  return target_of(it->second);
}

std::vector<Entity> GraspSystem::held_objects() const {
  std::vector<Entity> out;
  out.reserve(held_.size());
  for (const auto& [e, held] : held_) out.push_back(e);
  std::ranges::sort(out, [](Entity a, Entity b) { return a.index < b.index; });  // (not the map's order)
  return out;
}

double GraspSystem::out_of_surface_m(int hand, const GripPoint& g, const btTransform& target, btScalar grown) const {
  const btVector3 on_bone = hands_[static_cast<std::size_t>(hand)]->tracked_bone(g.bone) * g.on_bone;
  const btVector3 on_object = target * (g.on_object * grown);
  return static_cast<double>((on_bone - on_object).dot(target.getBasis() * g.normal)) + g.out_carried_m;
}

bool GraspSystem::grip_seen_closed(Entity object) const {
  const auto it = held_.find(object);
  if (it == held_.end()) return false;
  const Held& held = it->second;
  for (int hand = 0; hand < 2; ++hand) {
    const auto& grip = held.by[static_cast<std::size_t>(hand)];
    if (!grip || !hands_[static_cast<std::size_t>(hand)]->active()) continue;
    bool anchor = false, finger = false;
    for (const GripPoint& g : grip->grip) {
      if (!g.measured || grip_confidence(hand, g) < settings_.confident) continue;
      if (g.open) continue;  // as release_opened() judged it this step
      (g.group == 0 || g.group == kPalmGroup ? anchor : finger) = true;
    }
    if (anchor && finger) return true;
  }
  return false;
}

std::vector<InteractionEvent> GraspSystem::let_go(Entity object, const std::string& reason) {
  const auto it = held_.find(object);
  if (it == held_.end()) return {};
  const std::size_t before = events_.size();
  const bool both = it->second.both();
  for (int hand = 0; hand < 2; ++hand) {
    const auto h = held_.find(object);
    if (h != held_.end() && h->second.by[static_cast<std::size_t>(hand)])
      release(object, hand, both ? LetGo::kBoth : LetGo::kOpened, reason);
  }
  return {events_.begin() + static_cast<std::ptrdiff_t>(before), events_.end()};
}

void GraspSystem::emit(InteractionEventType type, Entity object, std::optional<int> hand) {
  InteractionEvent e{type, physics_.time_s(), object, std::nullopt, {}, false, Eigen::Vector3d::Zero(), Entity{}, 0.0, {}};
  if (hand) e.hand = side_of(*hand);
  events_.push_back(std::move(e));
}

void GraspSystem::ignore_hand(btRigidBody* object, int hand, bool ignore) {
  const HandColliders* h = hands_[static_cast<std::size_t>(hand)];
  if (!h) return;
  for (int i = 0; i < kHandBoneCount; ++i) {
    if (h->bone(i)) object->setIgnoreCollisionCheck(h->bone(i), ignore);
  }
  if (!ignore) return;
  // The ignore flag stops new contact points, but the manifolds the grasping bones already have
  // (a point a few millimetres deep) stay in the dispatcher, and Bullet's island manager still hands
  // them to the solver: their pushes turned a bar held in two hands 7-15 degrees off its grip.
  btDispatcher* dispatcher = physics_.bullet().getDispatcher();
  for (int m = 0; m < dispatcher->getNumManifolds(); ++m) {
    btPersistentManifold* manifold = dispatcher->getManifoldByIndexInternal(m);
    const btCollisionObject* a = manifold->getBody0();
    const btCollisionObject* b = manifold->getBody1();
    const btCollisionObject* other = a == object ? b : (b == object ? a : nullptr);
    if (other && h->bone_of(other)) manifold->clearManifold();
  }
}

double GraspSystem::curl_rad(int hand, int finger) const {
  const HandInput& in = hands_[static_cast<std::size_t>(hand)]->input();
  const auto p = [&](HandJoint j) { return in.joints_world[static_cast<std::size_t>(j)]; };
  const auto& bones = hand_bones();
  // The finger's first and last bones: root flexion plus both hinges.
  Eigen::Vector3d first = Eigen::Vector3d::Zero(), last = Eigen::Vector3d::Zero();
  bool have_first = false;
  for (const HandBone& b : bones) {
    if (b.group != finger) continue;
    const Eigen::Vector3d d = (p(b.to) - p(b.from)).normalized();
    if (!have_first) first = d;
    have_first = true;
    last = d;
  }
  if (finger != 0) {
    // A finger's root flexion is measured from its metacarpal (a palm bone).
    for (const HandBone& b : bones) {
      if (b.group == kPalmGroup && b.to == static_cast<HandJoint>(static_cast<int>(HandJoint::kIndexProximal) + 5 * (finger - 1))) {
        first = (p(b.to) - p(b.from)).normalized();
      }
    }
  }
  return std::acos(std::clamp(first.dot(last), -1.0, 1.0));
}

double GraspSystem::grip_confidence(int hand, const GripPoint& g) const {
  // A finger is measured when its tip is (its other joints are inferred by IK); the palm when its
  // knuckles are.
  const HandBone& bone = hand_bones()[static_cast<std::size_t>(g.bone)];
  const HandJoint judge = g.group == kPalmGroup ? bone.to : chain_joints(static_cast<Finger>(g.group))[3];
  return hands_[static_cast<std::size_t>(hand)]->input().confidence[static_cast<std::size_t>(judge)];
}

std::optional<double> GraspSystem::last_bone_distance_m(int hand, int finger, const btRigidBody& body, const btTransform& target) const {
  const HandInput& in = hands_[static_cast<std::size_t>(hand)]->input();
  const auto joints = chain_joints(static_cast<Finger>(finger));
  const auto tip = static_cast<std::size_t>(joints[3]);
  if (in.confidence[tip] < settings_.confident) return std::nullopt;
  // Measured against the object where the grip has it, as the grip points are: a held object lags
  // its target by millimetres (and by up to max_hold_error_m against an obstacle).
  const btTransform to_body = body.getWorldTransform() * target.inverse();
  const auto at = [&](std::size_t j) { return to_eigen(to_body * to_bt(in.joints_world[j])); };
  const double d = capsule_distance_m(body, at(static_cast<std::size_t>(joints[2])), at(tip), 0.001);
  if (!std::isfinite(d)) return std::nullopt;
  return d;
}

void GraspSystem::remember_last_bones(int hand, HandGrip& grip, const btRigidBody& body, const btTransform& target) const {
  std::array<bool, 5> done{};
  for (const GripPoint& g : grip.grip) {
    const auto f = static_cast<std::size_t>(g.group);
    if (g.group == 0 || g.group == kPalmGroup || done[f]) continue;
    done[f] = true;
    const auto d = last_bone_distance_m(hand, g.group, body, target);
    if (!d) continue;
    const double curl = curl_rad(hand, g.group);
    if (grip.curl_at_start_rad[f] == -kFar) grip.curl_at_start_rad[f] = curl;
    if (*d < grip.last_bone_nearest_m[f]) grip.last_bone_nearest_m[f] = *d, grip.curl_at_nearest_rad[f] = curl;
  }
}

double GraspSystem::finger_left_m(int hand, const HandGrip& grip, int finger, const btRigidBody& body, const btTransform& target) const {
  if (finger < 1 || finger > 4) return 0.0;
  const auto f = static_cast<std::size_t>(finger);
  if (grip.last_bone_nearest_m[f] == kFar) return 0.0;
  const auto d = last_bone_distance_m(hand, finger, body, target);
  if (!d) return 0.0;
  const double curl = curl_rad(hand, finger);
  if (!(grip.curl_at_nearest_rad[f] - curl > kOpenedCurl_rad && grip.curl_at_start_rad[f] - curl > kOpenedCurl_rad)) return 0.0;
  return std::max(0.0, *d - grip.last_bone_nearest_m[f]);
}

void GraspSystem::pre_step(World& world) {
  const btScalar dt = static_cast<btScalar>(physics_.step_s());
  for (auto& [object, held] : held_) {
    btRigidBody* body = physics_.body(object);
    if (!body) continue;
    if (held.both() && held.options.scale_with_hands) physics_.set_scale(world, object, pair_scale(held));
    const btTransform target = target_of(held);
    if (!finite(target.getOrigin()) || !finite(target.getBasis().getRow(0)) || !finite(target.getBasis().getRow(1)) ||
        !finite(target.getBasis().getRow(2))) {
      continue;  // (cannot happen from finite hands; the body then just keeps its velocity)
    }
    held.history.emplace_back(physics_.time_s(), target);
    while (held.history.size() > 2 && held.history.front().first < physics_.time_s() - 0.25) held.history.pop_front();
    const btTransform& now = body->getWorldTransform();
    btVector3 v = (target.getOrigin() - now.getOrigin()) / dt;
    const btScalar speed = v.length();
    const btScalar max_speed = static_cast<btScalar>(settings_.max_object_speed_mps);
    if (speed > max_speed) v *= max_speed / speed;
    body->activate(true);
    body->setLinearVelocity(v);
    body->setAngularVelocity(angular_velocity(now.getRotation(), target.getRotation(), dt));
  }
}

std::string GraspSystem::grasp_reason(const HandGrip& grip) {
  // "thumb against index, middle (index estimated)": the anchor, the opposing fingers, and those
  // of them whose tips were not measured (estimated, or placed against the object).
  std::string anchor, fingers, estimated;
  const auto add = [](std::string& list, const char* name) {
    if (list.find(name) == std::string::npos) list += std::string(list.empty() ? "" : ", ") + name;
  };
  for (const GripPoint& g : grip.grip) {
    add(g.group == 0 || g.group == kPalmGroup ? anchor : fingers, digit_name(g.group));
    if (!g.measured) add(estimated, digit_name(g.group));
  }
  return anchor + " against " + fingers + (estimated.empty() ? "" : " (" + estimated + " not measured)");
}

void GraspSystem::begin_grasp(World& world, int hand, Entity object, const std::vector<Contact>& contacts, const std::vector<int>& groups) {
  btRigidBody* body = physics_.body(object);
  HandColliders* h = hands_[static_cast<std::size_t>(hand)];
  const btTransform world_from_hand = to_bt(h->input().world_from_hand);
  const Grabbable options = world.get<Grabbable>(object);
  auto it = held_.find(object);
  // The other hand takes the object over when it is not two-handed or the grips would be too
  // close together to make a pair (the line between them would be noise).
  btVector3 centre_now(0, 0, 0);
  for (const Contact& c : contacts) centre_now += c.point;
  centre_now /= static_cast<btScalar>(std::max<std::size_t>(1, contacts.size()));
  if (it != held_.end() &&
      (!options.two_handed || static_cast<double>((grip_centre(it->second, it->second.first()) - centre_now).length()) < kMinPairSpan_m)) {
    release(object, it->second.first(), LetGo::kTaken, std::string("taken by the ") + (hand == 0 ? "left" : "right") + " hand");
    it = held_.end();
  }
  const bool joining = it != held_.end();
  // A joining hand takes the object where the pair's target has it (no jump); a first hand where it is.
  const btTransform world_from_object = joining ? target_of(it->second) : body->getWorldTransform();
  HandGrip grip;
  grip.hand_from_object = world_from_hand.inverse() * world_from_object;
  const btTransform object_from_world = world_from_object.inverse();
  btVector3 centre(0, 0, 0);
  for (const Contact& c : contacts) {
    const int group = hand_bones()[static_cast<std::size_t>(c.bone)].group;
    if (std::find(groups.begin(), groups.end(), group) == groups.end()) continue;
    GripPoint g;
    g.bone = c.bone;
    g.group = group;
    g.on_object = object_from_world * c.point;
    g.normal = object_from_world.getBasis() * c.normal;
    g.on_bone = h->tracked_bone(c.bone).inverse() * c.point;
    g.measured = grip_confidence(hand, g) >= settings_.confident;
    grip.grip.push_back(g);
    centre += c.point;
  }
  grip.centre = world_from_hand.inverse() * (centre / static_cast<btScalar>(std::max<std::size_t>(1, grip.grip.size())));
  grip.scale = physics_.scale(object);
  grip.began_s = physics_.time_s();
  remember_last_bones(hand, grip, *body, world_from_object);
  if (!joining) {
    Held held;
    held.options = options;
    held.by[static_cast<std::size_t>(hand)] = std::move(grip);
    held_[object] = std::move(held);
    body->setGravity({0, 0, 0});
    body->activate(true);
  } else {
    Held& held = it->second;
    held.by[static_cast<std::size_t>(hand)] = std::move(grip);
    for (int k = 0; k < 2; ++k) {
      held.by[static_cast<std::size_t>(k)]->rotation_paired =
          to_bt(hands_[static_cast<std::size_t>(k)]->input().world_from_hand).getRotation();
    }
    // The pair frame's first y: the world's up made perpendicular to the line between the hands
    // (or, for hands one above the other, the world's z).
    btVector3 x = grip_centre(held, 1) - grip_centre(held, 0);
    held.span_m = static_cast<double>(x.length());
    x = held.span_m > 1e-6 ? x / static_cast<btScalar>(held.span_m) : btVector3(1, 0, 0);
    btVector3 up = btVector3(0, 1, 0) - x * x.y();
    if (up.length() < btScalar(0.3)) up = btVector3(0, 0, 1) - x * x.z();
    held.pair_up = up.normalized();
    held.scale_paired = physics_.scale(object);
    held.pair_from_object = pair_frame(held).inverse() * world_from_object;
  }
  ignore_hand(body, hand, true);
  std::erase_if(reenable_, [&](const auto& r) { return r.first == object && r.second == hand; });
  emit(InteractionEventType::kGrasp, object, hand);
  events_.back().reason = grasp_reason(*held_[object].by[static_cast<std::size_t>(hand)]);
}

void GraspSystem::release(Entity object, int hand, LetGo how, std::string reason) {
  const auto it = held_.find(object);
  if (it == held_.end() || !it->second.by[static_cast<std::size_t>(hand)]) return;
  Held& held = it->second;
  const bool handed_over = how == LetGo::kTaken || (how == LetGo::kOpened && held.both());
  btRigidBody* body = physics_.body(object);
  InteractionEvent e{InteractionEventType::kRelease, physics_.time_s(), object, side_of(hand),    {}, handed_over,
                     Eigen::Vector3d::Zero(),        Entity{},          0.0,    std::move(reason)};
  if (held.both()) {
    // The other hand carries on from where the pair had the object.
    // Its grip points are taken afresh where its fingers are now: while paired the object moved
    // (and maybe scaled) relative to each hand. A measured point keeps how far out of the surface
    // it was: two hands let go together, and the one still opening when the other has let go would
    // otherwise start its opening again from nothing (and, its finger already most of the way open,
    // might never open the release distance more). Carrying only the points already past the
    // release distance kept the bar held on 4 of the workbench's 20 seeds (docs/PERFORMANCE.md).
    const int other = 1 - hand;
    const btTransform world_from_object = target_of(held);
    HandGrip& stays = *held.by[static_cast<std::size_t>(other)];
    HandColliders* h = hands_[static_cast<std::size_t>(other)];
    const btScalar grown = static_cast<btScalar>(physics_.scale(object) / stays.scale);
    for (GripPoint& g : stays.grip) {
      const bool trusted = g.measured && grip_confidence(other, g) >= settings_.confident;
      g.out_carried_m = trusted ? std::max(0.0, out_of_surface_m(other, g, world_from_object, grown)) : 0.0;
      g.on_object = world_from_object.inverse() * (h->tracked_bone(g.bone) * g.on_bone);
    }
    stays.hand_from_object = to_bt(h->input().world_from_hand).inverse() * world_from_object;
    stays.scale = physics_.scale(object);
    held.by[static_cast<std::size_t>(hand)].reset();
    if (body) reenable_.emplace_back(object, hand);
    released_at_s_[static_cast<std::size_t>(hand)] = physics_.time_s();
    events_.push_back(std::move(e));
    return;
  }
  if (body && !handed_over) {
    // The hand's velocity: a least-squares line through the grip's recent positions.
    const double end = physics_.time_s() - settings_.throw_window_end_s;
    const double begin = end - settings_.throw_window_s;
    std::vector<std::pair<double, btTransform>> window;
    for (const auto& s : held.history) {
      if (s.first >= begin - 1e-9 && s.first <= end + 1e-9) window.push_back(s);
    }
    if (window.size() < 2 && held.history.size() >= 2) window.assign(held.history.end() - 2, held.history.end());
    btVector3 v(0, 0, 0), w(0, 0, 0);
    if (window.size() >= 2) {
      double t_mean = 0.0;
      btVector3 p_mean(0, 0, 0);
      for (const auto& s : window) {
        t_mean += s.first;
        p_mean += s.second.getOrigin();
      }
      t_mean /= static_cast<double>(window.size());
      p_mean /= static_cast<btScalar>(window.size());
      double stt = 0.0;
      btVector3 stp(0, 0, 0);
      for (const auto& s : window) {
        const double dt = s.first - t_mean;
        stt += dt * dt;
        stp += (s.second.getOrigin() - p_mean) * static_cast<btScalar>(dt);
      }
      if (stt > 0.0) v = stp / static_cast<btScalar>(stt);
      const double span = window.back().first - window.front().first;
      if (span > 0.0)
        w = angular_velocity(window.front().second.getRotation(), window.back().second.getRotation(), static_cast<btScalar>(span));
    }
    if (!finite(v) || !finite(w)) v = w = btVector3(0, 0, 0);
    const btScalar max_speed = static_cast<btScalar>(settings_.max_object_speed_mps);
    if (v.length() > max_speed) v *= max_speed / v.length();
    body->setLinearVelocity(v);
    body->setAngularVelocity(w);
    e.velocity_mps = to_eigen(v);
  }
  if (body) {
    body->setGravity(physics_.bullet().getGravity());
    body->activate(true);
    reenable_.emplace_back(object, hand);
  }
  released_at_s_[static_cast<std::size_t>(hand)] = physics_.time_s();
  held_.erase(it);
  events_.push_back(std::move(e));
}

void GraspSystem::post_step(World& world) {
  events_.clear();
  contacts_ = read_contacts();
  const HandContacts& contacts = contacts_;
  update_hover_and_contact(contacts);
  join_fingers();
  release_opened();
  begin_new_grasps(world, contacts);
  resume_collisions();
}

// Contacts between hand bones and scene bodies, per hand and object.
GraspSystem::HandContacts GraspSystem::read_contacts() const {
  HandContacts contacts;
  btDispatcher* dispatcher = physics_.bullet().getDispatcher();
  for (int m = 0; m < dispatcher->getNumManifolds(); ++m) {
    const btPersistentManifold* manifold = dispatcher->getManifoldByIndexInternal(m);
    const btCollisionObject* a = manifold->getBody0();
    const btCollisionObject* b = manifold->getBody1();
    if (!a->checkCollideWith(b) || !b->checkCollideWith(a)) continue;  // ignored pair: stale points
    for (int hand = 0; hand < 2; ++hand) {
      HandColliders* h = hands_[static_cast<std::size_t>(hand)];
      if (!h || !h->active()) continue;
      auto bone = h->bone_of(a);
      const btCollisionObject* other = b;
      bool bone_is_a = true;
      if (!bone) {
        bone = h->bone_of(b);
        other = a;
        bone_is_a = false;
      }
      if (!bone || h->soft(*bone)) continue;
      const auto object = physics_.entity_of(other);
      if (!object) continue;
      for (int k = 0; k < manifold->getNumContacts(); ++k) {
        const btManifoldPoint& pt = manifold->getContactPoint(k);
        if (pt.getDistance() > static_cast<btScalar>(settings_.contact_distance_m)) continue;
        // normalWorldOnB points from body1 toward body0.
        const btVector3 normal = bone_is_a ? pt.m_normalWorldOnB : -pt.m_normalWorldOnB;
        const btVector3 point = bone_is_a ? pt.getPositionWorldOnB() : pt.getPositionWorldOnA();
        contacts[static_cast<std::size_t>(hand)][*object].push_back({*bone, point, normal});
      }
    }
  }

  return contacts;
}

// Hover and contact events, for every non-static body.
void GraspSystem::update_hover_and_contact(const HandContacts& contacts) {
  for (const Entity object : physics_.entities()) {
    btRigidBody* body = physics_.body(object);
    if (body->isStaticObject() && !body->isKinematicObject()) continue;
    auto& state = pairs_[object];
    btVector3 lo, hi;
    body->getAabb(lo, hi);
    for (int hand = 0; hand < 2; ++hand) {
      HandColliders* h = hands_[static_cast<std::size_t>(hand)];
      PairState& s = state[static_cast<std::size_t>(hand)];
      const bool active = h && h->active();
      const bool touching = active && contacts[static_cast<std::size_t>(hand)].contains(object);
      if (touching != s.touching) emit(touching ? InteractionEventType::kContactBegin : InteractionEventType::kContactEnd, object, hand);
      s.touching = touching;
      bool hovering = false;
      if (active) {
        const double d = box_distance(to_bt(h->input().joints_world[static_cast<std::size_t>(HandJoint::kPalm)]), lo, hi);
        hovering = d <= settings_.hover_distance_m * (s.hovering ? 1.5 : 1.0);
      }
      if (hovering != s.hovering) emit(hovering ? InteractionEventType::kHoverBegin : InteractionEventType::kHoverEnd, object, hand);
      s.hovering = hovering;
    }
  }
}

// Fingers that close on a held object after its grasp began join the grip: curled, touching the
// object where the grip has it (the holding hand's bones no longer collide with it, so this is a
// distance query per bone, not a contact), a touching bone's normal opposing a thumb or palm grip
// point's as at a grasp (own with own, or both as finger pads feel them). Every touching bone of
// the finger becomes a grip point, as at a grasp. The grip then holds until they open too: a
// grasp begun by the first finger to touch (a tracked finger grazing an edge) is not ended by that
// finger alone moving off while the others hold. A hidden finger joins where the hidden-finger rule
// placed it against the object, unmeasured: it never counts as open while hidden, and once
// measured it is judged against the surface it was placed on (release_opened).
void GraspSystem::join_fingers() {
  if (!settings_.fingers_join) return;
  const auto& bones = hand_bones();
  for (auto& [object, held] : held_) {
    btRigidBody* body = physics_.body(object);
    if (!body) continue;
    const btTransform target = target_of(held);
    // The tracked bones brought to the object where it is, from where the grip has it (it lags its
    // target by millimetres): last_bone_distance_m's frame.
    const btTransform to_body = body->getWorldTransform() * target.inverse();
    const btTransform& world_from_body = body->getWorldTransform();
    const btMatrix3x3 object_from_world = world_from_body.getBasis().transpose();
    btVector3 lo, hi;
    body->getAabb(lo, hi);
    for (int hand = 0; hand < 2; ++hand) {
      auto& grip = held.by[static_cast<std::size_t>(hand)];
      const HandColliders* h = hands_[static_cast<std::size_t>(hand)];
      if (!grip || !h->active()) continue;
      const HandInput& in = h->input();
      const btScalar grown = static_cast<btScalar>(physics_.scale(object) / grip->scale);
      // The thumb's and palm's grip normals (object frame), own and as a pad feels them.
      std::vector<std::pair<btVector3, btVector3>> anchors;
      for (const GripPoint& g : grip->grip) {
        if (g.group != 0 && g.group != kPalmGroup) continue;
        const btVector3 world_normal = world_from_body.getBasis() * g.normal;
        const btVector3 pad = pad_normal(*body, world_from_body * (g.on_object * grown), world_normal, settings_.pad_radius_m);
        anchors.emplace_back(g.normal, object_from_world * pad);
      }
      for (int f = 1; f <= 4; ++f) {
        if (std::any_of(grip->grip.begin(), grip->grip.end(), [&](const GripPoint& g) { return g.group == f; })) continue;
        if (!(curl_rad(hand, f) >= settings_.min_curl_rad)) continue;
        // A hidden finger past the window cannot join: no queries for it (a long hold with hidden
        // fingers placed against the object would otherwise query them every step).
        const bool tip_measured = in.confidence[static_cast<std::size_t>(chain_joints(static_cast<Finger>(f))[3])] >= settings_.confident;
        if (!tip_measured && physics_.time_s() - grip->began_s > kHiddenJoinWindow_s) continue;
        std::vector<GripPoint> touching;
        bool opposes = false;
        for (std::size_t i = 0; i < bones.size(); ++i) {
          if (bones[i].group != f) continue;
          const btVector3 a = to_body * to_bt(in.joints_world[static_cast<std::size_t>(bones[i].from)]);
          const btVector3 b = to_body * to_bt(in.joints_world[static_cast<std::size_t>(bones[i].to)]);
          const double radius = h->bone_radius_m(static_cast<int>(i));
          // Boxes first: the exact query only for a bone whose box (with its radius and the
          // contact distance) overlaps the object's.
          const btScalar pad_box = static_cast<btScalar>(radius + settings_.contact_distance_m);
          btVector3 bone_lo = a, bone_hi = a;
          bone_lo.setMin(b);
          bone_hi.setMax(b);
          const btVector3 grow(pad_box, pad_box, pad_box);
          if (!TestAabbAgainstAabb2(bone_lo - grow, bone_hi + grow, lo, hi)) continue;
          const CapsuleGap gap = capsule_gap(*body, to_eigen(a), to_eigen(b), radius);
          if (!(gap.distance_m <= settings_.contact_distance_m) || !gap.on_object.allFinite() || !gap.normal.allFinite() ||
              gap.normal.norm() < 0.5)
            continue;
          const btVector3 point = to_bt(gap.on_object);
          const btVector3 normal = to_bt(gap.normal.normalized());
          const btVector3 own = object_from_world * normal;
          const btVector3 pad = object_from_world * pad_normal(*body, point, normal, settings_.pad_radius_m);
          for (const auto& [anchor_own, anchor_pad] : anchors) {
            opposes = opposes || static_cast<double>(anchor_own.dot(own)) < settings_.opposing_cos ||
                      static_cast<double>(anchor_pad.dot(pad)) < settings_.opposing_cos;
          }
          GripPoint g;
          g.bone = static_cast<int>(i);
          g.group = f;
          g.on_object = world_from_body.invXform(point) / grown;
          g.normal = own;
          g.on_bone = h->tracked_bone(g.bone).inverse() * (target * (g.on_object * grown));
          g.measured = tip_measured;
          g.joined = true;
          touching.push_back(g);
        }
        if (opposes) grip->grip.insert(grip->grip.end(), touching.begin(), touching.end());
      }
    }
  }
}

// Releases: fingers opened, or the object stuck far from its grip.
void GraspSystem::release_opened() {
  struct LetGoOf {
    Entity object;
    int hand;
    std::string reason;
  };
  std::vector<LetGoOf> to_release;
  for (auto& [object, held] : held_) {
    btRigidBody* body = physics_.body(object);
    const btTransform target = target_of(held);
    const double error = static_cast<double>((body->getWorldTransform().getOrigin() - target.getOrigin()).length());
    if (error > settings_.max_hold_error_m) {
      if (held.stuck_since_s < 0.0) held.stuck_since_s = physics_.time_s();
      if (physics_.time_s() - held.stuck_since_s > 0.1) {
        for (int hand = 0; hand < 2; ++hand) {
          if (held.by[static_cast<std::size_t>(hand)])
            to_release.push_back({object, hand, "pulled out of the grip (kept " + millimetres(error) + " from it)"});
        }
        continue;
      }
    } else {
      held.stuck_since_s = -1.0;
    }
    for (int hand = 0; hand < 2; ++hand) {
      auto& grip = held.by[static_cast<std::size_t>(hand)];
      const HandColliders* h = hands_[static_cast<std::size_t>(hand)];
      if (!grip || !h->active()) continue;  // a lost hand keeps holding
      bool anchor_open = false, any_anchor = false;
      bool fingers_open = true, any_finger = false;
      std::string anchor_reason, finger_names;
      double finger_out_m = 0.0;
      const btScalar grown = static_cast<btScalar>(physics_.scale(object) / grip->scale);  // the object's scale since the grip points
      remember_last_bones(hand, *grip, *body, target);
      std::array<double, 5> left_m{};  // per finger: finger_left_m
      for (int f = 1; f <= 4; ++f) left_m[static_cast<std::size_t>(f)] = finger_left_m(hand, *grip, f, *body, target);
      bool by_last_bone = false;
      // Each point's distance out, and whether it has been out for open_for_s (GripPoint::open): a
      // few frames' jitter of a measured finger (its bones' estimate swings by several millimetres
      // from frame to frame in the realistic world) is no opening.
      std::vector<double>& out = point_out_m_;
      out.assign(grip->grip.size(), 0.0);
      for (std::size_t i = 0; i < grip->grip.size(); ++i) {
        GripPoint& g = grip->grip[i];
        const bool trusted = grip_confidence(hand, g) >= settings_.confident;
        if (trusted && !g.measured) {
          // Measured for the first time since the grasp: held from where it is now. A finger that
          // joined the grip hidden keeps its point on the surface it was placed against: measured
          // away from it, it has opened (else a hand opening as the finger comes into view would
          // hold on until the finger moved another release distance).
          if (!g.joined) g.on_object = target.inverse() * (h->tracked_bone(g.bone) * g.on_bone) / grown;
          g.measured = true;
        }
        const double left = g.group == kPalmGroup ? 0.0 : left_m[static_cast<std::size_t>(g.group)];
        out[i] = std::max(out_of_surface_m(hand, g, target, grown), left);
        // A frame it is not measured (or its hand is lost) is no evidence either way: the run goes
        // on through it, but only measured frames count toward open_for_s.
        const bool out_now = trusted && out[i] > settings_.release_distance_m;
        if (trusted && !out_now) {
          g.open_for_s = -1.0;
        } else if (out_now) {
          g.open_for_s = g.open_for_s < 0.0 ? 0.0 : g.open_for_s + physics_.step_s();
        }
        g.open = out_now && g.open_for_s >= settings_.open_for_s - 1e-9;
      }
      // A finger that joined the grip has opened when any of its points has: its points were all
      // taken at one moment, and a straightening finger's first bone stays by the surface it
      // touched while its last bones leave it (the bar, let go at the workbench's rack).
      std::array<bool, 5> joined_open{};
      for (const GripPoint& g : grip->grip) {
        if (g.joined && g.measured && g.open) joined_open[static_cast<std::size_t>(g.group)] = true;
      }
      for (std::size_t i = 0; i < grip->grip.size(); ++i) {
        GripPoint& g = grip->grip[i];
        const double left = g.group == kPalmGroup ? 0.0 : left_m[static_cast<std::size_t>(g.group)];
        const double out_m = out[i];
        g.open = g.open || (g.joined && g.measured && joined_open[static_cast<std::size_t>(g.group)]);
        const bool open = g.open;
        if (g.group == 0 || g.group == kPalmGroup) {
          any_anchor = true;
          if (open && !anchor_open) anchor_reason = std::string(digit_name(g.group)) + " opened " + millimetres(out_m) + " (measured)";
          anchor_open = anchor_open || open;
        } else {
          any_finger = true;
          fingers_open = fingers_open && open;
          if (finger_names.find(digit_name(g.group)) == std::string::npos)
            finger_names += std::string(finger_names.empty() ? "" : ", ") + digit_name(g.group);
          finger_out_m = std::max(finger_out_m, out_m);
          by_last_bone = by_last_bone || (open && left >= out_m);
        }
      }
      // The anchor opens when any of its grip points left; fingers when all of theirs did.
      if (any_anchor && anchor_open) {
        to_release.push_back({object, hand, anchor_reason});
      } else if (any_finger && fingers_open) {
        to_release.push_back(
            {object, hand,
             finger_names + " opened " + millimetres(finger_out_m) + (by_last_bone ? " (measured, last bone)" : " (measured)")});
      }
    }
  }
  for (std::size_t i = 0; i < to_release.size(); ++i) {
    auto& [object, hand, reason] = to_release[i];
    const bool both = (i + 1 < to_release.size() && to_release[i + 1].object == object) || (i > 0 && to_release[i - 1].object == object);
    release(object, hand, both ? LetGo::kBoth : LetGo::kOpened, std::move(reason));
  }
}

// New grasps: a hand not holding anything whose anchor (thumb or palm) and a curled finger touch
// one grabbable object with opposing normals.
void GraspSystem::begin_new_grasps(World& world, const HandContacts& contacts) {
  for (int hand = 0; hand < 2; ++hand) {
    HandColliders* h = hands_[static_cast<std::size_t>(hand)];
    if (!h || !h->active()) continue;
    if (physics_.time_s() - released_at_s_[static_cast<std::size_t>(hand)] < settings_.regrasp_delay_s) continue;
    if (holding(side_of(hand))) continue;
    for (const auto& [object, list] : contacts[static_cast<std::size_t>(hand)]) {
      btRigidBody* body = physics_.body(object);
      if (!body || body->isStaticOrKinematicObject() || !world.alive(object) || !world.has<Grabbable>(object)) continue;
      if (const auto it = held_.find(object); it != held_.end() && it->second.by[static_cast<std::size_t>(hand)]) continue;
      // Contacts by group; an anchor and a finger oppose when any pair of their contacts does
      // (the thumb's tip may be on the far side while its base touches the near face), with the
      // contacts' own normals or with those their finger pads feel. Either, because a pad near an
      // edge presses on both faces: 3 mm beside a peg's edge it pushes with the rounded normal,
      // and just below a cube's top edge, pinching, it still pushes with its face's.
      struct Normals {
        btVector3 own, pad;
      };
      std::array<std::vector<Normals>, 6> by_group;
      for (const Contact& c : list) {
        by_group[static_cast<std::size_t>(hand_bones()[static_cast<std::size_t>(c.bone)].group)].push_back(
            {c.normal, pad_normal(*body, c.point, c.normal, settings_.pad_radius_m)});
      }
      const auto oppose = [&](int a, int b) {
        for (const Normals& x : by_group[static_cast<std::size_t>(a)]) {
          for (const Normals& y : by_group[static_cast<std::size_t>(b)]) {
            if (static_cast<double>(x.own.dot(y.own)) < settings_.opposing_cos ||
                static_cast<double>(x.pad.dot(y.pad)) < settings_.opposing_cos)
              return true;
          }
        }
        return false;
      };
      std::vector<int> groups;
      for (const int anchor : {0, kPalmGroup}) {
        if (by_group[static_cast<std::size_t>(anchor)].empty()) continue;
        std::vector<int> opposing;
        for (int f = 1; f <= 4; ++f) {
          if (!by_group[static_cast<std::size_t>(f)].empty() && curl_rad(hand, f) >= settings_.min_curl_rad && oppose(anchor, f))
            opposing.push_back(f);
        }
        if (!opposing.empty()) {
          groups = opposing;
          groups.push_back(anchor);
          break;
        }
      }
      if (groups.empty()) continue;
      begin_grasp(world, hand, object, list, groups);
      break;  // one object per hand
    }
  }
}

// Collisions resume once no bone of the releasing hand overlaps the object.
void GraspSystem::resume_collisions() {
  std::erase_if(reenable_, [&](const std::pair<Entity, int>& r) {
    btRigidBody* body = physics_.body(r.first);
    HandColliders* h = hands_[static_cast<std::size_t>(r.second)];
    if (!body || !h) return true;
    if (const auto it = held_.find(r.first); it != held_.end() && it->second.by[static_cast<std::size_t>(r.second)]) return true;
    btVector3 lo, hi;
    body->getAabb(lo, hi);
    const btVector3 pad(0.002f, 0.002f, 0.002f);
    for (int i = 0; i < kHandBoneCount; ++i) {
      btVector3 blo, bhi;
      h->bone(i)->getAabb(blo, bhi);
      if (TestAabbAgainstAabb2(lo - pad, hi + pad, blo, bhi)) return false;
    }
    ignore_hand(body, r.second, false);
    return true;
  });
}

}  // namespace rhot
