// Loading a URDF with urdfdom into the plain data of Urdf.h, with every failure turned into a Status.
#include "cape/character/Urdf.h"

#include "cape/character/Grounding.h"
#include "cape/character/JointMapping.h"
#include "cape/character/Skeleton.h"

#include "UrdfGeometry.h"
#include "XmlOutline.h"

#include <console_bridge/console.h>
#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

namespace cape::character {

const char* toString(ErrorCode code) {
  switch (code) {
    case ErrorCode::Ok:
      return "ok";
    case ErrorCode::FileNotFound:
      return "file not found";
    case ErrorCode::MalformedXml:
      return "malformed XML";
    case ErrorCode::InvalidModel:
      return "invalid URDF model";
    case ErrorCode::MissingLink:
      return "missing link";
    case ErrorCode::NotATree:
      return "links do not form a tree";
    case ErrorCode::UnknownJoint:
      return "unknown joint";
    case ErrorCode::UnknownLink:
      return "unknown link";
    case ErrorCode::OutsideLimits:
      return "outside joint limits";
    case ErrorCode::NotMovable:
      return "joint not movable";
    case ErrorCode::InvalidArgument:
      return "invalid argument";
  }
  return "unknown error";
}

const char* toString(ShapeType type) {
  switch (type) {
    case ShapeType::Sphere:
      return "sphere";
    case ShapeType::Box:
      return "box";
    case ShapeType::Cylinder:
      return "cylinder";
    case ShapeType::Capsule:
      return "capsule";
    case ShapeType::ConvexHull:
      return "convex hull";
  }
  return "unknown";
}

const char* toString(JointType type) {
  switch (type) {
    case JointType::Fixed:
      return "fixed";
    case JointType::Revolute:
      return "revolute";
    case JointType::Continuous:
      return "continuous";
    case JointType::Prismatic:
      return "prismatic";
    case JointType::Floating:
      return "floating";
    case JointType::Planar:
      return "planar";
    case JointType::Spherical:
      return "spherical";
  }
  return "unknown";
}

namespace {

// Collects what urdfdom prints through console_bridge while one parse runs. console_bridge's handler is
// process-wide, so parses are serialised by a mutex; the handler in use before is restored afterwards.
class CapturedConsole : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char* /*filename*/,
           int /*line*/) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) {
      errors.push_back(text);
    } else if (level >= console_bridge::CONSOLE_BRIDGE_LOG_WARN) {
      warnings.push_back(text);
    }
  }
  std::vector<std::string> errors;
  std::vector<std::string> warnings;
};

std::mutex& parseMutex() {
  static std::mutex m;
  return m;
}

Eigen::Isometry3d toIsometry(const urdf::Pose& p) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  Eigen::Quaterniond q(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z);
  if (q.norm() > 0.0) q.normalize();
  t.linear() = q.toRotationMatrix();
  t.translation() = Eigen::Vector3d(p.position.x, p.position.y, p.position.z);
  return t;
}

std::string joinLines(const std::vector<std::string>& lines) {
  std::string out;
  for (const std::string& l : lines) {
    if (!out.empty()) out += "; ";
    out += l;
  }
  return out;
}

