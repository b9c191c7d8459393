/// \file
/// CapeAction: one cape stepping with a Bullet world. `world->addAction(&action)` is all it takes: Bullet
/// calls updateAction() once per internal fixed step, after the rigid bodies have moved, and the action
/// converts what it needs (pin targets from the bodies it is attached to, colliders from the bodies it
/// touches) and delegates the step to cape::Cape.
///
/// Discovery goes through the world's broadphase (btBroadphaseInterface::aabbTest over the cape's grown
/// bounds; btDbvtBroadphase answers from its AABB trees), so its cost follows the objects near the cape, not
/// the size of the world. What it finds is ordered by the objects' indices in the world's collision object
/// array (read while Bullet reports them, so while they are certainly in the world), never by the
/// broadphase's tree order or by addresses: the followed objects, and so the colliders, keep the order of
/// first sight, ties in one step broken by array index.
///
/// Ownership (Bullet's rule): the user owns the bodies, removes them from the world before deleting them,
/// and removes the action from the world before destroying it. The action never dereferences a body that
/// is no longer in the world. It remembers, for every object it follows (attachment bodies and colliders),
/// the index in the world's collision object array where it last saw it; at the start of every update it
/// checks `index < size && array[index] == pointer` for each (pointers only). If every check holds, nothing
/// left the world: O(followed objects) per step, whatever the size of the world. If one fails (an object
/// left the world, or btCollisionWorld::removeCollisionObject's swap-and-pop moved a followed object into
/// another slot), it scans the array once, pointers only, refreshing every index and dropping every
/// attachment and collider whose body is gone, releasing its particles, with one warning per body. So
/// removing a body (and deleting it) between two stepSimulation calls is safe; calling detach(body) first
/// is the tidy way and warns about nothing. (As with any pointer comparison, a new object that reuses a
/// deleted body's address is taken for it: detach(body) before deleting a body that another may replace.)
#pragma once

#include "cape/bullet/Export.h"
#include "cape/bullet/ShapeColliders.h"
#include "cape/core/Cape.h"
#include "cape/core/CapeMesh.h"

#include <BulletCollision/BroadphaseCollision/btBroadphaseProxy.h>
#include <BulletDynamics/Dynamics/btActionInterface.h>
#include <BulletDynamics/Dynamics/btRigidBody.h>

#include <cstdint>
#include <functional>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

class btCollisionWorld;
class btIDebugDraw;

namespace cape::bullet {

/// Receives the adapter's warnings (unsupported shapes, bodies removed while attached). Default: stderr.
using WarningHandler = std::function<void(const std::string&)>;

/// What a teleport does to the cape (CapeActionSettings::teleportMode), as Magica Cloth 2's and Chaos
/// Cloth's teleport controls.
enum class TeleportMode {
  Keep,   ///< The cape is moved rigidly with the body: its shape, folds and swing (turned) kept.
  Reset,  ///< The cape is moved with the body and put back at rest in its reference pose
          ///< (Cape::resetToReference).
};

/// Per-action parameters, plain data with units.
struct CapeActionSettings {
  /// Find colliders automatically (through the world's broadphase): every collision object whose broadphase
  /// AABB overlaps the cape's bounds (grown by discoveryMargin) and whose filter accepts the cape's group
  /// and mask (Bullet's rule: (object.group & cape.mask) != 0 and (cape.group & object.mask) != 0). Objects
  /// without contact response (CF_NO_CONTACT_RESPONSE: triggers, ghosts) and soft bodies are skipped.
  bool discoverColliders = true;
  int collisionGroup = btBroadphaseProxy::DefaultFilter;  ///< The cape's collision filter group (bit mask).
  int collisionMask = btBroadphaseProxy::AllFilter;       ///< The groups the cape collides with (bit mask).
  /// m: how far beyond the cape's particle bounds discovery looks; covers a step's motion of fast bodies.
  btScalar discoveryMargin = btScalar(0.25);

  /// How much of the reference body's motion the free particles feel, 0..1 (character-cloth "inertia").
  /// 1: all of it (plain physics). 0: the cape rides along with the body's frame as if glued to it, feeling
  /// none of its acceleration. Implemented as a change of frame before each step: every particle (and the
  /// start of every pin's sweep) moves by (1 - inertia) of the reference body's displacement (linear) and of
  /// its rotation about its origin (angular) over the step; velocities turn with that rotation.
  btScalar linearInertia = btScalar(1);
  btScalar angularInertia = btScalar(1);  ///< 0..1: the same for the body's rotation (see linearInertia).

