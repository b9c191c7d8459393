// Reading collision geometry and masses from the XML outline (see UrdfGeometry.h for why not urdfdom).
#include "UrdfGeometry.h"

#include "MeshHull.h"

#include <urdf_model/pose.h>
#include <urdf_model/utils.h>

#include <algorithm>
#include <cctype>
#include <climits>
#include <cmath>
#include <cstdint>
#include <exception>

namespace cape::character {
namespace {

bool isSpace(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r';
}

std::string trim(const std::string& s) {
  std::size_t a = 0, b = s.size();
  while (a < b && isSpace(s[a])) ++a;
  while (b > a && isSpace(s[b - 1])) --b;
  return s.substr(a, b - a);
}

// White space runs collapsed to one space, and none at either end.
std::string normalised(const std::string& s) {
  std::string out;
  bool gap = false;
  for (char c : s) {
    if (isSpace(c)) {
      gap = true;
      continue;
    }
    if (gap && !out.empty()) out += ' ';
    gap = false;
    out += c;
  }
  return out;
}

// What textForUrdfdom gives urdfdom for a value: runs of white space collapsed and none at the ends when the
// value has any around it or any tab or line break (urdfdom takes runs of spaces between numbers).
bool untidy(const std::string& value) {
  return trim(value) != value || value.find_first_of("\t\n\r") != std::string::npos;
}

std::string tidied(const std::string& value) {
  return untidy(value) ? normalised(value) : value;
}

int hexDigit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

void appendUtf8(std::uint32_t c, std::string& out) {
  if (c < 0x80) {
    out += static_cast<char>(c);
  } else if (c < 0x800) {
    out += static_cast<char>(0xC0 | (c >> 6));
    out += static_cast<char>(0x80 | (c & 0x3F));
  } else if (c < 0x10000) {
    out += static_cast<char>(0xE0 | (c >> 12));
    out += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (c & 0x3F));
  } else {
    out += static_cast<char>(0xF0 | (c >> 18));
    out += static_cast<char>(0x80 | ((c >> 12) & 0x3F));
    out += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (c & 0x3F));
  }
}

// The five entities XML predefines, and character references (&#N;, &#xH;) as UTF-8; any other '&' stays.
// False for a character reference that is not a character.
bool expandReferences(const std::string& s, std::string& out) {
  static const std::pair<const char*, char> entities[] = {
      {"&amp;", '&'}, {"&lt;", '<'}, {"&gt;", '>'}, {"&quot;", '"'}, {"&apos;", '\''}};
  out.clear();
  for (std::size_t i = 0; i < s.size();) {
    if (s[i] != '&') {
      out += s[i++];
      continue;
    }
    if (s.compare(i, 2, "&#") == 0) {
      const std::size_t semi = s.find(';', i);
      const bool hex = i + 2 < s.size() && s[i + 2] == 'x';
      const std::size_t from = i + (hex ? 3 : 2);
      if (semi == std::string::npos || from >= semi) return false;
      std::uint32_t c = 0;
      for (std::size_t k = from; k < semi; ++k) {
        const int d = hex ? hexDigit(s[k]) : (s[k] >= '0' && s[k] <= '9' ? s[k] - '0' : -1);
        if (d < 0) return false;
        c = c * (hex ? 16u : 10u) + static_cast<std::uint32_t>(d);
        if (c > 0x10FFFF) return false;
      }
      if (c == 0 || (c >= 0xD800 && c <= 0xDFFF)) return false;
      appendUtf8(c, out);
      i = semi + 1;
      continue;
    }
    bool matched = false;
    for (const auto& [name, c] : entities) {
      const std::size_t n = std::char_traits<char>::length(name);
      if (s.compare(i, n, name) == 0) {
        out += c;
        i += n;
        matched = true;
        break;
      }
    }
    if (!matched) out += s[i++];
  }
  return true;
}