bool contains(const std::string& text, const char* part) {
  return text.find(part) != std::string::npos;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

std::string limitError(const std::string& what, std::size_t count, std::size_t limit, const char* field) {
  return "URDF has " + std::to_string(count) + " " + what + "; the limit is " + std::to_string(limit) +
         " (UrdfLimits::" + field + ")";
}

Status checkLimits(const UrdfLimits& limits) {
  const std::pair<std::size_t, const char*> fields[] = {{limits.maxFileBytes, "maxFileBytes"},
                                                        {limits.maxXmlElements, "maxXmlElements"},
                                                        {limits.maxXmlDepth, "maxXmlDepth"},
                                                        {limits.maxLinks, "maxLinks"},
                                                        {limits.maxJoints, "maxJoints"},
                                                        {limits.maxCollisionElements, "maxCollisionElements"},
                                                        {limits.maxMeshTriangles, "maxMeshTriangles"}};
  for (const auto& [value, field] : fields) {
    if (value < 1)
      return Status::error(ErrorCode::InvalidArgument, std::string("UrdfLimits::") + field + " is 0");
  }
  if (!(std::isfinite(limits.maxLength) && limits.maxLength > 0.0))
    return Status::error(ErrorCode::InvalidArgument, "UrdfLimits::maxLength must be finite and > 0 (m)");
  if (limits.maxXmlDepth > kMaxXmlDepthCeiling) {
    return Status::error(ErrorCode::InvalidArgument, "UrdfLimits::maxXmlDepth is " +
                                                         std::to_string(limits.maxXmlDepth) + "; at most " +
                                                         std::to_string(kMaxXmlDepthCeiling) +
                                                         " (urdfdom's parser recurses once per level)");
  }
  return Status::success();
}

// Every length of the built model within UrdfLimits::maxLength (joint and shape offsets, sizes, hull
// vertices): a number urdfdom and our reader accept as finite may still be far beyond any robot.
Status checkLengths(const UrdfModel& model, double maxLength) {
  char limit[64];
  std::snprintf(limit, sizeof limit, "; the limit is %g m (UrdfLimits::maxLength)", maxLength);
  const auto far = [&](const Eigen::Vector3d& v) { return !(v.cwiseAbs().maxCoeff() <= maxLength); };
  const auto big = [&](double v) { return !(std::abs(v) <= maxLength); };
  for (const JointDesc& j : model.joints())
    if (far(j.origin.translation()))
      return Status::error(ErrorCode::InvalidModel, "joint '" + j.name + "' has an origin offset beyond " +
                                                        "the length limit" + limit);
  for (const LinkDesc& l : model.links())
    for (const ShapeDesc& shape : l.shapes) {
      bool beyond = far(shape.origin.translation()) || big(shape.radius) || big(shape.halfLength) ||
                    far(shape.halfExtents);
      for (const Eigen::Vector3d& v : shape.hull) beyond = beyond || far(v);
      if (beyond)
        return Status::error(ErrorCode::InvalidModel, "link '" + l.name + "': collision element '" +
                                                          shape.name + "' has a length beyond the limit" +
                                                          limit);
    }
  return Status::success();
}

// The links, joints and collision elements urdfdom and we read (the <robot>'s own <link> and <joint>
// elements, the links' own <collision> elements), counted against their limits before anything is built.
Status checkCounts(const std::vector<XmlElement>& outline, const UrdfLimits& limits) {
  if (outline.empty() || outline[0].name != "robot") return Status::success();
  std::size_t links = 0, joints = 0, collisions = 0;
  for (std::size_t i = 1; i < outline.size(); ++i) {
    const int parent = outline[i].parent;
    if (parent == 0) {
      links += outline[i].name == "link" ? 1 : 0;
      joints += outline[i].name == "joint" ? 1 : 0;
    } else if (parent > 0 && outline[i].name == "collision") {
      const XmlElement& up = outline[static_cast<std::size_t>(parent)];
      collisions += up.name == "link" && up.parent == 0 ? 1 : 0;
    }
  }
  if (links > limits.maxLinks)
    return Status::error(ErrorCode::InvalidModel, limitError("links", links, limits.maxLinks, "maxLinks"));
  if (joints > limits.maxJoints)
    return Status::error(ErrorCode::InvalidModel,
                         limitError("joints", joints, limits.maxJoints, "maxJoints"));
  if (collisions > limits.maxCollisionElements) {
    return Status::error(
        ErrorCode::InvalidModel,
        limitError("collision elements", collisions, limits.maxCollisionElements, "maxCollisionElements"));
  }
  return Status::success();
}

// "a -> b -> c -> a" for the cycle through links[0..n), the first 8 and the last 2 when it is longer.
std::string cyclePath(const std::vector<const std::string*>& links) {
  constexpr std::size_t kHead = 8, kTail = 2;
  std::string path;
  for (std::size_t k = 0; k < links.size(); ++k) {
    if (links.size() > kHead + kTail && k == kHead) {
      path += " -> ... (" + std::to_string(links.size() - kHead - kTail) + " more)";
      k = links.size() - kTail;
    }
    path += (k == 0 ? "" : " -> ") + *links[k];
  }
  return path + " -> " + *links[0];
}

// urdfdom links own their children through shared pointers: fed a cycle (a link its own parent included),
// the links own each other and are never freed (LeakSanitizer says so), whether urdfdom then rejects the
// model or not. So the joint graph urdfdom would build is checked here first, on the XML outline: every
// joint of the <robot> names exactly one parent and one child link, each link is the child of at most one
// joint, and no loop of parents. Link names are compared as urdfdom reads them (urdfdomName, and
// textForUrdfdom writes them so). Linear in the outline: every link is walked up from at most once.
Status checkJointGraph(const std::vector<XmlElement>& outline) {
  if (outline.empty() || outline[0].name != "robot")
    return Status::success();                // urdfdom will say what is wrong
  std::unordered_map<std::string, int> ids;  // link name -> index into the vectors below
  std::vector<const std::string*> names;     // per link: its name (the key in ids)
  std::vector<int> parentOf;                 // per link: its parent link, -1 for none
  std::vector<std::string> jointOf;          // per link: the joint whose child it is
  const auto idOf = [&](const std::string& name) {
    const auto [it, added] = ids.emplace(name, static_cast<int>(names.size()));
    if (added) {
      names.push_back(&it->first);
      parentOf.push_back(-1);
      jointOf.emplace_back();
    }
    return it->second;
  };
  for (std::size_t i = 1; i < outline.size(); ++i) {
    if (outline[i].name != "joint" || outline[i].parent != 0) continue;
    const std::string* given = outline[i].attribute("name");
    const std::string joint = given ? *given : std::string("?");
    const XmlElement* ends[2] = {nullptr, nullptr};  // its <parent>, its <child>
    const char* tags[2] = {"parent", "child"};
    for (std::size_t k = i + 1; k < outline.size() && outline[k].parent >= static_cast<int>(i); ++k) {
      if (outline[k].parent != static_cast<int>(i)) continue;
      for (int e = 0; e < 2; ++e) {
        if (outline[k].name != tags[e]) continue;
        if (ends[e]) {
          return Status::error(ErrorCode::InvalidModel, "joint '" + joint + "' has more than one <" +
                                                            tags[e] + "> element; a joint has one parent " +
                                                            "and one child link");
        }
        ends[e] = &outline[k];
      }
    }
    std::string link[2];
    for (int e = 0; e < 2; ++e) {
      if (!ends[e]) {
        return Status::error(ErrorCode::InvalidModel, "joint '" + joint + "' has no <" + tags[e] +
                                                          "> element; a joint has one " +
                                                          "parent and one child link");
      }
      const std::string* raw = ends[e]->attribute("link");
      if (!raw || !urdfdomName(*raw, link[e]) || link[e].empty()) {
        return Status::error(ErrorCode::InvalidModel, "joint '" + joint + "': its <" + tags[e] +
                                                          "> element names no link" +
                                                          (raw ? " (link=\"" + *raw + "\")" : std::string()));
      }
    }
    const int parent = idOf(link[0]), child = idOf(link[1]);
    if (parentOf[static_cast<std::size_t>(child)] >= 0) {
      return Status::error(ErrorCode::NotATree, "link '" + link[1] + "' is the child of two joints, '" +
                                                    jointOf[static_cast<std::size_t>(child)] + "' and '" +
                                                    joint + "'");
    }
    parentOf[static_cast<std::size_t>(child)] = parent;
    jointOf[static_cast<std::size_t>(child)] = joint;
  }
  // Each link has at most one parent, so walking up from a link ends at a root, at a link already known to
  // lead to one, or back on the walk itself: a cycle. Colours: 0 not seen, 1 on this walk, 2 leads to a root.
  std::vector<char> colour(names.size(), 0);
  std::vector<int> walk;
  for (std::size_t start = 0; start < names.size(); ++start) {
    walk.clear();
    int at = static_cast<int>(start);
    while (at >= 0 && colour[static_cast<std::size_t>(at)] == 0) {
      colour[static_cast<std::size_t>(at)] = 1;
      walk.push_back(at);
      at = parentOf[static_cast<std::size_t>(at)];
    }
    if (at >= 0 && colour[static_cast<std::size_t>(at)] == 1) {
      std::vector<const std::string*> cycle;
      for (auto k = std::find(walk.begin(), walk.end(), at); k != walk.end(); ++k)
        cycle.push_back(names[static_cast<std::size_t>(*k)]);
      return Status::error(ErrorCode::NotATree, "joints form a cycle of " + std::to_string(cycle.size()) +
                                                    " link(s) (child -> parent): " + cyclePath(cycle));
    }
    for (int k : walk) colour[static_cast<std::size_t>(k)] = 2;
  }
  return Status::success();
}

// Breaks urdfdom's parent-to-child ownership so that the parsed model is freed even if it holds a loop.
void release(urdf::ModelInterfaceSharedPtr& model) {
  if (!model) return;
  for (auto& entry : model->links_) {
    if (!entry.second) continue;
    entry.second->child_links.clear();
    entry.second->child_joints.clear();
  }
  model.reset();
}

}  // namespace

