// One walking character: skeleton, gait, mapping and bodies kept in step; its starting pose and its place on
// the ground.
#include "cape/character/Character.h"

#include "cape/character/Grounding.h"

#include <charconv>
#include <cmath>
#include <sstream>
#include <unordered_set>
#include <vector>

namespace cape::character {

namespace {

std::string trim(const std::string& s) {
  const std::size_t a = s.find_first_not_of(" \t\r\n");
  if (a == std::string::npos) return std::string();
  const std::size_t b = s.find_last_not_of(" \t\r\n");
  return s.substr(a, b - a + 1);
}

// The model's movable joints, for error messages.
std::string movableJoints(const UrdfModel& model) {
  std::string out;
  for (const JointDesc& j : model.joints()) {
    if (j.isMovable()) out += (out.empty() ? "" : ", ") + j.name;
  }
  return out.empty() ? std::string("none") : out;
}

}  // namespace

Status parsePose(const std::string& text, JointPose& out) {
  out.clear();
  JointPose pose;
  std::unordered_set<std::string> given;  // the names so far: linear in the entries
  if (trim(text).empty()) return Status::success();
  std::size_t start = 0;
  for (int entry = 1;; ++entry) {
    const std::size_t comma = text.find(',', start);
    const std::string item =
        text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    auto fail = [&](const std::string& why) {
      return Status::error(ErrorCode::InvalidArgument,
                           "pose entry " + std::to_string(entry) + " '" + trim(item) + "': " + why);
    };
    const std::size_t eq = item.find('=');
    if (eq == std::string::npos) return fail("no '=' (write name=value, value in rad or m)");
    const std::string name = trim(item.substr(0, eq));
    std::string value = trim(item.substr(eq + 1));
    if (name.empty()) return fail("no joint name before '='");
    if (value.empty()) return fail("no value after '='");
    if (value[0] == '+') value.erase(0, 1);
    double q = 0.0;
    const char* end = value.data() + value.size();
    const std::from_chars_result r = std::from_chars(value.data(), end, q);
    if (r.ec != std::errc() || r.ptr != end) return fail("'" + value + "' is not a number");
    if (!std::isfinite(q)) return fail("the value must be finite");
    if (!given.insert(name).second) return fail("joint '" + name + "' is given twice");
    pose.emplace_back(name, q);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  out = std::move(pose);
  return Status::success();
}

CharacterResult Character::create(const UrdfModelPtr& model, btDynamicsWorld& world, const Gait& gait,
                                  const CharacterSettings& settings, const JointMapping* mapping) {
  CharacterResult result;
  if (!model) {
    result.status = Status::error(ErrorCode::InvalidArgument, "Character::create: no model");
    return result;
  }
  if (settings.rootHeight && !std::isfinite(*settings.rootHeight)) {
    result.status =
        Status::error(ErrorCode::InvalidArgument, "Character::create: the root height is not finite");
    return result;
  }
  std::unique_ptr<Character> c(
      new Character(model, gait, settings, mapping ? *mapping : JointMapping::automatic(model)));
  result.status = c->skeleton_.setScale(settings.scale);
  if (!result.status.ok()) return result;
  result.status = c->applyPose();
  if (!result.status.ok()) return result;
  c->placeOnTheGround();
  c->gait_.apply(0.0, c->mapping_, c->skeleton_, c->rootOffset_);
  c->bodies_ = std::make_unique<CharacterBodies>(world, c->skeleton_, settings.bodies);
  result.character = std::move(c);
  return result;
}

Character::Character(const UrdfModelPtr& model, const Gait& gait, const CharacterSettings& settings,
                     JointMapping mapping)
    : skeleton_(model), gait_(gait), settings_(settings), mapping_(std::move(mapping)) {
  skeleton_.setUpAxis(settings.up);  // grounding and the gait work in the Y-up scene frame regardless
}

Status Character::applyPose() {
  const UrdfModel& model = skeleton_.model();
  std::vector<char> posed(model.joints().size(), 0);  // joints given so far: linear in the entries
  for (const auto& [name, value] : settings_.pose) {
    const int j = model.findJoint(name);
    if (j < 0) {
      return Status::error(ErrorCode::UnknownJoint,
                           "CharacterSettings::pose: no joint named '" + name + "' in '" + model.name() +
                               "' (its movable joints: " + movableJoints(model) + ")");
    }
    const JointDesc& joint = model.joints()[static_cast<std::size_t>(j)];
    if (!joint.isMovable()) {
      return Status::error(ErrorCode::NotMovable, "CharacterSettings::pose: joint '" + name + "' is " +
                                                      toString(joint.type) +
                                                      " and has no position (movable " + "joints of '" +
                                                      model.name() + "': " + movableJoints(model) + ")");
    }
    if (!std::isfinite(value)) {
      return Status::error(ErrorCode::InvalidArgument,
                           "CharacterSettings::pose: joint '" + name + "': the value is not finite");
    }
    if (posed[static_cast<std::size_t>(j)])
      return Status::error(ErrorCode::InvalidArgument,
                           "CharacterSettings::pose: joint '" + name + "' is given twice");
    posed[static_cast<std::size_t>(j)] = 1;
    const double q = skeleton_.clampToLimits(j, value);
    if (q != value) {
      std::ostringstream msg;
      msg << "pose: joint '" << name << "' = " << value << " is outside its limits [" << joint.lower << ", "
          << joint.upper << "]: clamped to " << q;
      warnings_.push_back(msg.str());
    }
    pose_.emplace_back(j, q);
    // Driven joints: the gait's angle is added to the pose. The others keep it.
    bool driven = false;
    for (int r = 0; r < kGaitRoleCount; ++r) {
      if (mapping_.entries()[static_cast<std::size_t>(r)].joint != j) continue;
      mapping_.setNeutral(static_cast<GaitRole>(r), q);
      driven = true;
    }
    if (!driven) (void)skeleton_.setJointPosition(j, q);
  }
  return Status::success();
}

void Character::placeOnTheGround() {
  // The standing pose on a skeleton of its own (root at the origin, yaw 0), so this one keeps its state.
  Skeleton standing(skeleton_.modelPtr());
  (void)standing.setScale(skeleton_.scale());
  for (const auto& [joint, q] : pose_) (void)standing.setJointPosition(joint, q);
  Gait::setJoints(gait_.standingAngles(), mapping_, standing);
  const GroundPlacement placed = placeOnGround(standing, settings_.rootHeight);
  rootHeight_ = placed.rootHeight;
  warnings_.insert(warnings_.end(), placed.warnings.begin(), placed.warnings.end());
  // A root on the ground keeps the offset as given, to the bit.
  rootOffset_ = settings_.offset;
  if (rootHeight_ != 0.0) rootOffset_.y() += rootHeight_;
}

void Character::advanceTo(double t) {
  gait_.apply(t, mapping_, skeleton_, rootOffset_);
  moveBodiesTo(t);
}

void Character::moveBodiesTo(double t) {
  if (t > time_) {
    (void)bodies_->update(t - time_);
  } else {
    bodies_->teleport();
  }
  time_ = t;
}

Eigen::Isometry3d Character::withOffset(const Eigen::Isometry3d& urdfFramePose) const {
  // The offset is in the Y-up scene frame (as the gait's root path): into the URDF frame.
  Eigen::Isometry3d pose = urdfFramePose;
  pose.translation() += Skeleton::urdfToWorld().transpose() * settings_.offset;
  return pose;
}

Status Character::setMotion(double t, const Eigen::Isometry3d& rootLinkPose, const JointPose& joints,
                            const JointRotations& rotations, MotionFrame frame) {
  const UrdfModel& model = skeleton_.model();
  auto fail = [](ErrorCode code, const std::string& what) {
    return Status::error(code, "Character::setMotion: " + what);
  };
  if (!std::isfinite(t)) return fail(ErrorCode::InvalidArgument, "the time is not finite");
  if (!rootLinkPose.matrix().allFinite())
    return fail(ErrorCode::InvalidArgument, "the root pose is not finite");
  // Everything is checked before anything moves.
  given_.assign(model.joints().size(), 0);
  for (const auto& [name, value] : joints) {
    const int j = model.findJoint(name);
    if (j < 0) {
      return fail(ErrorCode::UnknownJoint, "no joint named '" + name + "' in '" + model.name() +
                                               "' (its movable joints: " + movableJoints(model) + ")");
    }
    const JointDesc& joint = model.joints()[static_cast<std::size_t>(j)];
    if (!joint.isMovable()) {
      return fail(ErrorCode::NotMovable, "joint '" + name + "' is " + toString(joint.type) +
                                             " and takes no single value (movable joints of '" +
                                             model.name() + "': " + movableJoints(model) + ")");
    }
    if (!std::isfinite(value)) return fail(ErrorCode::InvalidArgument, "joint '" + name + "': not finite");
    if (given_[static_cast<std::size_t>(j)]++)
      return fail(ErrorCode::InvalidArgument, "joint '" + name + "' is given twice");
  }
  for (const auto& [name, q] : rotations) {
    const int j = model.findJoint(name);
    if (j < 0 || !model.joints()[static_cast<std::size_t>(j)].isSpherical()) {
      std::string balls;
      for (const JointDesc& d : model.joints())
        if (d.isSpherical()) balls += (balls.empty() ? "" : ", ") + d.name;
      return fail(j < 0 ? ErrorCode::UnknownJoint : ErrorCode::NotMovable,
                  (j < 0 ? "no joint named '" + name + "'" : "joint '" + name + "' is not spherical") +
                      " in '" + model.name() +
                      "' (its spherical joints: " + (balls.empty() ? "none" : balls) + ")");
    }
    const double n = q.norm();
    if (!std::isfinite(n) || n < 1e-9)
      return fail(ErrorCode::InvalidArgument, "joint '" + name + "': not a finite, non-zero quaternion");
    if (given_[static_cast<std::size_t>(j)]++)
      return fail(ErrorCode::InvalidArgument, "joint '" + name + "' is given twice");
  }
  for (const auto& [name, value] : joints) {
    const int j = model.findJoint(name);
    (void)skeleton_.setJointPosition(j, skeleton_.clampToLimits(j, value));
  }
  for (const auto& [name, q] : rotations) (void)skeleton_.setJointRotation(model.findJoint(name), q);
  skeleton_.setRootLinkPose(
      urdfFrameToWorld(withOffset(rootPoseToUrdfFrame(rootLinkPose, frame, skeleton_)), skeleton_.upAxis()));
  moveBodiesTo(t);
  return Status::success();
}

Status Character::play(const MotionPlayer& player, double t) {
  if (!std::isfinite(t)) return Status::error(ErrorCode::InvalidArgument, "Character::play: t is not finite");
  if (player.model().get() != &skeleton_.model())
    return Status::error(ErrorCode::InvalidArgument, "Character::play: the player is bound to another model");
  player.sample(t, sampled_);
  const std::vector<int>& ji = player.jointIndices();
  for (std::size_t k = 0; k < ji.size(); ++k)
    (void)skeleton_.setJointPosition(ji[k], skeleton_.clampToLimits(ji[k], sampled_.values[k]));
  const std::vector<int>& bi = player.ballIndices();
  for (std::size_t k = 0; k < bi.size(); ++k) (void)skeleton_.setJointRotation(bi[k], sampled_.rotations[k]);
  skeleton_.setRootLinkPose(urdfFrameToWorld(withOffset(sampled_.root), skeleton_.upAxis()));
  moveBodiesTo(t);
  return Status::success();
}

std::vector<std::string> Character::warnings() const {
  std::vector<std::string> out = skeleton_.model().warnings();
  out.insert(out.end(), mapping_.warnings().begin(), mapping_.warnings().end());
  out.insert(out.end(), warnings_.begin(), warnings_.end());
  return out;
}

}  // namespace cape::character
