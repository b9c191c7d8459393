#include "cape/scenes/BulletSimpleBody.h"

#include "cape/bullet/Convert.h"

namespace cape {

using bullet::toBt;

BulletSimpleBody::BulletSimpleBody(btDynamicsWorld& world, const Vec3& offset, const BodyPose& pose)
    : world_(world), body_(offset) {
  body_.moveTo(pose, true);
  const std::vector<Collider>& colliders = body_.colliders();
  for (int i = 0; i < SimpleBody::kGround; ++i) {
    const Collider& col = colliders[static_cast<std::size_t>(i)];
    std::unique_ptr<btCollisionShape> shape;
    switch (col.shape) {
      case ColliderShape::Box:
        shape = std::make_unique<btBoxShape>(toBt(col.halfExtents));
        break;
      case ColliderShape::Sphere:
        shape = std::make_unique<btSphereShape>(btScalar(col.radius));
        break;
      case ColliderShape::Capsule:
        // Bullet's capsule height is the cylinder between the caps: twice the collider's half height.
        shape = std::make_unique<btCapsuleShape>(btScalar(col.radius), btScalar(2.0f * col.halfHeight));
        break;
      default:
        break;  // the simple body has no other shapes
    }
    auto state = std::make_unique<btDefaultMotionState>(toBt(col.current));
    btRigidBody::btRigidBodyConstructionInfo info(btScalar(0), state.get(), shape.get());
    auto rigid = std::make_unique<btRigidBody>(info);
    rigid->setCollisionFlags(rigid->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
    // Bullet stops reading a sleeping kinematic body's motion state.
    rigid->setActivationState(DISABLE_DEACTIVATION);
    world_.addRigidBody(rigid.get());
    shapes_.push_back(std::move(shape));
    states_.push_back(std::move(state));
    bodies_.push_back(std::move(rigid));
  }
}

BulletSimpleBody::~BulletSimpleBody() {
  // Bullet's rule: what we added, we remove before it is deleted.
  for (auto& b : bodies_) world_.removeRigidBody(b.get());
}

void BulletSimpleBody::moveTo(const BodyPose& pose) {
  body_.moveTo(pose);
  // Kinematic bodies follow their motion states; Bullet derives their velocities in stepSimulation.
  for (std::size_t i = 0; i < bodies_.size(); ++i)
    states_[i]->setWorldTransform(toBt(body_.colliders()[i].current));
}

}  // namespace cape
