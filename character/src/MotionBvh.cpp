// BVH motion capture: the text read into a skeleton and rows of channels, and retargeted onto a URDF
// humanoid (MotionFormats.h; the rules are in character/README.md, "BVH motion capture").
//
// The retarget works in one common frame, the URDF's (z up, x forward, y left). A, the rotation taking the
// BVH's axes into it, sends the BVH's up axis to z and its facing (from the rest pose's hips) to x. A BVH
// joint's world rotation G(t) (its rest pose has every rotation at zero, so G_rest = I) becomes
// D(t) = A G(t) A^T in that frame: the bone's turn away from its rest pose. The URDF bone that plays the same
// role is given the world rotation D(t) S W0, where W0 is its zero-pose rotation and S the rest alignment
// (the shortest turn taking the URDF bone's zero-pose direction onto the BVH bone's rest direction), and its
// joints take what of that they can, relative to their parent's already retargeted rotation.
#include "BvhRoles.h"
#include "MotionText.h"
#include "cape/character/MotionFormats.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string_view>
#include <unordered_map>

namespace cape::character {

// --- Roles from names ------------------------------------------------------------------------------------
namespace bvh {

namespace {

constexpr const char* kRoleNames[kRoleCount] = {
    "hips",       "spine",       "neck",          "left_hip",       "right_hip",  "left_knee",  "right_knee",
    "left_ankle", "right_ankle", "left_shoulder", "right_shoulder", "left_elbow", "right_elbow"};

std::string lowerCase(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

bool startsWith(std::string_view s, std::string_view prefix) {
  return s.size() >= prefix.size() && s.substr(0, prefix.size()) == prefix;
}

bool endsWith(std::string_view s, std::string_view suffix) {
  return s.size() >= suffix.size() && s.substr(s.size() - suffix.size()) == suffix;
}

std::string withoutTrailingDigits(std::string s) {
  while (!s.empty() && std::isdigit(static_cast<unsigned char>(s.back()))) s.pop_back();
  return s;
}

// Limb parts: 0 upper leg, 1 lower leg, 2 foot, 3 upper arm, 4 forearm (the role is kLeftHip + 2 part +
// side).
struct LimbWord {
  const char* word;
  int part;
  int rank;
};
constexpr LimbWord kLimbWords[] = {
    {"upleg", 0, 0},    {"upperleg", 0, 0}, {"thigh", 0, 0},   {"femur", 0, 0},    {"hip", 0, 1},
    {"leg", 1, 0},      {"lowerleg", 1, 0}, {"lowleg", 1, 0},  {"knee", 1, 0},     {"shin", 1, 0},
    {"calf", 1, 0},     {"tibia", 1, 0},    {"foot", 2, 0},    {"ankle", 2, 0},    {"arm", 3, 0},
    {"upperarm", 3, 0}, {"uparm", 3, 0},    {"humerus", 3, 0}, {"shoulder", 3, 1}, {"forearm", 4, 0},
    {"lowerarm", 4, 0}, {"lowarm", 4, 0},   {"radius", 4, 0},  {"elbow", 4, 0},    {"ulna", 4, 0}};

const LimbWord* limbWord(const std::string& base) {
  for (const LimbWord& w : kLimbWords)
    if (base == w.word) return &w;
  return nullptr;
}

bool isSeparator(char c) {
  return c == '_' || c == '.' || c == '-' || c == ' ';
}

}  // namespace

const char* roleName(int role) {
  return role >= 0 && role < kRoleCount ? kRoleNames[role] : "none";
}

int roleFromName(const std::string& name) {
  for (int r = 0; r < kRoleCount; ++r)
    if (name == kRoleNames[r]) return r;
  return -1;
}

NameRole roleOfBvhName(const std::string& jointName) {
  std::string_view view = jointName;
  const std::size_t cut = view.find_last_of(":|");
  if (cut != std::string_view::npos) view.remove_prefix(cut + 1);
  std::string low = lowerCase(view);
  for (const char* prefix : {"mixamorig", "bip001", "bip01"}) {
    if (startsWith(low, prefix)) {
      low.erase(0, std::char_traits<char>::length(prefix));
      break;
    }
  }
  while (!low.empty() && isSeparator(low.front())) low.erase(0, 1);
  while (!low.empty() && isSeparator(low.back())) low.pop_back();
  std::string compact;
  for (char c : low)
    if (std::isalnum(static_cast<unsigned char>(c))) compact += c;

  int side = -1;
  const auto sideOf = [](char c) { return c == 'l' ? 0 : 1; };
  if (startsWith(compact, "left") || startsWith(compact, "right")) {
    side = compact[0] == 'l' ? 0 : 1;
    compact.erase(0, side == 0 ? 4 : 5);
  } else if (endsWith(compact, "left") || endsWith(compact, "right")) {
    side = endsWith(compact, "left") ? 0 : 1;
    compact.resize(compact.size() - (side == 0 ? 4 : 5));
  } else if (low.size() > 2 && (low[0] == 'l' || low[0] == 'r') && isSeparator(low[1])) {
    side = sideOf(low[0]);  // L_Hip, l.thigh, "L Thigh"
    compact.erase(0, 1);
  } else if (low.size() > 2 && (low.back() == 'l' || low.back() == 'r') && isSeparator(low[low.size() - 2])) {
    side = sideOf(low.back());  // Hip_L, thigh.l
    compact.pop_back();
  } else if (compact.size() > 1 && (compact[0] == 'l' || compact[0] == 'r')) {
    const std::string rest = withoutTrailingDigits(compact.substr(1));
    if (limbWord(rest) != nullptr || rest == "hipjoint") {  // lfemur, rtibia (CMU ASF), lhipjoint
      side = sideOf(compact[0]);
      compact.erase(0, 1);
    }
  }
  const std::string base = withoutTrailingDigits(compact);
  NameRole out;
  if (side >= 0) {
    if (const LimbWord* w = limbWord(base)) out = {kFirstLimbRole + 2 * w->part + side, w->rank};
    return out;
  }
  if (base == "hips" || base == "hip" || base == "pelvis") return {kHips, 0};
  if (base == "root") return {kHips, 2};
  for (const char* word :
       {"spine", "chest", "upperchest", "lowerback", "upperback", "thorax", "torso", "abdomen", "waist"})
    if (base == word) return {kSpine, 0};
  if (base == "head") return {kNeck, 0};
  if (base == "upperneck") return {kNeck, 1};
  if (base == "neck") return {kNeck, 2};
  if (base == "lowerneck") return {kNeck, 3};
  return out;
}

}  // namespace bvh

namespace {

using bvh::kRoleCount;
constexpr double kPi = 3.14159265358979323846;
constexpr double kRadiansPerDegree = kPi / 180.0;
/// BVH units or degrees: a larger value in a file is broken data (and would overflow the kinematics).
constexpr double kMaxBvhValue = 1e7;

Status lineError(const std::string& file, std::size_t line, const std::string& what) {
  return Status::error(ErrorCode::InvalidArgument, file + ":" + std::to_string(line) + ": " + what);
}

bool equalsIgnoringCase(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(a[i])) != std::tolower(static_cast<unsigned char>(b[i])))
      return false;
  return true;
}

bool isBlank(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v';
}

std::string_view trimmed(std::string_view s) {
  while (!s.empty() && isBlank(s.front())) s.remove_prefix(1);
  while (!s.empty() && isBlank(s.back())) s.remove_suffix(1);
  return s;
}

/// A token for a message: at most 40 characters of it.
std::string quoted(std::string_view token) {
  return "'" + std::string(token.substr(0, 40)) + (token.size() > 40 ? "...'" : "'");
}

// --- Reading the text ------------------------------------------------------------------------------------

/// The text line by line, each split at white space (CR of CRLF included); blank lines are skipped.
class Lines {
 public:
  explicit Lines(std::string_view text) : text_(text) {}
  /// The next line holding anything but white space, and its tokens; false at the end of the text.
  bool next(std::vector<std::string_view>& tokens, std::string_view& line) {
    while (pos_ < text_.size()) {
      std::size_t end = text_.find('\n', pos_);
      if (end == std::string_view::npos) end = text_.size();
      line = text_.substr(pos_, end - pos_);
      pos_ = end + 1;
      ++number_;
      tokens.clear();
      std::size_t i = 0;
      while (i < line.size()) {
        while (i < line.size() && isBlank(line[i])) ++i;
        const std::size_t start = i;
        while (i < line.size() && !isBlank(line[i])) ++i;
        if (i > start) tokens.push_back(line.substr(start, i - start));
      }
      if (!tokens.empty()) return true;
    }
    return false;
  }
  /// 1-based number of the line last returned (the last line once the text has ended).
  std::size_t number() const { return number_; }
  /// Bytes not read yet.
  std::size_t remaining() const { return pos_ < text_.size() ? text_.size() - pos_ : 0; }

