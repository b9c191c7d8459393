/// \file
/// Motion clips: sampled root poses and joint positions over time, played back on a character.
///
/// A MotionClip is plain data, the same whatever file it came from (MotionFormats.h reads joint-trajectory
/// CSV, DeepMimic motion files and BVH motion capture into one). A MotionPlayer binds a clip to a skeleton's
/// joints once (unknown names are an error that lists the model's joints) and samples it at any time:
///
/// \verbatim
///   clip time  c = startTime + speed * t
///   looping    c = k T + u, 0 <= u < T (T = duration()); the pose at u is carried by the k-th power of the
///              loop's displacement D (the horizontal move and the turn about the up axis from the first
///              sample to the last), so loop k starts exactly where loop k - 1 ended: no jump
///   not looping c is held in [0, T] (the first or the last pose before and after)
///   in place   the root's horizontal position stays at the first sample's (height and rotation kept)
///   between samples  positions and joint values linearly, rotations by slerp (the shorter way)
/// \endverbatim
///
/// Frames. Clip root poses are the URDF root link's frame, in one of three frames (MotionFrame): the URDF's
/// (REP 103: z up, x forward; the character at yaw 0 faces +x), the character's Bullet world (Y-up or Z-up as
/// the character's settings say), or a Y-up tool's world (x forward, y up, z right: DeepMimic and PyBullet's
/// Y-up humanoid), turned onto z as the URDF loader turns a Y-up model. The player works in the URDF frame.
#pragma once

#include "cape/character/Export.h"
#include "cape/character/Skeleton.h"
#include "cape/character/Status.h"

#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace cape::character {

/// The frame a clip's root poses are given in (see Motion.h).
enum class MotionFrame : int {
  Urdf,   ///< z up, x forward, y left (REP 103): the URDF's own axes
  World,  ///< the character's Bullet world: Y-up (the character at yaw 0 faces -Z) or Z-up (faces +X)
  YUp,    ///< x forward, y up, z right (DeepMimic); for a model turned onto z (UrdfModel::turnedOntoZ) the
          ///< root rotation is taken as the file's, before the turn
};
/// "urdf", "world" or "y-up".
CAPE_CHARACTER_API const char* toString(MotionFrame frame);

/// Samples of a motion: times, the root link's pose and named joints' positions at each.
struct CAPE_CHARACTER_API MotionClip {
  std::string name;                               ///< where it came from (file name), for messages
  MotionFrame frame = MotionFrame::Urdf;          ///< the frame of rootPositions and rootRotations
  std::vector<double> times;                      ///< s, strictly increasing, times[0] >= 0
  std::vector<Eigen::Vector3d> rootPositions;     ///< m, one per sample
  std::vector<Eigen::Quaterniond> rootRotations;  ///< unit, one per sample
  std::vector<std::string> joints;                ///< scalar joints (revolute, continuous, prismatic)
  std::vector<double> values;                     ///< rad or m, sample-major: values[s * joints + j]
  std::vector<std::string> balls;                 ///< spherical joints
  std::vector<Eigen::Quaterniond> rotations;      ///< unit, sample-major: rotations[s * balls + b]
  bool loop = true;                               ///< what the file says (DeepMimic "Loop")

  /// The number of samples.
  int sampleCount() const { return static_cast<int>(times.size()); }
  /// s: times.back() - times.front() (0 for fewer than two samples).
  double duration() const { return times.size() < 2 ? 0.0 : times.back() - times.front(); }
  /// InvalidArgument naming the first problem: no sample, arrays of the wrong sizes, times not finite or not
  /// strictly increasing, a value or position not finite, a quaternion not finite or of norm far from 1
  /// (beyond 1e-3: quaternions are normalised by the loaders), a joint named twice.
  Status check() const;
};

/// A loader's answer: ok and a clip, or an error naming the file, the line (or frame) and the problem.
struct MotionClipResult {
  Status status;                      ///< Why there is no clip, or success
  MotionClip clip;                    ///< The clip (empty on error)
  std::vector<std::string> warnings;  ///< What the loader said on the way (guesses, frames left out, ...)
  /// True when a clip was read.
  bool ok() const { return status.ok(); }
};

/// How a MotionPlayer plays a clip: speed, start, looping, root motion, and where it starts.
struct PlaybackSettings {
  double speed = 1.0;      ///< clip seconds per second, finite and > 0
  double startTime = 0.0;  ///< s of clip time at t = 0, finite (negative starts before the first sample)
  bool loop = true;        ///< loop (with the root carried over each loop) or hold the ends
  bool rootMotion = true;  ///< false: in place (the root's horizontal position held at the first sample's)
  /// Moves the whole clip horizontally so that its first sample's root is above the origin (the character
  /// then walks off from where it was put, plus CharacterSettings::offset). Off: the clip's positions as
  /// written.
  bool startAtOrigin = true;
  /// Turns the whole clip about the up axis through its first root so that it starts facing +x in the URDF
  /// frame (the way a character at yaw 0 faces: where its cape is put). Off: the clip's headings as written.
  bool alignHeading = true;
};

