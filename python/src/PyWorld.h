// The C++ side of the capecloth Python module: a Bullet world that owns everything Python adds to it
// (kinematic bodies, URDF characters, capes) and hands out plain values. Nothing here knows Python; bad
// input throws std::invalid_argument (ValueError in Python), a missing file FileNotFound (FileNotFoundError),
// a failure of the library std::runtime_error (RuntimeError), each with the library's message.
//
// Units: metres, seconds, kilograms, radians. Poses are rigid transforms in the world (x_world = R x_local +
// p). The world's up axis is +Y (the scenes' frame) or +Z (ROS, PyBullet, MuJoCo); gravity points down it.
//
// Threads: every public function takes the world's mutex, so Python threads may call in while step() runs
// with the GIL released; they wait for the step to finish.
#pragma once

#include "GltfExport.h"

#include "cape/bullet/CapeAction.h"
#include "cape/character/Character.h"
#include "cape/scenes/Metrics.h"
#include "cape/scenes/Scene.h"

#include <btBulletDynamicsCommon.h>

#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

namespace capepy {

/// A file that is not there (FileNotFoundError in Python).
class FileNotFound : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class BodyShape { Sphere, Box, Capsule };

struct WorldSettings {
  cape::character::UpAxis up = cape::character::UpAxis::Y;
  bool ground = true;         ///< a static ground plane through the origin, normal +up
  double groundHeight = 0.0;  ///< m along up
  /// m/s^2, world; unset: 9.81 down the up axis.
  std::optional<Eigen::Vector3d> gravity;
};

/// Which character and how: the shipped humanoid or a URDF file or text.
struct CharacterSpec {
  std::string path;  ///< a URDF file (empty: `text`, or the humanoid when that is empty too)
  std::string text;  ///< URDF text
  std::vector<std::string> packagePaths;
  double scale = 1.0;
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  ///< m, Y-up scene frame, added to the root path
  std::string gait = "stand";    ///< "stand" or a scene name: "walk", "sprint-turn", "hang", "wind", "crowd"
  std::string modelUp = "auto";  ///< the model's own up axis in its file: "auto", "z", "y"
};

/// A cape's rig: the canonical grid (cape::makeCapeRig) and its size.
struct CapeSpec {
  int resolution = 20;           ///< particles per side, 3..128
  std::string pins = "corners";  ///< "corners" or "collar"
  std::optional<double> width;   ///< m; unset: 0.6 on bodies, fitted on a character
  std::optional<double> height;  ///< m; unset: 1.0 on bodies, fitted on a character
  /// A fabric preset (cape/core/FabricPresets.h: "silk", "cotton", ...): its mass per area, and its springs,
  /// damping and wind coefficients applied over `settings` for the grid's spacing. Empty: none.
  std::string fabric;
  cape::CapeSettings settings;
};

/// A collider of a kinematic body, in the world (what the cape collides with).
struct ColliderInfo {
  std::string owner;  ///< the body's name, or "<character name>/<link>"
  cape::ColliderShape shape = cape::ColliderShape::Sphere;
  double radius = 0.0, halfHeight = 0.0;  ///< m
  int axis = 1;                           ///< capsule and cylinder: 0 x, 1 y, 2 z (local)
  Eigen::Vector3d halfExtents = Eigen::Vector3d::Zero();
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
};

class World {
 public:
  explicit World(const WorldSettings& settings);
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  cape::character::UpAxis up() const { return settings_.up; }
  double time() const;
  Eigen::Vector3d gravity() const;

  // --- Kinematic bodies of the user -------------------------------------------------------------------
  /// size: sphere (radius), box (half extents x, y, z), capsule (radius, half height between the sphere
  /// centres); axis: the capsule's (0, 1, 2).
  int addBody(BodyShape shape, const Eigen::Vector3d& size, int axis, const Eigen::Isometry3d& pose,
              const std::string& name);
  int bodyCount() const;
  std::string bodyName(int body) const;
  /// Moves a body for the next step (Bullet derives its velocity from the move over the step); teleport:
  /// a jump at rest, not a motion.
  void setBodyPose(int body, const Eigen::Isometry3d& pose, bool teleport);
  /// Every body at once, in the order they were added.
  void setBodyPoses(const std::vector<Eigen::Isometry3d>& poses, bool teleport);
  Eigen::Isometry3d bodyPose(int body) const;

  // --- Characters -------------------------------------------------------------------------------------
  /// Loads and builds a character standing on the ground; returns its index. Its warnings: characterWarnings.
  int addCharacter(const CharacterSpec& spec);
  int characterCount() const;
  std::vector<std::string> characterWarnings(int character) const;
  std::vector<std::string> linkNames(int character) const;
  /// Movable joints (revolute, continuous, prismatic) and spherical joints, by name.
  std::vector<std::string> jointNames(int character) const;
  std::vector<std::string> sphericalJointNames(int character) const;
  /// Each link's world pose from the skeleton (the gait's or set_motion's pose; not set_link_poses').
  std::vector<Eigen::Isometry3d> linkPoses(int character) const;
  double rootHeight(int character) const;
  double characterTime(int character) const;
  /// The gait's pose at time t (s).
  void advanceCharacter(int character, double t);
  /// The user's motion: root link pose (world), joint positions and spherical joints' rotations by name.
  void setCharacterMotion(int character, double t, const Eigen::Isometry3d& root,
                          const cape::character::JointPose& joints,
                          const cape::character::JointRotations& rotations);
  /// Moves each link's body to a pose (link order, as linkNames; links without a body are skipped).
  void setLinkPoses(int character, const std::vector<Eigen::Isometry3d>& poses, bool teleport);

