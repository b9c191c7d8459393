// A small well-formedness check for XML, run before urdfdom so that a broken file is reported as broken XML,
// with a line number, rather than as whatever urdfdom's parser happened to print. It checks structure only:
// balanced and matching tags, quoted attributes, one root element, nothing but white space outside it.
#include "XmlOutline.h"

#include "cape/character/Urdf.h"

#include <cctype>
#include <string>
#include <vector>

namespace cape::character {
namespace {

class XmlScanner {
 public:
  XmlScanner(const std::string& text, std::vector<XmlElement>* outline, const XmlScanLimits& limits,
             XmlScanDetails* details)
      : s_(text), outline_(outline), limits_(limits), details_(details) {}

  bool run(std::string& message) {
    if (s_.compare(0, 3, "\xEF\xBB\xBF") == 0) i_ = 3;  // UTF-8 byte order mark
    bool sawRoot = false;
    while (i_ < s_.size()) {
      if (s_[i_] != '<') {
        if (stack_.empty() && !std::isspace(static_cast<unsigned char>(s_[i_]))) {
          return fail(message, "text outside the root element");
        }
        advance(1);
        continue;
      }
      if (startsWith("<!--")) {
        if (!skipPast("-->")) return fail(message, "unterminated comment");
      } else if (startsWith("<![CDATA[")) {
        if (stack_.empty()) return fail(message, "CDATA outside the root element");
        if (!skipPast("]]>")) return fail(message, "unterminated CDATA section");
      } else if (startsWith("<?")) {
        const std::size_t begin = i_;
        if (!skipPast("?>")) return fail(message, "unterminated processing instruction");
        noteIfEndedEarlier(begin);
      } else if (startsWith("<!")) {
        const std::size_t begin = i_;
        if (!skipDeclaration()) return fail(message, "unterminated <! declaration");
        noteIfEndedEarlier(begin);
      } else if (startsWith("</")) {
        advance(2);
        const std::string name = readName();
        if (name.empty()) return fail(message, "end tag without a name");
        skipSpace();
        if (i_ >= s_.size() || s_[i_] != '>')
          return fail(message, "end tag </" + name + "> not closed by '>'");
        advance(1);
        if (stack_.empty()) return fail(message, "end tag </" + name + "> without a start tag");
        if (stack_.back() != name) {
          return fail(message, "end tag </" + name + "> does not match <" + stack_.back() + ">");
        }
        stack_.pop_back();
        if (outline_ && open_.back() >= 0) (*outline_)[static_cast<std::size_t>(open_.back())].end = i_;
        open_.pop_back();
      } else {
        const std::size_t begin = i_;
        advance(1);
        const std::string name = readName();
        if (name.empty()) return fail(message, "'<' not followed by a tag name");
        if (stack_.empty() && sawRoot) return fail(message, "a second root element <" + name + ">");
        sawRoot = true;
        XmlElement element;
        element.name = name;
        element.parent = open_.empty() ? -1 : open_.back();
        element.begin = begin;
        if (stack_.size() >= limits_.maxDepth) {
          return fail(message, "elements nested deeper than " + std::to_string(limits_.maxDepth) +
                                   " levels; the limit is " + std::to_string(limits_.maxDepth) +
                                   " (UrdfLimits::maxXmlDepth)");
        }
        if (++elements_ > limits_.maxElements) {
          if (details_) details_->tooLarge = true;
          return fail(message, "more than " + std::to_string(limits_.maxElements) +
                                   " XML elements; the limit is " + std::to_string(limits_.maxElements) +
                                   " (UrdfLimits::maxXmlElements)");
        }
        bool selfClosing = false;
        if (!readAttributes(selfClosing, element, message)) return false;
        if (selfClosing) element.end = i_;
        const int index = outline_ ? static_cast<int>(outline_->size()) : -1;
        if (outline_) outline_->push_back(std::move(element));
        if (!selfClosing) {
          stack_.push_back(name);
          open_.push_back(index);
        }
      }
    }
    if (!stack_.empty()) return fail(message, "end of text inside <" + stack_.back() + "> (not closed)");
    if (!sawRoot) return fail(message, "no root element (empty document)");
    return true;
  }

 private:
  bool startsWith(const char* prefix) const {
    return s_.compare(i_, std::char_traits<char>::length(prefix), prefix) == 0;
  }

  void advance(std::size_t n) {
    for (std::size_t k = 0; k < n && i_ < s_.size(); ++k, ++i_) {
      if (s_[i_] == '\n') ++line_;
    }
  }

