/// \file
/// The canonical scenes of docs/SCENES.md on the simple body, with no Bullet: tests, benchmarks and the
/// demos' --simple-body mode drive the solver exactly alike.
#pragma once

#include "cape/core/Cape.h"
#include "cape/scenes/Export.h"

#include <string>
#include <vector>

namespace cape {

/// The canonical scenes of docs/SCENES.md.
enum class SceneKind : int {
  Hang,        ///< The cape falls from horizontal and hangs from a still body.
  Walk,        ///< Walking at 1.4 m/s.
  SprintTurn,  ///< Sprinting at 5 m/s with a 180 degree turn every 2 s.
  Wind,        ///< A still body in gusty wind.
  Crowd,       ///< Many walking characters side by side.
};
/// The scene's name: "hang", "walk", "sprint-turn", "wind" or "crowd" ("?" outside the enum).
CAPE_SCENES_API const char* toString(SceneKind kind);
/// Parses "hang", "walk", "sprint-turn", "wind", "crowd"; false if unknown.
CAPE_SCENES_API bool parseSceneKind(const std::string& name, SceneKind& kind);

/// Which cape particles are pinned (docs/SCENES.md's attachment): the two top corners, or the whole top row
/// along the pin line, or the whole top row gathered onto a collar (a cape as tailors make one: wider than
/// the shoulders it hangs from, so that it falls in folds).
enum class PinLayout : int {
  Corners,   ///< The two top corners.
  Collar,    ///< Every particle of the top row, along the straight pin line.
  Gathered,  ///< Every particle of the top row, gathered onto a CollarShape across the shoulders.
};
/// The layout's name: "corners", "collar" or "gathered".
CAPE_SCENES_API const char* toString(PinLayout layout);
/// Parses "corners", "collar", "gathered"; false if unknown.
CAPE_SCENES_API bool parsePinLayout(const std::string& name, PinLayout& layout);

/// How the character moves in a scene. Times in s, lengths in m, angles in rad.
struct CAPE_SCENES_API MotionDesc {
  float speed = 0.0f;            ///< m/s along the heading
  float legFrequency = 0.0f;     ///< Hz, one full leg swing per period
  float legAmplitude = 0.5236f;  ///< rad (30 degrees)
  float bobAmplitude = 0.0f;     ///< m, half the peak-to-peak torso bob
  float bobFrequency = 0.0f;     ///< Hz
  bool turns = false;            ///< sprint-turn: 180 degrees in the last turnDuration of every turnPeriod
  float turnPeriod = 2.0f;       ///< s between the starts of two turns
  float turnDuration = 0.5f;     ///< s each turn takes
  float duration = 10.0f;        ///< s, the scene's length

  /// The motion of a canonical scene (docs/SCENES.md).
  static MotionDesc forScene(SceneKind kind);
};

/// The scene's wind: for "wind", the aerodynamic model at 8 m/s mean along +X with gusts of +-50 % (0.5 Hz,
/// 2 m turbulence); no wind in every other scene.
CAPE_SCENES_API WindSettings sceneWind(SceneKind kind);
/// `settings` with the scene's wind filled in when the settings name none (an explicit wind wins).
CAPE_SCENES_API CapeSettings settingsForScene(SceneKind kind, CapeSettings settings);

/// The character's pose at a time: its frame (origin on the ground between the feet, facing -Z when yaw = 0),
/// the torso bob and the left leg angle (the right leg is its negative).
struct CAPE_SCENES_API BodyPose {
  Vec3 position = Vec3::Zero();  ///< m, world: the frame's origin on the ground
  float yaw = 0.0f;              ///< rad about +Y
  float bob = 0.0f;              ///< m, added to every body part's height
  float legAngle = 0.0f;         ///< rad, the left leg's swing forward (the right leg's is its negative)
  Pose frame() const;            ///< The character frame in the world, bob included.
};

/// Exact pose at time t (closed form, independent of the step size).
CAPE_SCENES_API BodyPose motionAt(const MotionDesc& motion, double t);

/// The simple body of docs/SCENES.md: torso box, shoulder spheres, leg capsules and the ground plane.
/// Collider order: torso, left shoulder, right shoulder, left leg, right leg, ground.
class CAPE_SCENES_API SimpleBody {
 public:
  /// Collider indices: torso box, shoulder spheres, leg capsules, and the ground plane last.
  ///@{
  static constexpr int kTorso = 0, kLeftShoulder = 1, kRightShoulder = 2, kLeftLeg = 3, kRightLeg = 4,
                       kGround = 5;
  ///@}
  /// The body standing at `offset` (m, world) in the rest pose (BodyPose()), every collider at rest.
  explicit SimpleBody(const Vec3& offset = Vec3::Zero());
  /// Body colliders only (not the ground), for the penetration metric.
  ColliderSpan bodyColliders() const { return ColliderSpan(colliders_.data(), colliders_.size() - 1); }
  /// Every collider, the ground included, in the order of the indices above.
  const std::vector<Collider>& colliders() const { return colliders_; }
  /// Moves every body collider to the pose (sweeping from where it was); teleport = no sweep.
  void moveTo(const BodyPose& pose, bool teleport = false);
  /// Centre of the torso in the world at the current pose.
  Vec3 torsoCentre() const { return colliders_[kTorso].current.position; }