 private:
  std::string_view text_;
  std::size_t pos_ = 0;
  std::size_t number_ = 0;
};

enum class NumberRead { Ok, NotANumber, NotFinite };

/// A decimal number, the whole token (a leading '+' allowed), locale-free.
NumberRead readNumber(std::string_view token, double& out) {
  if (!token.empty() && token.front() == '+') {
    token.remove_prefix(1);
    if (!token.empty() && (token.front() == '+' || token.front() == '-')) return NumberRead::NotANumber;
  }
  if (token.empty()) return NumberRead::NotANumber;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), out);
  if (end != token.data() + token.size()) return NumberRead::NotANumber;
  if (ec == std::errc::result_out_of_range) return NumberRead::NotFinite;
  if (ec != std::errc()) return NumberRead::NotANumber;
  return std::isfinite(out) ? NumberRead::Ok : NumberRead::NotFinite;
}

/// A count: decimal digits only.
bool readCount(std::string_view token, unsigned long long& out) {
  if (token.empty() || !std::isdigit(static_cast<unsigned char>(token.front()))) return false;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), out);
  return ec == std::errc() && end == token.data() + token.size();
}

// --- The hierarchy ---------------------------------------------------------------------------------------

/// Channel codes: 'x', 'y', 'z' position (BVH units), 'X', 'Y', 'Z' rotation (degrees).
struct BvhJoint {
  std::string name;
  int parent = -1;
  int depth = 0;
  std::size_t line = 0;
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  ///< units, in the parent's frame
  std::array<char, 6> channels{};
  int channelCount = 0;
  bool channelsGiven = false;
  int firstChannel = 0;  ///< index of its first channel in a row
  std::vector<int> children;
  std::vector<Eigen::Vector3d> endSites;  ///< offsets of its End Sites
};

struct BvhHeader {
  std::vector<BvhJoint> joints;  ///< file order: parents before children, the root first
  int channels = 0;              ///< values per row
  std::size_t frames = 0;
  double frameTime = 0.0;  ///< s
};

/// From HIERARCHY to the ROOT's closing brace, with an explicit stack (no recursion): any nesting a file
/// asks for costs one stack entry, and MotionLimits::maxDepth of them at most.
class HierarchyReader {
 public:
  HierarchyReader(Lines& lines, const MotionLimits& limits, const std::string& file, BvhHeader& out)
      : lines_(lines), limits_(limits), file_(file), out_(out) {}

  Status read() {
    if (!lines_.next(tok_, line_)) return error("the file is empty: no HIERARCHY");
    if (!equalsIgnoringCase(tok_[0], "HIERARCHY") || tok_.size() != 1)
      return error("expected HIERARCHY, found " + quoted(line_));
    bool closed = false;
    while (lines_.next(tok_, line_)) {
      const Status s = step(closed);
      if (!s.ok() || closed) return s;
    }
    if (out_.joints.empty()) return error("the file ends before its ROOT (truncated hierarchy)");
    return error("the file ends inside " + openName() +
                 " (truncated hierarchy: " + std::to_string(stack_.size()) + " '}' missing)");
  }

 private:
  struct Open {
    int joint = -1;  ///< the joint, or the End Site's joint
    bool endSite = false;
    bool hasOffset = false;
    Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  };
  enum class Pending { None, Joint, EndSite };

  Status error(const std::string& what) const { return lineError(file_, lines_.number(), what); }

  std::string openName() const {
    if (stack_.empty()) return "the hierarchy";
    const std::string& joint = out_.joints[static_cast<std::size_t>(stack_.back().joint)].name;
    return stack_.back().endSite ? "the End Site of joint '" + joint + "'" : "joint '" + joint + "'";
  }

  Status step(bool& closed) {
    const std::string_view keyword = tok_[0];
    if (pending_ != Pending::None) {
      if (keyword == "{" && tok_.size() == 1) return open();
      const std::string what =
          pending_ == Pending::EndSite ? std::string("End Site") : "joint '" + out_.joints.back().name + "'";
      return error("expected '{' after " + what + ", found " + quoted(keyword));
    }
    if (equalsIgnoringCase(keyword, "ROOT") || equalsIgnoringCase(keyword, "JOINT"))
      return declareJoint(equalsIgnoringCase(keyword, "ROOT"));
    if (equalsIgnoringCase(keyword, "End")) return declareEndSite();
    if (keyword == "{") return error("'{' with no ROOT, JOINT or End Site before it");
    if (keyword == "}") {
      if (tok_.size() != 1) return error("unexpected " + quoted(tok_[1]) + " after '}'");
      const Status s = close();
      closed = s.ok() && stack_.empty();
      return s;
    }
    if (equalsIgnoringCase(keyword, "OFFSET")) return offset();
    if (equalsIgnoringCase(keyword, "CHANNELS")) return channels();
    if (equalsIgnoringCase(keyword, "MOTION"))
      return error("MOTION inside " + openName() + " (truncated hierarchy: " + std::to_string(stack_.size()) +
                   " '}' missing)");
    return error("unknown keyword " + quoted(keyword) + " in the hierarchy");
  }

  // "ROOT name" or "JOINT name", the name being the rest of the line (it may hold spaces), a '{' allowed at
  // its end.
  Status declareJoint(bool root) {
    if (root && !stack_.empty()) return error("ROOT inside " + openName());
    if (!root && stack_.empty()) return error("JOINT outside the ROOT");
    if (!root && stack_.back().endSite) return error("JOINT inside " + openName());
    std::string_view name =
        trimmed(line_.substr(static_cast<std::size_t>(tok_[0].data() - line_.data()) + tok_[0].size()));
    const bool opens = !name.empty() && name.back() == '{';
    if (opens) name = trimmed(name.substr(0, name.size() - 1));
    if (name.empty()) return error(std::string(root ? "ROOT" : "JOINT") + " without a name");
    if (out_.joints.size() >= limits_.maxJoints)
      return error("more than " + std::to_string(limits_.maxJoints) + " joints (MotionLimits::maxJoints)");
    BvhJoint joint;
    joint.name = std::string(name.substr(0, 200));
    joint.line = lines_.number();
    if (!root) {
      joint.parent = stack_.back().joint;
      joint.depth = out_.joints[static_cast<std::size_t>(joint.parent)].depth + 1;
      out_.joints[static_cast<std::size_t>(joint.parent)].children.push_back(
          static_cast<int>(out_.joints.size()));
    }
    out_.joints.push_back(std::move(joint));
    pending_ = Pending::Joint;
    return opens ? open() : Status::success();
  }

  Status declareEndSite() {
    const bool opens = tok_.size() == 3 && tok_[2] == "{";
    if (tok_.size() < 2 || !equalsIgnoringCase(tok_[1], "Site") || (tok_.size() > 2 && !opens))
      return error("expected 'End Site', found " + quoted(line_));
    if (stack_.empty() || stack_.back().endSite) return error("End Site outside a joint");
    pending_ = Pending::EndSite;
    return opens ? open() : Status::success();
  }

  Status open() {
    if (stack_.size() >= limits_.maxDepth)
      return error("the hierarchy nests deeper than " + std::to_string(limits_.maxDepth) +
                   " levels (MotionLimits::maxDepth)");
    Open o;
    o.endSite = pending_ == Pending::EndSite;
    o.joint = o.endSite ? stack_.back().joint : static_cast<int>(out_.joints.size()) - 1;
    stack_.push_back(o);
    pending_ = Pending::None;
    return Status::success();
  }

  Status close() {
    if (stack_.empty()) return error("'}' with nothing open");
    const Open o = stack_.back();
    if (!o.hasOffset) return error(openName() + " has no OFFSET");
    BvhJoint& joint = out_.joints[static_cast<std::size_t>(o.joint)];
    if (o.endSite)
      joint.endSites.push_back(o.offset);
    else
      joint.offset = o.offset;
    stack_.pop_back();
    return Status::success();
  }

  Status offset() {
    if (stack_.empty()) return error("OFFSET outside a joint");
    Open& o = stack_.back();
    if (o.hasOffset) return error("a second OFFSET in " + openName());
    if (tok_.size() != 4) return error("OFFSET needs 3 numbers, found " + std::to_string(tok_.size() - 1));
    for (int k = 0; k < 3; ++k) {
      const std::string_view t = tok_[static_cast<std::size_t>(k) + 1];
      double v = 0.0;
      const NumberRead r = readNumber(t, v);
      if (r != NumberRead::Ok || std::abs(v) > kMaxBvhValue)
        return error(
            "OFFSET of " + openName() + ": " + quoted(t) +
            (r == NumberRead::NotANumber ? " is not a number" : " is not a finite number up to 1e7"));
      o.offset[k] = v;
    }
    o.hasOffset = true;
    return Status::success();
  }

