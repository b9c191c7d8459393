// The procedural gait: closed-form root motion and joint angles (formulas in Gait.h).
#include "cape/character/Gait.h"

#include <algorithm>
#include <cmath>

namespace cape::character {

namespace {
constexpr double kPi = 3.14159265358979323846;
}

GaitParams GaitParams::forSpeed(double speed, double stepFrequency, double turnRate) {
  GaitParams p;
  p.speed = speed;
  p.turnRate = turnRate;
  p.stepFrequency = stepFrequency;
  const double v = std::abs(speed);
  // Linear in speed, capped: chosen by eye so that the 1.4 m/s walk and the 5 m/s sprint look plausible.
  p.kneeSwing = std::min(1.4, 0.6 + 0.15 * v);
  p.armSwing = std::min(0.7, 0.25 + 0.08 * v);
  p.elbowBase = std::min(1.3, 0.25 + 0.2 * v);
  if (stepFrequency > 0.0) {
    p.bobAmplitude = 0.015;
    p.bobFrequency = 2.0 * stepFrequency;
  }
  return p;
}

Gait::Gait(const GaitParams& params) : params_(params) {
  if (params_.turnRate == 0.0) {
    // No turn: motionAt's straight line, so the root path is bit for bit the scenes'.
    useMotion_ = true;
    motion_.speed = static_cast<float>(params_.speed);
    motion_.legFrequency = static_cast<float>(params_.stepFrequency);
    motion_.legAmplitude = static_cast<float>(params_.hipAmplitude);
    motion_.bobAmplitude = static_cast<float>(params_.bobAmplitude);
    motion_.bobFrequency = static_cast<float>(params_.bobFrequency);
    motion_.turns = false;
  }
}

Gait Gait::fromMotion(const cape::MotionDesc& motion) {
  GaitParams p = GaitParams::forSpeed(motion.speed, motion.legFrequency);
  p.hipAmplitude = motion.legAmplitude;
  p.bobAmplitude = motion.bobAmplitude;
  p.bobFrequency = motion.bobFrequency;
  Gait g(p);
  g.useMotion_ = true;
  g.motion_ = motion;
  return g;
}

Gait Gait::forScene(cape::SceneKind kind) {
  return fromMotion(cape::MotionDesc::forScene(kind));
}

RootPose Gait::rootAt(double t) const {
  RootPose r;
  if (useMotion_) {
    const cape::BodyPose b = cape::motionAt(motion_, t);
    r.position = b.position.cast<double>();
    r.yaw = b.yaw;
    r.bob = b.bob;
    r.origin = b.frame().position.cast<double>();
    return r;
  }
  const double v = params_.speed, w = params_.turnRate;
  r.yaw = std::remainder(w * t, 2.0 * kPi);
  // d/dt of (v/w)(cos wt - 1) is -v sin wt, and of -(v/w) sin wt is -v cos wt: forward at yaw = wt.
  r.position = Eigen::Vector3d(v / w * (std::cos(w * t) - 1.0), 0.0, -v / w * std::sin(w * t));
  r.bob = params_.bobAmplitude * std::sin(2.0 * kPi * params_.bobFrequency * t);
  r.origin = r.position + Eigen::Vector3d(0.0, r.bob, 0.0);
  return r;
}

std::array<double, kGaitRoleCount> Gait::standingAngles() const {
  std::array<double, kGaitRoleCount> a{};
  a[static_cast<std::size_t>(GaitRole::LeftShoulderRoll)] = params_.armOut;
  a[static_cast<std::size_t>(GaitRole::RightShoulderRoll)] = params_.armOut;
  return a;
}

std::array<double, kGaitRoleCount> Gait::anglesAt(double t) const {
  std::array<double, kGaitRoleCount> a = standingAngles();
  const GaitParams& g = params_;
  if (!(g.stepFrequency > 0.0)) return a;  // standing: the rest pose, arms down
  const double p = 2.0 * kPi * g.stepFrequency * t;
  const double s = std::sin(p), c = std::cos(p);
  auto at = [&](GaitRole role) -> double& { return a[static_cast<std::size_t>(role)]; };
  // The hip angle uses the same float amplitude and formula as motionAt's legAngle when it comes from a
  // scene.
  const double hip = g.hipAmplitude * s;
  at(GaitRole::LeftHip) = hip;
  at(GaitRole::RightHip) = -hip;
  const double cl = std::max(0.0, c), cr = std::max(0.0, -c);
  at(GaitRole::LeftKnee) = g.kneeStance + g.kneeSwing * cl * cl;
  at(GaitRole::RightKnee) = g.kneeStance + g.kneeSwing * cr * cr;
  at(GaitRole::LeftAnkle) = g.ankleFollow * (at(GaitRole::LeftKnee) - at(GaitRole::LeftHip));
  at(GaitRole::RightAnkle) = g.ankleFollow * (at(GaitRole::RightKnee) - at(GaitRole::RightHip));
  at(GaitRole::LeftShoulder) = -g.armSwing * s;
  at(GaitRole::RightShoulder) = g.armSwing * s;
  at(GaitRole::LeftElbow) = g.elbowBase + g.elbowSwing * 0.5 * (1.0 - s);
  at(GaitRole::RightElbow) = g.elbowBase + g.elbowSwing * 0.5 * (1.0 + s);
  at(GaitRole::LeftShoulderRoll) = g.armOut + g.armOutSwing * s * s;
  at(GaitRole::RightShoulderRoll) = g.armOut + g.armOutSwing * s * s;
  return a;
}

void Gait::setJoints(const std::array<double, kGaitRoleCount>& angles, const JointMapping& mapping,
                     Skeleton& skeleton) {
  for (int r = 0; r < kGaitRoleCount; ++r) {
    const JointMapping::Entry& e = mapping.entries()[static_cast<std::size_t>(r)];
    if (e.joint < 0) continue;
    const double turn = e.sign * angles[static_cast<std::size_t>(r)];
    // Exactly sign * angle when the neutral is 0 (0 + x is not x for x = -0), so models without neutral
    // positions keep their bits.
    const double q = e.neutral == 0.0 ? turn : e.neutral + turn;
    // Clamped here, so setJointPosition never reports OutsideLimits for the gait.
    (void)skeleton.setJointPosition(e.joint, skeleton.clampToLimits(e.joint, q));
  }
}

void Gait::apply(double t, const JointMapping& mapping, Skeleton& skeleton,
                 const Eigen::Vector3d& offset) const {
  const RootPose root = rootAt(t);
  skeleton.setRoot(root.origin + offset, root.yaw);
  setJoints(anglesAt(t), mapping, skeleton);
}

}  // namespace cape::character
