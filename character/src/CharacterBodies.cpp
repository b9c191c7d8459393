// Kinematic Bullet bodies that follow a Skeleton.
#include "cape/character/CharacterBodies.h"

#include <cassert>
#include <cmath>
#include <vector>

namespace cape::character {

btTransform toBullet(const Eigen::Isometry3d& pose) {
  const Eigen::Matrix3d& r = pose.linear();
  const Eigen::Vector3d& p = pose.translation();
  btMatrix3x3 basis(btScalar(r(0, 0)), btScalar(r(0, 1)), btScalar(r(0, 2)),  //
                    btScalar(r(1, 0)), btScalar(r(1, 1)), btScalar(r(1, 2)),  //
                    btScalar(r(2, 0)), btScalar(r(2, 1)), btScalar(r(2, 2)));
  return btTransform(basis, btVector3(btScalar(p.x()), btScalar(p.y()), btScalar(p.z())));
}

namespace {

std::unique_ptr<btCollisionShape> makeShape(const ShapeDesc& s) {
  switch (s.type) {
    case ShapeType::Sphere:
      return std::make_unique<btSphereShape>(btScalar(s.radius));
    case ShapeType::Box:
      return std::make_unique<btBoxShape>(
          btVector3(btScalar(s.halfExtents.x()), btScalar(s.halfExtents.y()), btScalar(s.halfExtents.z())));
    case ShapeType::Cylinder:
      // btCylinderShapeZ takes half extents (radius, radius, half length) with its axis along local z.
      return std::make_unique<btCylinderShapeZ>(
          btVector3(btScalar(s.radius), btScalar(s.radius), btScalar(s.halfLength)));
    case ShapeType::Capsule:
      // btCapsuleShapeZ takes the radius and the distance between the two sphere centres.
      return std::make_unique<btCapsuleShapeZ>(btScalar(s.radius), btScalar(2.0 * s.halfLength));
    case ShapeType::ConvexHull: {
      // The hull's margin is its rounding: Bullet's surface is the hull grown by the margin, as ours.
      auto hull = std::make_unique<btConvexHullShape>();
      for (const Eigen::Vector3d& v : s.hull)
        hull->addPoint(btVector3(btScalar(v.x()), btScalar(v.y()), btScalar(v.z())), false);
      hull->recalcLocalAabb();
      hull->setMargin(btScalar(s.radius));
      return hull;
    }
  }
  return nullptr;
}

// The order in which `count` bodies go into the world. Bullet's btDbvt inserts a leaf next to the nearest one
// without rebalancing, so links added in order along a chain make a tree as deep as the chain: adding
// 10,000 links took seconds, and every later update of a body's bounds walks that depth. Up to
// kLinkOrderBodies bodies keep link order, so that every ordinary model's world (and simulation) stays as it
// was to the bit; beyond, the bit-reversed order of the link indices spreads each chain over the whole tree
// (depth about log2 of the count).
constexpr std::size_t kLinkOrderBodies = 1024;

std::vector<std::size_t> worldOrder(std::size_t count) {
  std::vector<std::size_t> order;
  order.reserve(count);
  if (count <= kLinkOrderBodies) {
    for (std::size_t k = 0; k < count; ++k) order.push_back(k);
    return order;
  }
  int bits = 0;
  while ((std::size_t(1) << bits) < count) ++bits;
  for (std::size_t i = 0; i < (std::size_t(1) << bits); ++i) {
    std::size_t r = 0;
    for (int b = 0; b < bits; ++b) r |= ((i >> b) & 1u) << (bits - 1 - b);
    if (r < count) order.push_back(r);
  }
  return order;
}

}  // namespace

CharacterBodies::CharacterBodies(btDynamicsWorld& world, const Skeleton& skeleton,
                                 const BodySettings& settings)
    : world_(&world), skeleton_(&skeleton), settings_(settings) {
  const int n = skeleton.linkCount();
  links_.resize(static_cast<std::size_t>(n));
  for (int l = 0; l < n; ++l) {
    LinkBody& lb = links_[static_cast<std::size_t>(l)];
    const std::vector<ShapeDesc>& shapes = skeleton.shapes(l);
    if (shapes.empty() && !settings.bodiesForEmptyLinks) continue;

    btCollisionShape* shape = nullptr;
    if (shapes.empty()) {
      lb.childShapes.push_back(std::make_unique<btEmptyShape>());
      shape = lb.childShapes.back().get();
    } else if (shapes.size() == 1 && shapes[0].origin.isApprox(Eigen::Isometry3d::Identity(), 0.0)) {
      lb.childShapes.push_back(makeShape(shapes[0]));
      shape = lb.childShapes.back().get();
    } else {
      // Several elements, or one off the link origin: a compound whose children sit at the collision origins.
      auto compound =
          std::make_unique<btCompoundShape>(/*enableDynamicAabbTree=*/false, static_cast<int>(shapes.size()));
      for (const ShapeDesc& s : shapes) {
        lb.childShapes.push_back(makeShape(s));
        compound->addChildShape(toBullet(s.origin), lb.childShapes.back().get());
      }
      shape = compound.get();
      lb.compound = std::move(compound);
    }

    const btTransform start = toBullet(skeleton.linkPose(l));
    lb.previous = lb.current = start;
    lb.motionState = std::make_unique<btDefaultMotionState>(start);
    btRigidBody::btRigidBodyConstructionInfo info(0.0, lb.motionState.get(), shape, btVector3(0, 0, 0));
    info.m_friction = btScalar(settings.friction);
    info.m_restitution = btScalar(settings.restitution);
    lb.body = std::make_unique<btRigidBody>(info);
    btRigidBody* body = lb.body.get();
    body->setCollisionFlags(body->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
    body->setActivationState(DISABLE_DEACTIVATION);
    body->setWorldTransform(start);
    body->setInterpolationWorldTransform(start);

    lb.tag = std::make_unique<LinkBodyTag>();
    lb.tag->owner = this;
    lb.tag->link = l;
    lb.tag->linkName = skeleton.model().links()[static_cast<std::size_t>(l)].name;
    body->setUserPointer(lb.tag.get());
    body->setUserIndex(l);

    bodyList_.push_back(body);
    linkOfObject_[body] = l;
  }
  // Into the world in link order, or for a large model in bit-reversed link order (see worldOrder).
  for (std::size_t k : worldOrder(bodyList_.size()))
    world.addRigidBody(bodyList_[k], settings.group, settings.mask);
}

CharacterBodies::~CharacterBodies() {
  // Remove before freeing (Bullet's rule), then free bodies before the shapes they point to.
  for (LinkBody& lb : links_) {
    if (lb.body) world_->removeRigidBody(lb.body.get());
  }
  for (LinkBody& lb : links_) {
    lb.body.reset();
    lb.motionState.reset();
    lb.compound.reset();
    lb.childShapes.clear();
  }
}

void CharacterBodies::place(LinkBody& lb, const btTransform& t, double dt) {
  lb.previous = lb.current;
  lb.current = t;
  btVector3 linear(0, 0, 0), angular(0, 0, 0);
  if (dt > 0.0) btTransformUtil::calculateVelocity(lb.previous, lb.current, btScalar(dt), linear, angular);
  lb.motionState->setWorldTransform(t);
  btRigidBody* body = lb.body.get();
  body->setWorldTransform(t);
  // Bullet derives a kinematic body's velocity from its interpolation transform to the motion state's pose at
  // the next stepSimulation. Setting the former to our previous pose keeps that velocity equal to ours even
  // when the world was not stepped after every update; for a jump both are the new pose, so nothing seems to
  // move.
  body->setInterpolationWorldTransform(dt > 0.0 ? lb.previous : t);
  body->setLinearVelocity(linear);
  body->setAngularVelocity(angular);
  body->setInterpolationLinearVelocity(linear);
  body->setInterpolationAngularVelocity(angular);
}

Status CharacterBodies::update(double dt) {
  if (!std::isfinite(dt) || dt <= 0.0) {
    return Status::error(ErrorCode::InvalidArgument, "CharacterBodies::update: dt must be finite and > 0 s");
  }
  for (std::size_t l = 0; l < links_.size(); ++l) {
    if (links_[l].body) place(links_[l], toBullet(skeleton_->linkPose(static_cast<int>(l))), dt);
  }
  return Status::success();
}

void CharacterBodies::teleport() {
  for (std::size_t l = 0; l < links_.size(); ++l) {
    if (!links_[l].body) continue;
    const btTransform t = toBullet(skeleton_->linkPose(static_cast<int>(l)));
    place(links_[l], t, 0.0);
    links_[l].previous = t;
  }
}

btRigidBody* CharacterBodies::bodyForLink(const std::string& link) const {
  return bodyForLink(skeleton_->model().findLink(link));
}

btRigidBody* CharacterBodies::bodyForLink(int link) const {
  if (link < 0 || link >= static_cast<int>(links_.size())) return nullptr;
  return links_[static_cast<std::size_t>(link)].body.get();
}

int CharacterBodies::linkOf(const btCollisionObject* object) const {
  const auto it = linkOfObject_.find(object);
  return it == linkOfObject_.end() ? -1 : it->second;
}

const btTransform& CharacterBodies::previousTransform(int link) const {
  assert(link >= 0 && link < static_cast<int>(links_.size()));
  return links_[static_cast<std::size_t>(link)].previous;
}

const btTransform& CharacterBodies::currentTransform(int link) const {
  assert(link >= 0 && link < static_cast<int>(links_.size()));
  return links_[static_cast<std::size_t>(link)].current;
}

}  // namespace cape::character
