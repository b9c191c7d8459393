/// \file
/// Reading motion clips (Motion.h) from files: joint-trajectory CSV, DeepMimic motion files and BVH motion
/// capture retargeted onto a URDF humanoid. Every loader returns errors as values (MotionClipResult: the
/// file, the line or frame, and what is wrong) and never throws or crashes on a bad or hostile file; the
/// formats and the retargeting rules are documented in character/README.md ("Motion clips").
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

/// The motion file formats.
enum class MotionFormat : int {
  Auto,       ///< Detected (detectMotionFormat).
  Csv,        ///< Joint-trajectory CSV.
  DeepMimic,  ///< DeepMimic motion files (JSON).
  Bvh,        ///< BVH motion capture.
};
/// "auto", "csv", "deepmimic" or "bvh".
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
/// How a joint-trajectory CSV is read.
struct CsvMotionOptions {
  MotionFrame frame = MotionFrame::Urdf;  ///< the frame the root columns are in
  bool loop = true;                       ///< the clip's MotionClip::loop
  MotionLimits limits;                    ///< the most the file may hold
};
/// Reads a joint-trajectory CSV file (errors name the file and the line).
CAPE_CHARACTER_API MotionClipResult readMotionCsv(const std::string& path,
                                                  const CsvMotionOptions& options = {});
/// Parses joint-trajectory CSV text; `name` stands for the file in messages and MotionClip::name.
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
/// How a DeepMimic motion file is read.
struct DeepMimicOptions {
  /// 64 MiB of text at most (PyBullet's clips are about 100 kB): the JSON document is built whole, about 4
  /// bytes of memory per byte of text at the peak.
  MotionLimits limits{std::size_t(64) << 20};
};
/// The joint names of that order, and whether each is spherical.
CAPE_CHARACTER_API const std::vector<std::pair<std::string, bool>>& deepMimicJoints();
/// Reads a DeepMimic motion file (errors name the file and the frame).
CAPE_CHARACTER_API MotionClipResult readDeepMimic(const std::string& path,
                                                  const DeepMimicOptions& options = {});
/// Parses DeepMimic JSON text; `name` stands for the file in messages and MotionClip::name.
CAPE_CHARACTER_API MotionClipResult parseDeepMimic(const std::string& text,
                                                   const DeepMimicOptions& options = {},
                                                   const std::string& name = "deepmimic");

// --- BVH motion capture, retargeted -------------------------------------------------------------------
/// The BVH skeleton's up axis: Y (most mocap), Z, or a guess from the rest pose (the axis along which the
/// head is farthest from the feet).
enum class BvhUp : int {
  Auto,  ///< Guessed from the rest pose.
  Y,     ///< y up.
  Z,     ///< z up.
};
/// A first frame with more than half of its rotation channels exactly 0, followed by one with fewer than half
/// as many: the reference (rest or T-) pose many exporters write before the motion (CMU's BVH conversions:
/// a few limbs set, everything else 0; a captured angle is never exactly 0). Auto leaves it out (said in the
/// warnings; the clip starts at the second frame, at time 0); Keep plays it. Clips of fewer than 3 frames
/// are kept whole.
enum class BvhRestFrame : int {
  Auto,  ///< Left out when it looks like a reference pose.
  Keep,  ///< Always played.
};
/// How a BVH file is read and retargeted.
struct BvhOptions {
  /// Metres per BVH unit; 0: a guess from the skeleton's height in its rest pose (said in the warnings:
  /// centimetres, inches or metres).
  double scale = 0.0;
  BvhUp up = BvhUp::Auto;                       ///< the BVH skeleton's up axis
  BvhRestFrame restFrame = BvhRestFrame::Auto;  ///< what to do with a reference first frame
  /// (BVH joint name, role) pairs for skeletons the common naming schemes miss. Roles by name: "hips",
  /// "spine", "neck", "left_hip", "left_knee", "left_ankle", "left_shoulder", "left_elbow", and right_...
  std::vector<std::pair<std::string, std::string>> roles;
  /// Scale the root's motion by the URDF's leg length over the BVH's (so the feet keep their stride).
  bool scaleRootToLegs = true;
  bool loop = true;     ///< the clip's MotionClip::loop
  MotionLimits limits;  ///< the most the file may hold
};
/// Reads a BVH and retargets it onto `model` (its joints mapped by `mapping`, or JointMapping::automatic):
/// the result is a clip of the model's own joints in the URDF frame, for a character of `characterScale`.
CAPE_CHARACTER_API MotionClipResult readBvh(const std::string& path, const UrdfModelPtr& model,
                                            const BvhOptions& options = {},
                                            const JointMapping* mapping = nullptr,
                                            double characterScale = 1.0);
/// Parses BVH text and retargets it as readBvh does; `name` stands for the file in messages and
/// MotionClip::name.
CAPE_CHARACTER_API MotionClipResult parseBvh(const std::string& text, const UrdfModelPtr& model,
                                             const BvhOptions& options = {},
                                             const JointMapping* mapping = nullptr,
                                             double characterScale = 1.0, const std::string& name = "bvh");

/// Any of the three by format (Auto: detectMotionFormat). BVH needs the model; CSV and DeepMimic ignore it.
struct MotionLoadOptions {
  MotionFormat format = MotionFormat::Auto;  ///< the file's format (Auto: detected)
  CsvMotionOptions csv;                      ///< for a CSV file
  DeepMimicOptions deepMimic;                ///< for a DeepMimic file
  BvhOptions bvh;                            ///< for a BVH file
};
/// Reads a motion file of any of the three formats (see MotionLoadOptions): FileNotFound for no such file,
/// InvalidArgument for a format that cannot be told or a BVH without a model.
CAPE_CHARACTER_API MotionClipResult loadMotion(const std::string& path, const UrdfModelPtr& model,
                                               const MotionLoadOptions& options = {},
                                               const JointMapping* mapping = nullptr,
                                               double characterScale = 1.0);

}  // namespace cape::character
