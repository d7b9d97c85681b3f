#pragma once
// Grasping through contacts (docs/grasping.md).
//
// A grasp begins when the thumb (or the palm) and at least one other finger of one hand touch the
// same grabbable dynamic object, the finger curled and some pair of their contacts' normals
// roughly opposed (or the normals a finger pad of `pad_radius_m`, 10 mm by default, feels: on a
// box, rounded by it).
// The held object then follows the hand: every step its velocity is set to bring it to where the
// grasp found it relative to the hand frame (a velocity-level constraint that keeps the grip
// offset, like the hand bones themselves), without gravity and without colliding with that
// hand's bones (fingers squeezing into it would otherwise push it around; the contacts they had
// are cleared as the grasp begins); it still collides with everything else.
//
// The grasp ends when the fingers open: a grasping finger counts as open when its tracked bone
// has moved more than `release_distance_m` out of the object's surface from where it touched
// (measured so for `open_for_s` of the frames it is measured in: a few frames' jitter is no
// opening), or
// (a finger other than the thumb) its measured last bone has gone that much farther from the
// object than it came, straightening; the grasp ends when the thumb (or palm) or every opposing
// finger is open. A finger whose joints are not measured this frame (confidence below
// `confident`: a hidden fingertip marker, say) never counts as open, so a hand whose curled
// fingers hide their own markers keeps holding; and a
// finger that was not measured when the grasp began is re-anchored where it is the first time it
// is (its estimate may have been centimetres off: the jump to its marker is no opening). A finger
// that closes on the held object after the grasp began (curled, a bone touching it, opposing the
// thumb or palm) joins the grip (`fingers_join`), so a grasp begun by the first finger to touch
// does not end when that finger alone moves off while the others hold. On
// release the object takes the hand's velocity, fitted by least squares over a window that ends
// a little before the release (the hand slows while it opens), and its angular velocity, so it
// can be thrown. A hand cannot grasp again within `regrasp_delay_s` of releasing.
//
// Two hands: another hand that grasps a held object joins the grasp (when the object is
// `Grabbable::two_handed`; otherwise it takes the object over). Held in both, the object keeps its
// pose in the frame the hands span: origin midway between their grips, x along the line from the
// left grip to the right one, y the hands' mean roll about that line; so it moves with both hands'
// midpoint and turns with the line between them, and (with `scale_with_hands`) grows and shrinks
// with their distance. When one hand lets go, the other keeps the object where the pair held it
// (a hand-over: its release says `handed_over`), and carries on alone without a jump, each measured
// grip point keeping how far it had opened (two hands letting go together both let go).
//
// Collisions between a released object and its hand's bones resume once no bone overlaps it.

#include <array>
#include <deque>
#include <limits>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "engine/core/Entity.h"
#include "engine/physics/HandColliders.h"
#include "engine/physics/PhysicsWorld.h"
#include "engine/scene/SceneDesc.h"

namespace rhot {

class World;

enum class InteractionEventType {
  kHoverBegin,
  kHoverEnd,
  kContactBegin,
  kContactEnd,
  kGrasp,
  kRelease,
  kSuccess,
  kPress,       // a button pushed past its press depth by a fingertip (subject: the button)
  kUnpress,     // ... and back above its release depth
  kSnap,        // a socket took an object (subject: the socket, object: what it took)
  kUnsnap,      // a hand took it out
  kValueAbove,  // a joint's value rose past a rule's threshold (subject: the joint's entity, value)
  kValueBelow,  // ... fell below it
  kPoke,        // a fingertip touched a pokeable entity (subject), untouched by fingertips for 0.2 s before
  kEnter,       // an object's centre came into a zone (subject: the zone, object: what came in)
  kExit,        // ... and left it
};
const char* event_name(InteractionEventType type);

struct InteractionEvent {
  InteractionEventType type;
  double time_s = 0.0;
  Entity object;                                           // the object (for kSuccess: the interaction's object)
  std::optional<HandSide> hand;                            // none for kSuccess
  std::string interaction;                                 // kSuccess: the interaction's name
  bool handed_over = false;                                // kRelease: the other hand took the object
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();  // kRelease: what the object was given
  Entity subject;                                          // kPress.., kSnap.., kValue..: the button, socket or joint's entity
  double value = 0.0;                                      // kValueAbove, kValueBelow: the threshold crossed
  // kGrasp: which digits grasp ("thumb against index, middle", with those only estimated);
  // kRelease: the evidence that ended it ("thumb opened 14 mm", "pulled out of the grip", ...).
  std::string reason;
};

class GraspSystem {
 public:
  GraspSystem(PhysicsWorld& physics, std::array<HandColliders*, 2> hands, GraspSettings settings = {});

