/// \file
/// Conversions between Bullet's types (btVector3, btTransform) and the core's (cape::Vec3, cape::Pose).
/// Both describe metres and unit quaternions; only the layout differs.
#pragma once

#include "cape/core/Types.h"

#include <LinearMath/btTransform.h>

/// The Bullet adapter (library cape::bullet): CapeAction and CapeGroup step capes with a Bullet world, and
/// Bullet shapes become core colliders. Bullet's types (btScalar, btVector3, btTransform) in metres.
namespace cape::bullet {

/// A Bullet vector as a core one (rounded to float where btScalar is double).
inline Vec3 toVec3(const btVector3& v) {
  return Vec3(static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z()));
}
/// A core vector as a Bullet one.
inline btVector3 toBt(const Vec3& v) {
  return btVector3(btScalar(v.x()), btScalar(v.y()), btScalar(v.z()));
}

/// A Bullet transform as a core pose (the rotation normalised after rounding to float).
inline Pose toPose(const btTransform& t) {
  const btQuaternion q = t.getRotation();
  Pose p;
  p.position = toVec3(t.getOrigin());
  p.rotation = Quat(static_cast<float>(q.w()), static_cast<float>(q.x()), static_cast<float>(q.y()),
                    static_cast<float>(q.z()));
  p.rotation.normalize();
  return p;
}
/// A core pose as a Bullet transform.
inline btTransform toBt(const Pose& p) {
  const btQuaternion q(btScalar(p.rotation.x()), btScalar(p.rotation.y()), btScalar(p.rotation.z()),
                       btScalar(p.rotation.w()));
  return btTransform(q, toBt(p.position));
}

}  // namespace cape::bullet