  Status channels() {
    if (stack_.empty() || stack_.back().endSite)
      return error("CHANNELS outside a joint (an End Site has none)");
    BvhJoint& joint = out_.joints[static_cast<std::size_t>(stack_.back().joint)];
    if (joint.channelsGiven) return error("a second CHANNELS in joint '" + joint.name + "'");
    unsigned long long n = 0;
    if (tok_.size() < 2 || !readCount(tok_[1], n) || n > 6)
      return error("CHANNELS needs a count from 0 to 6, found " + quoted(tok_.size() < 2 ? "" : tok_[1]));
    if (tok_.size() != n + 2)
      return error("CHANNELS " + std::to_string(n) + " names " + std::to_string(tok_.size() - 2) +
                   " channels");
    static constexpr std::pair<const char*, char> kNames[] = {{"Xposition", 'x'}, {"Yposition", 'y'},
                                                              {"Zposition", 'z'}, {"Xrotation", 'X'},
                                                              {"Yrotation", 'Y'}, {"Zrotation", 'Z'}};
    for (std::size_t k = 0; k < n; ++k) {
      const std::string_view t = tok_[k + 2];
      char code = 0;
      for (const auto& [name, c] : kNames)
        if (equalsIgnoringCase(t, name)) code = c;
      if (code == 0)
        return error("unknown channel " + quoted(t) + " (Xposition .. Zposition, Xrotation .. Zrotation)");
      for (std::size_t i = 0; i < k; ++i)
        if (joint.channels[i] == code) return error("channel " + quoted(t) + " given twice");
      joint.channels[k] = code;
    }
    joint.channelCount = static_cast<int>(n);
    joint.channelsGiven = true;
    joint.firstChannel = out_.channels;
    out_.channels += joint.channelCount;
    return Status::success();
  }

  Lines& lines_;
  const MotionLimits& limits_;
  const std::string& file_;
  BvhHeader& out_;
  std::vector<std::string_view> tok_;
  std::string_view line_;
  std::vector<Open> stack_;
  Pending pending_ = Pending::None;
};

/// "Key: value" with the key's case and spacing free ("Frame Time:", "Frames:10").
bool keyValue(const std::vector<std::string_view>& tokens, const char* key, std::string_view& value,
              std::string& joined) {
  joined.clear();
  for (std::string_view t : tokens) joined += std::string(t) + " ";
  const std::size_t colon = joined.find(':');
  if (colon == std::string::npos) return false;
  std::string k;
  for (char c : std::string_view(joined).substr(0, colon))
    if (!isBlank(c)) k += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  value = trimmed(std::string_view(joined).substr(colon + 1));
  return k == key;
}

/// MOTION, Frames: and Frame Time:, after the hierarchy.
Status readMotionHeader(Lines& lines, const MotionLimits& limits, const std::string& file, BvhHeader& out) {
  std::vector<std::string_view> tok;
  std::string_view line;
  const auto truncated = [&](const char* what) {
    return lineError(file, lines.number(), std::string("the file ends before ") + what + " (truncated)");
  };
  if (!lines.next(tok, line)) return truncated("MOTION");
  if (equalsIgnoringCase(tok[0], "ROOT"))
    return lineError(file, lines.number(), "a second ROOT: one skeleton per file is read");
  if (!equalsIgnoringCase(tok[0], "MOTION") || tok.size() != 1)
    return lineError(file, lines.number(), "expected MOTION after the hierarchy, found " + quoted(line));
  if (out.channels == 0) return lineError(file, lines.number(), "the hierarchy has no channels");

  std::string joined;
  std::string_view value;
  if (!lines.next(tok, line)) return truncated("'Frames:'");
  unsigned long long frames = 0;
  if (!keyValue(tok, "frames", value, joined))
    return lineError(file, lines.number(), "expected 'Frames: <count>', found " + quoted(line));
  if (!readCount(value, frames))
    return lineError(file, lines.number(), "Frames: " + quoted(value) + " is not a whole number");
  if (frames == 0) return lineError(file, lines.number(), "Frames: 0 (a clip needs at least one frame)");
  if (frames > limits.maxSamples)
    return lineError(file, lines.number(),
                     "Frames: " + std::to_string(frames) + " is more than " +
                         std::to_string(limits.maxSamples) + " (MotionLimits::maxSamples)");
  out.frames = static_cast<std::size_t>(frames);

  if (!lines.next(tok, line)) return truncated("'Frame Time:'");
  if (!keyValue(tok, "frametime", value, joined))
    return lineError(file, lines.number(), "expected 'Frame Time: <seconds>', found " + quoted(line));
  double dt = 0.0;
  if (readNumber(value, dt) != NumberRead::Ok || !(dt > 0.0))
    return lineError(file, lines.number(),
                     "Frame Time must be a finite number of seconds > 0, found " + quoted(value));
  out.frameTime = dt;
  return Status::success();
}

// --- The URDF side -------------------------------------------------------------------------------------

/// A stretch of a kinematic chain, as rotations: `before` (the fixed part: joint origins, and joints held
/// at zero), then `joint`'s motion (-1: none).
struct ChainStep {
  Eigen::Quaterniond before = Eigen::Quaterniond::Identity();
  int joint = -1;
};

/// One URDF bone that a BVH role drives: its joints in chain order from the body outwards, the link they
/// turn (the bone link: the last joint's child) and what the retarget needs of its zero pose.
struct UrdfBone {
  int role = -1;
  std::vector<int> joints;
  int parentLink = -1;  ///< the first joint's parent
  int boneLink = -1;
  std::vector<ChainStep> fromRoot;  ///< root link -> parentLink
  std::vector<ChainStep> chain;     ///< parentLink -> boneLink
  /// suffix[i]: the fixed rotation of chain[i + 1 ..] with their joints at zero.
  std::vector<Eigen::Quaterniond> suffix;
  Eigen::Vector3d start = Eigen::Vector3d::Zero();  ///< m, the first joint's origin, zero pose, root frame
  Eigen::Quaterniond rest = Eigen::Quaterniond::Identity();        ///< W0: the bone link's zero-pose rotation
  Eigen::Quaterniond restTarget = Eigen::Quaterniond::Identity();  ///< S W0
  bool allRevolute = true;
};

/// Link poses in the zero pose (every joint at 0, balls at the identity), the root link at the origin.
std::vector<Eigen::Isometry3d> zeroPose(const UrdfModel& model) {
  const auto& links = model.links();
  std::vector<Eigen::Isometry3d> poses(links.size(), Eigen::Isometry3d::Identity());
  for (std::size_t l = 1; l < links.size(); ++l) {
    const JointDesc& j = model.joints()[static_cast<std::size_t>(links[l].parentJoint)];
    poses[l] = poses[static_cast<std::size_t>(links[l].parentLink)] * j.origin;
  }
  return poses;
}

bool isRotational(const JointDesc& j) {
  return j.type == JointType::Revolute || j.type == JointType::Continuous || j.type == JointType::Spherical;
}

/// What a URDF joint's name says: side (0 left, 1 right), limb part (0 hip .. 4 elbow), spine or neck.
struct UrdfName {
  int side = -1;
  int part = -1;
  bool spine = false;
  bool neck = false;
};

UrdfName readUrdfName(const std::string& name) {
  const std::string low = bvh::lowerCase(name);
  const auto has = [&](const char* w) { return low.find(w) != std::string::npos; };
  UrdfName out;
  if (has("left"))
    out.side = 0;
  else if (has("right"))
    out.side = 1;
  else if (bvh::startsWith(low, "l_") || bvh::endsWith(low, "_l"))
    out.side = 0;
  else if (bvh::startsWith(low, "r_") || bvh::endsWith(low, "_r"))
    out.side = 1;
  const char* parts[] = {"hip", "knee", "ankle", "shoulder", "elbow"};
  for (int p = 0; p < 5 && out.part < 0; ++p)
    if (has(parts[p])) out.part = p;
  for (const char* w : {"waist", "spine", "chest", "torso", "abdomen", "lumbar", "trunk"})
    if (has(w)) out.spine = true;
  out.neck = has("neck") || has("head");
  return out;
}

/// Links from `from` (an ancestor) down to `to`, as the joints between them, outermost last.
std::vector<int> jointsBetween(const UrdfModel& model, int from, int to) {
  std::vector<int> path;
  for (int l = to; l != from && l > 0; l = model.links()[static_cast<std::size_t>(l)].parentLink)
    path.push_back(model.links()[static_cast<std::size_t>(l)].parentJoint);
  std::reverse(path.begin(), path.end());
  return path;
}

bool isAncestorOrSelf(const UrdfModel& model, int ancestor, int link) {
  for (int l = link; l >= 0; l = model.links()[static_cast<std::size_t>(l)].parentLink)
    if (l == ancestor) return true;
  return false;
}

/// The joints as chain steps: runs of joints not driven (`driven[j]` false) fold into the next `before`.
std::vector<ChainStep> chainSteps(const UrdfModel& model, const std::vector<int>& joints,
                                  const std::vector<char>& driven) {
  std::vector<ChainStep> steps;
  Eigen::Quaterniond fixed = Eigen::Quaterniond::Identity();
  for (int j : joints) {
    const JointDesc& joint = model.joints()[static_cast<std::size_t>(j)];
    fixed = fixed * Eigen::Quaterniond(joint.origin.linear());
    if (driven[static_cast<std::size_t>(j)]) {
      steps.push_back({fixed.normalized(), j});
      fixed = Eigen::Quaterniond::Identity();
    }
  }
  steps.push_back({fixed.normalized(), -1});
  return steps;
}

