// A scene as the demos run it: one or more characters, each with a cape, advanced one 1/60 s frame at a time
// in a Bullet world (BulletScene.h), the cape attached through the Bullet adapter.
#pragma once

#include "cape/character/MotionFormats.h"

#include "cape/character/Skeleton.h"
#include "cape/character/Urdf.h"
#include "cape/core/FabricPresets.h"
#include "cape/scenes/Metrics.h"
#include "cape/scenes/Scene.h"

#include <Eigen/Core>

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace cape::demo {

/// What every run is asked for; each kind uses what applies to it.
struct RunOptions {
  SceneKind scene = SceneKind::Walk;
  int size = 20;  ///< particles per side; with capeWidth or capeHeight, particles across
  /// The cape's size, m (--width, --height). Neither: the canonical 0.6 x 1.0 m (or, on a URDF character,
  /// the size fitted to its shoulders) on a size x size grid. Either: the other one as it would have been,
  /// and a grid `size` particles across with as many rows as keep its cells square (squareCellRows).
  std::optional<float> capeWidth, capeHeight;
  /// A fabric preset (cape/core/FabricPresets.h; --fabric): the cape's mass from its areal density and its
  /// stiffness, damping and wind coefficients from applyFabric at the grid's spacing. nullptr: the
  /// canonical cape (0.4 kg per 0.6 m^2) with `settings` as they are.
  const FabricMaterial* fabric = nullptr;
  PinLayout pinLayout = PinLayout::Corners;
  /// The cape asked for (--cape): "canonical" (docs/SCENES.md's: corners, no fabric) or "cape" (gathered,
  /// wool); pinLayout and fabric hold what it became with --attachment and --fabric.
  std::string capeStyle = "canonical";
  double seconds = -1.0;  ///< < 0: the scene's own length
  int characters = 1;     ///< crowd size
  int threads = 1;
  bool parallelPrepare = false;    ///< the capes' prepare on the pool too (--parallel-prepare)
  double spinMicroseconds = -1.0;  ///< the pool's spin before sleeping, us (--spin; < 0: the group's default)
  CapeSettings settings;
  bool simpleBody = false;
  std::string urdf;                      ///< empty: the shipped humanoid
  std::vector<std::string> attachLinks;  ///< empty: the joint mapping's shoulders
  std::vector<std::string>
      packagePaths;  ///< where package:// mesh URIs are looked up (then ROS_PACKAGE_PATH)
  character::UpAxis up = character::UpAxis::Y;       ///< the world's up axis
  std::optional<double> rootHeight;                  ///< m; empty: the character stands on the ground
  std::vector<std::pair<std::string, double>> pose;  ///< the character's starting joint positions by name
  character::UrdfLoadOptions::Up modelUp = character::UrdfLoadOptions::Up::Auto;  ///< the model's own up
  double scale = 1.0;                                                             ///< of the URDF model
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< m: the world position where the character starts
  std::string motion;  ///< a motion clip played instead of the gait (empty: the procedural gait)
  character::MotionLoadOptions motionLoad;  ///< its format and the format's options
  character::PlaybackSettings playback;     ///< speed, start, in place
  /// A grayscale PNG painted over the cape's UVs (--max-distance-map, read by ImageFile.h's readGrayPng):
  /// each particle's max distance from its animated position (MotionConstraints), black
  /// maxDistanceRange[0] and white maxDistanceRange[1], m. Empty: no motion constraints.
  std::string maxDistanceMap;
  std::array<float, 2> maxDistanceRange{0.0f, 0.1f};  ///< m, black and white of maxDistanceMap
  /// Levels of detail by distance from `viewpoint` (--lod, 1 to 3 increasing distances, m): beyond the first
  /// a cape steps every second internal step, beyond the second once a frame, beyond the third once a frame
  /// with 2 substeps per 1/60 s (cape::bullet::CapeGroup::setDetailPolicy, 0.5 m hysteresis). Empty: full
  /// detail for every cape.
  std::vector<double> lodDistances;
  /// The levels beyond the second distance step the fabric's coarse level (--lod-coarse,
  /// DetailLevel::coarseFabric).
  bool lodCoarse = false;
  /// Where the levels of detail are measured from, m, in the scene's frame (Y up, the characters walking
  /// towards -Z) relative to `origin` (--viewpoint). Empty: 4 m behind the last row of characters at the
  /// middle of the rows, 1.6 m up.
  std::optional<Eigen::Vector3d> viewpoint;
};

/// The most particles along a side of the cape (--size and the rows that --width and --height make).
constexpr int kMaxGridSide = 256;

/// Rows of a grid `columns` particles across a width x height cape (m) whose cells are square:
/// round((columns - 1) height / width) + 1, at least 2.
int squareCellRows(int columns, double width, double height);

class SceneRun {
 public:
  virtual ~SceneRun() = default;
  virtual int characterCount() const = 0;
  /// Advances one frame of 1/60 s.
  virtual void advanceFrame() = 0;
  /// A character's cape. Its state is in its own frame (Cape::origin): see frameOffset().
  virtual const Cape& cape(int character) const = 0;
  /// Body colliders of a character at the current frame (ground excluded), in its cape's frame, for the
  /// metrics (precise there however far the character is) and, moved by frameOffset(), the outputs.
  virtual std::vector<Collider> bodyColliders(int character) const = 0;
  /// The torso's centre, in the cape's frame.
  virtual Vec3 torsoCentre(int character) const = 0;
  /// The cape's frame less the scene's origin (--origin), m: what turns the cape's frame coordinates into
  /// the scene's, in which every output is written (the ground through the scene's origin).
  virtual Eigen::Vector3d frameOffset(int character) const = 0;
  /// Particles the cape's numerical guard restored during the last frame (Cape::guard()).
  virtual std::uint32_t guardRestoredLastFrame(int character) const = 0;
  /// Wall time of the last frame's stepSimulation, and the capes' share of it (the wall time of their
  /// updateAction calls, on however many workers), µs; the rest is Bullet's own.
  virtual double lastFrameTimeUs() const = 0;
  virtual double lastCapeTimeUs() const = 0;
  /// Wall time of the last frame's character motion (the gait or a clip), before its step, µs.
  virtual double lastMotionTimeUs() const = 0;
  /// Collision objects in the world (every character's bodies and the ground).
  virtual int worldObjectCount() const = 0;
  /// A description for summary.json (body, URDF, attachment links, stepping).
  virtual std::string describe() const = 0;
  /// The world's up direction (the ground is the plane through the origin normal to it).
  virtual Vec3 up() const = 0;
  /// The cape's size (the canonical 0.6 x 1.0 m, or fitted to the character's shoulders).
  virtual CapeSize capeSize() const = 0;
  /// The capes' settings as given to them, before the scene's own (settingsForScene): the options'
  /// settings with the fabric preset applied, if any.
  virtual const CapeSettings& settings() const = 0;
  /// Capes per level of detail at the last step ([0] full detail, then one per --lod distance); empty
  /// without --lod.
  virtual std::vector<std::size_t> detailCounts() const { return {}; }
  /// Where the levels of detail were measured from, m, world (meaningful with --lod).
  virtual Eigen::Vector3d detailViewpoint() const { return Eigen::Vector3d::Zero(); }
};

/// The run the options ask for: the shipped humanoid, a URDF character or the simple body, in a Bullet
/// world, with our cape on each character (BulletCapeRun.cpp). nullptr and a one-line reason on bad input
/// (unreadable URDF, unknown link).
std::unique_ptr<SceneRun> makeSceneRun(const RunOptions& options, std::string& error);
}  // namespace cape::demo