  /// Speed limits (as Magica Cloth 2's and Chaos Cloth's): of the reference body's motion the cape feels
  /// (after the inertia above), no more than maxLinearSpeed (m/s) of travel and maxAngularSpeed (rad/s; 360
  /// degrees per second is 2 pi) of turn; the rest moves the cape along with the body, as an inertia of 0
  /// would. So a character dashing at 30 m/s or spinning on the spot drags its cape no harder than one moving
  /// at the limits. 0 (the default), negative or not finite: no limit.
  btScalar maxLinearSpeed = btScalar(0);
  btScalar maxAngularSpeed = btScalar(0);  ///< rad/s (see maxLinearSpeed)

  /// A reference body moving farther than this in one step (m), or turning more than teleportAngle (rad),
  /// teleports: the whole cape is moved rigidly with it (Cape::teleport) and no collider is swept.
  btScalar teleportDistance = btScalar(1);
  btScalar teleportAngle = btScalar(1.0);  ///< rad: a turn in one step beyond this teleports (see above).
  /// After the rigid move of a teleport, keep the cape's shape and motion or reset it to rest in its
  /// reference pose (TeleportMode).
  TeleportMode teleportMode = TeleportMode::Keep;

  /// Take gravity from the world the cape steps in (btDynamicsWorld::getGravity(), read before every step),
  /// so a Z-up world or a changed gravity needs nothing more. Off: CapeSettings::gravity stays in force. A
  /// world whose gravity is not finite leaves the cape's gravity as it was, with one warning.
  bool useWorldGravity = true;

  /// The cape simulates in a frame of its own (Cape::origin, local space as NvCloth's), so a character far
  /// from the world's origin gets the precision it has at the origin: its particles, pins and colliders are
  /// float coordinates relative to a point on a grid of this spacing (m), taken in double from Bullet's
  /// poses. The point is the grid point nearest the placement, and then, whenever the reference body is more
  /// than one spacing (along an axis) from it, the grid point nearest the body. A cape within half a spacing
  /// of the world's origin keeps the world's frame (origin zero) until it travels a spacing away; a teleport
  /// moves the frame with the cape exactly, however far. 0: always the world's frame (a float world
  /// position far from the origin then loses the precision Bullet's float loses there).
  btScalar frameSpacing = btScalar(16);
};

/// A level of detail: how often and how finely a cape steps (CapeAction::setDetailLevel, or by distance
/// from a viewpoint with CapeGroup::setDetailPolicy). The cape's state is carried across a switch as it is
/// (the same particles, pins and velocities), so no particle jumps when the level changes; to and from a
/// coarse fabric the coarse particles start from the cape's state and the fine detail fades over
/// Cape::kCoarseBlendTime (Cape::setCoarseLevel).
struct DetailLevel {
  /// The cape steps once every this many internal steps of the world (1..kMaxStepInterval), over their
  /// time together: the pins and colliders are swept over the longer step, discovery looks as many times
  /// farther (CapeActionSettings::discoveryMargin times the interval), and the steps between cost nothing.
  /// 4 steps a cape in a 1/240 s world once per 1/60 s frame. 1: every internal step (full detail).
  int stepInterval = 1;
  /// Substeps per CapeSettings::timeStep at this level (Cape::setSubstepOverride); 0: the settings' own.
  int substeps = 0;
  /// Step the fabric's coarse level (Cape::setCoarseLevel, Fabric::coarseLevel: a 20 x 20 grid's 10 x 10)
  /// and interpolate the cape's particles from it: about a quarter of the work per substep. Grid fabrics
  /// only (CapeAction::setDetailLevel refuses it for a fabric without a coarse level; a CapeGroup policy
  /// steps such a cape on its own fabric at the band's interval and substeps).
  bool coarseFabric = false;

