/// \file
/// Which joint of a URDF plays each role of the gait (left hip, right knee, ...), and which way it turns.
///
/// The gait speaks in anatomical angles, the same for every model: a positive hip or shoulder angle swings
/// the limb forward, a positive knee angle bends the knee (shin backwards), a positive elbow angle bends the
/// elbow (forearm forwards), a positive ankle angle lifts the toes, a positive shoulder roll angle lifts the
/// arm sideways, away from the body. A URDF may turn its joints either way, so each role carries a sign,
/// found from the model itself: with the joint turned a little either side of rest, do the links beyond it
/// move forward or backward (URDF +x, seen in the root link's frame)? Hip, ankle, shoulder and elbow want
/// "forward", the knee "backward" (where the links are: their origins, shape centres and mesh hulls'
/// centres). A joint that moves its links neither way (its axis is not side to side) cannot be signed:
/// byCommonNames leaves it unmapped, and any mapping warns. A knee or an elbow that moves them neither way is
/// signed by its bend (positive brings the limb's end nearer the link above: a bent elbow, as H1's) or,
/// failing that, by limits that let it turn one way only (Atlas's elbows about x, which bend the hanging
/// forearm out sideways), which is said.
///
/// Arms down. Each role also has a neutral joint position, where its anatomical angle is 0: 0 for every role
/// but the shoulder roll (abduction), whose neutral is the angle that brings the arm (the direction from the
/// roll joint to the farthest link origin or shape centre beyond it: the hand) as close as forward kinematics
/// allows to hanging straight down, from the rest pose. Its sign is the way that lifts the arm away from the
/// body there. So a model built in a T-pose or an A-pose walks with its arms at its sides. The other roles'
/// signs are found in that arms-down pose (in a T-pose the arm lies along the shoulder's pitch axis, and only
/// once it hangs down does a pitch joint swing it forward); a ball shoulder made of three revolute joints in
/// any order works the same way: whichever of them swings the hanging arm forward is the shoulder.
///
/// Names, then structure. byCommonNames reads the joint names, also the robot abbreviations (Hubo's LHP,
/// Atlas's l_leg_hpy). byStructure reads only the kinematic tree and the rest pose: the legs are the two
/// branches that go down to the lowest links, the arms the two that reach farthest to either side; in each,
/// the joints that turn about the side-to-side axis, in order from the body. automatic takes the names, and
/// structure fills what they left empty, saying each such choice in warnings().
#pragma once

#include "cape/character/Export.h"
#include "cape/character/Urdf.h"

#include <array>
#include <string>
#include <vector>

namespace cape::character {

/// The roles a joint can play in the gait (anatomical angles as described above).
enum class GaitRole : int {
  LeftHip,            ///< swings the left leg forward
  RightHip,           ///< swings the right leg forward
  LeftKnee,           ///< bends the left knee
  RightKnee,          ///< bends the right knee
  LeftAnkle,          ///< lifts the left toes
  RightAnkle,         ///< lifts the right toes
  LeftShoulder,       ///< swings the left arm forward
  RightShoulder,      ///< swings the right arm forward
  LeftElbow,          ///< bends the left elbow
  RightElbow,         ///< bends the right elbow
  LeftShoulderRoll,   ///< shoulder abduction: the arm up and down sideways (optional: no warning if absent)
  RightShoulderRoll,  ///< the same on the right
};
/// The number of roles (the size of per-role arrays).
constexpr int kGaitRoleCount = 12;
/// The role in words ("left hip", ...).
CAPE_CHARACTER_API const char* toString(GaitRole role);

/// Which joint of a URDF plays each GaitRole, which way it turns and where its arms-down neutral is (see
/// JointMapping.h).
class CAPE_CHARACTER_API JointMapping {
 public:
  /// One role's joint.
  struct Entry {
    int joint = -1;     ///< index into UrdfModel::joints(); -1 = unmapped (that joint stays at rest)
    double sign = 1.0;  ///< joint position = neutral + sign * anatomical angle, clamped to the limits
    /// Joint position (rad or m) where the anatomical angle is 0: 0, but for a shoulder roll the angle that
    /// hangs the arm down (see above); Character puts the user's pose here (CharacterSettings::pose).
    double neutral = 0.0;
  };

