// Reading motion clips (Motion.h) from files: joint-trajectory CSV, DeepMimic motion files and BVH motion
// capture retargeted onto a URDF humanoid. Every loader returns errors as values (MotionClipResult: the
// file, the line or frame, and what is wrong) and never throws or crashes on a bad or hostile file; the
// formats and the retargeting rules are documented in character/README.md ("Motion clips").
#pragma once

#include "cape/character/Export.h"
#include "cape/character/JointMapping.h"
#include "cape/character/Motion.h"
#include "cape/character/Urdf.h"

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

namespace cape::character {

enum class MotionFormat : int { Auto, Csv, DeepMimic, Bvh };
CAPE_CHARACTER_API const char* toString(MotionFormat format);
/// "csv", "deepmimic", "bvh" or "auto"; false for anything else.
CAPE_CHARACTER_API bool parseMotionFormat(const std::string& text, MotionFormat& out);
/// The format of a file from its extension (.csv, .bvh; .json is DeepMimic), else from its first bytes
/// ("HIERARCHY" is BVH, a '{' DeepMimic, a header starting with "time" CSV). A .txt (PyBullet's DeepMimic
/// files) is read by its first bytes too, and is DeepMimic when they fit none. Auto when nothing fits.
CAPE_CHARACTER_API MotionFormat detectMotionFormat(const std::string& path);

/// The most a motion file may hold; over a limit is InvalidArgument naming it.
struct MotionLimits {
  std::size_t maxFileBytes = std::size_t(256) << 20;  ///< 256 MiB
  std::size_t maxSamples = 1000000;                   ///< frames or rows
  std::size_t maxJoints = 1000;                       ///< columns, BVH joints, DeepMimic values per frame
  std::size_t maxDepth = 256;                         ///< BVH hierarchy nesting
};

// --- Joint trajectory CSV ------------------------------------------------------------------------------
// A header `time, root_x, root_y, root_z, root_qx, root_qy, root_qz, root_qw, <joint>...` (names as the
// URDF's joints; a spherical joint as four columns `<joint>.qx, .qy, .qz, .qw`), then one row per sample: s,
// m, a unit quaternion (normalised on reading), rad or m. Comma-separated, spaces around fields allowed,
// '#' comment lines and blank lines skipped, CRLF accepted.
struct CsvMotionOptions {
  MotionFrame frame = MotionFrame::Urdf;  ///< the frame the root columns are in
  bool loop = true;
  MotionLimits limits;
};
CAPE_CHARACTER_API MotionClipResult readMotionCsv(const std::string& path,
                                                  const CsvMotionOptions& options = {});
CAPE_CHARACTER_API MotionClipResult parseMotionCsv(const std::string& text,
                                                   const CsvMotionOptions& options = {},
                                                   const std::string& name = "csv");
/// Writes a clip in that format (the inverse of parseMotionCsv, to 17 significant digits).
CAPE_CHARACTER_API std::string writeMotionCsv(const MotionClip& clip);
/// The same, checked first: InvalidArgument (nothing written to `out`) for a clip that fails check() or a
/// joint name the format cannot hold (empty; a ',', '#', a line break, or spaces at either end; a root
/// column's name; a scalar joint named like a ball column, "NAME.qx"), naming it.
CAPE_CHARACTER_API Status writeMotionCsv(const MotionClip& clip, std::string& out);

// --- DeepMimic motion files ---------------------------------------------------------------------------
// JSON `{"Loop": "wrap"|"none", "Frames": [[duration, root position (3), root rotation (w x y z),
// joint values...], ...]}` for PyBullet's DeepMimic humanoid (pybullet_data/humanoid/humanoid.urdf): after
// the root, in this order, chest, neck, right_hip, right_knee, right_ankle, right_shoulder, right_elbow,
// left_hip, left_knee, left_ankle, left_shoulder, left_elbow; spherical joints as quaternions (w x y z),
// knees and elbows as one angle (rad): 44 numbers per frame. A frame's duration is the time to the next
// frame. The root is in the Y-up frame of the file (MotionFrame::YUp), in metres of PyBullet's scaled
// humanoid (it loads the URDF with globalScaling 0.25).
struct DeepMimicOptions {
  /// 64 MiB of text at most (PyBullet's clips are about 100 kB): the JSON document is built whole, about 4
  /// bytes of memory per byte of text at the peak.
  MotionLimits limits{std::size_t(64) << 20};
};
/// The joint names of that order, and whether each is spherical.
CAPE_CHARACTER_API const std::vector<std::pair<std::string, bool>>& deepMimicJoints();
CAPE_CHARACTER_API MotionClipResult readDeepMimic(const std::string& path,
                                                  const DeepMimicOptions& options = {});
CAPE_CHARACTER_API MotionClipResult parseDeepMimic(const std::string& text,
                                                   const DeepMimicOptions& options = {},
                                                   const std::string& name = "deepmimic");

// --- BVH motion capture, retargeted -------------------------------------------------------------------
/// The BVH skeleton's up axis: Y (most mocap), Z, or a guess from the rest pose (the axis along which the
/// head is farthest from the feet).
enum class BvhUp : int { Auto, Y, Z };
/// A first frame with more than half of its rotation channels exactly 0, followed by one with fewer than half
/// as many: the reference (rest or T-) pose many exporters write before the motion (CMU's BVH conversions:
/// a few limbs set, everything else 0; a captured angle is never exactly 0). Auto leaves it out (said in the
/// warnings; the clip starts at the second frame, at time 0); Keep plays it. Clips of fewer than 3 frames
/// are kept whole.
enum class BvhRestFrame : int { Auto, Keep };
struct BvhOptions {
  /// Metres per BVH unit; 0: a guess from the skeleton's height in its rest pose (said in the warnings:
  /// centimetres, inches or metres).
  double scale = 0.0;
  BvhUp up = BvhUp::Auto;
  BvhRestFrame restFrame = BvhRestFrame::Auto;
  /// (BVH joint name, role) pairs for skeletons the common naming schemes miss. Roles by name: "hips",
  /// "spine", "neck", "left_hip", "left_knee", "left_ankle", "left_shoulder", "left_elbow", and right_...
  std::vector<std::pair<std::string, std::string>> roles;
  /// Scale the root's motion by the URDF's leg length over the BVH's (so the feet keep their stride).
  bool scaleRootToLegs = true;
  bool loop = true;
  MotionLimits limits;
};
/// Reads a BVH and retargets it onto `model` (its joints mapped by `mapping`, or JointMapping::automatic):
/// the result is a clip of the model's own joints in the URDF frame, for a character of `characterScale`.
CAPE_CHARACTER_API MotionClipResult readBvh(const std::string& path, const UrdfModelPtr& model,
                                            const BvhOptions& options = {},
                                            const JointMapping* mapping = nullptr,
                                            double characterScale = 1.0);
CAPE_CHARACTER_API MotionClipResult parseBvh(const std::string& text, const UrdfModelPtr& model,
                                             const BvhOptions& options = {},
                                             const JointMapping* mapping = nullptr,
                                             double characterScale = 1.0, const std::string& name = "bvh");

/// Any of the three by format (Auto: detectMotionFormat). BVH needs the model; CSV and DeepMimic ignore it.
struct MotionLoadOptions {
  MotionFormat format = MotionFormat::Auto;
  CsvMotionOptions csv;
  DeepMimicOptions deepMimic;
  BvhOptions bvh;
};
CAPE_CHARACTER_API MotionClipResult loadMotion(const std::string& path, const UrdfModelPtr& model,
                                               const MotionLoadOptions& options = {},
                                               const JointMapping* mapping = nullptr,
                                               double characterScale = 1.0);

}  // namespace cape::character
