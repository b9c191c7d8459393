/// \file
/// A URDF robot description loaded with urdfdom into plain data: links with their collision shapes, joints
/// with their origins, axes and limits, in a parents-before-children order. Everything here is in the URDF's
/// own frame and units (REP 103: metres, radians, Z up, X forward); Skeleton maps it into the Y-up world.
///
/// Loading never throws and never crashes on bad data: it returns a Status (see Status.h) naming the problem.
/// urdfdom prints its diagnostics through console_bridge; while we parse they are captured instead and folded
/// into our error message or, for a model that loads, into warnings().
#pragma once

#include "cape/character/Export.h"
#include "cape/character/Status.h"

#include <Eigen/Geometry>

#include <cstddef>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

namespace cape::character {

/// Collision shapes. Capsule is the `<capsule radius length>` extension that Bullet's URDF importer,
/// PyBullet, Drake and the MuJoCo converters write (urdfdom itself has none). A mesh element becomes a
/// ConvexHull: the convex hull of the mesh file's vertices, simplified to a vertex budget (UrdfLoadOptions).
enum class ShapeType : int {
  Sphere,      ///< `radius`
  Box,         ///< `halfExtents`
  Cylinder,    ///< `radius` and `halfLength`, along local z
  Capsule,     ///< `radius` around a segment of `halfLength` along local z
  ConvexHull,  ///< `hull` and `hullPlanes`, grown by `radius`
};
/// The type's name ("sphere", "box", ...).
CAPE_CHARACTER_API const char* toString(ShapeType type);

/// One collision element of a link, in the link's frame.
struct ShapeDesc {
  ShapeType type = ShapeType::Sphere;  ///< Which of the size fields below apply
  double radius = 0.0;      ///< m; sphere, cylinder and capsule; for a hull, its rounding (see hull)
  double halfLength = 0.0;  ///< m; cylinder, and a capsule's cylindrical part, along its local z (URDF rule)
  Eigen::Vector3d halfExtents = Eigen::Vector3d::Zero();  ///< m; box, along its local x, y, z
  /// ConvexHull: the hull's vertices in the shape frame (m, the element's `scale` applied). The surface is
  /// the hull grown by `radius`, which covers every mesh vertex the simplification left out.
  std::vector<Eigen::Vector3d> hull;
  /// ConvexHull: its outward faces (unit normal n, offset d; inside where n . p <= d), in the shape frame.
  std::vector<Eigen::Vector4d> hullPlanes;
  std::string meshFile;  ///< ConvexHull: the mesh file it was made from, as resolved on disk
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();  ///< shape frame in the link frame
  std::string name;  ///< the element's name attribute, or `<link>#<k>` when it has none
};

/// Spherical is Bullet's importer's extension (`type="spherical"`, a ball joint: PyBullet's DeepMimic
/// humanoid has eight); urdfdom has none, so it is read as floating and marked spherical here. Its position
/// is a rotation (Skeleton::setJointRotation), not a number.
enum class JointType : int {
  Fixed,       ///< does not move
  Revolute,    ///< turns about `axis` within its limits, rad
  Continuous,  ///< turns about `axis` without limits, rad
  Prismatic,   ///< slides along `axis` within its limits, m
  Floating,    ///< six degrees of freedom (not driven here)
  Planar,      ///< moves in the plane normal to `axis` (not driven here)
  Spherical,   ///< a ball joint: a rotation (Skeleton::setJointRotation)
};
/// The type's name ("fixed", "revolute", ...).
CAPE_CHARACTER_API const char* toString(JointType type);

/// One link of the model.
struct LinkDesc {
  std::string name;               ///< The link's name in the URDF
  int parentJoint = -1;           ///< index into UrdfModel::joints(); -1 for the root
  int parentLink = -1;            ///< index into UrdfModel::links(); -1 for the root
  std::vector<int> childJoints;   ///< indices into UrdfModel::joints() of the joints below it
  std::vector<ShapeDesc> shapes;  ///< collision elements that could be used (the others: warnings())
  double mass = 0.0;              ///< kg, from `<inertial>`; 0 when absent
};

/// One joint of the model.
struct JointDesc {
  std::string name;                                          ///< The joint's name in the URDF
  JointType type = JointType::Fixed;                         ///< How it moves
  int parentLink = -1;                                       ///< index into UrdfModel::links()
  int childLink = -1;                                        ///< index into UrdfModel::links()
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();  ///< child joint frame in the parent link frame
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX();           ///< unit vector in the joint frame
  bool hasLimits = false;    ///< revolute and prismatic always; continuous never (position is unbounded)
  double lower = 0.0;        ///< rad (revolute) or m (prismatic)
  double upper = 0.0;        ///< rad (revolute) or m (prismatic)
  double maxVelocity = 0.0;  ///< rad/s or m/s, as written in `<limit velocity=...>`; 0 when absent

