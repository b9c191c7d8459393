// A plain Bullet world for the character's tests, as a user would make one (gravity -Y, docs/SCENES.md).
#pragma once

#include <btBulletDynamicsCommon.h>

namespace capetest {

struct World {
  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world{&dispatcher, &broadphase, &solver, &config};
  World() { world.setGravity(btVector3(0, -9.8f, 0)); }
};

}  // namespace capetest