// Builds a UrdfModel from urdfdom's model; a friend of UrdfModel.
struct UrdfModelBuilder {
  static Status build(const urdf::ModelInterface& in, std::vector<std::string> warnings,
                      std::unordered_map<std::string, LinkGeometry>& geometry,
                      std::shared_ptr<UrdfModel>& out) {
    auto model = std::make_shared<UrdfModel>();
    model->name_ = in.name_;
    model->warnings_ = std::move(warnings);
    urdf::LinkConstSharedPtr root = in.getRoot();
    if (!root) return Status::error(ErrorCode::NotATree, "URDF '" + in.name_ + "' has no root link");

    // Breadth-first from the root: parents come before children. urdfdom gives each link one parent, so a
    // cycle (or a second tree) shows up as links never reached from the root.
    std::vector<urdf::LinkConstSharedPtr> order{root};
    model->linkIndex_[root->name] = 0;
    for (std::size_t k = 0; k < order.size(); ++k) {
      for (const urdf::LinkSharedPtr& child : order[k]->child_links) {
        if (!child || model->linkIndex_.count(child->name) != 0) continue;
        model->linkIndex_[child->name] = static_cast<int>(order.size());
        order.push_back(child);
      }
    }
    if (order.size() != in.links_.size()) {
      std::string missing;
      for (const auto& [name, link] : in.links_) {
        if (model->linkIndex_.count(name) == 0) missing += (missing.empty() ? "" : ", ") + name;
      }
      return Status::error(ErrorCode::NotATree, "URDF '" + in.name_ + "': links not connected to the root '" +
                                                    root->name + "' (a cycle or a second tree): " + missing);
    }

    model->links_.resize(order.size());
    for (std::size_t k = 0; k < order.size(); ++k) {
      const urdf::Link& src = *order[k];
      LinkDesc& link = model->links_[k];
      link.name = src.name;
      // Shapes and mass as we read them from the XML (UrdfGeometry.h), not urdfdom's.
      const auto g = geometry.find(src.name);
      if (g != geometry.end()) {
        link.mass = g->second.mass;
        link.shapes = std::move(g->second.shapes);
      }
    }

    for (std::size_t k = 1; k < order.size(); ++k) {
      const urdf::JointSharedPtr& src = order[k]->parent_joint;
      if (!src)
        return Status::error(ErrorCode::NotATree, "link '" + order[k]->name + "' has no parent joint");
      JointDesc joint;
      joint.name = src->name;
      Status s = readJoint(*src, joint);
      if (!s.ok()) return s;
      if (src->mimic) {
        model->warnings_.push_back("joint '" + src->name + "' mimics '" + src->mimic->joint_name +
                                   "': mimic is not followed, the joint moves only when set");
      }
      joint.parentLink = model->linkIndex_.at(src->parent_link_name);
      joint.childLink = static_cast<int>(k);
      const int index = static_cast<int>(model->joints_.size());
      model->jointIndex_[joint.name] = index;
      model->links_[k].parentJoint = index;
      model->links_[k].parentLink = joint.parentLink;
      model->links_[joint.parentLink].childJoints.push_back(index);
      model->joints_.push_back(std::move(joint));
    }
    out = std::move(model);
    return Status::success();
  }