  /// The largest stepInterval.
  static constexpr int kMaxStepInterval = 64;
  /// An error naming the field for an interval outside 1..kMaxStepInterval or substeps outside 0..1000.
  Status validate() const;
  /// Full detail: every internal step, the settings' substeps, the cape's own fabric.
  bool full() const { return stepInterval == 1 && substeps == 0 && !coarseFabric; }
  /// The same interval, substeps and fabric.
  bool operator==(const DetailLevel& o) const {
    return stepInterval == o.stepInterval && substeps == o.substeps && coarseFabric == o.coarseFabric;
  }
  /// A different interval, substeps or fabric.
  bool operator!=(const DetailLevel& o) const { return !(*this == o); }
};

/// One particle pinned to a rigid body at a point in the body's frame.
struct Attachment {
  std::uint32_t particle = 0;         ///< The pinned particle's index.
  const btRigidBody* body = nullptr;  ///< Never dereferenced once the body left the world.
  btVector3 localPivot{0, 0, 0};      ///< m, in the body's frame.
};

/// One cape stepping with a Bullet world (a btActionInterface): pins on rigid bodies, colliders from the
/// bodies it touches, the cloth physics delegated to cape::Cape. See CapeAction.h for discovery and
/// ownership; positions in metres, world.
class CAPE_BULLET_API CapeAction : public btActionInterface {
 public:
  /// What attachNearest() returns when nothing was attached.
  static constexpr std::uint32_t kNoParticle = 0xffffffffu;

  /// A cape at the fabric's rest shape placed by `placement` (world = placement * rest), at rest.
  /// Check ok(): on bad fabric or settings the cape is empty and updates do nothing.
  CapeAction(FabricPtr fabric, const CapeSettings& settings,
             const btTransform& placement = btTransform::getIdentity(),
             const CapeActionSettings& actionSettings = CapeActionSettings());
  ~CapeAction() override;
  CapeAction(const CapeAction&) = delete;
  CapeAction& operator=(const CapeAction&) = delete;

  /// True when the core cape was made (cape().status() says why not).
  bool ok() const { return cape_.ok(); }
  /// The core cape (settings, pins, state).
  const Cape& cape() const { return cape_; }
  /// The core cape (settings, pins, state). Prefer the attach/detach methods for body pins.
  Cape& cape() { return cape_; }
  /// The action's own settings.
  const CapeActionSettings& actionSettings() const { return settings_; }
  /// Replaces the action's settings (read at the next step).
  void setActionSettings(const CapeActionSettings& settings) {
    settings_ = settings;
    changed_ = true;
  }
  /// Level of detail from the next internal step on (DetailLevel): an error for an interval outside
  /// 1..DetailLevel::kMaxStepInterval or substeps outside 0..1000, keeping the level in use. Internal steps
  /// already skipped at the old level count towards the new one's interval (a switch to full detail steps
  /// the cape at once, over the time it skipped).
  Status setDetailLevel(const DetailLevel& level);
  /// The level of detail in use.
  const DetailLevel& detailLevel() const { return detail_; }
  /// The point a level-of-detail policy measures its distance to (CapeGroup::setDetailPolicy), m, world:
  /// the mean of the pins' targets, or particle 0 when nothing is pinned.
  btVector3 detailPoint() const;
  /// True when prepare() planned a step of the cape that advance() has not taken yet (false after an
  /// internal step skipped at a level of detail, or when nothing can step).
  bool stepDue() const { return due_; }
  /// Where warnings go (stderr by default; an empty handler drops them).
  void setWarningHandler(WarningHandler handler) { warn_ = std::move(handler); }

  // --- Attachments --------------------------------------------------------------------------------------
  /// Pins `particle` to `body` at `localPivot` (m, body frame); the particle jumps there at the next step.
  /// Re-attaching an attached particle moves its attachment. False on a bad particle or null body.
  bool attach(std::uint32_t particle, const btRigidBody* body, const btVector3& localPivot);
  /// Pins `particle` to `body` where the particle is now.
  bool attach(std::uint32_t particle, const btRigidBody* body);
  /// Pins the particle nearest to `worldPoint` to `body` at that point. Returns the particle (kNoParticle
  /// on failure).
  std::uint32_t attachNearest(const btRigidBody* body, const btVector3& worldPoint);
  /// Pins a whole grid row (row 0 is the top; fabrics built by Fabric::grid only) where its particles are
  /// now. Returns how many particles were attached.
  std::size_t attachRow(int row, const btRigidBody* body);
  /// Releases a particle (it falls freely again).
  void detach(std::uint32_t particle);
  /// Releases every particle attached to `body` (call before deleting an attached body). Compares
  /// pointers only, so it is safe with a body already deleted.
  void detach(const btCollisionObject* body);
  /// Releases every attached particle.
  void detachAll();
  /// Every attachment, in the order they were made.
  const std::vector<Attachment>& attachments() const { return attachments_; }
  /// The body whose motion inertia and teleports refer to: set here, else the first attachment's body.
  void setReferenceBody(const btRigidBody* body) {
    referenceBody_ = body;
    changed_ = true;
  }

