/// \file
/// One walking character in a Bullet world: a Skeleton posed by a Gait through a JointMapping, and its
/// CharacterBodies. The short way to run a scene:
///
/// \code{.cpp}
///   auto model = cape::character::UrdfModel::humanoid();            // or UrdfModel::fromFile(path)
///   if (!model.ok()) { print(model.status.message()); return; }
///   auto made = cape::character::Character::create(model.model, world,
///                                                  cape::character::Gait::forScene(cape::SceneKind::Walk));
///   for (const std::string& w : made.character->warnings()) print(w);
///   btRigidBody* leftShoulder = made.character->bodies().bodyForLink("left_shoulder");
///   std::printf("root %.3f m above the ground\n", made.character->rootHeight());
///   for (int frame = 1; frame <= 600; ++frame) {
///     made.character->advanceTo(frame / 60.0);  // poses the skeleton, moves the bodies (velocities too)
///     world.stepSimulation(1 / 60.f, 8, 1 / 240.f);
///     made.character->skeleton().worldShapes(shapes);  // colliders to export: link, type, sizes, world pose
///   }
/// \endcode
///
/// It stands on the ground: its root goes where the lowest collision point of its standing pose touches
/// world y = 0 (Grounding.h), or at CharacterSettings::rootHeight. A floating base (a root at the pelvis, a
/// floating joint, a dummy "world" link) is said in warnings(). CharacterSettings::pose gives it a starting
/// pose; parsePose reads one from text.
#pragma once

#include "cape/character/CharacterBodies.h"
#include "cape/character/Export.h"
#include "cape/character/Gait.h"
#include "cape/character/JointMapping.h"
#include "cape/character/Motion.h"
#include "cape/character/Skeleton.h"

#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace cape::character {

/// A starting joint configuration: (joint name, position in rad, or m for a prismatic joint) pairs.
using JointPose = std::vector<std::pair<std::string, double>>;
/// Rotations of spherical joints by name (see Skeleton::setJointRotation).
using JointRotations = std::vector<std::pair<std::string, Eigen::Quaterniond>>;

/// How Character::create builds a character: scale, where it stands, its bodies, the world's up axis, its
/// root height and starting pose.
struct CharacterSettings {
  double scale = 1.0;                                ///< uniform scale of the URDF, > 0
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  ///< m, world, added to the gait's root path (a crowd)
  BodySettings bodies;                               ///< collision group, mask, ...
  /// The world's up axis: the gait and the offset stay in the Y-up scene frame, the bodies are turned into
  /// the world by Skeleton::sceneToWorld(up).
  UpAxis up = UpAxis::Y;
  /// m: the height of the URDF root link origin above the ground (world y = 0; the offset and the gait's bob
  /// come on top). Unset: automatic, so that the lowest collision point of the standing pose (the gait's
  /// standingAngles with `pose` applied) touches the ground; a root already on the ground stays at exactly 0.
  std::optional<double> rootHeight;
  /// The starting pose, the base of every frame: a joint the gait does not drive keeps its value; a joint it
  /// drives gets the gait's angle added to it (its mapping neutral; for a shoulder roll the value replaces
  /// the arms-down neutral). Names must be movable joints of the model (each once); values outside the
  /// limits are clamped, with a warning.
  JointPose pose;
};

/// Parses the demos' `--pose` text: `name=value[,name=value...]` (rad, or m for a prismatic joint; spaces
/// around names and values allowed; an empty text is an empty pose). InvalidArgument, saying which entry and
/// why, for an entry without '=', an empty name, a value that is not a number or not finite, or a name given
/// twice; `out` is then left empty.
CAPE_CHARACTER_API Status parsePose(const std::string& text, JointPose& out);

class Character;
/// What Character::create returns: ok and a character, or an error status and none.
struct CharacterResult {
  Status status;                         ///< Why there is no character, or success
  std::unique_ptr<Character> character;  ///< The character; null on error
  /// True when a character was made.
  bool ok() const { return status.ok() && character != nullptr; }
};