  // urdfdom read the spherical joints as floating (textForUrdfdom): they are ball joints.
  static void markSpherical(UrdfModel& model, const std::vector<std::string>& names) {
    for (const std::string& name : names) {
      const auto j = model.jointIndex_.find(name);
      if (j == model.jointIndex_.end()) continue;
      JointDesc& joint = model.joints_[static_cast<std::size_t>(j->second)];
      if (joint.type == JointType::Floating) joint.type = JointType::Spherical;
    }
  }

  // A model that stands along its y axis turned onto z (REP 103), by turning what hangs below the root link
  // (its shapes and its child joints' origins) +90 degrees about x: y -> z, z -> -y, x stays forward.
  static void turnOntoZ(UrdfModel& model) {
    const Eigen::Isometry3d turn(Eigen::AngleAxisd(0.5 * 3.14159265358979323846, Eigen::Vector3d::UnitX()));
    for (ShapeDesc& shape : model.links_[0].shapes) shape.origin = turn * shape.origin;
    for (int j : model.links_[0].childJoints) {
      JointDesc& joint = model.joints_[static_cast<std::size_t>(j)];
      joint.origin = turn * joint.origin;
    }
    model.turnedOntoZ_ = true;
  }

  // How many of the legs' joints (hips, knees, ankles) the joint mapping finds by structure alone.
  static int legJointsByStructure(const UrdfModel& model) {
    const JointMapping m = JointMapping::byStructure(std::make_shared<const UrdfModel>(model));
    int found = 0;
    for (GaitRole role : {GaitRole::LeftHip, GaitRole::RightHip, GaitRole::LeftKnee, GaitRole::RightKnee,
                          GaitRole::LeftAnkle, GaitRole::RightAnkle})
      found += m[role].joint >= 0 ? 1 : 0;
    return found;
  }

