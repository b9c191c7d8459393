// The promises a loaded UrdfModel makes (Urdf.h, character/README.md), checked on every model a fuzz target
// gets back, and the character built from it as a user builds one: Character::create, the cape's shoulder
// anchors, one frame of the walk in a Bullet world and one world step.
#pragma once

#include "FuzzSupport.h"

#include <btBulletDynamicsCommon.h>

#include "cape/character/Anchors.h"
#include "cape/character/Character.h"
#include "cape/character/Urdf.h"

#include <cmath>
#include <string>
#include <vector>

namespace capefuzz {

inline bool positiveFinite(double x) {
  return std::isfinite(x) && x > 0.0;
}

/// Every shape that loaded has the sizes of its type, positive and finite, and a finite origin.
inline void checkShape(const cape::character::ShapeDesc& s, const std::string& link) {
  using cape::character::ShapeType;
  const std::string where = "link '" + link + "' shape '" + s.name + "' (" + toString(s.type) + ")";
  CAPE_FUZZ_CHECK(s.origin.matrix().allFinite(), where + ": origin not finite");
  switch (s.type) {
    case ShapeType::Sphere:
      CAPE_FUZZ_CHECK(positiveFinite(s.radius), where + ": radius");
      break;
    case ShapeType::Box:
      CAPE_FUZZ_CHECK(s.halfExtents.allFinite() && s.halfExtents.minCoeff() > 0.0, where + ": half extents");
      break;
    case ShapeType::Cylinder:
    case ShapeType::Capsule:
      CAPE_FUZZ_CHECK(positiveFinite(s.radius) && positiveFinite(s.halfLength), where + ": radius or length");
      break;
    case ShapeType::ConvexHull:
      CAPE_FUZZ_CHECK(s.hull.size() >= 4 && !s.hullPlanes.empty(), where + ": hull with < 4 vertices");
      CAPE_FUZZ_CHECK(std::isfinite(s.radius) && s.radius >= 0.0, where + ": hull rounding");
      for (const Eigen::Vector3d& v : s.hull) CAPE_FUZZ_CHECK(v.allFinite(), where + ": hull vertex");
      break;
  }
}

/// Links in parents-before-children order with the root at 0, joints and links naming each other
/// consistently, names found by find*, movable joints' axes of unit length, shapes as checkShape says.
inline void checkModel(const cape::character::UrdfModel& model) {
  const auto& links = model.links();
  const auto& joints = model.joints();
  CAPE_FUZZ_CHECK(!links.empty(), "a model without links");
  CAPE_FUZZ_CHECK(links[0].parentJoint == -1 && links[0].parentLink == -1, "link 0 is not the root");
  CAPE_FUZZ_CHECK(joints.size() + 1 == links.size(), "not one joint per non-root link");
  for (std::size_t i = 0; i < links.size(); ++i) {
    const cape::character::LinkDesc& l = links[i];
    CAPE_FUZZ_CHECK(model.findLink(l.name) == static_cast<int>(i), "findLink('" + l.name + "')");
    if (i > 0) {
      CAPE_FUZZ_CHECK(l.parentLink >= 0 && l.parentLink < static_cast<int>(i),
                      "link '" + l.name + "' comes before its parent");
      CAPE_FUZZ_CHECK(l.parentJoint >= 0 && l.parentJoint < static_cast<int>(joints.size()),
                      "link '" + l.name + "' parent joint out of range");
      const cape::character::JointDesc& j = joints[static_cast<std::size_t>(l.parentJoint)];
      CAPE_FUZZ_CHECK(j.childLink == static_cast<int>(i) && j.parentLink == l.parentLink,
                      "joint '" + j.name + "' and link '" + l.name + "' disagree");
    }
    for (int c : l.childJoints)
      CAPE_FUZZ_CHECK(c >= 0 && c < static_cast<int>(joints.size()) &&
                          joints[static_cast<std::size_t>(c)].parentLink == static_cast<int>(i),
                      "link '" + l.name + "' child joint");
    for (const cape::character::ShapeDesc& s : l.shapes) checkShape(s, l.name);
  }
  for (std::size_t k = 0; k < joints.size(); ++k) {
    const cape::character::JointDesc& j = joints[k];
    CAPE_FUZZ_CHECK(model.findJoint(j.name) == static_cast<int>(k), "findJoint('" + j.name + "')");
    if (j.isMovable())
      CAPE_FUZZ_CHECK(std::abs(j.axis.norm() - 1.0) < 1e-6,
                      "joint '" + j.name + "' axis is not a unit vector");
  }
}

/// A plain Bullet world, made once per process (a character removes its bodies when it goes).
inline btDiscreteDynamicsWorld& world() {
  struct World {
    btDefaultCollisionConfiguration config;
    btCollisionDispatcher dispatcher{&config};
    btDbvtBroadphase broadphase;
    btSequentialImpulseConstraintSolver solver;
    btDiscreteDynamicsWorld world{&dispatcher, &broadphase, &solver, &config};
    World() { world.setGravity(btVector3(0, -9.8f, 0)); }
  };
  static World w;
  return w.world;
}

/// The character as cape_walk builds it: the model checked, then created in the world (walk gait, default
/// mapping), its shoulder anchors found, one frame of the gait, the world stepped once, the shapes read.
inline void buildCharacter(const cape::character::UrdfLoadResult& loaded) {
  using namespace cape::character;
  if (!loaded.ok()) return;
  checkModel(*loaded.model);
  CharacterResult made = Character::create(loaded.model, world(), Gait::forScene(cape::SceneKind::Walk));
  if (!made.ok()) return;
  Character& c = *made.character;
  const ShoulderAnchors anchors = findShoulderAnchors(c);
  if (anchors.status.ok()) {
    const int n = c.skeleton().linkCount();
    for (int link : {anchors.leftLink, anchors.rightLink, anchors.upperTorsoLink})
      CAPE_FUZZ_CHECK(link >= 0 && link < n, "shoulder anchors on link " + std::to_string(link));
  }
  c.advanceTo(1.0 / 60.0);
  world().stepSimulation(1.0f / 60.0f, 8, 1.0f / 240.0f);
  std::vector<WorldShape> shapes;
  c.skeleton().worldShapes(shapes);
  for (const WorldShape& s : shapes)
    CAPE_FUZZ_CHECK(s.link >= 0 && s.link < c.skeleton().linkCount() && s.shape != nullptr, "world shape");
}

}  // namespace capefuzz
