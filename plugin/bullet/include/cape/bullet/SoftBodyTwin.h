// The btSoftBody twin of a cape: Bullet's own soft body on the same grid (nodes where the cape's particles
// are now, the same masses), with a link for every spring of the chosen families, anchored to the same
// bodies at the same body-local pivots, colliding with the same rigid bodies. For the comparison demo and
// tests. Anchored bodies should be kinematic: btSoftBody anchors pull on dynamic bodies, the cape's pins
// do not.
#pragma once

#include "cape/bullet/CapeAction.h"

#include <BulletSoftBody/btSoftBody.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>

#include <memory>

namespace cape::bullet {

struct SoftBodyTwinSettings {
  bool structuralLinks = true;  ///< Rows and columns.
  bool shearLinks = true;       ///< Both diagonals of every cell.
  bool bendLinks = false;       ///< Every second particle along rows and columns (the fabric's bend family).
  btScalar linearStiffness = btScalar(1);       ///< Material m_kLST, 0..1 (1: as stiff as the solver allows).
  int positionIterations = 4;                   ///< m_cfg.piterations.
  int velocityIterations = 0;                   ///< m_cfg.viterations.
  int driftIterations = 0;                      ///< m_cfg.diterations.
  btScalar damping = btScalar(0.0);             ///< m_cfg.kDP, 0..1.
  btScalar friction = btScalar(0.3);            ///< m_cfg.kDF, 0..1 (the cape's default friction).
  btScalar anchorHardness = btScalar(1);        ///< m_cfg.kAHR, 0..1.
  btScalar rigidContactHardness = btScalar(1);  ///< m_cfg.kCHR, 0..1.
  /// Collision margin of the soft body, m (the cape's thickness is a good value).
  btScalar margin = btScalar(0.01);
  /// m_cfg.collisions: signed-distance-field contacts against rigid bodies (Bullet's default soft-rigid
  /// model; cluster modes need clusters, which a cloth twin does not generate).
  int collisions = btSoftBody::fCollision::SDF_RS;
  /// Collision filter of the soft body in the world (the cape's, by default).
  int collisionGroup = btBroadphaseProxy::DefaultFilter;
  int collisionMask = btBroadphaseProxy::AllFilter;
};

/// Builds the twin of `cape` from its current state and attachments, adds it to `world` and returns it.
/// The caller owns it: world.removeSoftBody(twin.get()) before it is destroyed. Nodes are the cape's
/// particles in order; links are appended family by family in the fabric's spring order; triangles are the
/// fabric's (for drawing and aerodynamics).
std::unique_ptr<btSoftBody> makeSoftBodyTwin(btSoftRigidDynamicsWorld& world, const CapeAction& cape,
                                             const SoftBodyTwinSettings& settings = SoftBodyTwinSettings());

}  // namespace cape::bullet