/// One walking character in a Bullet world: a Skeleton posed by a Gait (or the user's motion, or a clip)
/// through a JointMapping, and its CharacterBodies (see Character.h for the short way to run a scene).
class CAPE_CHARACTER_API Character {
 public:
  /// Builds the skeleton (joints mapped with JointMapping::automatic, unless `mapping` is given), applies the
  /// settings' pose, places the root on the ground (see CharacterSettings::rootHeight), poses it at t = 0 and
  /// adds its bodies to `world` at rest. Errors: InvalidArgument (null model, bad scale, a non-finite root
  /// height or pose value, a joint named twice); UnknownJoint and NotMovable for a pose naming no joint or a
  /// fixed one (the message lists the model's movable joints).
  static CharacterResult create(const UrdfModelPtr& model, btDynamicsWorld& world, const Gait& gait,
                                const CharacterSettings& settings = {},
                                const JointMapping* mapping = nullptr);

  /// Poses the skeleton at time t (s) and moves the bodies there, with velocities over t - time(). A t not
  /// after time() is a jump (teleport, zero velocity). Call before stepping the world.
  void advanceTo(double t);
  /// s: the time of the last pose.
  double time() const { return time_; }

  /// The user's own motion at time t (s), from a controller or an animation system, instead of the gait:
  /// `rootLinkPose` is the URDF root link's pose in `frame` (CharacterSettings::offset added, the automatic
  /// root height not: the pose is where the root link goes), `joints` positions by name (rad, or m for a
  /// prismatic joint; clamped to the limits), `rotations` spherical joints' rotations by name. Joints not
  /// given keep their value. The bodies move there with the velocities of the change since time() (a t not
  /// after time() is a jump, as for advanceTo), so Bullet's contacts and the cape's sweeps see the motion.
  /// Errors, with nothing changed: UnknownJoint and NotMovable (the message lists the model's joints of the
  /// kind), InvalidArgument (t, the pose or a value not finite, a zero quaternion, a joint given twice). No
  /// allocation once the character has run a frame.
  Status setMotion(double t, const Eigen::Isometry3d& rootLinkPose, const JointPose& joints = {},
                   const JointRotations& rotations = {}, MotionFrame frame = MotionFrame::World);
  /// A clip's pose at time t through a player bound to this character's model (MotionPlayer::create with
  /// skeleton()), moved as setMotion moves it. InvalidArgument for a player bound to another model or a t
  /// that is not finite. No allocation once it has run a frame.
  Status play(const MotionPlayer& player, double t);

  Character(const Character&) = delete;  // the bodies point at this skeleton: not copyable, not movable
  Character& operator=(const Character&) = delete;

  /// The posed skeleton.
  const Skeleton& skeleton() const { return skeleton_; }
  /// The character's Bullet bodies.
  CharacterBodies& bodies() { return *bodies_; }
  /// The character's Bullet bodies.
  const CharacterBodies& bodies() const { return *bodies_; }
  /// The gait advanceTo() follows.
  const Gait& gait() const { return gait_; }
  /// Which joint plays each role of the gait.
  const JointMapping& mapping() const { return mapping_; }
  /// The settings it was made with.
  const CharacterSettings& settings() const { return settings_; }
  /// m: the height of the URDF root link origin above the ground that was chosen (CharacterSettings::
  /// rootHeight, or the automatic one); the gait's bob and the offset come on top.
  double rootHeight() const { return rootHeight_; }
  /// The model's load warnings, then the mapping's (unmapped roles and why), then the character's own (pose
  /// values clamped, a floating base and how it was placed, no collision shapes).
  std::vector<std::string> warnings() const;

 private:
  Character(const UrdfModelPtr& model, const Gait& gait, const CharacterSettings& settings,
            JointMapping mapping);
  Status applyPose();  // the settings' pose: checked, clamped, into the skeleton and the mapping's neutrals
  void placeOnTheGround();
  void moveBodiesTo(double t);  // after the skeleton is posed at t
  Eigen::Isometry3d withOffset(const Eigen::Isometry3d& urdfFramePose) const;
  Skeleton skeleton_;
  Gait gait_;
  CharacterSettings settings_;
  JointMapping mapping_;
  std::unique_ptr<CharacterBodies> bodies_;  ///< made after the skeleton is posed; reads skeleton_
  double time_ = 0.0;
  double rootHeight_ = 0.0;
  Eigen::Vector3d rootOffset_ = Eigen::Vector3d::Zero();  ///< settings' offset, raised by the root height
  std::vector<std::pair<int, double>> pose_;              ///< joint index, clamped value
  std::vector<std::string> warnings_;
  std::vector<char> given_;  ///< setMotion: joints named so far in this call
  MotionPose sampled_;       ///< play: the clip's pose, reused
};

}  // namespace cape::character
