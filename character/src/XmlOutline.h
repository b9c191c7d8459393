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
  const std::string* attribute(const std::string& key) const;
};

/// checkXmlWellFormed, also filling `outline` (when not null) with every element in document order.
bool scanXml(const std::string& text, std::string& message, std::vector<XmlElement>* outline);

}  // namespace cape::character
