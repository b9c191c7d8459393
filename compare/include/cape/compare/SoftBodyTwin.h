/// \file
/// The btSoftBody twin of a cape: Bullet's own soft body on the same grid (nodes where the cape's particles
/// are now, the same masses), with a link for every spring of the chosen families, anchored to the same
/// bodies at the same body-local pivots, colliding with the same rigid bodies; and its twin in Bullet's
/// deformable world. The comparison's own tools (library cape::compare_twins, used by cape_compare and its
/// tests), not part of the Bullet adapter. Anchored bodies should be kinematic: btSoftBody anchors pull on
/// dynamic bodies, the cape's pins do not.
#pragma once

#include "cape/bullet/CapeAction.h"
#include "cape/compare/Export.h"

#include <BulletSoftBody/btDeformableLagrangianForce.h>
#include <BulletSoftBody/btDeformableMultiBodyDynamicsWorld.h>
#include <BulletSoftBody/btSoftBody.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>

#include <memory>
#include <vector>

/// The comparison's tools (library cape::compare_twins): Bullet's btSoftBody and deformable-world twins of a
/// cape, for cape_compare and its tests.
namespace cape::compare {

/// How makeSoftBodyTwin builds the btSoftBody twin: which links, and Bullet's soft body parameters (Bullet's
/// own names given; its coefficients are dimensionless).
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
  int collisionMask = btBroadphaseProxy::AllFilter;  ///< The groups it collides with (bit mask).
};

/// Builds the twin of `cape` from its current state and attachments, adds it to `world` and returns it.
/// The caller owns it: world.removeSoftBody(twin.get()) before it is destroyed. Nodes are the cape's
/// particles in order; links are appended family by family in the fabric's spring order; triangles are the
/// fabric's (for drawing and aerodynamics).
CAPE_COMPARE_API std::unique_ptr<btSoftBody> makeSoftBodyTwin(
    btSoftRigidDynamicsWorld& world, const bullet::CapeAction& cape,
    const SoftBodyTwinSettings& settings = SoftBodyTwinSettings());

/// The twin for Bullet's deformable world (btDeformableMultiBodyDynamicsWorld, Xuchen Han's solver of
/// Bullet 3): the same nodes, masses, links, faces and anchors as makeSoftBodyTwin, driven by a mass-spring
/// force and a gravity force. Step the world explicitly (its default), as Bullet's cloth demos do: on this
/// cape the implicit mode leaves the nodes where they are with its Lagrange multipliers and blows up with
/// projection (measured with Bullet 3.24).
struct DeformableTwinSettings {
  bool structuralLinks = true;  ///< Rows and columns.
  bool shearLinks = true;       ///< Both diagonals of every cell.
  bool bendLinks = false;       ///< Every second particle along rows and columns.
  /// btDeformableMassSpringForce: Hooke stiffness of every link, N/m, and damping along the links, N s/m.
  /// The default is about the stiffest the deformable world keeps finite with the canonical cape's light
  /// nodes at 1/240 s, far softer than the cape's own structural springs (docs/COMPARISON.md, "Method").
  btScalar elasticStiffness = btScalar(50);
  btScalar dampingStiffness = btScalar(0.1);  ///< N s/m, damping along the links (see elasticStiffness).
  btScalar friction = btScalar(0.3);          ///< m_cfg.kDF.
  btScalar margin = btScalar(0.01);           ///< Collision margin, m.
  /// m_cfg.collisions: the deformable world's contacts against rigid bodies, nodes and faces.
  int collisions = btSoftBody::fCollision::SDF_RD | btSoftBody::fCollision::SDF_RDF;
  int collisionGroup = btBroadphaseProxy::DefaultFilter;  ///< Its collision filter group (bit mask).
  int collisionMask = btBroadphaseProxy::AllFilter;       ///< The groups it collides with (bit mask).
};

/// A deformable twin in its world; removes itself (body and forces) when destroyed, so it must not outlive
/// the world.
class CAPE_COMPARE_API DeformableTwin {
 public:
  /// Takes the body and its forces, already added to `world`, and owns them.
  DeformableTwin(btDeformableMultiBodyDynamicsWorld& world, std::unique_ptr<btSoftBody> body,
                 std::vector<std::unique_ptr<btDeformableLagrangianForce>> forces);
  ~DeformableTwin();
  DeformableTwin(const DeformableTwin&) = delete;
  DeformableTwin& operator=(const DeformableTwin&) = delete;
  /// The soft body (its nodes are the cape's particles, in order).
  btSoftBody& body() { return *body_; }
  /// The soft body (its nodes are the cape's particles, in order).
  const btSoftBody& body() const { return *body_; }

 private:
  btDeformableMultiBodyDynamicsWorld& world_;
  std::unique_ptr<btSoftBody> body_;
  std::vector<std::unique_ptr<btDeformableLagrangianForce>> forces_;
};

/// Builds the deformable twin of `cape` from its current state and attachments and adds it to `world`;
/// nullptr if the cape is not ok. Anchors are Bullet's deformable anchors to the attachment bodies.
CAPE_COMPARE_API std::unique_ptr<DeformableTwin> makeDeformableTwin(
    btDeformableMultiBodyDynamicsWorld& world, const bullet::CapeAction& cape,
    const DeformableTwinSettings& settings = DeformableTwinSettings());

}  // namespace cape::compare