// `name` written for TinyXML with the five named entities alone.
std::string escapedForXml(const std::string& name) {
  std::string out;
  for (char c : name) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

// Whether attribute a of outline[i] names a link: a top-level <link>'s name, or the link of a top-level
// <joint>'s <parent> or <child>.
bool namesALink(const std::vector<XmlElement>& outline, std::size_t i, std::size_t a) {
  const XmlElement& e = outline[i];
  const std::string& key = e.attributes[a].first;
  if (e.parent < 0) return false;
  const XmlElement& up = outline[static_cast<std::size_t>(e.parent)];
  if (e.name == "link") return key == "name" && e.parent == 0;
  return (e.name == "parent" || e.name == "child") && key == "link" && up.name == "joint" && up.parent == 0;
}

// A vector of exactly `count` numbers (or, with allowOne, one number repeated), as urdfdom reads vectors but
// with any white space between and around them.
bool parseNumbers(const std::string& text, int count, bool allowOne, Eigen::Vector3d& out) {
  try {
    urdf::Vector3 v;
    const std::string s = normalised(text);
    int pieces = s.empty() ? 0 : 1;
    for (char c : s) pieces += c == ' ' ? 1 : 0;
    if (allowOne && pieces == 1) {
      const double x = urdf::strToDouble(s.c_str());
      out = Eigen::Vector3d(x, x, x);
      return std::isfinite(x);
    }
    if (pieces != count) return false;
    v.init(s);
    out = Eigen::Vector3d(v.x, v.y, v.z);
    return out.allFinite();
  } catch (const std::exception&) {
    return false;
  }
}

Eigen::Isometry3d readOrigin(const XmlElement* origin, bool& ok) {
  ok = true;
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  if (!origin) return t;
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero(), rpy = Eigen::Vector3d::Zero();
  if (const std::string* a = origin->attribute("xyz")) ok = ok && parseNumbers(*a, 3, false, xyz);
  if (const std::string* a = origin->attribute("rpy")) ok = ok && parseNumbers(*a, 3, false, rpy);
  if (!ok) return t;
  // urdfdom's own rule (roll about x, then pitch about y, then yaw about z, fixed axes), so a collision
  // origin comes out bit for bit as urdfdom would have given it.
  urdf::Rotation r;
  r.setFromRPY(rpy.x(), rpy.y(), rpy.z());
  Eigen::Quaterniond q(r.w, r.x, r.y, r.z);
  if (q.norm() > 0.0) q.normalize();
  t.linear() = q.toRotationMatrix();
  t.translation() = xyz;
  return t;
}

class GeometryReader {
 public:
  GeometryReader(const std::vector<XmlElement>& outline, const UrdfLoadOptions& options,
                 std::vector<std::string>& warnings)
      : outline_(outline), options_(options), warnings_(warnings), children_(outline.size()) {
    for (std::size_t i = 1; i < outline.size(); ++i) {
      if (outline[i].parent >= 0) children_[static_cast<std::size_t>(outline[i].parent)].push_back(i);
    }
  }

  Status run(std::unordered_map<std::string, LinkGeometry>& links) {
    links.clear();
    if (outline_.empty() || outline_[0].name != "robot") return Status::success();
    for (std::size_t i : children_[0]) {
      if (outline_[i].name != "link") continue;
      const std::string* name = outline_[i].attribute("name");
      if (!name) continue;  // urdfdom reports a link without a name
      if (!urdfdomName(*name, link_)) link_ = *name;
      LinkGeometry& g = links[link_];
      int ordinal = 0;
      for (std::size_t c : children_[i]) {
        if (outline_[c].name == "inertial") readMass(c, g);
        if (outline_[c].name == "collision") readCollision(c, ordinal++, g);
        if (!fatal_.ok()) return fatal_;
      }
    }
    return Status::success();
  }

 private:
  const XmlElement* child(std::size_t of, const char* name) const {
    for (std::size_t k : children_[of])
      if (outline_[k].name == name) return &outline_[k];
    return nullptr;
  }
  std::size_t childIndex(std::size_t of, const char* name) const {
    for (std::size_t k : children_[of])
      if (outline_[k].name == name) return k;
    return 0;
  }

  void warn(const std::string& element, const std::string& why) {
    warnings_.push_back("link '" + link_ + "': collision element '" + element + "' " + why + "; skipped");
  }

  void readMass(std::size_t inertial, LinkGeometry& g) {
    const XmlElement* mass = child(inertial, "mass");
    const std::string* value = mass ? mass->attribute("value") : nullptr;
    if (!value) return;
    double m = 0.0;
    if (parseUrdfNumber(*value, m) && m >= 0.0) {
      g.mass = m;
    } else {
      warnings_.push_back("link '" + link_ + "': <mass value=\"" + *value +
                          "\"> is not a non-negative number; the mass is taken as 0");
    }
  }

  void readCollision(std::size_t c, int ordinal, LinkGeometry& g) {
    const std::string* given = outline_[c].attribute("name");
    const std::string label = given ? *given : link_ + "#" + std::to_string(ordinal);
    bool originOk = true;
    ShapeDesc shape;
    shape.name = label;
    shape.origin = readOrigin(child(c, "origin"), originOk);
    if (!originOk) return warn(label, "has an <origin> whose xyz or rpy is not three finite numbers");
    const std::size_t geometry = childIndex(c, "geometry");
    if (geometry == 0 || children_[geometry].empty()) return warn(label, "has no geometry");
    const XmlElement& e = outline_[children_[geometry].front()];
    const auto number = [&](const char* key, double& v) {
      const std::string* a = e.attribute(key);
      return a && parseUrdfNumber(*a, v) && v > 0.0;
    };
    const char* bad = "has a size that is not a positive finite number";
    if (e.name == "sphere") {
      shape.type = ShapeType::Sphere;
      if (!number("radius", shape.radius)) return warn(label, std::string("(a sphere) ") + bad);
    } else if (e.name == "box") {
      shape.type = ShapeType::Box;
      const std::string* size = e.attribute("size");
      Eigen::Vector3d d;
      if (!size || !parseNumbers(*size, 3, false, d) || !(d.array() > 0.0).all())
        return warn(label, std::string("(a box) ") + bad);
      shape.halfExtents = 0.5 * d;
    } else if (e.name == "cylinder" || e.name == "capsule") {
      shape.type = e.name == "cylinder" ? ShapeType::Cylinder : ShapeType::Capsule;
      double length = 0.0;
      if (!number("radius", shape.radius) || !number("length", length))
        return warn(label, "(a " + e.name + ") " + bad);
      shape.halfLength = 0.5 * length;
    } else if (e.name == "mesh") {
      if (!readMesh(e, label, shape)) return;
    } else {
      return warn(label,
                  "has a geometry <" + e.name + "> that is not a sphere, box, cylinder, capsule or mesh");
    }
    g.shapes.push_back(std::move(shape));
  }

  bool readMesh(const XmlElement& e, const std::string& label, ShapeDesc& shape) {
    const std::string* file = e.attribute("filename");
    if (!file || trim(*file).empty()) {
      warn(label, "is a mesh without a filename");
      return false;
    }
    // Read as TinyXML reads attribute values (entities and character references); a reference that is no
    // character stays as written, and the file is then not found.
    std::string uri;
    if (!expandReferences(trim(*file), uri)) uri = trim(*file);
    Eigen::Vector3d scale = Eigen::Vector3d::Ones();
    if (const std::string* s = e.attribute("scale")) {
      if (!parseNumbers(*s, 3, true, scale) || !(scale.array() > 0.0).all()) {
        warn(label, "is a mesh ('" + uri + "') whose scale \"" + *s + "\" is not 1 or 3 positive numbers");
        return false;
      }
    }
    if (!options_.loadMeshes) {
      warn(label, "is a mesh ('" + uri + "'), and mesh loading is off");
      return false;
    }
    std::string path;
    Status s = resolveMeshUri(uri, options_.baseDir, options_.packagePaths, path);
    MeshHullResult loaded;
    const std::size_t limit = options_.limits.maxMeshTriangles;
    if (s.ok()) {
      MeshHullOptions hullOptions;
      hullOptions.maxVertices = options_.maxHullVertices;
      // The whole model's budget is the most one mesh may have (the file is not counted past it).
      hullOptions.maxTriangles = static_cast<int>(std::min<std::size_t>(limit, INT_MAX));
      loaded = loadMeshHull(path, scale, hullOptions);
      s = loaded.status;
    }
    const std::string where = "link '" + link_ + "', collision element '" + label + "', mesh '" + uri + "'";
    const std::string limitIs =
        "; the limit is " + std::to_string(limit) + " (UrdfLimits::maxMeshTriangles, all meshes together)";
    if (loaded.overTriangleLimit) {
      fatal_ = Status::error(ErrorCode::InvalidModel, "URDF mesh at " + where + " alone has more than " +
                                                          std::to_string(limit) + " triangles" + limitIs);
      return false;
    }
    if (s.ok() && loaded.hull) {
      triangles_ += static_cast<std::size_t>(loaded.hull->meshTriangles);
      if (triangles_ > limit) {
        fatal_ = Status::error(ErrorCode::InvalidModel,
                               "URDF meshes have at least " + std::to_string(triangles_) +
                                   " triangles (the limit passed at " + where + ")" + limitIs);
        return false;
      }
    }
    if (!s.ok() || !loaded.hull) {
      warn(label, "is a mesh ('" + uri + "') that cannot be used: " + s.message());
      return false;
    }
    shape.type = ShapeType::ConvexHull;
    shape.hull = loaded.hull->vertices;
    shape.hullPlanes = loaded.hull->planes;
    shape.radius = loaded.hull->radius;
    shape.meshFile = path;
    return true;
  }

  const std::vector<XmlElement>& outline_;
  const UrdfLoadOptions& options_;
  std::vector<std::string>& warnings_;
  std::vector<std::vector<std::size_t>> children_;
  std::string link_;
  std::size_t triangles_ = 0;  ///< of the meshes read so far, each element counting its file's
  Status fatal_;               ///< a limit passed: the reading stops
};

// The name of the link or joint an element belongs to, for messages.
std::string ownerOf(const std::vector<XmlElement>& outline, std::size_t i) {
  for (int k = static_cast<int>(i); k >= 0; k = outline[static_cast<std::size_t>(k)].parent) {
    const XmlElement& e = outline[static_cast<std::size_t>(k)];
    if (e.name == "link" || e.name == "joint") {
      const std::string* name = e.attribute("name");
      return e.name + " '" + (name ? *name : std::string("?")) + "'";
    }
  }
  return "the robot";
}

}  // namespace