  static void standUp(UrdfModel& model, UrdfLoadOptions::Up up) {
    if (up == UrdfLoadOptions::Up::Z) return;
    if (up == UrdfLoadOptions::Up::Y) return turnOntoZ(model);
    // Auto: a model more than twice as long along y as along z in its zero pose may stand along y. So may an
    // upper body in a T-pose; what tells them apart is the legs: turned, a Y-up humanoid's legs go down and
    // the mapping finds their joints by structure. Turned only then, and said.
    const Skeleton probe(std::make_shared<const UrdfModel>(model));
    const Eigen::AlignedBox3d box = skeletonBounds(probe, Skeleton::urdfToWorld().transpose());
    if (box.isEmpty() || !(box.sizes().y() > 2.0 * box.sizes().z())) return;
    UrdfModel turned = model;
    turnOntoZ(turned);
    const int asIs = legJointsByStructure(model), standing = legJointsByStructure(turned);
    char line[300];
    if (standing > asIs) {
      std::snprintf(
          line, sizeof line,
          "the model is %.2f m long along y and %.2f m along z in its zero pose, and its legs go down "
          "along y: read as a Y-up model and turned onto z (UrdfLoadOptions::modelUp, cape_walk "
          "--model-up z keeps it as written)",
          box.sizes().y(), box.sizes().z());
      model = std::move(turned);
    } else {
      std::snprintf(
          line, sizeof line,
          "the model is %.2f m long along y and %.2f m along z in its zero pose: if it stands along "
          "y (a Y-up model), load it with UrdfLoadOptions::modelUp = Y (cape_walk --model-up y)",
          box.sizes().y(), box.sizes().z());
    }
    model.warnings_.push_back(line);
  }

  static Status readJoint(const urdf::Joint& src, JointDesc& joint) {
    switch (src.type) {
      case urdf::Joint::REVOLUTE:
        joint.type = JointType::Revolute;
        break;
      case urdf::Joint::CONTINUOUS:
        joint.type = JointType::Continuous;
        break;
      case urdf::Joint::PRISMATIC:
        joint.type = JointType::Prismatic;
        break;
      case urdf::Joint::FLOATING:
        joint.type = JointType::Floating;
        break;
      case urdf::Joint::PLANAR:
        joint.type = JointType::Planar;
        break;
      case urdf::Joint::FIXED:
        joint.type = JointType::Fixed;
        break;
      default:
        return Status::error(ErrorCode::InvalidModel, "joint '" + src.name + "' has an unknown type");
    }
    joint.origin = toIsometry(src.parent_to_joint_origin_transform);
    const Eigen::Vector3d axis(src.axis.x, src.axis.y, src.axis.z);
    if (joint.isMovable()) {
      // Scaled by its largest component first: the square of a component beyond 1e154 overflows the
      // norm to inf, and the axis "normalised" by it to zero (found by the urdf fuzz target).
      const double largest = axis.cwiseAbs().maxCoeff();
      if (!std::isfinite(largest) || !((axis / std::max(largest, 1e-300)).norm() * largest >= 1e-9)) {
        return Status::error(ErrorCode::InvalidModel,
                             "joint '" + src.name + "' has a zero or not finite axis");
      }
      joint.axis = std::isfinite(axis.norm()) ? axis.normalized() : (axis / largest).normalized();
    }
    if (src.limits) {
      joint.maxVelocity = src.limits->velocity;
      if (joint.type == JointType::Revolute || joint.type == JointType::Prismatic) {
        joint.hasLimits = true;
        joint.lower = src.limits->lower;
        joint.upper = src.limits->upper;
        if (!(joint.lower <= joint.upper)) {
          return Status::error(ErrorCode::InvalidModel, "joint '" + src.name + "' has lower limit " +
                                                            std::to_string(joint.lower) + " above upper " +
                                                            std::to_string(joint.upper));
        }
      }
    }
    return Status::success();
  }
};

