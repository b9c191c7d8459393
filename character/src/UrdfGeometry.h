// Internal: the parts of a URDF that we read ourselves from the XML outline rather than through urdfdom,
// because urdfdom drops them where Bullet's own importer (and PyBullet, Drake, the MuJoCo converters) reads
// them: <capsule> geometry, numbers with white space around them, and the rest of a link's collision list
// after one element it cannot read. Also the one change made to the text urdfdom is given.
#pragma once

#include "XmlOutline.h"

#include "cape/character/Urdf.h"

#include <string>
#include <unordered_map>
#include <vector>

namespace cape::character {

/// What we read of one <link>: its collision shapes (meshes already made into hulls) and its mass.
struct LinkGeometry {
  std::vector<ShapeDesc> shapes;
  double mass = 0.0;  ///< kg, from <inertial><mass value>; 0 when absent or unreadable
};

/// Every top-level <link> of the outline by name (as urdfdom reads it, see urdfdomName) into `links`. Each
/// element that cannot be used (unknown geometry, a size that is not a positive finite number, a mesh file
/// that is missing, empty or unreadable) is left out with one warning naming the link, the element and the
/// reason. Fails (InvalidModel) only when the meshes together hold more triangles than
/// options.limits.maxMeshTriangles; the mesh that passed it is named.
Status readLinkGeometry(const std::vector<XmlElement>& outline, const UrdfLoadOptions& options,
                        std::vector<std::string>& warnings,
                        std::unordered_map<std::string, LinkGeometry>& links);

/// The value urdfdom reads for a link name written as `raw` (a <link name>, or the link of a joint's <parent>
/// or <child>): white space tidied as textForUrdfdom does, then the references TinyXML expands (&amp; &lt;
/// &gt; &quot; &apos;, and &#N; &#xH; as UTF-8; any other '&' stays as written). textForUrdfdom writes every
/// such value that holds a '&' as this name escaped with the five named entities alone, so urdfdom sees
/// exactly this name whatever its own reading of character references. False for a character reference
/// that is not a character (0, a surrogate, above U+10FFFF, or not a number).
bool urdfdomName(const std::string& raw, std::string& name);

/// The text urdfdom is given: without the <collision>, <visual> and <inertial> elements of the links (we read
/// what we need of them ourselves, and urdfdom drops a link's shapes after one it cannot read), with the
/// white space around every other attribute value removed (urdfdom refuses " 0.1 " as a number; Bullet's
/// importer reads it), link names with a '&' written as urdfdomName reads them, and `spherical` joints
/// (Bullet's importer's extension) given to urdfdom as `floating`.
/// One warning says how many values changed and where the first was, one names the spherical joints.
std::string textForUrdfdom(const std::string& text, const std::vector<XmlElement>& outline,
                           std::vector<std::string>& warnings);

/// The names of the <robot>'s joints of type `spherical` (as urdfdom reads names), in file order.
std::vector<std::string> sphericalJointNames(const std::vector<XmlElement>& outline);

/// A number as Bullet's importer reads it: white space around it allowed, nothing else. False otherwise.
bool parseUrdfNumber(const std::string& text, double& value);

}  // namespace cape::character