  /// One scalar position (revolute, continuous, prismatic); fixed, floating, planar and spherical joints have
  /// none (a spherical joint's position is a rotation: isSpherical).
  bool isSpherical() const { return type == JointType::Spherical; }
  /// True for a joint with one scalar position: revolute, continuous or prismatic.
  bool isMovable() const {
    return type == JointType::Revolute || type == JointType::Continuous || type == JointType::Prismatic;
  }
};

class UrdfModel;
/// A shared, immutable model.
using UrdfModelPtr = std::shared_ptr<const UrdfModel>;

/// The most a URDF may hold. A model over a limit is refused before the expensive part of the load, with an
/// error naming the limit, e.g. "URDF has 10001 links; the limit is 10000 (UrdfLimits::maxLinks)". The
/// defaults are far above any real robot (the largest public humanoids have about 100 links and a few
/// collision elements per link) and keep a hostile file's load to seconds and its memory to hundreds of MB.
/// Each may be set, and every value must be at least 1 (InvalidArgument otherwise).
struct UrdfLimits {
  /// Bytes of URDF text (fromString: the whole string; fromFile: the file's size, checked before it is
  /// read). InvalidModel. Real URDFs are kilobytes to a few MB.
  std::size_t maxFileBytes = std::size_t(64) << 20;  // 64 MiB
  /// XML elements of any kind, counted while the text is checked. InvalidModel. Bounds the memory of our
  /// outline of the text (about 100 bytes per element); a 10,000-link model is some 200,000 elements.
  std::size_t maxXmlElements = 1000000;
  /// Nesting depth of the XML elements (a URDF is 5 deep). MalformedXml. At most 1024: urdfdom's parser
  /// recurses once per level (tens of thousands of levels overflow its stack).
  std::size_t maxXmlDepth = 256;
  /// `<link>` elements of the `<robot>`. InvalidModel. Each link becomes one rigid body.
  std::size_t maxLinks = 10000;
  /// `<joint>` elements of the `<robot>`. InvalidModel. A tree of n links has n - 1 joints.
  std::size_t maxJoints = 10000;
  /// `<collision>` elements of all links together. InvalidModel.
  std::size_t maxCollisionElements = 100000;
  /// Triangles of all mesh collision elements of the model together: each element counts every triangle of
  /// its file (every node instance), also when another element uses the same file. InvalidModel. A detailed
  /// visual mesh is 100,000 to 500,000 triangles; a collision mesh a few thousand.
  std::size_t maxMeshTriangles = 4000000;
  /// m: the largest length the model may hold: every joint origin's offset and every collision element's
  /// (along any axis), every shape's radius, length and box size, every hull vertex (a mesh's scale
  /// applied). InvalidModel. A robot is metres; a 1e30 m offset or sphere is a broken file, and no float
  /// pipeline downstream (Bullet's, the cape's) can simulate it. Finite and > 0.
  double maxLength = 1000.0;
};

/// How a URDF's mesh collision elements are found and made into hulls, and the limits of what is read.
struct UrdfLoadOptions {
  /// Folder that relative mesh paths resolve against. fromFile uses the URDF file's folder when empty;
  /// fromString the working directory.
  std::string baseDir;
  /// Where `package://NAME/path` looks: DIR/NAME/path, or DIR/path when DIR itself is the folder NAME, for
  /// each DIR here, then for each entry of the ROS_PACKAGE_PATH environment variable.
  std::vector<std::string> packagePaths;
  /// Vertex budget of each mesh's simplified convex hull (>= 4).
  int maxHullVertices = 64;
  /// Off: mesh elements are skipped with a warning, no file is opened.
  bool loadMeshes = true;
  /// The axis the model stands along in its own file. REP 103 says z; models from Y-up tools (PyBullet's
  /// DeepMimic humanoid) stand along y, with x forward, and are turned here onto z (a +90 degree turn about
  /// x of everything below the root link). Auto: z, unless the model in its zero pose is more than twice as
  /// long along y as along z and, turned, has legs whose joints the mapping finds by structure (an upper body
  /// in a T-pose is long along y too, but has no legs either way); either case is said in a warning.
  enum class Up : int {
    Auto,  ///< Z, unless the model looks Y-up as described above.
    Z,     ///< The file is Z-up (REP 103).
    Y,     ///< The file is Y-up: turned onto z.
  };
  Up modelUp = Up::Auto;  ///< The axis the model stands along in its file.
  /// The most a model may hold (file size, XML depth and elements, links, joints, collision elements, mesh
  /// triangles).
  UrdfLimits limits;
};

/// What a load returns: ok and a model, or an error status and no model. `warnings` holds what was said on
/// the way, in order, also when the load failed (so the cause of a failure is not hidden).
struct UrdfLoadResult {
  Status status;                      ///< Why there is no model, or success
  UrdfModelPtr model;                 ///< The model; null on error
  std::vector<std::string> warnings;  ///< What was said on the way, in order
  /// True when a model was loaded.
  bool ok() const { return status.ok() && model != nullptr; }
};

/// Shared and immutable once loaded: any number of Skeletons may use one model.
/// A URDF robot description as plain data (see Urdf.h).
class CAPE_CHARACTER_API UrdfModel {
 public:
  /// Reads and parses a URDF file. FileNotFound when the path is not a readable regular file; InvalidModel,
  /// before anything is read, when it is larger than options.limits.maxFileBytes.
  static UrdfLoadResult fromFile(const std::string& path, const UrdfLoadOptions& options = {});
  /// Parses URDF text. The text ends at its first NUL byte, as for Bullet's importer (PyBullet's humanoid
  /// ships with one after `</robot>`).
  static UrdfLoadResult fromString(const std::string& xml, const UrdfLoadOptions& options = {});
  /// The humanoid shipped in character/models/humanoid.urdf, compiled into the library (no file needed).
  static UrdfLoadResult humanoid();
  /// The text of that humanoid.
  static const std::string& humanoidUrdf();

