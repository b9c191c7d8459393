// Which role a BVH joint plays, read from its name (private to the character library; tested alone).
//
// The roles are the bones a retarget drives (README "BVH motion capture"): the hips (the root's pose), the
// spine (the chest: the last spine joint below the neck), the neck (the head: the joint whose rotation
// turns the head), and per side the upper leg (hip), lower leg (knee), foot (ankle), upper arm (shoulder)
// and forearm (elbow). A BVH joint's rotation turns the bone from it to its child, so the joint that plays
// "left_knee" is the one at the knee (CMU/Mixamo LeftLeg, ASF ltibia).
#pragma once

#include <string>

namespace cape::character::bvh {

enum Role : int {
  kHips,
  kSpine,
  kNeck,
  kLeftHip,  ///< upper leg; then per part left and right alternate, as GaitRole's limb roles
  kRightHip,
  kLeftKnee,
  kRightKnee,
  kLeftAnkle,
  kRightAnkle,
  kLeftShoulder,  ///< upper arm (Mixamo LeftArm; Mixamo's LeftShoulder is the clavicle)
  kRightShoulder,
  kLeftElbow,
  kRightElbow,
};
constexpr int kRoleCount = 13;
constexpr int kFirstLimbRole = kLeftHip;

/// "hips", "spine", "neck", "left_hip", "right_hip", ..., "right_elbow"; "none" out of range.
const char* roleName(int role);
/// The role of that name (as BvhOptions::roles spells it), -1 for none.
int roleFromName(const std::string& name);

/// A name's role and how good a match it is (rank: lower wins when several joints claim one role).
struct NameRole {
  int role = -1;
  int rank = 0;
};
/// The role a BVH joint's name says, case-insensitively, after any namespace (`mixamorig:`, `Armature|`) and
/// a `mixamorig` or `Bip01` prefix: a side (`Left`/`Right` leading or trailing, `L_`, `_L`, `L.`, `.L`, `L `,
/// or a bare `l`/`r` glued before a part: `lfemur`) and a part (upper leg: UpLeg, UpperLeg, Thigh, femur,
/// then Hip; lower leg: Leg, LowerLeg, Knee, Shin, Calf, tibia; foot: Foot, Ankle; upper arm: Arm,
/// UpperArm, humerus, then Shoulder; forearm: ForeArm, LowerArm, Elbow, radius, ulna), or no side and hips
/// (Hips, Hip, Pelvis, then Root), spine (Spine, Spine1.., Chest, UpperChest, LowerBack, UpperBack, thorax,
/// Torso, Abdomen, Waist) or head and neck (Head, then UpperNeck, Neck, Neck1.., then LowerNeck). Anything
/// else (hands, toes, clavicles, ASF's lhipjoint) plays no role.
NameRole roleOfBvhName(const std::string& jointName);

}  // namespace cape::character::bvh