/// m: the distance limit for joints in series to count as one compound joint (hip yaw, roll and pitch).
constexpr double kCompoundJointSpan = 0.05;

// --- Retargeting -----------------------------------------------------------------------------------------

struct RoleMatch {
  int bvhJoint = -1;
  int urdfBone = -1;  ///< index into bones_
};

class BvhRetarget {
 public:
  BvhRetarget(const BvhHeader& bvh, const UrdfModelPtr& model, const BvhOptions& options,
              const JointMapping& mapping, double characterScale, std::vector<std::string>& warnings)
      : bvh_(bvh),
        model_(*model),
        options_(options),
        mapping_(mapping),
        characterScale_(characterScale),
        warnings_(warnings) {}

  Status prepare(const std::string& file);
  /// One row of channel values: appends a sample to `clip`.
  void frame(const std::vector<double>& row, std::size_t index, MotionClip& clip);
  /// The clip's joint names, in the order frame() writes them.
  void names(MotionClip& clip) const;
  void finish(std::size_t frames);

 private:
  Status findBvhRoles(const std::string& file);
  void findUrdfRoles();
  void chooseFrame();
  void chooseUnits();
  void buildBones();
  void alignRest();
  void scaleRoot();
  Eigen::Vector3d bvhRestEnd(int role) const;
  Eigen::Vector3d urdfRestEnd(const UrdfBone& bone, int role) const;
  void solve(const UrdfBone& bone, const Eigen::Quaterniond& parent, const Eigen::Quaterniond& target);
  Eigen::Quaterniond motion(int joint) const;
  Eigen::Quaterniond evaluate(Eigen::Quaterniond r, const std::vector<ChainStep>& steps) const;
  void setAngle(int joint, double q);

  const BvhHeader& bvh_;
  const UrdfModel& model_;
  const BvhOptions& options_;
  const JointMapping& mapping_;
  double characterScale_;
  std::vector<std::string>& warnings_;

  std::array<RoleMatch, kRoleCount> roles_{};
  std::array<std::vector<int>, kRoleCount> urdfJoints_;  ///< per role, before bones are built
  std::vector<UrdfBone> bones_;                          ///< parents before children
  std::vector<Eigen::Vector3d> bvhRest_;                 ///< units, every joint's rest position
  std::vector<char> bvhNeeded_;                          ///< joints whose world pose a frame needs
  std::vector<Eigen::Isometry3d> urdfZero_;
  Eigen::Matrix3d toCommon_ = Eigen::Matrix3d::Identity();  ///< A: BVH axes -> URDF frame
  Eigen::Quaterniond toCommonQ_ = Eigen::Quaterniond::Identity();
  int upAxis_ = 1;                                      ///< 1 = y, 2 = z
  double metresPerUnit_ = 0.01;                         ///< m per BVH unit
  double rootScale_ = 0.01;                             ///< m per BVH unit for the root's motion
  int pelvis_ = 0;                                      ///< URDF link the hips drive
  Eigen::Vector3d urdfHips_ = Eigen::Vector3d::Zero();  ///< m, the hips point in the root frame (scaled)
  bool hipsMidpoint_ = false;  ///< the hips point is between the hip joints (else the hips joint)

  // Per frame, reused.
  std::vector<Eigen::Quaterniond> bvhRotation_;
  std::vector<Eigen::Vector3d> bvhPosition_;
  std::vector<double> q_;                 ///< per URDF joint
  std::vector<Eigen::Quaterniond> ball_;  ///< per URDF joint
  std::vector<int> clampCount_;           ///< per URDF joint
  std::vector<int> scalarOut_, ballOut_;  ///< the clip's joints and balls, as URDF joint indices
};

Status BvhRetarget::prepare(const std::string& file) {
  const std::size_t n = bvh_.joints.size();
  bvhRest_.assign(n, Eigen::Vector3d::Zero());
  for (std::size_t j = 0; j < n; ++j) {
    const BvhJoint& joint = bvh_.joints[j];
    bvhRest_[j] =
        (joint.parent >= 0 ? bvhRest_[static_cast<std::size_t>(joint.parent)] : Eigen::Vector3d::Zero()) +
        joint.offset;
  }
  urdfZero_ = zeroPose(model_);
  Status s = findBvhRoles(file);
  if (!s.ok()) return s;
  findUrdfRoles();
  chooseFrame();
  chooseUnits();
  buildBones();
  alignRest();
  scaleRoot();

  bvhNeeded_.assign(n, 0);
  for (const RoleMatch& r : roles_)
    for (int j = r.bvhJoint; j >= 0 && !bvhNeeded_[static_cast<std::size_t>(j)];
         j = bvh_.joints[static_cast<std::size_t>(j)].parent)
      bvhNeeded_[static_cast<std::size_t>(j)] = 1;
  bvhRotation_.assign(n, Eigen::Quaterniond::Identity());
  bvhPosition_.assign(n, Eigen::Vector3d::Zero());
  q_.assign(model_.joints().size(), 0.0);
  ball_.assign(model_.joints().size(), Eigen::Quaterniond::Identity());
  clampCount_.assign(model_.joints().size(), 0);
  for (const UrdfBone& bone : bones_)
    for (int j : bone.joints)
      (model_.joints()[static_cast<std::size_t>(j)].isSpherical() ? ballOut_ : scalarOut_).push_back(j);
  return Status::success();
}

// Each role's BVH joint: the user's map first, then the names (the best rank; the shallowest on a tie, but
// the deepest for the head and neck; for the spine the deepest spine joint above the neck: the chest).
Status BvhRetarget::findBvhRoles(const std::string& file) {
  std::unordered_map<std::string, int> byName;
  for (std::size_t j = 0; j < bvh_.joints.size(); ++j)
    byName.emplace(bvh_.joints[j].name, static_cast<int>(j));
  std::array<bool, kRoleCount> given{};
  for (const auto& [jointName, roleName] : options_.roles) {
    const int role = bvh::roleFromName(roleName);
    if (role < 0) {
      std::string all;
      for (int r = 0; r < kRoleCount; ++r) all += std::string(r ? ", " : "") + bvh::roleName(r);
      return Status::error(ErrorCode::InvalidArgument, file + ": BvhOptions::roles: unknown role '" +
                                                           roleName + "' (roles: " + all + ")");
    }
    const auto found = byName.find(jointName);
    if (found == byName.end())
      return Status::error(ErrorCode::InvalidArgument, file + ": BvhOptions::roles: the BVH has no joint '" +
                                                           jointName + "' (for role '" + roleName + "')");
    if (given[static_cast<std::size_t>(role)])
      return Status::error(ErrorCode::InvalidArgument,
                           file + ": BvhOptions::roles: role '" + roleName + "' is given twice");
    given[static_cast<std::size_t>(role)] = true;
    roles_[static_cast<std::size_t>(role)].bvhJoint = found->second;
  }
  std::array<int, kRoleCount> rank;
  rank.fill(1 << 20);
  std::vector<int> spineJoints;
  for (std::size_t j = 0; j < bvh_.joints.size(); ++j) {
    const bvh::NameRole nr = bvh::roleOfBvhName(bvh_.joints[j].name);
    if (nr.role < 0) continue;
    if (nr.role == bvh::kSpine) spineJoints.push_back(static_cast<int>(j));
    RoleMatch& r = roles_[static_cast<std::size_t>(nr.role)];
    if (given[static_cast<std::size_t>(nr.role)]) continue;
    const bool deeper = nr.role == bvh::kNeck;  // file order is depth-first: later in a chain is deeper
    if (nr.rank < rank[static_cast<std::size_t>(nr.role)] ||
        (deeper && nr.rank == rank[static_cast<std::size_t>(nr.role)] &&
         bvh_.joints[j].depth > bvh_.joints[static_cast<std::size_t>(r.bvhJoint)].depth)) {
      rank[static_cast<std::size_t>(nr.role)] = nr.rank;
      r.bvhJoint = static_cast<int>(j);
    }
  }
  RoleMatch& spine = roles_[bvh::kSpine];
  if (!given[bvh::kSpine] && !spineJoints.empty()) {
    // The chest: of the spine joints above the neck (or above either upper arm), the deepest.
    int below = roles_[bvh::kNeck].bvhJoint;
    if (below < 0) below = roles_[bvh::kLeftShoulder].bvhJoint;
    if (below < 0) below = roles_[bvh::kRightShoulder].bvhJoint;
    spine.bvhJoint = -1;
    for (int j : spineJoints) {
      bool above = below < 0;
      for (int a = below; a >= 0 && !above; a = bvh_.joints[static_cast<std::size_t>(a)].parent)
        above = a == j;
      if (above && (spine.bvhJoint < 0 || bvh_.joints[static_cast<std::size_t>(j)].depth >
                                              bvh_.joints[static_cast<std::size_t>(spine.bvhJoint)].depth))
        spine.bvhJoint = j;
    }
  }
  if (roles_[bvh::kHips].bvhJoint < 0) {
    roles_[bvh::kHips].bvhJoint = 0;
    warnings_.push_back(file + ": no joint named like the hips: the ROOT '" + bvh_.joints[0].name +
                        "' plays them");
  }
  for (int r = 0; r < kRoleCount; ++r)
    if (roles_[static_cast<std::size_t>(r)].bvhJoint < 0)
      warnings_.push_back(
          std::string("BVH role '") + bvh::roleName(r) +
          "': no joint of the BVH matched (BvhOptions::roles names one); it is not retargeted");
  return Status::success();
}