  // --- Colliders ---------------------------------------------------------------------------------------
  /// Always collide with `object` (whether or not discovery is on or would find it).
  void addCollider(const btCollisionObject* object);
  /// Stop colliding with an object added by addCollider (discovery may still find it).
  void removeCollider(const btCollisionObject* object);
  /// The core colliders of the last step (poses at its start and end, in the cape's frame: world less
  /// frameOrigin()), for drawing, metrics and tests.
  const std::vector<Collider>& coreColliders() const { return colliders_; }
  /// The collision objects whose shapes were used in the last step (in a deterministic order).
  const std::vector<const btCollisionObject*>& activeObjects() const { return activeObjects_; }
  /// Triangle-mesh colliders (meshes, heightfields) in the last step; their triangles near the cape are
  /// gathered with Bullet's mesh queries once per step.
  std::size_t meshShapeCount() const { return meshCount_; }

  // --- Stepping ----------------------------------------------------------------------------------------
  /// One internal step of the world (dt s): prepare() then advance().
  void updateAction(btCollisionWorld* world, btScalar dt) override;
  /// Draws the cape as Bullet's debug drawers expect (world coordinates, m), by the drawer's debug mode:
  /// always every triangle filled (drawTriangle, with its face normal at the corners, in the colour of
  /// setDebugColor) and each pin's target as a 1 cm sphere; with DBG_DrawWireframe the triangles' edges, with
  /// DBG_DrawNormals the face normals (5 cm), with DBG_DrawContactPoints every particle within the
  /// thicknesses of a collider of the last step (drawContactPoint at the collider's nearest surface point,
  /// outward normal, signed distance), with DBG_DrawAabb the cape's bounds. A world calls it from
  /// debugDrawWorld() when the mode has DBG_DrawWireframe, DBG_DrawAabb or DBG_DrawNormals.
  void debugDraw(btIDebugDraw* drawer) override;
  /// The faces' colour in debugDraw (red, green, blue in 0..1); the edges are drawn at half of it.
  void setDebugColor(const btVector3& color) { debugColor_ = color; }

  /// The two halves of updateAction, for CapeGroup: prepare() reads the world (bodies still present,
  /// their poses, collider discovery) and must run on one thread; advance() touches only this cape and
  /// the shapes' read-only data, so several capes may advance at once on different threads.
  void prepare(btCollisionWorld* world, btScalar dt);
  /// The second half of updateAction: steps the core cape against the colliders prepare() built, over the
  /// time prepare() planned (dt s at full detail; the skipped internal steps' time too at a coarser level);
  /// nothing when prepare() planned no step (stepDue()). `dt` is that of the internal step.
  void advance(btScalar dt);