UrdfLoadResult UrdfModel::fromString(const std::string& xmlIn, const UrdfLoadOptions& options) {
  UrdfLoadResult result;
  std::vector<std::string>& warnings = result.warnings;
  const auto fail = [&](ErrorCode code, const std::string& message) {
    result.status = Status::error(code, message);
    return result;
  };
  result.status = checkLimits(options.limits);
  if (!result.status.ok()) return result;
  if (xmlIn.size() > options.limits.maxFileBytes) {
    return fail(ErrorCode::InvalidModel,
                limitError("bytes", xmlIn.size(), options.limits.maxFileBytes, "maxFileBytes"));
  }
  // The text ends at its first NUL, as for Bullet's importer (it reads a C string).
  const std::size_t nul = xmlIn.find('\0');
  const std::string xml = nul == std::string::npos ? xmlIn : xmlIn.substr(0, nul);
  if (nul != std::string::npos &&
      xmlIn.find_first_not_of(std::string(" \t\r\n\0", 5), nul) != std::string::npos) {
    warnings.push_back("the text ends at a NUL byte; the " + std::to_string(xmlIn.size() - nul) +
                       " bytes from there on are ignored");
  }
  std::string xmlError;
  std::vector<XmlElement> outline;
  XmlScanLimits scanLimits;
  scanLimits.maxDepth = options.limits.maxXmlDepth;
  scanLimits.maxElements = options.limits.maxXmlElements;
  XmlScanDetails scanned;
  if (!scanXml(xml, xmlError, &outline, scanLimits, &scanned)) {
    if (scanned.tooLarge) return fail(ErrorCode::InvalidModel, "URDF is too large: " + xmlError);
    return fail(ErrorCode::MalformedXml, "URDF is not well-formed XML: " + xmlError);
  }
  result.status = checkCounts(outline, options.limits);
  if (!result.status.ok()) return result;
  result.status = checkJointGraph(outline);
  if (!result.status.ok()) return result;

  UrdfLoadOptions resolved = options;
  if (resolved.baseDir.empty()) resolved.baseDir = ".";
  if (resolved.maxHullVertices < 4) {
    return fail(ErrorCode::InvalidArgument, "maxHullVertices is " + std::to_string(options.maxHullVertices) +
                                                "; a hull needs at least 4");
  }
  std::unordered_map<std::string, LinkGeometry> geometry;
  result.status = readLinkGeometry(outline, resolved, warnings, geometry);
  if (!result.status.ok()) return result;
  // What TinyXML would read differently from the outline is blanked (line breaks kept), so that urdfdom
  // builds the model that was checked: no element hidden in a declaration or a processing instruction.
  std::string seen = xml;
  for (const auto& [begin, end] : scanned.endedEarlierByTinyXml) {
    for (std::size_t k = begin; k < end; ++k)
      if (seen[k] != '\n') seen[k] = ' ';
  }
  const std::string clean = textForUrdfdom(seen, outline, warnings);

  CapturedConsole console;
  urdf::ModelInterfaceSharedPtr parsed;
  bool threw = false;
  std::string thrown;
  {
    std::lock_guard<std::mutex> lock(parseMutex());
    console_bridge::useOutputHandler(&console);
    try {
      parsed = urdf::parseURDF(clean);
    } catch (const std::exception& e) {
      threw = true;
      thrown = e.what();
    } catch (...) {
      threw = true;
      thrown = "unknown exception";
    }
    console_bridge::restorePreviousOutputHandler();
  }
  if (threw) console.errors.push_back("urdfdom threw: " + thrown);

  if (!parsed) {
    const std::string what = joinLines(console.errors.empty() ? console.warnings : console.errors);
    ErrorCode code = ErrorCode::InvalidModel;
    if (contains(what, "not found")) {
      code = ErrorCode::MissingLink;  // "parent link [x] of joint [j] not found" (or child)
    } else if (contains(what, "root link")) {
      code = ErrorCode::NotATree;  // "No root link found" (a cycle) or "Two root links found"
    }
    return fail(code, "URDF rejected by urdfdom: " + (what.empty() ? "no reason given" : what));
  }

  // urdfdom may skip what it cannot read and still return a model: keep its words.
  for (const std::string& e : console.errors) warnings.push_back("urdfdom: " + e);
  for (const std::string& w : console.warnings) warnings.push_back("urdfdom: " + w);

  std::shared_ptr<UrdfModel> model;
  try {
    result.status = UrdfModelBuilder::build(*parsed, warnings, geometry, model);
  } catch (const std::exception& e) {
    result.status =
        Status::error(ErrorCode::InvalidModel, std::string("URDF could not be read: ") + e.what());
  }
  release(parsed);
  if (result.status.ok()) result.status = checkLengths(*model, options.limits.maxLength);
  if (result.status.ok()) {
    UrdfModelBuilder::markSpherical(*model, sphericalJointNames(outline));
    UrdfModelBuilder::standUp(*model, options.modelUp);
    result.model = std::move(model);
    result.warnings = result.model->warnings();
  }
  return result;
}