  // Before the physics step: held objects are aimed at their grip.
  void pre_step(World& world);
  // After the physics step: contacts read, grasps begun and ended, events raised.
  void post_step(World& world);

  // Events of the last post_step.
  const std::vector<InteractionEvent>& events() const { return events_; }
  // The hand holding `object` (the left one when both do).
  std::optional<HandSide> held_by(Entity object) const;
  bool held_by_both(Entity object) const;
  std::optional<Entity> holding(HandSide hand) const;
  const GraspSettings& settings() const { return settings_; }
  // Where the hand holds `object` now (world), if held.
  std::optional<btTransform> grip_target(Entity object) const;
  // The objects held now, by one hand or two.
  std::vector<Entity> held_objects() const;
  // Whether some hand is seen to hold `object` now: a grip point of each side of the grasp (the
  // anchor, and a finger) measured this frame and not open, as release_opened() judged it this
  // step (out of the surface for open_for_s: a frame's jitter is no opening). False for an object
  // not held, and for one held only by digits that are hidden or measured open.
  bool grip_seen_closed(Entity object) const;
  // Something other than the hand takes `object` out of its grip (a socket it is seated in):
  // every hand holding it lets go with `reason`, as when it opens (the object keeps the hand's
  // velocity). Returns the release events, which are also this step's; none if it was not held.
  std::vector<InteractionEvent> let_go(Entity object, const std::string& reason);

  struct Contact {
    int bone;
    btVector3 point;   // world, on the object
    btVector3 normal;  // world, out of the object toward the bone
  };
  using HandContacts = std::array<std::unordered_map<Entity, std::vector<Contact>>, 2>;  // per hand, per object
  // The hand bones touching each object in the last post_step.
  const HandContacts& contacts() const { return contacts_; }

 private:
  struct GripPoint {
    int bone = 0;
    int group = 0;
    btVector3 on_object;  // object frame
    btVector3 normal;     // object frame, outward
    btVector3 on_bone;    // tracked bone frame
    // Its finger was measured when it entered the grip (else: it is, once measured, re-anchored
    // there, unless it joined the grip: GraspSystem::join_fingers).
    bool measured = true;
    bool joined = false;  // added after the grasp began (join_fingers): its point is on the surface it touched
    // How long it has been measured out of the surface, in the frames it was measured, since it last
    // was measured in (release_opened); -1: it is not out.
    double open_for_s = -1.0;
    bool open = false;           // release_opened's verdict this step (out for open_for_s, or its joined finger's other point is)
    double out_carried_m = 0.0;  // how far out it had moved when taken afresh as the other hand let go (release)
  };
  // One hand's hold of an object.
  struct HandGrip {
    btTransform hand_from_object;  // where the object is, hand frame (while this hand holds it alone)
    std::vector<GripPoint> grip;
    btVector3 centre;              // hand frame: the middle of its grip points
    double began_s = 0.0;          // physics time of the grasp (join_fingers: hidden fingers join only soon after)
    btQuaternion rotation_paired;  // the hand's rotation (world) when the other hand joined
    double scale = 1.0;            // the object's scale (PhysicsWorld::scale) when the grip points were taken
    // Per finger (index 1-4; the thumb and palm open by their grip points alone): the nearest its
    // last bone came to the object while its tip was measured, since the grip began (+infinity:
    // not measured since), its curl then, and its curl when first measured in the grip (-infinity:
    // not yet). See finger_left_m.
    std::array<double, 5> last_bone_nearest_m{kFar, kFar, kFar, kFar, kFar};
    std::array<double, 5> curl_at_nearest_rad{};
    std::array<double, 5> curl_at_start_rad{-kFar, -kFar, -kFar, -kFar, -kFar};
  };
  static constexpr double kFar = std::numeric_limits<double>::infinity();
  // A finger whose last bone left the object has also straightened by this much, since it came
  // nearest and since it was first measured in the grip: a finger curling on past a thin handle takes its last bone
  // away from it too, but closing; one that squeezed and relaxed is back where it grasped.
  static constexpr double kOpenedCurl_rad = 0.3;
  // A hidden finger joins a grip only this soon after the grasp began, as the hand closes on the
  // object: later, while carrying, the hidden-finger rule keeps placing hidden fingers against what
  // the hand holds whether or not they are there, and those could hold the grip closed as the hand
  // opens (docs/grasping.md, "Fingers join the grip", and what joining still costs at the bar).
  static constexpr double kHiddenJoinWindow_s = 0.5;
  struct Held {
    std::array<std::optional<HandGrip>, 2> by;  // per hand (left, right)
    Grabbable options;
    // Both hands: the object in the frame they span, when they began holding it together.
    btTransform pair_from_object;
    btVector3 pair_up;  // world: that frame's y then
    double span_m = 0.0;
    double scale_paired = 1.0;
    std::deque<std::pair<double, btTransform>> history;  // (time, target)
    double stuck_since_s = -1.0;