  /// Explicit joint names per role (an empty name leaves the role unmapped). A name that is not a movable
  /// joint of the model leaves the role unmapped and adds a warning. Signs are found as described above.
  static JointMapping fromNames(const UrdfModelPtr& model,
                                const std::array<std::string, kGaitRoleCount>& names);
  /// The joint names of the shipped humanoid (character/models/humanoid.urdf); it has no shoulder roll
  /// joints, so those two names are empty.
  static std::array<std::string, kGaitRoleCount> shippedHumanoidNames();
  /// Recognises common names: a part (hip, knee, ankle, shoulder, elbow) and a side ("left"/"right", an "l_"
  /// or "r_" prefix, an "_l" or "_r" suffix, or "l"/"r" right before the part, as in "lknee"),
  /// case-insensitive; only revolute and continuous joints ("arm_sh" counts as a shoulder, as in l_arm_shx).
  /// A name with none of these is read as tokens (split at '_', '-', '.', digits and case changes): a part
  /// token hip|hp, knee|kn, ankle|ak, shoulder|sh, elbow|el, the short ones with an axis letter glued on
  /// (l_leg_hpy, l_leg_kny, l_arm_elx), with a side token l|left|r|right before or after it; or a short code
  /// in capitals, side + part letter (h, k, a, s, e) + axis letter (p, r, y), as Hubo's LHP, LKP, LSR. Axis
  /// words and letters (pitch|p|y, roll|r|x, yaw|z; a code's y is yaw) only break ties, as below.
  /// Shoulder rolls first: in each side's shoulder chain (its shoulder-named joints, and the joints between
  /// the first of them and the elbow), the joint whose axis is most nearly the forward axis (URDF x, at least
  /// cos 45 degrees), a name saying so (roll, abduct, adduct, shx, "_x") preferred; it lowers the arm (see
  /// above). Then, in that arms-down pose, where a part has several joints on one side (hip roll, pitch,
  /// yaw), the one turning most nearly about the side-to-side axis is taken (on a tie, one named pitch, flex,
  /// shy or "_y"; then the first).
  static JointMapping byCommonNames(const UrdfModelPtr& model);
  /// Names ignored: the limbs from the kinematic tree and the rest pose (URDF z up, x forward, y left). The
  /// legs: the branches from the two feet (the lowest links to the left and to the right) up to where they
  /// meet (the pelvis), which must lie in the lower three quarters of the model. The arms: the branches, not
  /// legs, from the links farthest to the left and to the right up to where they meet (the chest), to the
  /// farthest link beyond (the hand); when three or more branches leave the chest, the one reaching highest
  /// is the head, never an arm. In a leg, the hip is its first joint turning about the side-to-side axis
  /// (|axis y| > 0.7 in the root frame), the knee the next, the ankle the next (toe joints beyond stay free).
  /// In an arm, the shoulder roll is the joint among its first three with a forward axis (as above) that
  /// brings the arm nearest straight down; then, arms down, the shoulder is the first side-to-side joint and
  /// the elbow the next one, or else the first joint beyond that turns across the upper arm and moves
  /// something. Each role found is said in warnings() ("left knee: joint 'j4' (by structure: ...)").
  static JointMapping byStructure(const UrdfModelPtr& model);
  /// The shipped humanoid's names when the model has them all (and shoulder rolls found as byCommonNames
  /// finds them). Otherwise byCommonNames, with the roles it left empty filled by structure as byStructure
  /// finds them (a role mapped by name keeps its joint), each said in warnings().
  static JointMapping automatic(const UrdfModelPtr& model);

  /// The role's entry.
  const Entry& operator[](GaitRole role) const { return entries_[static_cast<std::size_t>(role)]; }
  /// Every role's entry, indexed by GaitRole.
  const std::array<Entry, kGaitRoleCount>& entries() const { return entries_; }
  /// Changes a role's neutral position (rad or m): Character puts the user's starting pose there.
  void setNeutral(GaitRole role, double q) { entries_[static_cast<std::size_t>(role)].neutral = q; }
  /// Shoulder rolls: optional roles, said nothing of when absent.
  static bool isShoulderRoll(GaitRole role) {
    return role == GaitRole::LeftShoulderRoll || role == GaitRole::RightShoulderRoll;
  }
  /// Roles with no joint; those joints stay at rest.
  std::vector<GaitRole> unmappedRoles() const;
  /// What the caller may want to print: unmapped roles, names not found, joints that could not be signed,
  /// arms that cannot be brought down, roles found by structure.
  const std::vector<std::string>& warnings() const { return warnings_; }

 private:
  static JointMapping build(const UrdfModelPtr& model, bool byName, bool byTree);
  void finish(const UrdfModelPtr& model);  // signs, and a warning per unmapped role
  std::array<Entry, kGaitRoleCount> entries_{};
  std::vector<std::string> warnings_;
};

}  // namespace cape::character
