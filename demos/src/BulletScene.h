// The canonical scenes of docs/SCENES.md in a Bullet world: each character as kinematic rigid bodies
// (the shipped humanoid or a URDF through the character library, or the simple body of docs/SCENES.md), a
// static ground plane, and where each character's cape starts and which bodies it is pinned to. The world is
// stepped as docs/SCENES.md says: stepSimulation(1/60, 8, 1/240). cape_walk puts our cape on it; cape_compare
// puts our cape on one and the btSoftBody twin on another.
#pragma once

#include "SceneRun.h"

#include "cape/bullet/CapeAction.h"
#include "cape/character/Anchors.h"
#include "cape/character/Character.h"

#include <BulletSoftBody/btDeformableBodySolver.h>
#include <BulletSoftBody/btDeformableMultiBodyConstraintSolver.h>
#include <BulletSoftBody/btDeformableMultiBodyDynamicsWorld.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>
#include <btBulletDynamicsCommon.h>

#include <memory>
#include <string>
#include <vector>

namespace cape::demo {

/// A cape particle pinned to a body at a point in the body's frame (m).
struct PinSpec {
  std::uint32_t particle = 0;
  btRigidBody* body = nullptr;
  btVector3 localPivot{0, 0, 0};
};

/// Which Bullet world the scene lives in: the soft-rigid world of btSoftBody (the default; our cape and
/// the btSoftBody twin), or Bullet's deformable world (deformable bodies with Lagrangian forces,
/// multibodies), where cape_compare puts the deformable twin.
enum class WorldKind { SoftRigid, Deformable };

class BulletScene {
 public:
  /// Builds the world and its characters for the options; nullptr and a one-line reason on bad input
  /// (unreadable or malformed URDF, unknown attachment link, no link to attach to).
  /// `warnings`, when given, receives what was said on the way, also when the build fails (a URDF's skipped
  /// elements may be why).
  static std::unique_ptr<BulletScene> create(const RunOptions& options, std::string& error,
                                             WorldKind kind = WorldKind::SoftRigid,
                                             std::vector<std::string>* warnings = nullptr);
  ~BulletScene();
  BulletScene(const BulletScene&) = delete;
  BulletScene& operator=(const BulletScene&) = delete;

  /// The world, whichever kind (actions, rigid bodies).
  btDiscreteDynamicsWorld& world() { return *world_; }
  /// The soft-rigid world, or nullptr in a deformable scene.
  btSoftRigidDynamicsWorld* softRigidWorld() { return softRigidWorld_; }
  /// The deformable world, or nullptr in a soft-rigid scene.
  btDeformableMultiBodyDynamicsWorld* deformableWorld() { return deformableWorld_; }
  int characterCount() const { return static_cast<int>(characters_.size()); }
  /// The cape every character wears (fabric, pinned particles).
  const CapeRig& rig() const { return rig_; }
  /// The scene's motion (its length, speeds).
  const MotionDesc& motion() const { return motion_; }

  /// Moves every character to its pose at time t (s), then steps the world one 1/60 s frame; returns the
  /// wall time of the stepSimulation call, µs.
  double stepFrame(double t);
  /// The wall time of the last stepFrame's character motion (poseAt: the gait or the clip), µs.
  double lastMotionTimeUs() const { return motionUs_; }