    bool both() const { return by[0] && by[1]; }
    int first() const { return by[0] ? 0 : 1; }
  };
  struct PairState {
    bool hovering = false;
    bool touching = false;
  };

  // post_step's phases, in order.
  HandContacts read_contacts() const;
  void update_hover_and_contact(const HandContacts& contacts);
  void join_fingers();
  void release_opened();
  void begin_new_grasps(World& world, const HandContacts& contacts);
  void resume_collisions();

  void begin_grasp(World& world, int hand, Entity object, const std::vector<Contact>& contacts, const std::vector<int>& groups);
  // How a hand lets go: it opened (a hand-over when the other still holds), the other hand took
  // the object from it (a hand-over), or both let go at once (none).
  enum class LetGo { kOpened, kTaken, kBoth };
  // Two grips closer than this do not make a pair: the second hand takes the object over.
  static constexpr double kMinPairSpan_m = 0.05;
  void release(Entity object, int hand, LetGo how, std::string reason);
  static std::string grasp_reason(const HandGrip& grip);
  btTransform target_of(const Held& held) const;
  btVector3 grip_centre(const Held& held, int hand) const;  // world
  btTransform pair_frame(const Held& held) const;
  double pair_scale(const Held& held) const;
  void ignore_hand(btRigidBody* object, int hand, bool ignore);
  void emit(InteractionEventType type, Entity object, std::optional<int> hand);
  double curl_rad(int hand, int finger) const;
  // How far a grip point's bone is out of the object's surface now, along its normal at the point
  // (metres; negative: pressed in): `target` where the grip has the object, `grown` its scale
  // since the grip point was taken.
  double out_of_surface_m(int hand, const GripPoint& g, const btTransform& target, btScalar grown) const;
  // The confidence of the joint that tells whether a grip point's finger is measured.
  double grip_confidence(int hand, const GripPoint& g) const;
  // How far a finger's last bone (its centre line) is from the object where the grip has it
  // (`target`; metres), or nothing while its tip is not measured or the object's shape is not
  // convex.
  std::optional<double> last_bone_distance_m(int hand, int finger, const btRigidBody& body, const btTransform& target) const;
  // Remembers how near each measured grasping finger's last bone came to the object, and its curls.
  void remember_last_bones(int hand, HandGrip& grip, const btRigidBody& body, const btTransform& target) const;
  // How far a grasping finger's measured last bone has gone from the object since it came nearest,
  // where the finger has also straightened by kOpenedCurl_rad since then and since first measured;
  // 0 otherwise. A hand holding the workbench's bar by its fingers' middle bones, thumb hidden,
  // straightens them by 1.5 rad as it lets go while those grip points move only 6-12 mm.
  double finger_left_m(int hand, const HandGrip& grip, int finger, const btRigidBody& body, const btTransform& target) const;

  PhysicsWorld& physics_;
  std::array<HandColliders*, 2> hands_;
  GraspSettings settings_;
  std::unordered_map<Entity, Held> held_;
  std::array<double, 2> released_at_s_{-1e9, -1e9};
  // release_opened's per grip point distances out, kept so that a frame allocates nothing.
  std::vector<double> point_out_m_;
  std::vector<std::pair<Entity, int>> reenable_;  // (object, hand) whose collisions resume once clear
  std::unordered_map<Entity, std::array<PairState, 2>> pairs_;
  std::vector<InteractionEvent> events_;
  HandContacts contacts_;
};

}  // namespace rhot