// Each role's URDF joints: the limbs from the joint mapping (unless the joint's name says another part),
// else by name (spherical joints first); the spine and neck by name. A limb's joint takes in the joints in
// series with it within kCompoundJointSpan (a hip's yaw, roll and pitch).
void BvhRetarget::findUrdfRoles() {
  const auto& joints = model_.joints();
  std::vector<char> used(joints.size(), 0);
  std::vector<UrdfName> names;
  names.reserve(joints.size());
  for (const JointDesc& j : joints) names.push_back(readUrdfName(j.name));
  for (int r = bvh::kFirstLimbRole; r < kRoleCount; ++r) {
    const int part = (r - bvh::kFirstLimbRole) / 2, side = (r - bvh::kFirstLimbRole) % 2;
    int found = mapping_[static_cast<GaitRole>(r - bvh::kFirstLimbRole)].joint;
    if (found >= static_cast<int>(joints.size()) ||
        (found >= 0 && !isRotational(joints[static_cast<std::size_t>(found)])))
      found = -1;
    if (found >= 0) {
      const UrdfName& n = names[static_cast<std::size_t>(found)];
      if (n.part >= 0 && n.side >= 0 && (n.part != part || n.side != side)) {
        warnings_.push_back(std::string("URDF role '") + bvh::roleName(r) + "': the joint mapping's '" +
                            joints[static_cast<std::size_t>(found)].name +
                            "' is named as another part; not used");
        found = -1;
      }
    }
    for (int pass = 0; pass < 2 && found < 0; ++pass) {
      for (std::size_t j = 0; j < joints.size() && found < 0; ++j) {
        const bool kind = pass == 0 ? joints[j].isSpherical() : isRotational(joints[j]);
        if (kind && !used[j] && names[j].part == part && names[j].side == side) found = static_cast<int>(j);
      }
    }
    if (found < 0 || used[static_cast<std::size_t>(found)]) continue;
    used[static_cast<std::size_t>(found)] = 1;
    urdfJoints_[static_cast<std::size_t>(r)].push_back(found);
  }
  // Compound joints: in series with a limb's joint, no branch between, within kCompoundJointSpan of it.
  const auto near = [&](int a, int b) {
    const auto& pa = urdfZero_[static_cast<std::size_t>(joints[static_cast<std::size_t>(a)].childLink)];
    const auto& pb = urdfZero_[static_cast<std::size_t>(joints[static_cast<std::size_t>(b)].childLink)];
    return (pa.translation() - pb.translation()).norm() <= kCompoundJointSpan;
  };
  for (int r = bvh::kFirstLimbRole; r < kRoleCount; ++r) {
    std::vector<int>& group = urdfJoints_[static_cast<std::size_t>(r)];
    if (group.empty()) continue;
    const int core = group[0];
    for (int link = joints[static_cast<std::size_t>(core)].parentLink; link > 0 && group.size() < 6;) {
      const LinkDesc& l = model_.links()[static_cast<std::size_t>(link)];
      const int j = l.parentJoint;
      if (l.childJoints.size() != 1 || used[static_cast<std::size_t>(j)] || !near(core, j)) break;
      if (isRotational(joints[static_cast<std::size_t>(j)])) {
        group.insert(group.begin(), j);
        used[static_cast<std::size_t>(j)] = 1;
      }
      link = l.parentLink;
    }
    for (int link = joints[static_cast<std::size_t>(core)].childLink; group.size() < 6;) {
      const LinkDesc& l = model_.links()[static_cast<std::size_t>(link)];
      if (l.childJoints.size() != 1) break;
      const int j = l.childJoints[0];
      if (used[static_cast<std::size_t>(j)] || !near(core, j)) break;
      if (isRotational(joints[static_cast<std::size_t>(j)])) {
        group.push_back(j);
        used[static_cast<std::size_t>(j)] = 1;
      }
      link = joints[static_cast<std::size_t>(j)].childLink;
    }
  }
  // Spine and neck by name, each kept to one chain: the matches above the deepest of them.
  for (int r : {bvh::kSpine, bvh::kNeck}) {
    std::vector<int> matches;
    for (std::size_t j = 0; j < joints.size(); ++j)
      if (!used[j] && isRotational(joints[j]) && (r == bvh::kSpine ? names[j].spine : names[j].neck) &&
          names[j].part < 0)
        matches.push_back(static_cast<int>(j));
    if (matches.empty()) continue;
    std::sort(matches.begin(), matches.end(), [&](int a, int b) {
      return joints[static_cast<std::size_t>(a)].childLink < joints[static_cast<std::size_t>(b)].childLink;
    });
    const int deepest = joints[static_cast<std::size_t>(matches.back())].childLink;
    for (int j : matches) {
      if (!isAncestorOrSelf(model_, joints[static_cast<std::size_t>(j)].childLink, deepest)) continue;
      urdfJoints_[static_cast<std::size_t>(r)].push_back(j);
      used[static_cast<std::size_t>(j)] = 1;
    }
  }
}

// A: the BVH's up axis onto z, its facing onto x. The facing is the rest pose's left (left upper leg minus
// right upper leg, else the upper arms) turned a quarter about up: forward = left x up.
void BvhRetarget::chooseFrame() {
  const auto restOf = [&](int role) -> const Eigen::Vector3d* {
    const int j = roles_[static_cast<std::size_t>(role)].bvhJoint;
    return j >= 0 ? &bvhRest_[static_cast<std::size_t>(j)] : nullptr;
  };
  if (options_.up != BvhUp::Auto) {
    upAxis_ = options_.up == BvhUp::Z ? 2 : 1;
  } else {
    // Head (the neck role, else the spine) above the feet (the ankles, else the hips); else the longer
    // extent.
    const Eigen::Vector3d* head = restOf(bvh::kNeck) ? restOf(bvh::kNeck) : restOf(bvh::kSpine);
    Eigen::Vector3d feet = Eigen::Vector3d::Zero();
    int count = 0;
    for (int r : {bvh::kLeftAnkle, bvh::kRightAnkle})
      if (const Eigen::Vector3d* p = restOf(r)) {
        feet += *p;
        ++count;
      }
    Eigen::Vector3d span;
    const char* how = "the head above the feet";
    if (head && count > 0) {
      span = (*head - feet / count).cwiseAbs();
    } else {
      Eigen::AlignedBox3d box;
      for (const Eigen::Vector3d& p : bvhRest_) box.extend(p);
      span = box.sizes();
      how = "the rest pose's longer extent";
    }
    upAxis_ = span.z() > span.y() ? 2 : 1;
    warnings_.push_back(std::string("BVH up axis guessed: ") + (upAxis_ == 2 ? "z" : "y") + " (" + how +
                        "; BvhOptions::up sets it)");
  }
  const Eigen::Vector3d up = Eigen::Vector3d::Unit(upAxis_);
  Eigen::Vector3d left = Eigen::Vector3d::Zero();
  constexpr std::array<std::pair<int, int>, 2> kPairs = {
      {{bvh::kLeftHip, bvh::kRightHip}, {bvh::kLeftShoulder, bvh::kRightShoulder}}};
  for (const auto& [l, r] : kPairs) {
    if (restOf(l) && restOf(r)) {
      left = *restOf(l) - *restOf(r);
      left -= left.dot(up) * up;
      if (left.norm() > 1e-9 * (1.0 + restOf(l)->norm())) break;
    }
    left.setZero();
  }
  if (left.isZero()) {
    left = Eigen::Vector3d::UnitX();
    warnings_.push_back(
        std::string("BVH facing: no left and right upper legs or arms apart in the rest pose; "
                    "taken to face ") +
        (upAxis_ == 2 ? "-y" : "+z") + " (its left +x)");
  }
  left.normalize();
  const Eigen::Vector3d forward = left.cross(up);
  toCommon_.row(0) = forward.transpose();
  toCommon_.row(1) = left.transpose();
  toCommon_.row(2) = up.transpose();
  toCommonQ_ = Eigen::Quaterniond(toCommon_).normalized();
}