  // --- Capes ------------------------------------------------------------------------------------------
  /// The canonical cape placed by `frame` (the Y-up character frame of docs/SCENES.md in the world: the pins
  /// at frame * (+-w/2, 1.56, 0.15)), each pin on the body (of `bodies`) nearest it.
  int addCapeOnBodies(const CapeSpec& spec, const Eigen::Isometry3d& frame, const std::vector<int>& bodies);
  /// The cape fitted to a character's shoulders (cape::character::findShoulderAnchors at its current pose).
  int addCapeOnCharacter(const CapeSpec& spec, int character);
  int capeCount() const;
  std::string capeDescription(int cape) const;
  cape::CapeSettings capeSettings(int cape) const;
  void setCapeSettings(int cape, const cape::CapeSettings& settings);
  /// Cape::setMotionConstraints; a ValueError with the library's message on bad arrays.
  /// Cape::setMassScale (mass true) or setStiffnessScale: ValueError on bad values, the old scale kept.
  void setWeightScale(int cape, bool mass, const Eigen::VectorXf& scale);
  /// CapeAction::setDetailLevel: ValueError on a bad level, the old one kept.
  void setDetailLevel(int cape, int stepInterval, int substeps, bool coarseFabric);
  /// The cape's level of detail: (step interval, substeps).
  std::tuple<int, int, bool> detailLevel(int cape) const;
  void setMotionConstraints(int cape, const cape::MotionConstraints& constraints);
  /// Each particle's animated position of the last step (Cape::animatedPositions), m, world.
  cape::Points capeAnimatedPositions(int cape) const;
  /// Also counts self-intersecting triangle pairs in the per-frame metrics (costs a spatial hash a frame).
  void setCountSelfIntersections(int cape, bool on);
  bool countSelfIntersections(int cape) const;

  /// Mesh, world: positions and normals one row per particle, triangles CCW, UVs.
  cape::Points capePositions(int cape) const;
  cape::Points capeNormals(int cape) const;
  cape::Points capeVelocities(int cape) const;
  std::vector<std::uint32_t> capeTriangles(int cape) const;
  std::vector<Eigen::Vector2f> capeUvs(int cape) const;
  std::vector<std::uint32_t> capePinnedParticles(int cape) const;
  std::vector<std::string> capeWarnings(int cape) const;
  cape::FrameMetrics capeMetrics(int cape) const;
  cape::RunSummary capeSummary(int cape) const;
  bool capeAsleep(int cape) const;

  // --- Colliders, stepping, export --------------------------------------------------------------------
  /// Every kinematic body's colliders (user bodies, then characters' links), world poses.
  std::vector<ColliderInfo> colliders() const;
  /// `frames` frames of dt s, each stepSimulation(dt, maxSubsteps, fixedStep); then every cape's metrics.
  void step(double dt, int frames, int maxSubsteps, double fixedStep);
  /// Starts recording every cape and every body collider, frame by frame, into a glTF binary; this frame is
  /// the first. Bodies, characters and capes cannot be added while recording.
  void startRecording();
  bool recording() const;
  int recordedFrames() const;
  /// Writes the recording (a .glb) and ends it; returns the frames written.
  int writeRecording(const std::string& path);

 private:
  struct UserBody;
  struct CharacterEntry;
  struct CapeEntry;
  /// One kinematic body's colliders in its own frame, converted once (cape::bullet::convertShape).
  struct BodyColliders {
    const btRigidBody* body = nullptr;
    std::string owner;
    std::vector<std::pair<cape::Collider, btTransform>> parts;
  };

  void checkBody(int body) const;
  void checkCharacter(int character) const;
  void checkCape(int cape) const;
  void checkNotRecording(const char* what) const;
  void addBodyColliders(const btRigidBody* body, const std::string& owner);
  int addCape(const cape::CapeRig& rig, const CapeSpec& spec, const btTransform& placement,
              const std::vector<std::pair<std::uint32_t, std::pair<btRigidBody*, btVector3>>>& pins,
              const btRigidBody* reference, std::string description);
  /// Colliders at their current world poses, less `origin` (a cape's frame).
  std::vector<cape::Collider> currentColliders(const Eigen::Vector3d& origin) const;
  void measureCapes();
  void recordFrame();

  mutable std::mutex mutex_;
  WorldSettings settings_;
  std::unique_ptr<btDefaultCollisionConfiguration> configuration_;
  std::unique_ptr<btCollisionDispatcher> dispatcher_;
  std::unique_ptr<btDbvtBroadphase> broadphase_;
  std::unique_ptr<btSequentialImpulseConstraintSolver> solver_;
  std::unique_ptr<btDiscreteDynamicsWorld> world_;
  std::unique_ptr<btStaticPlaneShape> groundShape_;
  std::unique_ptr<btRigidBody> ground_;
  std::vector<std::unique_ptr<UserBody>> bodies_;
  std::vector<std::unique_ptr<CharacterEntry>> characters_;
  std::vector<std::unique_ptr<CapeEntry>> capes_;
  std::vector<BodyColliders> bodyColliders_;
  std::unique_ptr<cape::demo::GltfRecorder> recorder_;
  double time_ = 0.0;
};

}  // namespace capepy
