#include "cape/compare/SoftBodyTwin.h"

#include "cape/bullet/Convert.h"

#include <BulletSoftBody/btDeformableGravityForce.h>
#include <BulletSoftBody/btDeformableMassSpringForce.h>

#include <vector>

namespace cape::compare {

using bullet::Attachment;
using bullet::CapeAction;

namespace {

/// A btSoftBody with the cape's particles as nodes (positions now, masses), a link for every spring of the
/// wanted families at the fabric's rest length, and the fabric's triangles as faces.
std::unique_ptr<btSoftBody> makeTwinBody(btSoftBodyWorldInfo& info, const CapeAction& cape,
                                         btScalar linearStiffness, const bool (&wanted)[kSpringFamilyCount]) {
  const Fabric& fabric = cape.cape().fabric();
  const int n = static_cast<int>(fabric.particleCount());
  std::vector<btVector3> x(static_cast<std::size_t>(n));
  std::vector<btScalar> m(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    x[static_cast<std::size_t>(i)] = cape.position(static_cast<std::uint32_t>(i));
    m[static_cast<std::size_t>(i)] = btScalar(fabric.masses()[i]);  // kg
  }
  auto body = std::make_unique<btSoftBody>(&info, n, x.data(), m.data());

  btSoftBody::Material* material = body->appendMaterial();
  material->m_kLST = linearStiffness;
  material->m_kAST = btScalar(1);
  material->m_kVST = btScalar(1);
  for (int f = 0; f < kSpringFamilyCount; ++f) {
    if (!wanted[f]) continue;
    const SpringSet& springs = fabric.springs(static_cast<SpringFamily>(f));
    for (std::size_t s = 0; s < springs.size(); ++s) {
      // appendLink takes the rest length from the nodes' current distance; the fabric's rest length wins.
      body->appendLink(static_cast<int>(springs.first[s]), static_cast<int>(springs.second[s]), material);
      btSoftBody::Link& link = body->m_links[body->m_links.size() - 1];
      link.m_rl = btScalar(springs.restLength[s]);
      link.m_c1 = link.m_rl * link.m_rl;
    }
  }
  const std::vector<std::uint32_t>& tri = fabric.triangles();
  for (std::size_t k = 0; k + 2 < tri.size(); k += 3)
    body->appendFace(static_cast<int>(tri[k]), static_cast<int>(tri[k + 1]), static_cast<int>(tri[k + 2]),
                     material);
  return body;
}

}  // namespace

std::unique_ptr<btSoftBody> makeSoftBodyTwin(btSoftRigidDynamicsWorld& world, const CapeAction& cape,
                                             const SoftBodyTwinSettings& settings) {
  if (!cape.ok()) return nullptr;
  const bool wanted[kSpringFamilyCount] = {settings.structuralLinks, settings.shearLinks, settings.bendLinks};
  std::unique_ptr<btSoftBody> body =
      makeTwinBody(world.getWorldInfo(), cape, settings.linearStiffness, wanted);

  btSoftBody::Config& cfg = body->m_cfg;
  cfg.piterations = settings.positionIterations;
  cfg.viterations = settings.velocityIterations;
  cfg.diterations = settings.driftIterations;
  cfg.kDP = settings.damping;
  cfg.kDF = settings.friction;
  cfg.kAHR = settings.anchorHardness;
  cfg.kCHR = settings.rigidContactHardness;
  cfg.collisions = settings.collisions;
  body->getCollisionShape()->setMargin(settings.margin);

  for (const Attachment& a : cape.attachments()) {
    // appendAnchor wants a mutable body; the anchor reads the body's transform and, for dynamic bodies,
    // pushes on it (kinematic bodies make the anchor one-way, like the cape's pins).
    auto* rigid = const_cast<btRigidBody*>(a.body);
    body->appendAnchor(static_cast<int>(a.particle), rigid, a.localPivot, true, btScalar(1));
  }
  world.addSoftBody(body.get(), settings.collisionGroup, settings.collisionMask);
  return body;
}

DeformableTwin::DeformableTwin(btDeformableMultiBodyDynamicsWorld& world, std::unique_ptr<btSoftBody> body,
                               std::vector<std::unique_ptr<btDeformableLagrangianForce>> forces)
    : world_(world), body_(std::move(body)), forces_(std::move(forces)) {}

DeformableTwin::~DeformableTwin() {
  world_.removeSoftBodyForce(body_.get());
  world_.removeSoftBody(body_.get());
}

std::unique_ptr<DeformableTwin> makeDeformableTwin(btDeformableMultiBodyDynamicsWorld& world,
                                                   const CapeAction& cape,
                                                   const DeformableTwinSettings& settings) {
  if (!cape.ok()) return nullptr;
  const bool wanted[kSpringFamilyCount] = {settings.structuralLinks, settings.shearLinks, settings.bendLinks};
  std::unique_ptr<btSoftBody> body = makeTwinBody(world.getWorldInfo(), cape, btScalar(1), wanted);
  btSoftBody::Config& cfg = body->m_cfg;
  cfg.kDF = settings.friction;
  cfg.kCHR = btScalar(1);
  cfg.kKHR = btScalar(1);
  cfg.collisions = settings.collisions;
  body->getCollisionShape()->setMargin(settings.margin);
  // A cape at rest would fall asleep in the deformable world (and stay behind its walking character).
  body->setActivationState(DISABLE_DEACTIVATION);
  world.addSoftBody(body.get(), settings.collisionGroup, settings.collisionMask);

  std::vector<std::unique_ptr<btDeformableLagrangianForce>> forces;
  forces.push_back(std::make_unique<btDeformableMassSpringForce>(settings.elasticStiffness,
                                                                 settings.dampingStiffness, true));
  forces.push_back(std::make_unique<btDeformableGravityForce>(world.getWorldInfo().m_gravity));
  for (auto& f : forces) world.addForce(body.get(), f.get());
  // A deformable anchor holds its node at the body-frame point where the node is when it is appended: the
  // node goes to the cape's pin pivot first. (It wants a mutable body; kinematic bodies are not pushed.)
  for (const Attachment& a : cape.attachments()) {
    btSoftBody::Node& node = body->m_nodes[static_cast<int>(a.particle)];
    node.m_x = node.m_q = a.body->getWorldTransform() * a.localPivot;
    body->appendDeformableAnchor(static_cast<int>(a.particle), const_cast<btRigidBody*>(a.body));
  }
  return std::make_unique<DeformableTwin>(world, std::move(body), std::move(forces));
}

}  // namespace cape::compare