UrdfLoadResult UrdfModel::fromFile(const std::string& path, const UrdfLoadOptions& options) {
  UrdfLoadResult result;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    result.status =
        Status::error(ErrorCode::FileNotFound, "URDF file '" + path + "' does not exist or is not a file");
    return result;
  }
  result.status = checkLimits(options.limits);
  if (!result.status.ok()) return result;
  // The size is checked before the file is read, and the read stops one byte past the limit (the file may
  // grow meanwhile, or a special file report no size).
  const std::size_t limit = options.limits.maxFileBytes;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (!ec && size > limit) {
    result.status = Status::error(
        ErrorCode::InvalidModel,
        path + ": " + limitError("bytes", static_cast<std::size_t>(size), limit, "maxFileBytes"));
    return result;
  }
  std::ifstream in(path, std::ios::binary);
  std::string text;
  if (in) {
    text.resize(static_cast<std::size_t>(ec ? 0 : size));
    in.read(text.data(), static_cast<std::streamsize>(text.size()));
    text.resize(static_cast<std::size_t>(in.gcount()));
    char chunk[65536];
    while (in && text.size() <= limit) {
      in.read(chunk,
              static_cast<std::streamsize>(std::min<std::size_t>(sizeof chunk, limit + 1 - text.size())));
      text.append(chunk, static_cast<std::size_t>(in.gcount()));
    }
  }
  if (!in && !in.eof()) {
    result.status = Status::error(ErrorCode::FileNotFound, "URDF file '" + path + "' cannot be read");
    return result;
  }
  if (text.size() > limit) {
    result.status =
        Status::error(ErrorCode::InvalidModel, path + ": URDF has more than " + std::to_string(limit) +
                                                   " bytes; the limit is " + std::to_string(limit) +
                                                   " (UrdfLimits::maxFileBytes)");
    return result;
  }
  UrdfLoadOptions withBase = options;
  if (withBase.baseDir.empty()) {
    const std::filesystem::path folder = std::filesystem::path(path).parent_path();
    withBase.baseDir = folder.empty() ? std::string(".") : folder.string();
  }
  result = fromString(text, withBase);
  if (!result.status.ok()) {
    result.status = Status::error(result.status.code(), path + ": " + result.status.message());
  }
  return result;
}

UrdfLoadResult UrdfModel::humanoid() {
  return fromString(humanoidUrdf());
}

int UrdfModel::findLink(const std::string& name) const {
  const auto it = linkIndex_.find(name);
  return it == linkIndex_.end() ? -1 : it->second;
}

int UrdfModel::findJoint(const std::string& name) const {
  const auto it = jointIndex_.find(name);
  return it == jointIndex_.end() ? -1 : it->second;
}

std::vector<std::string> UrdfModel::linksContaining(const std::string& part) const {
  std::vector<std::string> found;
  const std::string p = lower(part);
  for (const LinkDesc& link : links_) {
    if (lower(link.name).find(p) != std::string::npos) found.push_back(link.name);
  }
  return found;
}

}  // namespace cape::character