// Metres per unit: given, or from the rest height (head to feet along up: the extent of every joint and end
// site).
void BvhRetarget::chooseUnits() {
  if (options_.scale > 0.0) {
    metresPerUnit_ = options_.scale;
    return;
  }
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (std::size_t j = 0; j < bvh_.joints.size(); ++j) {
    lo = std::min(lo, bvhRest_[j][upAxis_]), hi = std::max(hi, bvhRest_[j][upAxis_]);
    for (const Eigen::Vector3d& e : bvh_.joints[j].endSites) {
      const double h = bvhRest_[j][upAxis_] + e[upAxis_];
      lo = std::min(lo, h), hi = std::max(hi, h);
    }
  }
  const double height = hi - lo;
  const char* unit = "centimetres";
  if (height >= 0.5 && height <= 3.0) {
    metresPerUnit_ = 1.0, unit = "metres";
  } else if (height >= 40.0 && height < 100.0) {
    metresPerUnit_ = 0.0254, unit = "inches";
  } else if (height >= 100.0 && height <= 300.0) {
    metresPerUnit_ = 0.01;
  } else if (height >= 1000.0 && height <= 3000.0) {
    metresPerUnit_ = 0.001, unit = "millimetres";
  } else {
    metresPerUnit_ = height > 0.0 ? 1.7 / height : 0.01;
    unit = nullptr;
  }
  std::ostringstream msg;
  msg << "BVH units guessed from its rest height of " << height << " units (head to feet along "
      << (upAxis_ == 2 ? "z" : "y") << "): ";
  if (unit)
    msg << unit << ", " << metresPerUnit_ << " m per unit";
  else
    msg << "no usual unit fits; scaled to 1.7 m tall, " << metresPerUnit_ << " m per unit";
  msg << " (BvhOptions::scale sets it)";
  warnings_.push_back(msg.str());
}

// Bones for the roles both sides have, their chains as steps, parents first. Joints between the root link and
// the pelvis (the link the hips drive) stay at zero.
void BvhRetarget::buildBones() {
  const auto& joints = model_.joints();
  const auto firstJoint = [&](int role) {
    const auto& g = urdfJoints_[static_cast<std::size_t>(role)];
    return g.empty() ? -1 : g.front();
  };
  const int lh = firstJoint(bvh::kLeftHip), rh = firstJoint(bvh::kRightHip);
  pelvis_ = 0;
  if (lh >= 0 && rh >= 0) {
    for (int a = joints[static_cast<std::size_t>(lh)].parentLink; a >= 0;
         a = model_.links()[static_cast<std::size_t>(a)].parentLink)
      if (isAncestorOrSelf(model_, a, joints[static_cast<std::size_t>(rh)].parentLink)) {
        pelvis_ = a;
        break;
      }
  }
  std::vector<char> driven(joints.size(), 0);
  for (int r = 1; r < kRoleCount; ++r) {
    std::vector<int>& group = urdfJoints_[static_cast<std::size_t>(r)];
    for (auto it = group.begin(); it != group.end();) {
      if (isAncestorOrSelf(model_, joints[static_cast<std::size_t>(*it)].childLink, pelvis_)) {
        warnings_.push_back("URDF joint '" + joints[static_cast<std::size_t>(*it)].name +
                            "' lies between the root link and the pelvis: held at zero");
        it = group.erase(it);
      } else {
        ++it;
      }
    }
    if (group.empty()) {
      warnings_.push_back(std::string("URDF role '") + bvh::roleName(r) + "': no joint of the model found" +
                          (r == bvh::kSpine || r == bvh::kNeck ? " (by name)" : "") +
                          "; it is not retargeted");
      continue;
    }
    if (roles_[static_cast<std::size_t>(r)].bvhJoint < 0) {
      group.clear();  // said with the BVH's roles
      continue;
    }
    UrdfBone bone;
    bone.role = r;
    bone.joints = group;
    bone.parentLink = joints[static_cast<std::size_t>(group.front())].parentLink;
    bone.boneLink = joints[static_cast<std::size_t>(group.back())].childLink;
    for (int j : group) {
      driven[static_cast<std::size_t>(j)] = 1;
      bone.allRevolute = bone.allRevolute && !joints[static_cast<std::size_t>(j)].isSpherical();
    }
    bones_.push_back(std::move(bone));
  }
  std::sort(bones_.begin(), bones_.end(),
            [](const UrdfBone& a, const UrdfBone& b) { return a.boneLink < b.boneLink; });
  for (std::size_t b = 0; b < bones_.size(); ++b) {
    UrdfBone& bone = bones_[b];
    roles_[static_cast<std::size_t>(bone.role)].urdfBone = static_cast<int>(b);
    bone.fromRoot = chainSteps(model_, jointsBetween(model_, 0, bone.parentLink), driven);
    bone.chain = chainSteps(model_, jointsBetween(model_, bone.parentLink, bone.boneLink), driven);
    bone.suffix.assign(bone.chain.size(), Eigen::Quaterniond::Identity());
    for (std::size_t i = bone.chain.size(); i-- > 1;)
      bone.suffix[i - 1] = bone.chain[i].before * bone.suffix[i];
    bone.start =
        urdfZero_[static_cast<std::size_t>(joints[static_cast<std::size_t>(bone.joints.front())].childLink)]
            .translation();
    bone.rest = Eigen::Quaterniond(urdfZero_[static_cast<std::size_t>(bone.boneLink)].linear()).normalized();
  }
}

int nextRole(int role) {
  switch (role) {
    case bvh::kSpine:
      return bvh::kNeck;
    case bvh::kLeftHip:
    case bvh::kRightHip:
    case bvh::kLeftKnee:
    case bvh::kRightKnee:
    case bvh::kLeftShoulder:
    case bvh::kRightShoulder:
      return role + 2;
    default:
      return -1;
  }
}

// The BVH bone's far end at rest (units): the next role's joint when both sides have it, else the farthest of
// the joints and end sites below.
Eigen::Vector3d BvhRetarget::bvhRestEnd(int role) const {
  const int next = nextRole(role);
  if (next >= 0 && roles_[static_cast<std::size_t>(next)].bvhJoint >= 0 &&
      roles_[static_cast<std::size_t>(next)].urdfBone >= 0)
    return bvhRest_[static_cast<std::size_t>(roles_[static_cast<std::size_t>(next)].bvhJoint)];
  const int top = roles_[static_cast<std::size_t>(role)].bvhJoint;
  const Eigen::Vector3d& start = bvhRest_[static_cast<std::size_t>(top)];
  Eigen::Vector3d far = start;
  const auto consider = [&](const Eigen::Vector3d& p) {
    if ((p - start).squaredNorm() > (far - start).squaredNorm()) far = p;
  };
  // The joints below `top` follow it in file order until the first joint no deeper than it.
  const int depth = bvh_.joints[static_cast<std::size_t>(top)].depth;
  for (std::size_t j = static_cast<std::size_t>(top); j < bvh_.joints.size(); ++j) {
    if (j != static_cast<std::size_t>(top) && bvh_.joints[j].depth <= depth) break;
    consider(bvhRest_[j]);
    for (const Eigen::Vector3d& e : bvh_.joints[j].endSites) consider(bvhRest_[j] + e);
  }
  return far;
}

// The URDF bone's far end in the zero pose (m): the next role's first joint when both sides have it, else the
// farthest link origin or shape centre of the bone link and the links below it.
Eigen::Vector3d BvhRetarget::urdfRestEnd(const UrdfBone& bone, int role) const {
  const int next = nextRole(role);
  if (next >= 0 && roles_[static_cast<std::size_t>(next)].urdfBone >= 0)
    return bones_[static_cast<std::size_t>(roles_[static_cast<std::size_t>(next)].urdfBone)].start;
  Eigen::Vector3d far = bone.start;
  const auto consider = [&](const Eigen::Vector3d& p) {
    if ((p - bone.start).squaredNorm() > (far - bone.start).squaredNorm()) far = p;
  };
  const auto& links = model_.links();
  std::vector<char> below(links.size(), 0);
  below[static_cast<std::size_t>(bone.boneLink)] = 1;
  for (std::size_t l = static_cast<std::size_t>(bone.boneLink); l < links.size(); ++l) {
    if (l != static_cast<std::size_t>(bone.boneLink) &&
        (links[l].parentLink < 0 || !below[static_cast<std::size_t>(links[l].parentLink)]))
      continue;
    below[l] = 1;
    consider(urdfZero_[l].translation());
    for (const ShapeDesc& s : links[l].shapes) consider(urdfZero_[l] * s.origin.translation());
  }
  return far;
}