  /// The `<robot>`'s name.
  const std::string& name() const { return name_; }
  /// Links in parents-before-children order; links()[rootLink()] is the root (index 0).
  const std::vector<LinkDesc>& links() const { return links_; }
  /// Joints in the order of their child links.
  const std::vector<JointDesc>& joints() const { return joints_; }
  /// The root link's index: 0.
  int rootLink() const { return 0; }
  /// Index of the link or joint of that name, -1 if none.
  int findLink(const std::string& name) const;
  /// Index of the joint of that name, -1 if none.
  int findJoint(const std::string& name) const;
  /// Names of the links whose name contains `part` (case-insensitive), in link order: "shoulder" finds the
  /// shipped humanoid's left_shoulder and right_shoulder.
  std::vector<std::string> linksContaining(const std::string& part) const;
  /// Things that loaded but not as written: mesh elements left out, geometry urdfdom could not read, ... Each
  /// names its link.
  const std::vector<std::string>& warnings() const { return warnings_; }
  /// True when the model stood along y in its file and was turned onto z (UrdfLoadOptions::modelUp): what
  /// hangs below the root link was turned +90 degrees about x. A motion written for the file's Y-up frame
  /// (MotionFrame::YUp) is turned the same way.
  bool turnedOntoZ() const { return turnedOntoZ_; }

 private:
  friend struct UrdfModelBuilder;
  bool turnedOntoZ_ = false;
  std::string name_;
  std::vector<LinkDesc> links_;
  std::vector<JointDesc> joints_;
  std::unordered_map<std::string, int> linkIndex_;
  std::unordered_map<std::string, int> jointIndex_;
  std::vector<std::string> warnings_;
};

/// Checks that `text` is well-formed XML with a single root element (tags balanced and matched, attributes
/// quoted, comments, CDATA, processing instructions and a DOCTYPE allowed) nested at most
/// UrdfLimits().maxXmlDepth deep. On failure `message` says what and on which line. Used before urdfdom so
/// that broken XML is told apart from a broken robot description.
CAPE_CHARACTER_API bool checkXmlWellFormed(const std::string& text, std::string& message);

}  // namespace cape::character