 private:
  std::vector<Collider> colliders_;
  Vec3 offset_;  ///< Where the character stands in the world (crowd members are side by side).
};

/// A cape's size, m: the canonical 0.6 x 1.0 (docs/SCENES.md), or one fitted to a character.
struct CapeSize {
  float width = 0.6f;   ///< m, along the top row
  float height = 1.0f;  ///< m, from the top row down
};

/// The collar a gathered cape (PinLayout::Gathered) is sewn onto, in the character frame: an arc across the
/// shoulders through the pin line's middle (0, 1.56, 0.15), `span` from end to end along X, its ends `wrap`
/// forward (towards -Z, round the neck onto the shoulders): z = 0.15 - wrap (2x / span)^2. The top row's
/// particles sit on it evenly in X, so a cape wider than the span is gathered by span / width.
struct CollarShape {
  float span = 0.44f;  ///< m, end to end along X (> 0): the canonical body's shoulders are 0.44 m apart
  float wrap = 0.03f;  ///< m, >= 0
};

/// Where a point of a width x height grid (its local frame: x from 0 to width along the top row, y from 0
/// down to -height, z out of its back) starts when the cape is gathered onto `collar`, in the same frame: x
/// pulled towards the middle by span / width, and the top rows bent along the collar's arc (fully at the
/// top, fading out over 6 cm down the cape). capeStartPlacement maps it into the character frame; the top
/// row's images are the pins of makeCapeRig's Gathered layout.
CAPE_SCENES_API Vec3 gatheredPoint(const Vec3& local, const CapeSize& size, const CollarShape& collar);
/// Where a point of the grid starts when the cape is gathered onto `collar` and starts level, sticking out
/// behind it (SceneKind::Hang): x pulled in as gatheredPoint does, and each column moved along the cape by
/// the collar's wrap at its place, so that under the hang's turn the top row lies on the collar exactly as
/// gatheredPoint's does under the walk's (the pins of makeCapeRig's Gathered layout), and every column
/// starts straight and at its rest length.
CAPE_SCENES_API Vec3 gatheredLevelPoint(const Vec3& local, const CapeSize& size, const CollarShape& collar);
/// Where a point of the grid starts in scene `kind` when the cape is gathered onto `collar`:
/// gatheredLevelPoint for the hang, which starts the cape level behind the collar (capeStartPlacement),
/// gatheredPoint otherwise.
CAPE_SCENES_API Vec3 gatheredStartPoint(SceneKind kind, const Vec3& local, const CapeSize& size,
                                        const CollarShape& collar);

/// Character-frame attachment points: "corners" pins the top corners at (+-0.30, 1.56, 0.15); "collar" pins
/// the whole top row along the same line; "gathered" pins the whole top row on `collar` (gatheredPoint).
struct CapeRig {
  FabricPtr fabric;                            ///< The cape's fabric, with tethers to the pinned particles
  std::vector<std::uint32_t> pinnedParticles;  ///< Fabric particle indices
  std::vector<Vec3> pinLocalPoints;            ///< in the character frame, m
};
/// The N x N cape (the canonical 0.6 m x 1.0 m, 0.4 kg; another size keeps its mass per area) with tethers
/// to its attachment particles, its top row centred on the canonical pin line. `rows` > 0 gives it that many
/// rows instead of N (N stays the particles across); `totalMass` > 0 (kg) replaces the canonical mass per
/// area (e.g. a fabric preset's, cape::fabricMass). `collar` is read by the Gathered layout only.
CAPE_SCENES_API CapeRig makeCapeRig(int n, PinLayout layout, bool bendSprings = true,
                                    const CapeSize& size = CapeSize(), int rows = 0, float totalMass = 0.0f,
                                    const CollarShape& collar = CollarShape());
/// The cape's starting placement in the character frame: flat and vertical at z = 0.15 with its top row on
/// the pins, or for "hang" flat and horizontal reaching from the pins towards +Z.
CAPE_SCENES_API Pose capeStartPlacement(SceneKind kind, const CapeSize& size = CapeSize());

/// One cape on the simple body, stepped frame by frame: what tests and benchmarks run.
class CAPE_SCENES_API SimpleScene {
 public:
  /// The scene's N x N cape (makeCapeRig) on the simple body standing at `offset` (m, world), with the
  /// scene's settings (settingsForScene) at t = 0. Check status().
  SimpleScene(SceneKind kind, int n, PinLayout layout, const CapeSettings& settings,
              const Vec3& offset = Vec3::Zero());
  /// The cape's status (an error for bad settings).
  const Status& status() const { return cape_.status(); }
  /// Advances one frame of dt seconds: moves the body and the pins, then steps the cape.
  void advanceFrame(float dt = 1.0f / 60.0f);
  /// s simulated so far.
  double time() const { return time_; }
  /// The scene it was made for (its motion and the cape's settings follow from it).
  SceneKind kind() const { return kind_; }
  /// The body's motion (MotionDesc::forScene).
  const MotionDesc& motion() const { return motion_; }
  /// The cape.
  Cape& cape() { return cape_; }
  /// The cape.
  const Cape& cape() const { return cape_; }
  /// The simple body and its colliders.
  const SimpleBody& body() const { return body_; }
  /// The cape's fabric and pins.
  const CapeRig& rig() const { return rig_; }

 private:
  SceneKind kind_;
  MotionDesc motion_;
  CapeRig rig_;
  SimpleBody body_;
  Cape cape_;
  Vec3 offset_;
  double time_ = 0.0;
};

}  // namespace cape