// S per bone: the shortest turn taking the URDF bone's zero-pose direction onto the BVH bone's rest direction
// (in the common frame), so that a BVH in a T-pose drives a model built arms down.
void BvhRetarget::alignRest() {
  for (UrdfBone& bone : bones_) {
    const int j = roles_[static_cast<std::size_t>(bone.role)].bvhJoint;
    Eigen::Vector3d urdfDir = urdfRestEnd(bone, bone.role) - bone.start;
    Eigen::Vector3d bvhDir = toCommon_ * (bvhRestEnd(bone.role) - bvhRest_[static_cast<std::size_t>(j)]);
    Eigen::Quaterniond align = Eigen::Quaterniond::Identity();
    if (bone.role == bvh::kLeftAnkle || bone.role == bvh::kRightAnkle) {
      // A foot stands flat in both rest poses, whatever its bone's direction says (the BVH's ankle to toe
      // base, a little down; the URDF's ankle to its foot's shapes, well down): only its heading is aligned.
      const double urdfLength = urdfDir.norm(), bvhLength = bvhDir.norm();
      urdfDir.z() = 0.0;
      bvhDir.z() = 0.0;
      if (urdfDir.norm() > 1e-3 * urdfLength && bvhDir.norm() > 1e-3 * bvhLength)
        align = Eigen::Quaterniond::FromTwoVectors(urdfDir, bvhDir);
      bone.restTarget = (align * bone.rest).normalized();
      continue;
    }
    if (urdfDir.norm() > 1e-9 && bvhDir.norm() > 1e-12)
      align = Eigen::Quaterniond::FromTwoVectors(urdfDir, bvhDir);
    else
      warnings_.push_back(std::string("role '") + bvh::roleName(bone.role) +
                          "': a bone of no length; its rest pose is taken as the URDF's");
    bone.restTarget = (align * bone.rest).normalized();
  }
}

// The root's motion: metres per unit times, with scaleRootToLegs, the URDF's leg over the BVH's (hip to
// ankle at rest, both sides that both have); the hips point between the hip joints where both sides have
// both.
void BvhRetarget::scaleRoot() {
  double urdfLegs = 0.0, bvhLegs = 0.0;
  int legs = 0;
  for (int side = 0; side < 2; ++side) {
    const RoleMatch& hip = roles_[static_cast<std::size_t>(bvh::kLeftHip + side)];
    const RoleMatch& ankle = roles_[static_cast<std::size_t>(bvh::kLeftAnkle + side)];
    if (hip.urdfBone < 0 || ankle.urdfBone < 0) continue;
    urdfLegs += (bones_[static_cast<std::size_t>(hip.urdfBone)].start -
                 bones_[static_cast<std::size_t>(ankle.urdfBone)].start)
                    .norm();
    bvhLegs += (bvhRest_[static_cast<std::size_t>(hip.bvhJoint)] -
                bvhRest_[static_cast<std::size_t>(ankle.bvhJoint)])
                   .norm();
    ++legs;
  }
  rootScale_ = metresPerUnit_;
  if (options_.scaleRootToLegs) {
    if (urdfLegs > 0.0 && bvhLegs > 0.0) {
      rootScale_ = characterScale_ * urdfLegs / bvhLegs;
      std::ostringstream msg;
      msg << "root motion scaled by the legs (hip to ankle): the URDF's " << characterScale_ * urdfLegs / legs
          << " m over the BVH's " << bvhLegs * metresPerUnit_ / legs << " m (" << rootScale_
          << " m per BVH unit)";
      warnings_.push_back(msg.str());
    } else {
      warnings_.push_back("root motion not scaled by the legs (no hip and ankle on both sides): " +
                          std::to_string(metresPerUnit_) + " m per BVH unit");
    }
  }
  const RoleMatch& lh = roles_[bvh::kLeftHip];
  const RoleMatch& rh = roles_[bvh::kRightHip];
  hipsMidpoint_ = lh.urdfBone >= 0 && rh.urdfBone >= 0;
  urdfHips_ = hipsMidpoint_ ? 0.5 * (bones_[static_cast<std::size_t>(lh.urdfBone)].start +
                                     bones_[static_cast<std::size_t>(rh.urdfBone)].start)
                            : Eigen::Vector3d(urdfZero_[static_cast<std::size_t>(pelvis_)].translation());
  urdfHips_ *= characterScale_;
}

Eigen::Quaterniond BvhRetarget::motion(int joint) const {
  const JointDesc& j = model_.joints()[static_cast<std::size_t>(joint)];
  if (j.isSpherical()) return ball_[static_cast<std::size_t>(joint)];
  return Eigen::Quaterniond(Eigen::AngleAxisd(q_[static_cast<std::size_t>(joint)], j.axis));
}

Eigen::Quaterniond BvhRetarget::evaluate(Eigen::Quaterniond r, const std::vector<ChainStep>& steps) const {
  for (const ChainStep& s : steps) {
    r = r * s.before;
    if (s.joint >= 0) r = r * motion(s.joint);
  }
  return r;
}

/// The angle about unit `axis` of q's twist (swing-twist decomposition), in (-pi, pi]: the hinge rotation
/// nearest q.
double twistAngle(Eigen::Quaterniond q, const Eigen::Vector3d& axis) {
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();
  return 2.0 * std::atan2(q.vec().dot(axis), q.w());
}

void BvhRetarget::setAngle(int joint, double q) {
  const JointDesc& j = model_.joints()[static_cast<std::size_t>(joint)];
  double& out = q_[static_cast<std::size_t>(joint)];
  if (j.type == JointType::Continuous) {
    // Unbounded: the turn nearest the last frame's, so that the clip does not jump by 2 pi.
    q += 2.0 * kPi * std::round((out - q) / (2.0 * kPi));
  } else if (j.hasLimits && (q < j.lower || q > j.upper)) {
    q = std::clamp(q, j.lower, j.upper);
    ++clampCount_[static_cast<std::size_t>(joint)];
  }
  out = q;
}

