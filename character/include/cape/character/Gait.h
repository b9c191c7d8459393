/// \file
/// A procedural walking (or running) gait: a closed-form function of time, so any frame can be posed
/// directly, with no state and no dependence on the step size.
///
/// Root motion. The character frame (origin on the ground between the feet, facing -Z at yaw 0) follows the
/// canonical scenes exactly: for a scene, or for any gait that does not turn, it is the scenes'
/// (cape::scenes) cape::motionAt(MotionDesc, t) (docs/SCENES.md: walk at 1.4 m/s, sprint-turn at 5 m/s with a
/// 180 degree turn in the last 0.5 s of every 2 s), with the torso bob added to the root height, as the
/// simple body does. A gait with a constant turn rate w follows the exact arc: yaw = w t, and with forward =
/// (-sin yaw, 0, -cos yaw), position = (v/w (cos w t - 1), 0, -v/w sin w t). (Character lifts this path by
/// its root height, so that a model whose root is not on the ground stands on it.)
///
/// Joint angles, anatomical (see JointMapping.h), with phase p = 2 pi f t:
/// \verbatim
///   hip       left  A sin p                        right  -A sin p   (docs/SCENES.md: A = 0.5236 rad)
///   knee      left  k0 + K max(0, cos p)^2         right  k0 + K max(0, -cos p)^2
///             (the knee bends while its leg swings forward, most at mid-swing; C1-smooth)
///   ankle     a (knee - hip): a = 1 keeps the foot level, a < 1 lets it follow the shin a little
///   shoulder  left  -S sin p                       right  S sin p    (arms swing against the legs)
///   elbow     left  E0 + E1 (1 - sin p) / 2        right  E0 + E1 (1 + sin p) / 2 (more bent when forward)
///   shoulder roll  both  O + Os sin^2 p           (arms held a little away from the body, a little further
///                                                  out at each end of their swing)
/// \endverbatim
/// then joint position = neutral + sign * angle, clamped to the joint's limits (see JointMapping.h: the
/// neutral is 0, but the shoulder roll's, which hangs the arm down; when the neutral is 0 the position is
/// exactly sign * angle). Every angle is a function of p alone, so the joint trajectories repeat every 1/f
/// seconds (and the bob too when its frequency is a multiple of f). With f = 0 (standing) every angle is 0
/// but the shoulder roll's O: the standing pose (standingAngles), the rest pose with the arms down.
#pragma once

#include "cape/character/Export.h"
#include "cape/character/JointMapping.h"
#include "cape/character/Skeleton.h"

#include "cape/scenes/Scene.h"

#include <array>

namespace cape::character {

/// The gait's parameters: root motion and the amplitudes of the joint angle formulas above.
struct CAPE_CHARACTER_API GaitParams {
  double speed = 0.0;            ///< m/s along the heading
  double turnRate = 0.0;         ///< rad/s about world +Y (positive turns to the character's left)
  double stepFrequency = 0.0;    ///< Hz: full leg cycles per second (one left and one right step),
                                 ///< docs/SCENES.md's "legs swing at"
  double bobAmplitude = 0.0;     ///< m, half the peak-to-peak torso bob (the whole body rises and falls)
  double bobFrequency = 0.0;     ///< Hz, usually 2 * stepFrequency (one bob per step)
  double hipAmplitude = 0.5236;  ///< rad, A above
  double kneeStance = 0.05;      ///< rad, k0: the knee's least bend
  double kneeSwing = 0.8;        ///< rad, K: extra bend at mid-swing
  double ankleFollow = 0.8;      ///< a in [0, 1]
  double armSwing = 0.35;        ///< rad, S
  double elbowBase = 0.5;        ///< rad, E0
  double elbowSwing = 0.2;       ///< rad, E1
  double armOut = 0.12;          ///< rad, O: the shoulder roll's hold away from the body (hands clear thighs)
  double armOutSwing = 0.05;     ///< rad, Os

  /// Amplitudes that look right at a speed: knees and elbows bend more, arms swing wider as it speeds up
  /// (walk at 1.4 m/s: K 0.81, S 0.36, E0 0.53; sprint at 5 m/s: K 1.35, S 0.65, E0 1.25). Bob 1.5 cm at
  /// twice the step frequency when moving.
  static GaitParams forSpeed(double speed, double stepFrequency, double turnRate = 0.0);
};

/// The character frame at a time: world position on the ground (m), yaw about +Y (rad), bob (m).
struct RootPose {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  ///< m, world, on the ground
  double yaw = 0.0;                                    ///< rad about +Y (0 faces -Z)
  double bob = 0.0;                                    ///< m, the torso bob's height
  /// Where the URDF origin goes: position raised by the bob (for a scene motion, summed in float exactly as
  /// cape::BodyPose::frame() does, so the simple body and the URDF body share their frame to the last bit).
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
};

/// A procedural walking (or running) gait: root motion and anatomical joint angles as closed-form functions
/// of time (see Gait.h).
class CAPE_CHARACTER_API Gait {
 public:
  /// A gait of its own: root motion from speed and turn rate (exactly motionAt's straight line when the turn
  /// rate is 0).
  explicit Gait(const GaitParams& params);
  /// A canonical scene's motion (cape::MotionDesc::forScene): hang, walk, sprint-turn, wind, crowd.
  static Gait forScene(cape::SceneKind kind);
  /// Any scene motion description; amplitudes from GaitParams::forSpeed.
  static Gait fromMotion(const cape::MotionDesc& motion);

  /// The gait's parameters.
  const GaitParams& params() const { return params_; }
  /// s after which the joint angles repeat (1 / stepFrequency); 0 when standing still.
  double period() const { return params_.stepFrequency > 0.0 ? 1.0 / params_.stepFrequency : 0.0; }

  /// The character frame at time t (s).
  RootPose rootAt(double t) const;
  /// Anatomical angles of every role at time t (rad), indexed by GaitRole.
  std::array<double, kGaitRoleCount> anglesAt(double t) const;
  /// The angles with every swing at 0: all 0 but the shoulder rolls' armOut. What the gait stands in, and
  /// what Character puts on the ground.
  std::array<double, kGaitRoleCount> standingAngles() const;
  /// Sets every mapped joint from anatomical angles: neutral + sign * angle, clamped to the joint's limits
  /// (apply's joint half). Unmapped joints and joints of no role are left where they are. No allocation.
  static void setJoints(const std::array<double, kGaitRoleCount>& angles, const JointMapping& mapping,
                        Skeleton& skeleton);
  /// Poses `skeleton` at time t: the root (bob included, `offset` added: m, in the world, for characters side
  /// by side) and every mapped joint; unmapped joints and joints of no role are left where they are. No
  /// allocation.
  void apply(double t, const JointMapping& mapping, Skeleton& skeleton,
             const Eigen::Vector3d& offset = Eigen::Vector3d::Zero()) const;

 private:
  GaitParams params_;
  bool useMotion_ = false;  ///< root from cape::motionAt(motion_, t)
  cape::MotionDesc motion_;
};

}  // namespace cape::character