  // --- Results -----------------------------------------------------------------------------------------
  /// The number of particles (0 when not ok()).
  std::size_t particleCount() const { return cape_.ok() ? cape_.fabric().particleCount() : 0; }
  /// Particle positions, m, world (one row per particle, columns x, y, z), as floats. The solver's own are
  /// cape().state().positions, relative to cape().origin(); with a frame away from the world's origin this
  /// converts them into a buffer of the action's (valid until the next call; not for concurrent callers).
  const Points& positions() const;
  /// The world position of the cape's frame (Cape::origin), m.
  const Eigen::Vector3d& frameOrigin() const { return cape_.origin(); }
  /// Moves the cape rigidly, frame and all, so that the frame's origin is `origin` (a translation by
  /// origin - frameOrigin(), exact however far): build a cape placed relative to a point far from the world's
  /// origin, then relocate it there, and it keeps every bit of its shape. Ignored unless finite.
  void relocate(const Eigen::Vector3d& origin);
  /// One particle's position, m, world ((0, 0, 0) for an index out of range).
  btVector3 position(std::uint32_t particle) const;
  /// The render mesh of the cape as it is now, in the world: positions (as positions()), area-weighted
  /// vertex normals, the fabric's UVs and its counter-clockwise triangles; `twoSided` adds a back copy
  /// (flipped winding and normals) for renderers without two-sided shading. Refreshed on each call; its
  /// buffers are allocated on the first call (and again only when `twoSided` changes), never after. The
  /// reference stays valid until the next call or the action's end.
  const CapeMesh& mesh(bool twoSided = false) const;
  /// Particle positions, m, world, at the time of the bodies' rendered poses: what a renderer that draws
  /// the bodies from their motion states should draw (with a remainder, stepSimulation writes each dynamic
  /// body's motion state at a time between its last two internal steps, Bullet's interpolation). The cape
  /// of the last internal step (positions()) is carried rigidly by the reference body's motion from its
  /// pose at that step to its rendered pose, and every attached particle is put on its attachment point at
  /// its body's rendered pose: the cape is drawn in the character's frame as it moves on between steps, as
  /// Chaos Cloth and NvCloth draw the simulation they keep in the character's space. A body's rendered pose
  /// is its motion state's transform when it has one (Bullet's interpolated pose for a dynamic body, the
  /// user's for a kinematic one), else its world transform. `world` is the world the action steps in; only
  /// bodies still in it are read (one that left it, or whose rendered pose is not finite, keeps its pose of
  /// the last step). Allocates nothing after the first call; valid until the next call; not for concurrent
  /// callers.
  const Points& renderPositions(const btCollisionWorld& world) const;
  /// The render mesh (as mesh()) at renderPositions(world): positions, normals, UVs and triangles as a
  /// renderer drawing the bodies from their motion states should draw the cape.
  const CapeMesh& renderMesh(const btCollisionWorld& world, bool twoSided = false) const;
  /// Wall time of the cape's own work in the last internal step (prepare() and advance()), microseconds.
  /// The advance of a resting cape (asleep, nothing it follows changed) only counts the step and is not
  /// timed: its time is the prepare's.
  double lastStepMicroseconds() const { return lastStepMicroseconds_; }
  /// Sum of lastStepMicroseconds() over the internal steps since the last call of this function (a frame's
  /// cape time when called once per stepSimulation).
  double takeAccumulatedMicroseconds();
  /// Pin error of docs/SCENES.md: the largest distance, m, of an attached particle from its attachment point
  /// at the body pose of the last step's end (the pose the action drove the pin to; no body is dereferenced).
  btScalar maxPinError() const;
  /// True when the last step teleported the cape.
  bool teleportedLastStep() const { return teleported_; }
  /// Steps the cape took so far (one per internal step at full detail; see DetailLevel).
  std::uint64_t stepCount() const { return stepCount_; }

 private:
  /// A collision object the action follows: an attachment body, a collider, or both.
  struct Tracked {
    const btCollisionObject* object = nullptr;
    btTransform lastSeen;          ///< Its world transform when last read (the rest: in the cape's frame).
    btTransform segmentStart;      ///< The motion being spread over internal steps: from here...
    btTransform segmentEnd;        ///< ...to here,
    btScalar segmentDuration = 0;  ///< over this long, s (from the body's velocity; 0: at once).
    btScalar segmentElapsed = 0;   ///< s spent of it so far.
    btTransform stepStart;         ///< Pose at the start of this internal step.
    btTransform stepEnd;           ///< Pose at the end of this internal step.
    bool jumped = false;           ///< Teleported in this step: no sweep.
    bool settled = false;  ///< After the last full prepare: not jumped, its motion spent (start = end).
    bool present = false;  ///< Still in the world at this update (set by a full scan).
    int worldIndex = -1;   ///< Index in the world's collision object array when last seen there
                           ///< (a hint: checked by pointer comparison before it is trusted).
    bool explicitCollider = false;
    bool discovered = false;  ///< Found by discovery for this step.
    bool converted = false;
    ShapeConversion shape;
    std::vector<std::shared_ptr<TriangleSoup>> soups;  ///< One per shape.meshes, refilled every step.
  };

