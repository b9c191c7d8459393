// The README's "Your own world" example, built against the installed package: a plain
// btDiscreteDynamicsWorld, two kinematic shoulder spheres and a torso box, a cape attached in a few lines.
// Checks that the cape hangs from the shoulders behind the torso after two seconds. Exit status 0 on success.
#include <cape/bullet/CapeAction.h>
#include <cape/scenes/Scene.h>

#include <btBulletDynamicsCommon.h>

#include <cstdio>
#include <memory>

namespace {
std::unique_ptr<btRigidBody> kinematic(btCollisionShape* shape, const btVector3& at) {
  btRigidBody::btRigidBodyConstructionInfo info(0, nullptr, shape);
  info.m_startWorldTransform.setOrigin(at);
  auto body = std::make_unique<btRigidBody>(info);
  body->setCollisionFlags(body->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
  return body;
}
}  // namespace

int main() {
  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher(&configuration);
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world(&dispatcher, &broadphase, &solver, &configuration);
  world.setGravity(btVector3(0, -9.8f, 0));
  btSphereShape shoulderShape(0.08f);
  btBoxShape torsoShape(btVector3(0.20f, 0.30f, 0.12f));
  auto leftBody = kinematic(&shoulderShape, btVector3(-0.22f, 1.52f, 0));
  auto rightBody = kinematic(&shoulderShape, btVector3(0.22f, 1.52f, 0));
  auto torso = kinematic(&torsoShape, btVector3(0, 1.25f, 0));
  btRigidBody* leftShoulder = leftBody.get();
  btRigidBody* rightShoulder = rightBody.get();
  world.addRigidBody(leftShoulder);
  world.addRigidBody(rightShoulder);
  world.addRigidBody(torso.get());

  // --- The README's example. ---
  cape::CapeRig rig = cape::makeCapeRig(20, cape::PinLayout::Corners);
  btTransform placement(btQuaternion::getIdentity(), btVector3(-0.30f, 1.56f, 0.15f));  // top-left corner
  cape::bullet::CapeAction cape(rig.fabric, cape::CapeSettings(), placement);
  cape.attachNearest(leftShoulder, btVector3(-0.30f, 1.56f, 0.15f));
  cape.attachNearest(rightShoulder, btVector3(0.30f, 1.56f, 0.15f));
  world.addAction(&cape);
  for (int frame = 0; frame < 120; ++frame) world.stepSimulation(1.f / 60, 8, 1.f / 240);
  const cape::Points& x = cape.positions();
  // --- End of the example. ---

  const float lowest = x.col(1).minCoeff();
  const float front = x.col(2).minCoeff();  // no particle in front of the torso's back (z = -0.12 .. 0.12)
  const bool ok = x.allFinite() && lowest < 0.65f && front > 0.12f && cape.attachments().size() == 2;
  std::printf("bullet consumer: lowest particle at y = %.3f m, nearest the body at z = %.3f m: %s\n", lowest,
              front, ok ? "ok" : "FAILED");
  world.removeAction(&cape);
  world.removeRigidBody(torso.get());
  world.removeRigidBody(rightShoulder);
  world.removeRigidBody(leftShoulder);
  return ok ? 0 : 1;
}
