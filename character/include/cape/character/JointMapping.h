// Which joint of a URDF plays each role of the gait (left hip, right knee, ...), and which way it turns.
//
// The gait speaks in anatomical angles, the same for every model: a positive hip or shoulder angle swings the
// limb forward, a positive knee angle bends the knee (shin backwards), a positive elbow angle bends the elbow
// (forearm forwards), a positive ankle angle lifts the toes. A URDF may turn its joints either way, so each
// role carries a sign, found from the model itself: with the joint turned a little either side of rest, do
// the links beyond it move forward or backward (URDF +x, seen in the root link's frame)? Hip, ankle, shoulder
// and elbow want "forward", the knee "backward". A joint that moves its links neither way (its axis is not
// side to side) cannot be signed and is left unmapped, with a warning.
#pragma once

#include "cape/character/Urdf.h"

#include <array>
#include <string>
#include <vector>

namespace cape::character {

enum class GaitRole : int {
  LeftHip,
  RightHip,
  LeftKnee,
  RightKnee,
  LeftAnkle,
  RightAnkle,
  LeftShoulder,
  RightShoulder,
  LeftElbow,
  RightElbow,
};
constexpr int kGaitRoleCount = 10;
const char* toString(GaitRole role);

class JointMapping {
 public:
  struct Entry {
    int joint = -1;     ///< index into UrdfModel::joints(); -1 = unmapped (that joint stays at rest)
    double sign = 1.0;  ///< joint position = sign * anatomical angle (then clamped to the joint's limits)
  };

  /// Explicit joint names per role (an empty name leaves the role unmapped). A name that is not a movable
  /// joint of the model leaves the role unmapped and adds a warning. Signs are found as described above.
  static JointMapping fromNames(const UrdfModelPtr& model,
                                const std::array<std::string, kGaitRoleCount>& names);
  /// The joint names of the shipped humanoid (character/models/humanoid.urdf).
  static std::array<std::string, kGaitRoleCount> shippedHumanoidNames();
  /// Recognises common names: a part (hip, knee, ankle, shoulder, elbow) and a side ("left"/"right", an "l_"
  /// or "r_" prefix, an "_l" or "_r" suffix, or "l"/"r" right before the part, as in "lknee"),
  /// case-insensitive; only revolute and continuous joints. Where a part has several joints on one side (hip
  /// roll, pitch, yaw), the one turning most nearly about the side-to-side axis is taken.
  static JointMapping byCommonNames(const UrdfModelPtr& model);
  /// The shipped humanoid's names when the model has them all, common names otherwise.
  static JointMapping automatic(const UrdfModelPtr& model);

  const Entry& operator[](GaitRole role) const { return entries_[static_cast<std::size_t>(role)]; }
  const std::array<Entry, kGaitRoleCount>& entries() const { return entries_; }
  /// Roles with no joint; those joints stay at rest.
  std::vector<GaitRole> unmappedRoles() const;
  /// What the caller may want to print: unmapped roles, names not found, joints that could not be signed.
  const std::vector<std::string>& warnings() const { return warnings_; }

 private:
  void finish(const UrdfModelPtr& model);  // signs, and a warning per unmapped role
  std::array<Entry, kGaitRoleCount> entries_{};
  std::vector<std::string> warnings_;
};

}  // namespace cape::character