bool parseUrdfNumber(const std::string& text, double& value) {
  try {
    const std::string s = trim(text);
    if (s.empty()) return false;
    value = urdf::strToDouble(s.c_str());
    return std::isfinite(value);
  } catch (const std::exception&) {
    return false;
  }
}

Status readLinkGeometry(const std::vector<XmlElement>& outline, const UrdfLoadOptions& options,
                        std::vector<std::string>& warnings,
                        std::unordered_map<std::string, LinkGeometry>& links) {
  return GeometryReader(outline, options, warnings).run(links);
}

bool urdfdomName(const std::string& raw, std::string& name) {
  return expandReferences(tidied(raw), name);
}

std::vector<std::string> sphericalJointNames(const std::vector<XmlElement>& outline) {
  std::vector<std::string> out;
  for (const XmlElement& e : outline) {
    if (e.name != "joint" || e.parent != 0) continue;
    const std::string* type = e.attribute("type");
    const std::string* name = e.attribute("name");
    std::string read;
    if (type && name && normalised(*type) == "spherical" && urdfdomName(*name, read)) out.push_back(read);
  }
  return out;
}

std::string textForUrdfdom(const std::string& text, const std::vector<XmlElement>& outline,
                           std::vector<std::string>& warnings) {
  std::string out;
  std::size_t copied = 0, changed = 0;
  std::string first, spherical;
  std::size_t skipUntil = 0;  // the end of the element being left out
  for (std::size_t i = 0; i < outline.size(); ++i) {
    const XmlElement& e = outline[i];
    if (e.begin < skipUntil) continue;  // inside a left-out element
    const int parent = e.parent;
    if (parent >= 0 && outline[static_cast<std::size_t>(parent)].name == "link" &&
        outline[static_cast<std::size_t>(parent)].parent == 0 &&
        (e.name == "collision" || e.name == "visual" || e.name == "inertial") && e.end > e.begin) {
      out.append(text, copied, e.begin - copied);
      copied = skipUntil = e.end;
      continue;
    }
    for (std::size_t a = 0; a < e.attributes.size() && a < e.valueOffsets.size(); ++a) {
      const std::string& value = e.attributes[a].second;
      std::string clean;
      if (e.name == "joint" && parent == 0 && e.attributes[a].first == "type" &&
          normalised(value) == "spherical") {
        const std::string* name = e.attribute("name");
        spherical += (spherical.empty() ? "'" : ", '") + (name ? *name : std::string("?")) + "'";
        clean = "floating";
      } else {
        // Runs of spaces between a vector's numbers are fine for urdfdom; white space around a value, or tabs
        // and line breaks inside one, are not. A link name with a reference in it is written as we read it,
        // so that urdfdom's links are joined exactly as our check of the joint graph saw them.
        const bool spaced = untidy(value);
        std::string name;
        const bool named =
            value.find('&') != std::string::npos && namesALink(outline, i, a) && urdfdomName(value, name);
        if (!spaced && !named) continue;
        clean = named ? escapedForXml(name) : normalised(value);
        if (spaced && changed++ == 0) {
          first =
              "<" + e.name + " " + e.attributes[a].first + "=\"" + value + "\"> of " + ownerOf(outline, i);
        }
      }
      out.append(text, copied, e.valueOffsets[a] - copied);
      out += clean;
      copied = e.valueOffsets[a] + value.size();
    }
  }
  out.append(text, copied, std::string::npos);
  if (changed > 0) {
    warnings.push_back(std::to_string(changed) +
                       " attribute value(s) had extra white space, read without it (as Bullet's importer "
                       "does); the first: " +
                       first);
  }
  if (!spherical.empty()) {
    warnings.push_back(
        "spherical joint(s) " + spherical +
        " are ball joints: the gait holds them at their origin, a motion clip or Character::setMotion turns "
        "them (Skeleton::setJointRotation)");
  }
  return out;
}

}  // namespace cape::character