/// One sampled pose, bound to a skeleton: the root link's pose in the URDF frame and the bound joints'
/// positions, in the player's binding order (MotionPlayer::jointIndices(), ballIndices()).
struct MotionPose {
  Eigen::Isometry3d root = Eigen::Isometry3d::Identity();  ///< The root link's pose, URDF frame, m
  std::vector<double> values;                              ///< rad or m, per bound scalar joint
  std::vector<Eigen::Quaterniond> rotations;               ///< unit, per bound ball joint
};

/// A clip bound to a skeleton's joints, sampled at any time (see Motion.h for looping and frames).
class CAPE_CHARACTER_API MotionPlayer {
 public:
  /// Binds `clip` to `skeleton`'s model: every scalar joint must be a movable joint of it and every ball a
  /// spherical one (UnknownJoint / NotMovable otherwise, the message listing the model's joints of that
  /// kind); the clip must pass check() and the settings be valid (InvalidArgument). A World clip is read in
  /// the skeleton's up axis. Joint values outside the limits are clamped when applied.
  static Status create(const MotionClip& clip, const Skeleton& skeleton, const PlaybackSettings& settings,
                       MotionPlayer& out);
  MotionPlayer() = default;  ///< Unbound: create() binds it.

  /// The pose at time t (s; any finite t). `out` is reused: no allocation once it has grown.
  void sample(double t, MotionPose& out) const;
  /// Clip time (s, in [0, duration]) and loop count at time t.
  double clipTime(double t, long long* loops = nullptr) const;

  /// The bound clip, in the URDF frame, its first sample at time 0.
  const MotionClip& clip() const { return clip_; }
  /// How it plays.
  const PlaybackSettings& settings() const { return settings_; }
  /// s: the clip's duration.
  double duration() const { return clip_.duration(); }
  /// Skeleton joint index of each of the clip's scalar joints and balls.
  const std::vector<int>& jointIndices() const { return jointIndex_; }
  /// Skeleton joint index of each of the clip's ball joints.
  const std::vector<int>& ballIndices() const { return ballIndex_; }
  /// The model it was bound to (kept alive by the player).
  const UrdfModelPtr& model() const { return model_; }

 private:
  void sampleAt(double u, MotionPose& out) const;  // u in clip time from the first sample, no looping
  UrdfModelPtr model_;
  MotionClip clip_;  ///< in the URDF frame, first time at 0
  PlaybackSettings settings_;
  std::vector<int> jointIndex_, ballIndex_;
  Eigen::Isometry3d loopStep_ = Eigen::Isometry3d::Identity();  ///< D: last sample's pose from the first's
  double loopYaw_ = 0.0;                                        ///< rad, D's turn about z
  Eigen::Vector3d shift_ = Eigen::Vector3d::Zero();             ///< startAtOrigin's horizontal move
};

/// A root link pose given in `frame` as a pose in the URDF frame, for `skeleton` (its up axis for World, its
/// model's turnedOntoZ for YUp).
CAPE_CHARACTER_API Eigen::Isometry3d rootPoseToUrdfFrame(const Eigen::Isometry3d& pose, MotionFrame frame,
                                                         const Skeleton& skeleton);
/// A pose in the URDF frame as a pose in a world with that up axis (the identity for Z).
CAPE_CHARACTER_API Eigen::Isometry3d urdfFrameToWorld(const Eigen::Isometry3d& pose, UpAxis up);

/// Rotation about z that the root's heading (its x axis projected on the ground) makes with +x, rad.
CAPE_CHARACTER_API double headingAboutZ(const Eigen::Quaterniond& q);

/// How far a clip's pose jumps where a loop wraps from its last sample to its first: the largest change of
/// a scalar joint (rad or m), of a ball joint's rotation (its angle, rad) and of the root's tilt (the angle
/// between its up axes, rad, in a Urdf or YUp clip; its heading and position are carried over by the loop),
/// and where it is (a
/// joint's name or "root"). A cycle (a walk or a run cut at the same phase) has a small gap; a clip that is
/// not one jumps every loop. 0 and "" for fewer than two samples.
struct LoopGap {
  double value = 0.0;  ///< rad or m: the largest jump
  std::string where;   ///< the joint's name, or "root"
};
/// The clip's loop gap (see LoopGap).
CAPE_CHARACTER_API LoopGap loopGap(const MotionClip& clip);

}  // namespace cape::character
