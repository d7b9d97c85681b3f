#include "engine/interact/FingerContact.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <unordered_map>
#include <vector>

#include <BulletCollision/CollisionShapes/btCapsuleShape.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkEpaPenetrationDepthSolver.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkPairDetector.h>
#include <BulletCollision/NarrowPhaseCollision/btPointCollector.h>
#include <BulletCollision/NarrowPhaseCollision/btVoronoiSimplexSolver.h>
#include <Eigen/Geometry>
#include <glm/gtc/quaternion.hpp>

#include "engine/core/Transform.h"
#include "engine/core/World.h"
#include "engine/interact/GraspSystem.h"
#include "engine/physics/HandColliders.h"
#include "engine/physics/BulletMath.h"
#include "engine/scene/Components.h"
#include "engine/physics/PhysicsWorld.h"

namespace rhot {

namespace {

// A digit's joints from its first knuckle that can bend to its tip, and how much each knuckle
// bends for one unit of curl (a finger's last knuckle follows the middle one at about two
// thirds, as real fingers' do).
struct DigitChain {
  std::array<int, 4> joints;  // knuckles then the tip; -1 past the end
  std::array<double, 3> weight;
  int count;  // joints used (3 for the thumb: two knuckles and its tip; 4 for a finger)
};

DigitChain digit_chain(int digit) {
  if (digit == 0) {
    return {{static_cast<int>(HandJoint::kThumbProximal), static_cast<int>(HandJoint::kThumbDistal), static_cast<int>(HandJoint::kThumbTip),
             -1},
            {1.0, 1.0, 0.0},
            3};
  }
  const int base = static_cast<int>(HandJoint::kIndexProximal) + 5 * (digit - 1);
  return {{base, base + 1, base + 2, base + 3}, {1.0, 1.0, 0.7}, 4};
}

constexpr double kFlicker_s = 0.3;  // a digit hidden no longer than this was only flickering
// A closing digit hidden no longer than this reaches for what is within its length, and says its
// hand closes.
constexpr double kReaching_s = 0.5;
// A fingertip moves no faster than this in its hand's frame: a faster one is a marker's jump, and
// would lift the bound on how far a hidden digit can have moved for as long as it stays hidden.
constexpr double kMaxTipSpeed_mps = 3.0;

// A world transform without its scale.
Rigid3d rigid_from(const glm::mat4& world_from_local) {
  glm::mat3 r(world_from_local);
  for (int k = 0; k < 3; ++k) {
    const float length = glm::length(r[k]);
    if (length > 0.0f) r[k] /= length;
  }
  const glm::quat q = glm::quat_cast(r);
  const glm::vec3 t(world_from_local[3]);
  return Rigid3d{Eigen::Quaternionf(q.w, q.x, q.y, q.z).cast<double>().normalized(), Eigen::Vector3f(t.x, t.y, t.z).cast<double>()};
}

// The distance from p to the box from lo to hi (0 inside it).
double box_gap_m(const btVector3& lo, const btVector3& hi, const btVector3& p) {
  btVector3 gap(0, 0, 0);
  for (int a = 0; a < 3; ++a) gap[a] = std::max({lo[a] - p[a], p[a] - hi[a], btScalar(0)});
  return static_cast<double>(gap.length());
}

// The collider's radius of the bone from joint a to joint b (HandColliders: the smaller of its
// joints', at least min_radius_m).
double bone_radius_m(const HandInput& hand, std::size_t a, std::size_t b) {
  return std::max(HandColliderSettings{}.min_radius_m, std::min(hand.radius_m[a], hand.radius_m[b]));
}

bool all_finite(const HandInput& hand) {
  for (const Eigen::Vector3d& j : hand.joints_world)
    if (!j.allFinite()) return false;
  return hand.world_from_hand.translation.allFinite() && hand.world_from_hand.rotation.coeffs().allFinite();
}

// A contact by the palm or by a digit whose tip is measured (confidence at least `confident`).
bool measured_contact_of(const HandInput& hand, const GraspSystem::Contact& c, double confident) {
  const int group = hand_bones()[static_cast<std::size_t>(c.bone)].group;
  if (group == kPalmGroup) return true;
  const DigitChain chain = digit_chain(group);
  return hand.confidence[static_cast<std::size_t>(chain.joints[static_cast<std::size_t>(chain.count - 1)])] >= confident;
}

// Curls a digit of `hand` (its joints after knuckle `first`) about `axis` until its bones rest
// `rest_m` off the body's surface (negative: into it), each knuckle turning by its weight: the
// angle turned (negative: uncurled out of the body), or nothing where the digit cannot reach the
// body (or leave it) within the limits. The hand is changed only when it returns an angle.
std::optional<double> rest_digit(HandInput& hand, const DigitChain& chain, int first, const Eigen::Vector3d& axis, const btRigidBody& body,
                                 double rest_m, double max_curl_rad, double max_uncurl_rad) {
  const auto at = [&](int k) { return static_cast<std::size_t>(chain.joints[static_cast<std::size_t>(k)]); };
  const auto curled = [&](double theta) {
    std::array<Eigen::Vector3d, 4> p;
    for (int k = 0; k < chain.count; ++k) p[static_cast<std::size_t>(k)] = hand.joints_world[at(k)];
    for (int k = first; k < chain.count - 1; ++k) {
      const Eigen::AngleAxisd turn(chain.weight[static_cast<std::size_t>(k)] * theta, axis);
      for (int m = k + 1; m < chain.count; ++m)
        p[static_cast<std::size_t>(m)] =
            p[static_cast<std::size_t>(k)] + turn * (p[static_cast<std::size_t>(m)] - p[static_cast<std::size_t>(k)]);
    }
    return p;
  };
  const auto radius = [&](int k) { return bone_radius_m(hand, at(k), at(k + 1)); };
  // How far the curled digit's bones are out of the body, less the rest: <= 0 is resting on it.
  const auto gap = [&](double theta) {
    const auto p = curled(theta);
    double d = std::numeric_limits<double>::infinity();
    for (int k = first; k < chain.count - 1; ++k)
      d = std::min(d, capsule_distance_m(body, p[static_cast<std::size_t>(k)], p[static_cast<std::size_t>(k + 1)], radius(k)));
    return d - rest_m;
  };
  // gap(theta) <= 0, asking the exact distance only of bones that the body's bounding box does not
  // already put beyond the rest (a bone is no nearer the body than its box, less its half length
  // and radius, from its middle): the march below needs only the sign, and the distance queries
  // were most of a step's placement.
  btVector3 box_lo, box_hi;
  body.getAabb(box_lo, box_hi);
  const auto box_distance = [&](const Eigen::Vector3d& x) {
    double d2 = 0.0;
    for (int a = 0; a < 3; ++a) {
      const double out = std::max({static_cast<double>(box_lo[a]) - x[a], x[a] - static_cast<double>(box_hi[a]), 0.0});
      d2 += out * out;
    }
    return std::sqrt(d2);
  };
  const auto touches = [&](double theta) {
    const auto p = curled(theta);
    for (int k = first; k < chain.count - 1; ++k) {
      const Eigen::Vector3d& a = p[static_cast<std::size_t>(k)];
      const Eigen::Vector3d& b = p[static_cast<std::size_t>(k + 1)];
      if (box_distance(0.5 * (a + b)) - 0.5 * (b - a).norm() - radius(k) > rest_m + 1e-6) continue;
      if (capsule_distance_m(body, a, b, radius(k)) - rest_m <= 0.0) return true;
    }
    return false;
  };
  // March toward the rest (curling when clear of it, uncurling when deeper), then halve the last
  // step five times.
  constexpr double kStep_rad = 0.1, kTolerance_m = 0.0005;
  const double g0 = gap(0.0);
  if (!std::isfinite(g0)) return std::nullopt;
  if (g0 <= 0.0 && g0 >= -kTolerance_m) return 0.0;  // resting already
  const bool inside = g0 < 0.0;
  if (!inside) {
    // Every point of the curled digit stays within its bones' summed length of the knuckle it
    // turns about: a body's box farther than that (and the radius) is never reached.
    double reach = 0.0, thickest = 0.0;
    for (int k = first; k < chain.count - 1; ++k) {
      reach += (hand.joints_world[at(k + 1)] - hand.joints_world[at(k)]).norm();
      thickest = std::max(thickest, radius(k));
    }
    if (box_distance(hand.joints_world[at(first)]) - reach - thickest > rest_m + 1e-6) return std::nullopt;
  }
  const double direction = inside ? -1.0 : 1.0, limit = inside ? max_uncurl_rad : max_curl_rad;
  double before = 0.0, after = -1.0;
  for (double theta = kStep_rad; theta <= limit + 1e-9; theta += kStep_rad) {
    if (touches(direction * theta) != inside) {
      after = theta;
      break;
    }
    before = theta;
  }
  // A limit between two steps (a hidden digit's, bounded by how far it can have moved) is tried too.
  if (after < 0.0 && before < limit - 1e-9 && touches(direction * limit) != inside) after = limit;
  if (after < 0.0) return std::nullopt;
  for (int i = 0; i < 5; ++i) {
    const double mid = 0.5 * (before + after);
    (touches(direction * mid) != inside ? after : before) = mid;
  }
  // Curling: the first angle resting; uncurling: the last one still on it.
  const double theta = direction * (inside ? before : after);
  const auto p = curled(theta);
  for (int k = first + 1; k < chain.count; ++k) hand.joints_world[at(k)] = p[static_cast<std::size_t>(k)];
  return theta;
}

// A curl of theta from knuckle `first` moves the digit's tip at most theta times this: the sum of
// its knuckles' weighted distances to the tip (at least a millimetre).
double tip_lever_m(const HandInput& hand, const DigitChain& chain, int first) {
  const Eigen::Vector3d& tip = hand.joints_world[static_cast<std::size_t>(chain.joints[static_cast<std::size_t>(chain.count - 1)])];
  double lever_m = 0.0;
  for (int k = first; k < chain.count - 1; ++k) {
    lever_m += chain.weight[static_cast<std::size_t>(k)] *
               (tip - hand.joints_world[static_cast<std::size_t>(chain.joints[static_cast<std::size_t>(k)])]).norm();
  }
  return std::max(lever_m, 1e-3);
}

}  // namespace

double capsule_distance_m(const btCollisionObject& object, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius_m) {
  return capsule_gap(object, a, b, radius_m).distance_m;
}

CapsuleGap capsule_gap(const btCollisionObject& object, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius_m) {
  const btCollisionShape* shape = object.getCollisionShape();
  if (!shape || !shape->isConvex()) return {};
  const Eigen::Vector3d axis = b - a;
  const double length = axis.norm();
  btCapsuleShape capsule(static_cast<btScalar>(radius_m), static_cast<btScalar>(length));
  btTransform pose = btTransform::getIdentity();
  pose.setOrigin(to_bt(0.5 * (a + b)));
  if (length > 1e-9) pose.setRotation(shortestArcQuat(btVector3(0, 1, 0), to_bt(axis / length)));
  btVoronoiSimplexSolver simplex;
  btGjkEpaPenetrationDepthSolver depth;
  btGjkPairDetector gjk(&capsule, static_cast<const btConvexShape*>(shape), &simplex, &depth);
  btGjkPairDetector::ClosestPointInput in;
  in.m_transformA = pose;
  in.m_transformB = object.getWorldTransform();
  btPointCollector out;
  gjk.getClosestPoints(in, out, nullptr);
  if (!out.m_hasResult) return {};
  return {static_cast<double>(out.m_distance), to_eigen(out.m_pointInWorld), to_eigen(out.m_normalOnBInWorld)};
}

double digit_curl_rad(const HandInput& hand, int digit) {
  const DigitChain chain = digit_chain(digit);
  const auto joint = [&](int index) { return hand.joints_world[static_cast<std::size_t>(index)]; };
  const int root = chain.joints[0] - 1;  // the metacarpal joint behind the first knuckle
  const Eigen::Vector3d first = joint(chain.joints[0]) - joint(root);
  const Eigen::Vector3d last =
      joint(chain.joints[static_cast<std::size_t>(chain.count - 1)]) - joint(chain.joints[static_cast<std::size_t>(chain.count - 2)]);
  if (first.norm() < 1e-9 || last.norm() < 1e-9) return 0.0;
  return std::acos(std::clamp(first.normalized().dot(last.normalized()), -1.0, 1.0));
}

void FingerContact::follow(std::size_t side, double t_s, const HandInput& hand) {
  const Rigid3d hand_from_world = hand.world_from_hand.inverse();
  for (int digit = 0; digit < 5; ++digit) {
    DigitMotion& m = motion_[side][static_cast<std::size_t>(digit)];
    const DigitChain chain = digit_chain(digit);
    const bool measured = hand.seen && hand.confidence[static_cast<std::size_t>(chain.joints[static_cast<std::size_t>(chain.count - 1)])] >=
                                           settings_.confident;
    if (!measured) {
      m.hidden = true;  // its rate stays what it was when last seen
      continue;
    }
    const double curl = digit_curl_rad(hand, digit);
    const Eigen::Vector3d tip =
        hand_from_world * hand.joints_world[static_cast<std::size_t>(chain.joints[static_cast<std::size_t>(chain.count - 1)])];
    const double dt = t_s - m.t_s;
    // Measured again after a short gap (a marker that flickers), the rate goes on across the gap;
    // after a long one it starts afresh.
    if (m.t_s >= 0.0 && dt > 0.0 && dt <= kFlicker_s) {
      const double blend = std::min(1.0, dt / 0.1);
      m.rate_rad_s += blend * ((curl - m.curl_rad) / dt - m.rate_rad_s);
      m.tip_speed_mps += blend * (std::min((tip - m.tip_hand).norm() / dt, kMaxTipSpeed_mps) - m.tip_speed_mps);
    } else {
      m.rate_rad_s = 0.0;
      m.tip_speed_mps = 0.0;
    }
    m.curl_rad = curl;
    m.tip_hand = tip;
    m.t_s = t_s;
    m.hidden = false;
    m.hidden_speed_mps = 0.0;
    m.may_have_moved_m = 0.0;
  }
  // How far each hidden digit's tip may have moved in the hand since it hid: at its own speed
  // when last seen, or its hand's since, whichever is faster (the fastest tip of the digits
  // measured now or hidden only kReaching_s ago, as they were last seen). A tip's speed, not a
  // curl's rate: the thumb closes by turning more than by curling.
  double hand_speed_mps = 0.0;
  for (const DigitMotion& m : motion_[side]) {
    if (m.t_s >= 0.0 && t_s - m.t_s <= kReaching_s) hand_speed_mps = std::max(hand_speed_mps, m.tip_speed_mps);
  }
  const double dt = followed_t_s_[side] >= 0.0 ? std::clamp(t_s - followed_t_s_[side], 0.0, 0.1) : 0.0;
  followed_t_s_[side] = t_s;
  for (DigitMotion& m : motion_[side]) {
    if (!m.hidden) continue;
    m.hidden_speed_mps = std::max({m.hidden_speed_mps, m.tip_speed_mps, hand_speed_mps});
    m.may_have_moved_m += m.hidden_speed_mps * dt;
  }
}

std::optional<Entity> FingerContact::object_for(const World& world, HandSide side, const HandInput& hand,
                                                const std::array<bool, 5>& closing, const std::array<bool, 5>& reaching) const {
  if (const auto held = grasp_.holding(side)) return held;
  if (const Carry& c = carry_[side == HandSide::kLeft ? 0 : 1]; c.carried) return c.object;
  // The body (not a static one) that the most bones of measured digits touched.
  const auto& touched = grasp_.contacts()[side == HandSide::kLeft ? 0 : 1];
  std::optional<Entity> best;
  std::size_t most = 0;
  for (const auto& [object, contacts] : touched) {
    const btRigidBody* body = physics_.body(object);
    if (!body || body->isStaticObject()) continue;
    // Touched by a measured digit counts first; by a hidden one (its estimate already on it), next.
    std::size_t score = 0;
    for (const GraspSystem::Contact& c : contacts) score += measured_contact_of(hand, c, settings_.confident) ? 1000 : 1;
    if (score > most) {
      most = score;
      best = object;
    }
  }
  if (best || std::none_of(closing.begin(), closing.end(), [](bool c) { return c; })) return best;
  // The hand closing within reach: of the bodies whose bounding box the palm is within
  // hover_distance_m of, or, for a grabbable one, a `reaching` digit could reach (within its own
  // length of its first knuckle), the one nearest the palm. (Only grabbable ones by a digit's reach:
  // fingers curled beside a button the index pokes are not closing on the button.)
  const btVector3 palm = to_bt(hand.joints_world[static_cast<std::size_t>(HandJoint::kPalm)]);
  double nearest = 1e9;
  for (const Entity e : physics_.entities()) {
    const btRigidBody* body = physics_.body(e);
    if (!body || body->isStaticObject()) continue;
    btVector3 lo, hi;
    body->getAabb(lo, hi);
    const double d = box_gap_m(lo, hi, palm);
    bool reach = d <= settings_.hover_distance_m;
    const bool grabbable = world.alive(e) && world.has<Grabbable>(e);
    for (int digit = 0; digit < 5 && !reach && grabbable; ++digit) {
      if (!reaching[static_cast<std::size_t>(digit)]) continue;
      const DigitChain chain = digit_chain(digit);
      const auto at = [&](int k) { return hand.joints_world[static_cast<std::size_t>(chain.joints[static_cast<std::size_t>(k)])]; };
      double length = 0.0;
      for (int k = 0; k + 1 < chain.count; ++k) length += (at(k + 1) - at(k)).norm();
      reach = box_gap_m(lo, hi, to_bt(at(0))) <= length;
    }
    if (reach && d < nearest) {
      nearest = d;
      best = e;
    }
  }
  return best;
}

void FingerContact::follow_carry(const World& world, std::size_t side, double t_s, const HandInput& hand) {
  Carry& c = carry_[side];
  // The tracked object whose bounding box is nearest the palm, within hover_distance_m.
  const btVector3 palm = to_bt(hand.joints_world[static_cast<std::size_t>(HandJoint::kPalm)]);
  std::optional<Entity> near;
  double nearest = settings_.hover_distance_m;
  for (const Entity e : physics_.entities()) {
    const btRigidBody* body = physics_.body(e);
    if (!body || !body->isKinematicObject() || !world.alive(e) || !world.has<TrackedBy>(e)) continue;
    btVector3 lo, hi;
    body->getAabb(lo, hi);
    const double d = box_gap_m(lo, hi, palm);
    if (d <= nearest) {
      nearest = d;
      near = e;
    }
  }
  if (!near) {
    c = Carry{};
    return;
  }
  // Where the object is this frame (its entity's pose; the kinematic body takes it only in the
  // step after this, and a step behind, a hand at 1.3 m/s is 15 mm from it at 90 Hz).
  const WorldTransform* wt = world.find<WorldTransform>(*near);
  const Rigid3d world_from_object = wt ? rigid_from(wt->world_from_local) : to_rigid(physics_.body(*near)->getWorldTransform());
  const Rigid3d hand_from_object = hand.world_from_hand.inverse() * world_from_object;
  if (!world_from_object.is_finite() || !hand_from_object.is_finite()) {
    c = Carry{};
    return;
  }
  const bool same = c.object == near && (hand_from_object.translation - c.hand_from_object.translation).norm() <= settings_.carry_slack_m &&
                    hand_from_object.rotation.angularDistance(c.hand_from_object.rotation) <= settings_.carry_turn_rad;
  // The object begins moving with the hand from here: each digit's curl as last measured then.
  const auto start = [&] {
    c = Carry{near, hand_from_object, world_from_object.translation, false, {}, {}};
    for (std::size_t d = 0; d < 5; ++d) {
      c.curl_rad[d] = motion_[side][d].t_s >= 0.0 ? motion_[side][d].curl_rad : -2.0;
      // Hidden then for longer than a flicker: the object hides it.
      c.hidden[d] = motion_[side][d].hidden && t_s - motion_[side][d].t_s > kFlicker_s;
    }
  };
  if (!same) {
    start();  // another object, or this one moved in the hand (set down, or the hand let go of it)
    return;
  }
  if (!c.carried) {
    // Not carried yet: each digit as it is now, so that the hand's opening is judged against the
    // grip it carries with (a hand reaches the object open and closes on it before lifting it).
    const Carry began = c;
    start();
    c.hand_from_object = began.hand_from_object;
    c.from_m = began.from_m;
    c.carried = (world_from_object.translation - c.from_m).norm() >= settings_.carry_moved_m;
    return;
  }
  // The hand letting go: a measured digit straighter by carry_open_rad than it was (measured) when
  // the object began moving with the hand, or one hidden then (the object hid it) seen again
  // more than carry_slack_m off the object's surface, or two of those seen again wherever they are.
  // Carried no longer, until it moves the object with the hand again.
  const auto& digits = motion_[side];
  const btRigidBody& body = *physics_.body(*near);
  int uncovered = 0;
  for (std::size_t d = 0; d < 5; ++d) uncovered += c.hidden[d] && !digits[d].hidden ? 1 : 0;
  if (uncovered >= 2) {
    start();
    return;
  }
  for (std::size_t d = 0; d < 5; ++d) {
    if (digits[d].hidden || digits[d].t_s < 0.0) continue;
    const bool straighter = c.curl_rad[d] >= -1.0 && digits[d].curl_rad < c.curl_rad[d] - settings_.carry_open_rad;
    bool lifted = false;
    if (c.hidden[d]) {
      const DigitChain chain = digit_chain(static_cast<int>(d));
      const auto at = [&](int k) { return hand.joints_world[static_cast<std::size_t>(chain.joints[static_cast<std::size_t>(k)])]; };
      const double radius_m = bone_radius_m(hand, static_cast<std::size_t>(chain.joints[static_cast<std::size_t>(chain.count - 2)]),
                                            static_cast<std::size_t>(chain.joints[static_cast<std::size_t>(chain.count - 1)]));
      lifted = capsule_distance_m(body, at(chain.count - 2), at(chain.count - 1), radius_m) > settings_.carry_slack_m;
    }
    if (straighter || lifted) {
      start();
      return;
    }
  }
}

FingerPlacement FingerContact::place(const World& world, HandSide side, double t_s, HandInput& hand) {
  FingerPlacement result;
  const std::size_t s = side == HandSide::kLeft ? 0 : 1;
  if (!all_finite(hand)) return result;
  follow(s, t_s, hand);
  if (hand.seen) follow_carry(world, s, t_s, hand);
  if (!hand.seen || settings_.max_curl_rad <= 0.0) return result;
  // Which hidden digits are closing: they were when last seen, or the hand is closing: a measured
  // digit is now, or one hidden only a moment ago (kReaching_s) was when last seen. The thumb
  // closes by turning toward the fingers, barely curling: hidden before the fingers close (a
  // tool's takeover from the other hand, the fingers hiding too as they close), its own rate
  // says nothing.
  bool hand_closing = false, any_hidden = false;
  std::array<bool, 5> closing{};
  for (std::size_t digit = 0; digit < 5; ++digit) {
    const DigitMotion& m = motion_[s][digit];
    const bool was_closing = m.rate_rad_s > settings_.closing_rad_s;
    hand_closing = hand_closing || (was_closing && m.t_s >= 0.0 && t_s - m.t_s <= kReaching_s);  // a measured digit's t_s is now
    any_hidden = any_hidden || m.hidden;
  }
  if (!any_hidden) return result;
  // Reaching: closing, and hidden only a moment ago (a digit hidden since before a grasp, still
  // "closing" as it was last seen, reaches for nothing after the release).
  std::array<bool, 5> reaching{};
  for (std::size_t digit = 0; digit < 5; ++digit) {
    const DigitMotion& m = motion_[s][digit];
    closing[digit] = m.hidden && (hand_closing || m.rate_rad_s > settings_.closing_rad_s);
    reaching[digit] = closing[digit] && m.t_s >= 0.0 && t_s - m.t_s <= kReaching_s;
  }
  result.object = object_for(world, side, hand, closing, reaching);
  if (!result.object) return result;
  const btRigidBody* body = physics_.body(*result.object);
  if (!body) {
    result.object.reset();
    return result;
  }
  // Held, or touched by a measured digit or the palm: every hidden digit goes to the object; else
  // only the closing ones.
  bool in_hand = grasp_.holding(side) == result.object || (carry_[s].carried && carry_[s].object == result.object);
  if (const auto touched = grasp_.contacts()[s].find(*result.object); touched != grasp_.contacts()[s].end()) {
    for (const GraspSystem::Contact& c : touched->second) in_hand = in_hand || measured_contact_of(hand, c, settings_.confident);
  }
  const Eigen::Vector3d centre = to_eigen(body->getWorldTransform().getOrigin());
  const Eigen::Matrix3d hand_rotation = hand.world_from_hand.rotation.toRotationMatrix();
  const Eigen::Vector3d palm_normal = -hand_rotation.col(1);  // the palm faces the hand frame's -Y
  struct Bend {
    int first = 0;
    Eigen::Vector3d axis = Eigen::Vector3d::UnitX();
  };
  std::array<Bend, 5> bends;
  // Closing on a grabbable object not yet held (a held one ignores its hand's bones): just short of it.
  const bool loose = grasp_.holding(side) != result.object && world.alive(*result.object) && world.has<Grabbable>(*result.object);
  const double rest_m = loose ? settings_.rest_gap_m : 0.0;
  const auto holder = grasp_.held_by(*result.object);
  const bool from_other = holder && *holder != side;
  for (int digit = 0; digit < 5; ++digit) {
    const DigitChain chain = digit_chain(digit);
    const auto at = [&](int k) { return static_cast<std::size_t>(chain.joints[static_cast<std::size_t>(k)]); };
    if (hand.confidence[at(chain.count - 1)] >= settings_.confident) continue;
    if (!in_hand && !closing[static_cast<std::size_t>(digit)]) continue;
    // Bend from the first knuckle whose next joint is not measured.
    int first = 0;
    while (first < chain.count - 2 && hand.confidence[at(first + 1)] >= settings_.confident) ++first;
    // Fingers bend about the hand's lateral axis (in their own plane); the thumb turns below.
    Eigen::Vector3d axis = -hand_rotation.col(0);
    if (digit == 0) {
      // The thumb turns about its first knuckle toward the object's surface nearest its last bone
      // (toward the centre of a long handle, 6 cm along it, it swept along the handle and never met
      // it), or, with that straight ahead of it, toward the palm.
      const Eigen::Vector3d along = hand.joints_world[at(chain.count - 1)] - hand.joints_world[at(first)];
      const CapsuleGap gap = capsule_gap(*body, hand.joints_world[at(chain.count - 2)], hand.joints_world[at(chain.count - 1)],
                                         bone_radius_m(hand, at(chain.count - 2), at(chain.count - 1)));
      const Eigen::Vector3d toward = std::isfinite(gap.distance_m) ? gap.on_object : centre;
      Eigen::Vector3d across = along.cross(toward - hand.joints_world[at(first)]);
      if (across.norm() < 1e-6 * along.norm()) across = along.cross(palm_normal);
      if (across.norm() > 1e-9) axis = across.normalized();
    }
    bends[static_cast<std::size_t>(digit)] = {first, axis};
    // Held or touched, the digit goes to the object however far, and closing on a loose one, as far
    // as it must. Closing on one the other hand holds, curled no farther from where the tracker has
    // it than its tip can have moved since it hid (the tracker holds a hidden digit where it was,
    // or curls it with the fingers it sees): the grasp it makes takes the object from that hand (a
    // release, which needs evidence) or joins it (and the object then moves with both). A hidden thumb and finger pulled to a cube
    // as soon as they could reach it took it from the other hand 0.1-0.3 s before the real ones
    // closed on it. (A loose object is not held back so: a grasp a moment early there changes no
    // one's hold, and the measured fingers beside the hidden ones are often a few millimetres short
    // of it.)
    const double max_curl_rad = in_hand || !from_other
                                    ? settings_.max_curl_rad
                                    : std::min(settings_.max_curl_rad, motion_[s][static_cast<std::size_t>(digit)].may_have_moved_m /
                                                                           tip_lever_m(hand, chain, first));
    const auto theta = rest_digit(hand, chain, first, axis, *body, rest_m, max_curl_rad, settings_.max_uncurl_rad);
    if (!theta) continue;  // it never meets (or leaves) the object within reach
    result.placed[static_cast<std::size_t>(digit)] = true;
    result.curl_rad[static_cast<std::size_t>(digit)] = *theta;
  }
  // Held between both sides (the thumb or palm, and a finger, each placed or touching it measured),
  // the placed digits squeeze, as a grasping hand does; on one side only they rest on the surface
  // (a light peg pushed by a hidden index slid away from the thumb still closing on it).
  bool anchor = result.placed[0], finger = false;
  if (const auto touched = grasp_.contacts()[s].find(*result.object); touched != grasp_.contacts()[s].end()) {
    for (const GraspSystem::Contact& c : touched->second) {
      if (!measured_contact_of(hand, c, settings_.confident)) continue;
      const int group = hand_bones()[static_cast<std::size_t>(c.bone)].group;
      (group == 0 || group == kPalmGroup ? anchor : finger) = true;
    }
  }
  for (std::size_t digit = 1; digit < 5; ++digit) finger = finger || result.placed[digit];
  if (!anchor || !finger || settings_.squeeze_m <= 0.0) return result;
  for (std::size_t digit = 0; digit < 5; ++digit) {
    if (!result.placed[digit]) continue;
    const auto more = rest_digit(hand, digit_chain(static_cast<int>(digit)), bends[digit].first, bends[digit].axis, *body,
                                 -settings_.squeeze_m, settings_.max_curl_rad, settings_.max_uncurl_rad);
    if (more) result.curl_rad[digit] += *more;
  }
  result.squeezing = true;
  return result;
}

}  // namespace rhot
