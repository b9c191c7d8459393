/// \file
/// A skeleton's links as kinematic Bullet rigid bodies: what other rigid bodies (and the cape, through the
/// Bullet adapter) collide with.
///
/// One btRigidBody per link that has collision shapes (optionally also for links without: an empty shape),
/// whose frame is the link frame (so the compound child transforms are the URDF collision origins, scaled).
/// Shapes:
/// \verbatim
///   URDF sphere   -> btSphereShape(radius)
///   URDF box      -> btBoxShape(half extents)
///   URDF cylinder -> btCylinderShapeZ(radius, radius, half length): URDF cylinders lie along their local z
///   several elements, or one with an origin other than identity -> btCompoundShape, children in the order of
///   Skeleton::shapes(link), so child k of the compound is ShapeDesc k.
/// \endverbatim
/// Bullet's collision margins do not move these surfaces: a sphere's radius is its margin, and boxes and
/// cylinders keep their margin inside the given extents.
///
/// The bodies are kinematic (mass 0, CF_KINEMATIC_OBJECT, DISABLE_DEACTIVATION): call update(dt) once per
/// frame, after posing the skeleton and before btDynamicsWorld::stepSimulation. It writes each link pose into
/// the body's motion state (what Bullet reads for kinematic bodies at the start of stepSimulation) and into
/// the body itself (so queries made before the step already see it), and sets linear and angular velocities
/// from the pose change over dt (btTransformUtil::calculateVelocity, the same rule Bullet applies) so
/// contacts with dynamic bodies push the right way.
///
/// Ownership follows Bullet's rule: what we add we own and remove. The destructor removes the bodies from the
/// world and frees bodies, motion states and shapes; the world must outlive this object, and so must the
/// Skeleton it reads.
#pragma once

#include "cape/character/Export.h"
#include "cape/character/Skeleton.h"
#include "cape/character/Status.h"

#include <btBulletDynamicsCommon.h>

#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

namespace cape::character {

/// How CharacterBodies makes its bodies: collision filter, empty links, friction and restitution.
struct BodySettings {
  /// Collision filter group of every body of the character. Bullet's CharacterFilter by default.
  int group = btBroadphaseProxy::CharacterFilter;
  /// What they collide with: by default everything but other character bodies (the links of one skeleton
  /// overlap at their joints) and static or kinematic objects (Bullet makes no contacts between those
  /// anyway).
  int mask =
      btBroadphaseProxy::AllFilter & ~(btBroadphaseProxy::CharacterFilter | btBroadphaseProxy::StaticFilter |
                                       btBroadphaseProxy::KinematicFilter);
  /// Also make a body (with a btEmptyShape) for links without collision shapes, so that every link has one.
  bool bodiesForEmptyLinks = false;
  /// Friction and restitution given to every body (Bullet's defaults are 0.5 and 0).
  double friction = 0.5;
  double restitution = 0.0;  ///< Bullet's restitution coefficient, 0..1 (see friction).
};

class CharacterBodies;

/// What each body's user pointer points to (btCollisionObject::getUserPointer()); its user index is the link
/// index too. Lives as long as the CharacterBodies.
struct LinkBodyTag {
  const CharacterBodies* owner = nullptr;  ///< The bodies' owner
  int link = -1;                           ///< The link's index in the skeleton
  std::string linkName;                    ///< The link's name
};

/// A skeleton's links as kinematic Bullet rigid bodies in a world it does not own (see CharacterBodies.h).
class CAPE_CHARACTER_API CharacterBodies {
 public:
  /// Builds the bodies at the skeleton's current pose, at rest, and adds them to `world`.
  CharacterBodies(btDynamicsWorld& world, const Skeleton& skeleton, const BodySettings& settings = {});
  ~CharacterBodies();
  CharacterBodies(const CharacterBodies&) = delete;
  CharacterBodies& operator=(const CharacterBodies&) = delete;

  /// Moves every body to the skeleton's current link poses; velocities are the change since the last
  /// update (or teleport) divided by dt (s, > 0; InvalidArgument otherwise and nothing moves). No allocation.
  Status update(double dt);
  /// Moves every body to the skeleton's current pose with zero velocity: a jump, not a motion.
  void teleport();

  /// The skeleton the bodies follow.
  const Skeleton& skeleton() const { return *skeleton_; }
  /// The settings the bodies were made with.
  const BodySettings& settings() const { return settings_; }

  /// The body of a link, or nullptr (unknown link, or a link without shapes and no empty bodies asked for).
  btRigidBody* bodyForLink(const std::string& link) const;
  /// The same by link index (nullptr out of range).
  btRigidBody* bodyForLink(int link) const;
  /// The link a collision object belongs to, or -1 if it is not one of ours.
  int linkOf(const btCollisionObject* object) const;
  /// Every body, in link order (links without a body left out).
  const std::vector<btRigidBody*>& bodies() const { return bodyList_; }

  /// A link's collision shapes (type, sizes in m, origin in the link frame = the body frame); the same list
  /// as skeleton().shapes(link), and in compound child order.
  const std::vector<ShapeDesc>& shapes(int link) const { return skeleton_->shapes(link); }
  /// A body's pose at the previous and at the latest update, in the world: to interpolate or sweep across
  /// a frame (Bullet moves kinematic bodies once per stepSimulation, not per internal step).
  const btTransform& previousTransform(int link) const;
  /// The body's pose at the latest update, in the world (m).
  const btTransform& currentTransform(int link) const;

 private:
  struct LinkBody {
    std::unique_ptr<LinkBodyTag> tag;
    std::vector<std::unique_ptr<btCollisionShape>> childShapes;  ///< compound children (or the single shape)
    std::unique_ptr<btCollisionShape> compound;                  ///< the compound, if one was needed
    std::unique_ptr<btDefaultMotionState> motionState;
    std::unique_ptr<btRigidBody> body;
    btTransform previous = btTransform::getIdentity();
    btTransform current = btTransform::getIdentity();
  };
  void place(LinkBody& lb, const btTransform& t, double dt);

  btDynamicsWorld* world_;
  const Skeleton* skeleton_;
  BodySettings settings_;
  std::vector<LinkBody> links_;  ///< one per skeleton link; `body` null for links without one
  std::vector<btRigidBody*> bodyList_;
  std::unordered_map<const btCollisionObject*, int> linkOfObject_;
};

/// A link pose as a Bullet transform (btScalar precision).
CAPE_CHARACTER_API btTransform toBullet(const Eigen::Isometry3d& pose);

}  // namespace cape::character