  Tracked& track(const btCollisionObject* object);
  Tracked* find(const btCollisionObject* object);
  void followGravity(btCollisionWorld* world);
  void dropMissing(btCollisionWorld* world);
  void discover(btCollisionWorld* world);
  /// Asleep with nothing followed moving, coming or going: the step needs nothing new from the world.
  bool resting() const;
  void advancePoses(btScalar dt);
  void applyTeleport();
  void applyInertia(btScalar dt);
  void updatePins();
  void buildColliders();
  void gatherTriangles(const btConcaveShape* shape, const btTransform& start, const btTransform& end,
                       TriangleSoup& soup) const;
  void refreshPinIndices();
  /// A world pose in the cape's frame (the origin subtracted in double), and the frame's grid point near p.
  btTransform toFrame(const btTransform& world) const;
  /// A point of the cape's frame (relative to Cape::origin) in the world, m.
  btVector3 toWorld(const Vec3& framePoint) const;
  Eigen::Vector3d gridPoint(const btVector3& worldPoint) const;
  /// Moves the cape's frame to `origin` (the cape stays put in the world, or jumps with the frame when
  /// `carry`) and re-expresses every followed pose in it.
  void moveFrame(const Eigen::Vector3d& origin, bool carry);
  void followReference();
  void reportGuard();
  void warnOnce(const std::string& key, const std::string& message);
  /// Warnings held back while prepare() runs on a worker of a CapeGroup, said on its calling thread.
  void sayDeferredWarnings();
  friend class CapeGroup;  // defers warnings around a parallel prepare
  const btRigidBody* referenceBody() const;
  /// How far beyond the cape's bounds discovery and mesh queries look for one step of the cape, m.
  btScalar discoveryReach() const;
  /// The particles' lowest (`low`) or highest coordinates in the cape's frame, m (kept while it sleeps).
  Vec3 particleBounds(bool low);

  Cape cape_;
  CapeActionSettings settings_;
  WarningHandler warn_;
  std::unordered_set<std::string> warned_;
  bool deferWarnings_ = false;  ///< warnOnce() holds its messages in deferred_.
  std::vector<std::string> deferredWarnings_;

  std::vector<Attachment> attachments_;
  std::vector<std::size_t> pinIndex_;  ///< Core pin index of each attachment.
  const btRigidBody* referenceBody_ = nullptr;

  std::vector<Tracked> tracked_;
  std::unordered_map<const btCollisionObject*, std::size_t> trackedIndex_;
  /// Discovery's scratch: (world array index, object) of every object the broadphase reported this step.
  std::vector<std::pair<int, const btCollisionObject*>> found_;
  std::vector<std::pair<int, const btCollisionObject*>> lastFound_;  ///< found_ of the step before
  /// The broadphase's report of the step before, in its order (before found_ was sorted).
  std::vector<std::pair<int, const btCollisionObject*>> lastReported_;
  bool discoveryChanged_ = true;
  bool changed_ = true;  ///< Colliders, settings or the reference body changed since the last full prepare.

  std::vector<Collider> colliders_;
  std::vector<const btCollisionObject*> activeObjects_;
  std::size_t meshCount_ = 0;

  /// The rendered pose of a followed body (renderPositions()) in the cape's frame, if it is in `world`.
  bool renderedPose(const btCollisionWorld& world, const btRigidBody* body, btTransform& framePose) const;

  Vec3 boundsLow_ = Vec3::Zero(), boundsHigh_ = Vec3::Zero();
  bool boundsKept_ = false;  ///< particleBounds() holds a sleeping cape's bounds.
  DetailLevel detail_;
  int skippedSteps_ = 0;      ///< Internal steps since the cape last stepped (at a coarser level).
  btScalar skippedTime_ = 0;  ///< Their time, s.
  bool due_ = false;          ///< prepare() planned a step of stepTime_ s.
  bool resting_ = false;  ///< prepare() found the cape resting (resting()): advance() only counts the step.
  btScalar stepTime_ = 0;

  bool teleported_ = false;
  mutable Points worldPositions_;   ///< positions() when the frame is away from the world's origin.
  mutable Points renderPositions_;  ///< renderPositions()'s buffer.
  mutable CapeMesh mesh_;           ///< mesh()'s buffers.
  mutable bool meshAllocated_ = false;
  std::uint64_t guardReported_ = 0;
  std::uint64_t stepCount_ = 0;
  double lastStepMicroseconds_ = 0.0;
  double prepareMicroseconds_ = 0.0;
  double accumulatedMicroseconds_ = 0.0;
  btVector3 debugColor_{btScalar(0.9), btScalar(0.2), btScalar(0.2)};
};

}  // namespace cape::bullet
