#include "cape/bullet/SoftBodyTwin.h"

#include "cape/bullet/Convert.h"

#include <vector>

namespace cape::bullet {

std::unique_ptr<btSoftBody> makeSoftBodyTwin(btSoftRigidDynamicsWorld& world, const CapeAction& cape,
                                             const SoftBodyTwinSettings& settings) {
  if (!cape.ok()) return nullptr;
  const Fabric& fabric = cape.cape().fabric();
  const int n = static_cast<int>(fabric.particleCount());
  std::vector<btVector3> x(static_cast<std::size_t>(n));
  std::vector<btScalar> m(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    x[static_cast<std::size_t>(i)] = cape.position(static_cast<std::uint32_t>(i));
    m[static_cast<std::size_t>(i)] = btScalar(fabric.masses()[i]);  // kg
  }
  auto body = std::make_unique<btSoftBody>(&world.getWorldInfo(), n, x.data(), m.data());

  btSoftBody::Material* material = body->appendMaterial();
  material->m_kLST = settings.linearStiffness;
  material->m_kAST = btScalar(1);
  material->m_kVST = btScalar(1);
  const bool wanted[kSpringFamilyCount] = {settings.structuralLinks, settings.shearLinks, settings.bendLinks};
  for (int f = 0; f < kSpringFamilyCount; ++f) {
    if (!wanted[f]) continue;
    const SpringSet& springs = fabric.springs(static_cast<SpringFamily>(f));
    for (std::size_t s = 0; s < springs.size(); ++s) {
      // appendLink takes the rest length from the nodes' current distance; the fabric's rest length wins.
      body->appendLink(static_cast<int>(springs.first[s]), static_cast<int>(springs.second[s]), material);
      body->m_links[body->m_links.size() - 1].m_rl = btScalar(springs.restLength[s]);
      body->m_links[body->m_links.size() - 1].m_c1 =
          body->m_links[body->m_links.size() - 1].m_rl * body->m_links[body->m_links.size() - 1].m_rl;
    }
  }
  const std::vector<std::uint32_t>& tri = fabric.triangles();
  for (std::size_t k = 0; k + 2 < tri.size(); k += 3)
    body->appendFace(static_cast<int>(tri[k]), static_cast<int>(tri[k + 1]), static_cast<int>(tri[k + 2]),
                     material);

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

}  // namespace cape::bullet