  /// A character's body colliders at its current pose (true surfaces, ground excluded), for the metrics and
  /// colliders.jsonl, relative to the world point `frame` (a cape's frame; subtracted in double).
  std::vector<Collider> bodyColliders(int character,
                                      const Eigen::Vector3d& frame = Eigen::Vector3d::Zero()) const;
  /// Where the blow-up metric measures from: the torso's centre, relative to `frame`.
  Vec3 torsoCentre(int character, const Eigen::Vector3d& frame = Eigen::Vector3d::Zero()) const;
  /// The scene's origin in the world (--origin): the characters start there, on the ground through it.
  const Eigen::Vector3d& origin() const { return options_.origin; }
  /// The cape's starting placement relative to origin() (world = origin + placement * fabric rest shape).
  Pose capePlacement(int character) const;
  /// Puts a character's new cape (made at capePlacement and relocated to its frame) in the shape it starts
  /// in: a gathered cape (PinLayout::Gathered) gathered onto its collar, its top row on the pins; any other
  /// as it was placed.
  void startCape(int character, bullet::CapeAction& cape) const;
  /// The collar a gathered cape hangs from (across the character's shoulder span).
  const CollarShape& collar() const { return collar_; }
  /// The cape's pins: particles, bodies and body-frame pivots.
  const std::vector<PinSpec>& pins(int character) const;
  /// One line for summary.json: the body, the attachment links, the stepping.
  std::string describe() const;
  /// Load and mapping warnings worth printing once (meshes left out, joints the gait could not map).
  const std::vector<std::string>& warnings() const { return warnings_; }
  /// What was chosen for the user (where the cape is pinned, its size), worth printing once.
  const std::vector<std::string>& notes() const { return notes_; }
  /// The world's up direction (+Y, or +Z with --up z), and the turn from the Y-up scene frame into the world.
  Vec3 up() const { return toWorld_ * Vec3::UnitY(); }
  const Eigen::Matrix3f& sceneToWorld() const { return toWorld_; }
  /// The cape's size (canonical, or fitted to the character's shoulders).
  const CapeSize& capeSize() const { return capeSize_; }
  /// The options' cape settings with the fabric preset applied (RunOptions::fabric), if any.
  const CapeSettings& settings() const { return settings_; }

 private:
  struct Character;
  BulletScene() = default;
  bool build(const RunOptions& options, WorldKind kind, std::string& error);
  void makeWorld(WorldKind kind);
  bool loadModel(const RunOptions& options, std::string& error);
  void addSimpleCharacter(const Vec3& offset);
  bool addUrdfCharacter(const Vec3& offset, bool first, std::string& error);
  void placeCape(Character& c);
  /// The cape's rig and size: `fitted` (the canonical size, or the one fitted to the character) unless the
  /// options give a width or a height. False and the reason when no such cape can be built.
  /// The rig for the fitted size (or the options' size), its collar across `shoulderSpan` (m).
  bool makeRig(const CapeSize& fitted, double shoulderSpan, std::string& error);
  Vec3 toWorld(const Vec3& scene) const;
  void poseAt(double t);

  // Bullet's world, in construction order (destroyed in reverse).
  std::unique_ptr<btSoftBodyRigidBodyCollisionConfiguration> configuration_;
  std::unique_ptr<btCollisionDispatcher> dispatcher_;
  std::unique_ptr<btDbvtBroadphase> broadphase_;
  std::unique_ptr<btDeformableBodySolver> deformableSolver_;  ///< Deformable worlds only.
  std::unique_ptr<btConstraintSolver> solver_;
  std::unique_ptr<btDiscreteDynamicsWorld> world_;
  btSoftRigidDynamicsWorld* softRigidWorld_ = nullptr;             ///< world_, when it is one
  btDeformableMultiBodyDynamicsWorld* deformableWorld_ = nullptr;  ///< world_, when it is one
  std::unique_ptr<btStaticPlaneShape> groundShape_;
  std::unique_ptr<btRigidBody> ground_;

  RunOptions options_;
  MotionDesc motion_;
  Eigen::Matrix3f toWorld_ = Eigen::Matrix3f::Identity();  ///< Y-up scene frame -> world
  character::UrdfModelPtr model_;
  character::MotionClip clip_;                       ///< --motion, as loaded
  std::unique_ptr<character::MotionPlayer> player_;  ///< bound to model_ by the first character
  double motionUs_ = 0.0;                            ///< stepFrame's poseAt, µs
  CapeSize capeSize_;
  CollarShape collar_;
  CapeSettings settings_;
  CapeRig rig_;
  std::vector<std::unique_ptr<Character>> characters_;
  std::vector<std::string> attachLinks_;
  std::string body_;
  std::vector<std::string> warnings_;
  std::vector<std::string> notes_;
  std::string attachDescription_;
};

}  // namespace cape::demo
