// One walking character in a Bullet world: a Skeleton posed by a Gait through a JointMapping, and its
// CharacterBodies. The short way to run a scene:
//
//   auto model = cape::character::UrdfModel::humanoid();            // or UrdfModel::fromFile(path)
//   if (!model.ok()) { print(model.status.message()); return; }
//   auto made = cape::character::Character::create(model.model, world,
//                                                  cape::character::Gait::forScene(cape::SceneKind::Walk));
//   for (const std::string& w : made.character->warnings()) print(w);
//   btRigidBody* leftShoulder = made.character->bodies().bodyForLink("left_shoulder");
//   for (int frame = 1; frame <= 600; ++frame) {
//     made.character->advanceTo(frame / 60.0);        // poses the skeleton, moves the bodies (velocities
//     too) world.stepSimulation(1 / 60.f, 8, 1 / 240.f); made.character->skeleton().worldShapes(shapes);  //
//     colliders to export: link, type, sizes, world pose
//   }
#pragma once

#include "cape/character/CharacterBodies.h"
#include "cape/character/Gait.h"
#include "cape/character/JointMapping.h"
#include "cape/character/Skeleton.h"

#include <memory>
#include <string>
#include <vector>

namespace cape::character {

struct CharacterSettings {
  double scale = 1.0;                                ///< uniform scale of the URDF, > 0
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  ///< m, world, added to the gait's root path (a crowd)
  BodySettings bodies;                               ///< collision group, mask, ...
};

class Character;
struct CharacterResult {
  Status status;
  std::unique_ptr<Character> character;
  bool ok() const { return status.ok() && character != nullptr; }
};

class Character {
 public:
  /// Builds the skeleton (joints mapped with JointMapping::automatic, unless `mapping` is given), poses it at
  /// t = 0 and adds its bodies to `world` at rest. Errors: InvalidArgument (null model, bad scale).
  static CharacterResult create(const UrdfModelPtr& model, btDynamicsWorld& world, const Gait& gait,
                                const CharacterSettings& settings = {},
                                const JointMapping* mapping = nullptr);

  /// Poses the skeleton at time t (s) and moves the bodies there, with velocities over t - time(). A t not
  /// after time() is a jump (teleport, zero velocity). Call before stepping the world.
  void advanceTo(double t);
  double time() const { return time_; }

  Character(const Character&) = delete;  // the bodies point at this skeleton: not copyable, not movable
  Character& operator=(const Character&) = delete;

  const Skeleton& skeleton() const { return skeleton_; }
  CharacterBodies& bodies() { return *bodies_; }
  const CharacterBodies& bodies() const { return *bodies_; }
  const Gait& gait() const { return gait_; }
  const JointMapping& mapping() const { return mapping_; }
  const CharacterSettings& settings() const { return settings_; }
  /// The model's load warnings followed by the mapping's (unmapped roles and why).
  std::vector<std::string> warnings() const;

 private:
  Character(const UrdfModelPtr& model, const Gait& gait, const CharacterSettings& settings,
            JointMapping mapping);
  Skeleton skeleton_;
  Gait gait_;
  CharacterSettings settings_;
  JointMapping mapping_;
  std::unique_ptr<CharacterBodies> bodies_;  ///< made after the skeleton is posed; reads skeleton_
  double time_ = 0.0;
};

}  // namespace cape::character