  // A processing instruction or <! declaration from `begin` to here that TinyXML ends at an earlier '>'.
  void noteIfEndedEarlier(std::size_t begin) {
    if (details_ && s_.find('>', begin) + 1 < i_) details_->endedEarlierByTinyXml.emplace_back(begin, i_);
  }

  bool skipPast(const char* end) {
    const std::size_t at = s_.find(end, i_);
    if (at == std::string::npos) return false;
    advance(at + std::char_traits<char>::length(end) - i_);
    return true;
  }

  // <!DOCTYPE ...> with an optional internal subset in [ ... ].
  bool skipDeclaration() {
    int bracket = 0;
    while (i_ < s_.size()) {
      const char c = s_[i_];
      advance(1);
      if (c == '[') ++bracket;
      if (c == ']') --bracket;
      if (c == '>' && bracket <= 0) return true;
    }
    return false;
  }

  static bool isNameChar(char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == ':' || c == '-' || c == '.' ||
           static_cast<unsigned char>(c) >= 0x80;
  }

  std::string readName() {
    const std::size_t start = i_;
    if (i_ < s_.size() &&
        (std::isdigit(static_cast<unsigned char>(s_[i_])) || s_[i_] == '-' || s_[i_] == '.')) {
      return std::string();
    }
    while (i_ < s_.size() && isNameChar(s_[i_])) ++i_;
    return s_.substr(start, i_ - start);
  }

  void skipSpace() {
    while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_]))) advance(1);
  }

  bool readAttributes(bool& selfClosing, XmlElement& element, std::string& message) {
    std::vector<std::pair<std::string, std::string>>& attributes = element.attributes;
    for (;;) {
      const std::size_t before = i_;
      skipSpace();
      if (i_ >= s_.size()) return fail(message, "end of text inside a start tag");
      if (s_[i_] == '>') {
        advance(1);
        return true;
      }
      if (s_[i_] == '/') {
        advance(1);
        if (i_ >= s_.size() || s_[i_] != '>') return fail(message, "'/' in a start tag not followed by '>'");
        advance(1);
        selfClosing = true;
        return true;
      }
      if (i_ == before) return fail(message, "attributes must be separated by white space");
      const std::string attr = readName();
      if (attr.empty()) return fail(message, std::string("unexpected '") + s_[i_] + "' in a start tag");
      for (const auto& other : attributes) {
        if (other.first == attr) return fail(message, "attribute '" + attr + "' given twice");
      }
      skipSpace();
      if (i_ >= s_.size() || s_[i_] != '=')
        return fail(message, "attribute '" + attr + "' without '=' and a value");
      advance(1);
      skipSpace();
      if (i_ >= s_.size() || (s_[i_] != '"' && s_[i_] != '\'')) {
        return fail(message, "value of attribute '" + attr + "' is not quoted");
      }
      const char quote = s_[i_];
      advance(1);
      const std::size_t valueStart = i_;
      while (i_ < s_.size() && s_[i_] != quote) {
        if (s_[i_] == '<') return fail(message, "'<' inside the value of attribute '" + attr + "'");
        advance(1);
      }
      if (i_ >= s_.size()) return fail(message, "unterminated value of attribute '" + attr + "'");
      attributes.emplace_back(attr, s_.substr(valueStart, i_ - valueStart));
      element.valueOffsets.push_back(valueStart);
      advance(1);
    }
  }

  bool fail(std::string& message, const std::string& what) const {
    message = "line " + std::to_string(line_) + ": " + what;
    return false;
  }

  const std::string& s_;
  std::size_t i_ = 0;
  int line_ = 1;
  std::vector<std::string> stack_;  ///< names of the open elements
  std::vector<int> open_;           ///< their indices in *outline_ (-1 without an outline)
  std::vector<XmlElement>* outline_;
  XmlScanLimits limits_;
  XmlScanDetails* details_;
  std::size_t elements_ = 0;
};

}  // namespace

bool scanXml(const std::string& text, std::string& message, std::vector<XmlElement>* outline,
             const XmlScanLimits& limits, XmlScanDetails* details) {
  if (outline) outline->clear();
  if (details) *details = XmlScanDetails();
  XmlScanner scanner(text, outline, limits, details);
  return scanner.run(message);
}

bool checkXmlWellFormed(const std::string& text, std::string& message) {
  return scanXml(text, message, nullptr);
}

const std::string* XmlElement::attribute(const std::string& key) const {
  for (const auto& [k, v] : attributes) {
    if (k == key) return &v;
  }
  return nullptr;
}

}  // namespace cape::character
