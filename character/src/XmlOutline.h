// Internal: the element outline the XML check can record on the way (names, nesting, raw attribute values),
// so that the loader can look at the joint graph before handing the text to urdfdom.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace cape::character {

struct XmlElement {
  std::string name;
  int parent = -1;  ///< index of the enclosing element in the outline, -1 for the root
  std::vector<std::pair<std::string, std::string>> attributes;  ///< values as written (entities not expanded)
  std::vector<std::size_t> valueOffsets;  ///< byte offset in the text of each attribute's value
  std::size_t begin = 0;                  ///< byte offset of its '<'
  std::size_t end = 0;                    ///< byte offset just after its end tag (or its "/>")
  const std::string* attribute(const std::string& key) const;
};

/// Elements nested deeper than this are refused as malformed by default (UrdfLimits::maxXmlDepth): a URDF is
/// a few levels deep, and urdfdom's XML parser recurses once per level (tens of thousands of levels overflow
/// its stack).
constexpr std::size_t kMaxXmlDepth = 256;
/// The deepest nesting a user may allow (UrdfLimits::maxXmlDepth): a few hundred KB of urdfdom's stack.
constexpr std::size_t kMaxXmlDepthCeiling = 1024;

/// What the scan refuses (the XML parts of UrdfLimits). Each message names the UrdfLimits field.
struct XmlScanLimits {
  std::size_t maxDepth = kMaxXmlDepth;
  std::size_t maxElements = static_cast<std::size_t>(-1);
};

/// What else the scan found out.
struct XmlScanDetails {
  /// The scan failed on limits.maxElements: a limit of the model rather than broken XML.
  bool tooLarge = false;
  /// [begin, end) of each processing instruction and <! declaration that holds a '>' before its own end (a
  /// DOCTYPE with an internal subset, a PI with a '>' inside). urdfdom's parser (TinyXML) ends those at
  /// their first '>' and reads what follows as markup, elements the outline does not have; so the loader
  /// blanks them out of the text urdfdom is given.
  std::vector<std::pair<std::size_t, std::size_t>> endedEarlierByTinyXml;
};

/// checkXmlWellFormed, also filling `outline` (when not null) with every element in document order and
/// `details` (when not null). More elements than limits.maxElements, or nesting deeper than
/// limits.maxDepth, fail as malformed.
bool scanXml(const std::string& text, std::string& message, std::vector<XmlElement>* outline,
             const XmlScanLimits& limits = {}, XmlScanDetails* details = nullptr);

}  // namespace cape::character