// The bone's joints take the world rotation `target` as far as they can, from its parent's rotation:
// one joint after another, each the twist about its axis (a ball: all) of what is left with the joints
// after it at zero; several hinges then refined together (Gauss-Newton on the rotation error, the joints'
// world axes as the Jacobian, within their limits).
void BvhRetarget::solve(const UrdfBone& bone, const Eigen::Quaterniond& parent,
                        const Eigen::Quaterniond& target) {
  Eigen::Quaterniond r = parent;
  for (std::size_t i = 0; i < bone.chain.size(); ++i) {
    const ChainStep& s = bone.chain[i];
    r = r * s.before;
    if (s.joint < 0) continue;
    const Eigen::Quaterniond left = r.conjugate() * target * bone.suffix[i].conjugate();
    const JointDesc& j = model_.joints()[static_cast<std::size_t>(s.joint)];
    if (j.isSpherical())
      ball_[static_cast<std::size_t>(s.joint)] = left.normalized();
    else
      setAngle(s.joint, twistAngle(left, j.axis));
    r = r * motion(s.joint);
  }
  if (!bone.allRevolute || bone.joints.size() < 2) return;
  const std::size_t n = bone.joints.size();
  Eigen::MatrixXd jac(3, static_cast<Eigen::Index>(n));
  for (int iteration = 0; iteration < 30; ++iteration) {
    r = parent;
    std::size_t k = 0;
    for (const ChainStep& s : bone.chain) {
      r = r * s.before;
      if (s.joint < 0) continue;
      jac.col(static_cast<Eigen::Index>(k++)) = r * model_.joints()[static_cast<std::size_t>(s.joint)].axis;
      r = r * motion(s.joint);
    }
    Eigen::Quaterniond err = target * r.conjugate();
    if (err.w() < 0.0) err.coeffs() = -err.coeffs();
    const Eigen::AngleAxisd aa(err.normalized());
    const Eigen::Vector3d e = aa.angle() * aa.axis();
    if (e.norm() < 1e-13) break;
    const Eigen::MatrixXd jtj =
        jac.transpose() * jac +
        1e-12 * Eigen::MatrixXd::Identity(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
    const Eigen::VectorXd step = jtj.ldlt().solve(jac.transpose() * e);
    for (std::size_t i = 0; i < n; ++i) {
      const int joint = bone.joints[i];
      const JointDesc& j = model_.joints()[static_cast<std::size_t>(joint)];
      double q = q_[static_cast<std::size_t>(joint)] + step[static_cast<Eigen::Index>(i)];
      if (j.hasLimits) q = std::clamp(q, j.lower, j.upper);
      q_[static_cast<std::size_t>(joint)] = q;
    }
  }
}

void BvhRetarget::frame(const std::vector<double>& row, std::size_t index, MotionClip& clip) {
  // The BVH's world rotations and positions (units) of the joints the roles need, parents first.
  for (std::size_t j = 0; j < bvh_.joints.size(); ++j) {
    if (!bvhNeeded_[j]) continue;
    const BvhJoint& joint = bvh_.joints[j];
    Eigen::Vector3d t = joint.offset;
    Eigen::Quaterniond local = Eigen::Quaterniond::Identity();
    for (int c = 0; c < joint.channelCount; ++c) {
      const double v = row[static_cast<std::size_t>(joint.firstChannel + c)];
      const char code = joint.channels[static_cast<std::size_t>(c)];
      if (code >= 'x')
        t[code - 'x'] = v;  // a position channel replaces that axis of the offset
      else
        local = local * Eigen::Quaterniond(
                            Eigen::AngleAxisd(v * kRadiansPerDegree, Eigen::Vector3d::Unit(code - 'X')));
    }
    if (joint.parent < 0) {
      bvhPosition_[j] = t;
      bvhRotation_[j] = local;
    } else {
      const std::size_t p = static_cast<std::size_t>(joint.parent);
      bvhPosition_[j] = bvhPosition_[p] + bvhRotation_[p] * t;
      bvhRotation_[j] = bvhRotation_[p] * local;
    }
  }
  const auto turn = [&](int role) {  // D = A G A^T
    return (toCommonQ_ *
            bvhRotation_[static_cast<std::size_t>(roles_[static_cast<std::size_t>(role)].bvhJoint)] *
            toCommonQ_.conjugate())
        .normalized();
  };
  const auto at = [&](int role) {
    return bvhPosition_[static_cast<std::size_t>(roles_[static_cast<std::size_t>(role)].bvhJoint)];
  };
  const Eigen::Quaterniond root = turn(bvh::kHips);
  const Eigen::Vector3d hips =
      hipsMidpoint_ ? Eigen::Vector3d(0.5 * (at(bvh::kLeftHip) + at(bvh::kRightHip))) : at(bvh::kHips);
  clip.times.push_back(static_cast<double>(index) * bvh_.frameTime);
  clip.rootRotations.push_back(root);
  clip.rootPositions.push_back(rootScale_ * (toCommon_ * hips) - root * urdfHips_);
  for (const UrdfBone& bone : bones_)
    solve(bone, evaluate(root, bone.fromRoot), turn(bone.role) * bone.restTarget);
  for (int j : scalarOut_) clip.values.push_back(q_[static_cast<std::size_t>(j)]);
  for (int j : ballOut_) clip.rotations.push_back(ball_[static_cast<std::size_t>(j)]);
}

void BvhRetarget::names(MotionClip& clip) const {
  for (int j : scalarOut_) clip.joints.push_back(model_.joints()[static_cast<std::size_t>(j)].name);
  for (int j : ballOut_) clip.balls.push_back(model_.joints()[static_cast<std::size_t>(j)].name);
}

void BvhRetarget::finish(std::size_t frames) {
  for (std::size_t j = 0; j < clampCount_.size(); ++j)
    if (clampCount_[j] > 0)
      warnings_.push_back("URDF joint '" + model_.joints()[j].name + "': held at its limits in " +
                          std::to_string(clampCount_[j]) + " of " + std::to_string(frames) + " frames");
}

Status checkOptions(const BvhOptions& options, double characterScale) {
  const auto bad = [](const std::string& what) { return Status::error(ErrorCode::InvalidArgument, what); };
  if (!std::isfinite(options.scale) || options.scale < 0.0)
    return bad("BvhOptions::scale must be finite and >= 0 (0: guessed)");
  if (!std::isfinite(characterScale) || characterScale <= 0.0)
    return bad("characterScale must be finite and > 0");
  const MotionLimits& l = options.limits;
  if (l.maxFileBytes < 1 || l.maxSamples < 1 || l.maxJoints < 1 || l.maxDepth < 1)
    return bad("MotionLimits: every limit must be at least 1");
  return Status::success();
}

MotionClipResult parse(const std::string& text, const UrdfModelPtr& model, const BvhOptions& options,
                       const JointMapping* mapping, double characterScale, const std::string& file,
                       const std::string& clipName) {
  MotionClipResult result;
  result.status = checkOptions(options, characterScale);
  if (!result.status.ok()) return result;
  if (!model) {
    result.status = Status::error(ErrorCode::InvalidArgument, file + ": no URDF model to retarget onto");
    return result;
  }
  if (text.size() > options.limits.maxFileBytes) {
    result.status =
        Status::error(ErrorCode::InvalidArgument,
                      file + ": " + std::to_string(text.size()) + " bytes; the limit is " +
                          std::to_string(options.limits.maxFileBytes) + " (MotionLimits::maxFileBytes)");
    return result;
  }
  Lines lines(text);
  BvhHeader header;
  result.status = HierarchyReader(lines, options.limits, file, header).read();
  if (result.status.ok()) result.status = readMotionHeader(lines, options.limits, file, header);
  if (!result.status.ok()) return result;

  const JointMapping automatic = mapping ? JointMapping() : JointMapping::automatic(model);
  BvhRetarget retarget(header, model, options, mapping ? *mapping : automatic, characterScale,
                       result.warnings);
  result.status = retarget.prepare(file);
  if (!result.status.ok()) return result;

  MotionClip& clip = result.clip;
  clip.name = clipName;
  clip.frame = MotionFrame::Urdf;
  clip.loop = options.loop;
  retarget.names(clip);
  // Reserved for no more rows than the rest of the text could hold (two bytes a value), whatever Frames says.
  const std::size_t rows =
      std::min(header.frames, lines.remaining() / (2 * static_cast<std::size_t>(header.channels)) + 1);
  clip.times.reserve(rows), clip.rootPositions.reserve(rows), clip.rootRotations.reserve(rows);
  clip.values.reserve(rows * clip.joints.size()), clip.rotations.reserve(rows * clip.balls.size());

  // A first frame whose rotation channels are mostly exactly 0, before a frame with fewer than half as many
  // exact zeros, is the reference pose many exporters write (CMU's conversions: a few limbs set, the rest
  // 0), not motion (a captured angle is never exactly 0): held until the second frame says which.
  std::vector<char> rotation(static_cast<std::size_t>(header.channels), 0);
  std::size_t rotations = 0;
  for (const BvhJoint& joint : header.joints)
    for (int c = 0; c < joint.channelCount; ++c)
      if (joint.channels[static_cast<std::size_t>(c)] < 'x') {
        rotation[static_cast<std::size_t>(joint.firstChannel + c)] = 1;
        ++rotations;
      }
  const auto zeros = [&](const std::vector<double>& r) {
    std::size_t n = 0;
    for (std::size_t c = 0; c < r.size(); ++c) n += rotation[c] && r[c] == 0.0 ? 1 : 0;
    return n;
  };
  std::vector<double> held;
  std::size_t skipped = 0;

  std::vector<std::string_view> tok;
  std::string_view line;
  std::vector<double> row(static_cast<std::size_t>(header.channels));
  for (std::size_t k = 0; k < header.frames; ++k) {
    if (!lines.next(tok, line)) {
      result.status = lineError(file, lines.number(),
                                "Frames: " + std::to_string(header.frames) + " but the file ends after " +
                                    std::to_string(k) + " rows (truncated motion)");
      return result;
    }
    if (tok.size() != row.size()) {
      result.status = lineError(file, lines.number(),
                                "frame " + std::to_string(k) + " has " + std::to_string(tok.size()) +
                                    " values; the hierarchy has " + std::to_string(row.size()) + " channels");
      return result;
    }
    for (std::size_t c = 0; c < row.size(); ++c) {
      const NumberRead r = readNumber(tok[c], row[c]);
      if (r != NumberRead::Ok || std::abs(row[c]) > kMaxBvhValue) {
        result.status = lineError(
            file, lines.number(),
            "frame " + std::to_string(k) + ", value " + std::to_string(c + 1) + ": " + quoted(tok[c]) +
                (r == NumberRead::NotANumber ? " is not a number" : " is not a finite number up to 1e7"));
        return result;
      }
    }
    if (k == 0 && options.restFrame == BvhRestFrame::Auto && header.frames >= 3 && rotations > 0 &&
        2 * zeros(row) > rotations) {
      held = row;
      continue;
    }
    if (k == 1 && !held.empty()) {
      const std::size_t first = zeros(held), second = zeros(row);
      if (2 * second >= first) {
        retarget.frame(held, 0, clip);  // as still as the next one: the clip starts there
      } else {
        skipped = 1;
        result.warnings.push_back(file + ": frame 0 is a reference pose (" + std::to_string(first) + " of " +
                                  std::to_string(rotations) + " rotations exactly 0, frame 1 " +
                                  std::to_string(second) + "): not played (BvhOptions::restFrame keeps it)");
      }
    }
    retarget.frame(row, k - skipped, clip);
  }
  std::size_t extra = 0;
  while (lines.next(tok, line)) ++extra;
  if (extra > 0)
    result.warnings.push_back(file + ": " + std::to_string(extra) + " lines after the last of the " +
                              std::to_string(header.frames) + " frames ignored");
  retarget.finish(header.frames - skipped);
  result.status = clip.check();
  return result;
}

}  // namespace

MotionClipResult parseBvh(const std::string& text, const UrdfModelPtr& model, const BvhOptions& options,
                          const JointMapping* mapping, double characterScale, const std::string& name) {
  return parse(text, model, options, mapping, characterScale, name, name);
}

MotionClipResult readBvh(const std::string& path, const UrdfModelPtr& model, const BvhOptions& options,
                         const JointMapping* mapping, double characterScale) {
  MotionClipResult result;
  std::string text;
  result.status = motiontext::readTextFile(path, options.limits.maxFileBytes, text);
  if (!result.status.ok()) return result;
  return parse(text, model, options, mapping, characterScale, path,
               std::filesystem::path(path).filename().string());
}

}  // namespace cape::character
