/// \file
/// The simple body of docs/SCENES.md as kinematic Bullet rigid bodies: one per body collider of
/// cape::SimpleBody (torso box, shoulder spheres, leg capsules; not the ground plane, which a world has once
/// for every character), moved through their motion states so that Bullet derives their velocities. The
/// Bullet scene of the demos and the adapter's tests build the body with it, so both put the same bodies in
/// the same order.
#pragma once

#include "cape/scenes/BulletExport.h"
#include "cape/scenes/Scene.h"

#include <btBulletDynamicsCommon.h>

#include <memory>
#include <vector>

namespace cape {

/// The simple body as kinematic Bullet rigid bodies in a world it does not own (see BulletSimpleBody.h).
class CAPE_SCENES_BULLET_API BulletSimpleBody {
 public:
  /// Places the simple body standing at `offset` in `pose` (teleported: no sweep) and adds one kinematic,
  /// never-sleeping btRigidBody per body collider to `world`, in SimpleBody's order (kTorso, kLeftShoulder,
  /// kRightShoulder, kLeftLeg, kRightLeg), each at its collider's pose.
  BulletSimpleBody(btDynamicsWorld& world, const Vec3& offset = Vec3::Zero(),
                   const BodyPose& pose = BodyPose());
  /// Removes the bodies from the world (the world must still exist).
  ~BulletSimpleBody();
  BulletSimpleBody(const BulletSimpleBody&) = delete;
  BulletSimpleBody& operator=(const BulletSimpleBody&) = delete;

  /// Moves the simple body to the pose (its colliders sweep from where they were) and hands every collider's
  /// new pose to its rigid body's motion state, read at the next stepSimulation.
  void moveTo(const BodyPose& pose);

  /// The simple body itself: its colliders (true surfaces, for the metrics) and torso centre.
  const SimpleBody& body() const { return body_; }
  /// The rigid body of a part, SimpleBody::kTorso .. SimpleBody::kRightLeg.
  btRigidBody* rigidBody(int part) const { return bodies_[static_cast<std::size_t>(part)].get(); }
  /// How many rigid bodies there are (one per body collider: SimpleBody::kGround).
  int rigidBodyCount() const { return static_cast<int>(bodies_.size()); }

 private:
  btDynamicsWorld& world_;
  SimpleBody body_;
  std::vector<std::unique_ptr<btCollisionShape>> shapes_;
  std::vector<std::unique_ptr<btDefaultMotionState>> states_;
  std::vector<std::unique_ptr<btRigidBody>> bodies_;
};

}  // namespace cape
