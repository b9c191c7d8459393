// Forward kinematics: one pass over the links in parents-before-children order.
#include "cape/character/Skeleton.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <sstream>

namespace cape::character {

Eigen::Matrix3d Skeleton::urdfToWorld() {
  Eigen::Matrix3d m;
  // Columns are the images of the URDF axes: x -> -Z, y -> -X, z -> +Y (a proper rotation, det = +1).
  m.col(0) = Eigen::Vector3d(0.0, 0.0, -1.0);
  m.col(1) = Eigen::Vector3d(-1.0, 0.0, 0.0);
  m.col(2) = Eigen::Vector3d(0.0, 1.0, 0.0);
  return m;
}

const char* toString(UpAxis up) {
  return up == UpAxis::Z ? "z" : "y";
}

Eigen::Matrix3d Skeleton::sceneToWorld(UpAxis up) {
  return up == UpAxis::Z ? Eigen::Matrix3d(urdfToWorld().transpose()) : Eigen::Matrix3d::Identity();
}

void Skeleton::setUpAxis(UpAxis up) {
  up_ = up;
  dirty_ = true;
}

Skeleton::Skeleton(UrdfModelPtr model) : model_(std::move(model)) {
  assert(model_ && "Skeleton needs a loaded UrdfModel");
  q_.assign(model_->joints().size(), 0.0);
  rotations_.assign(model_->joints().size(), Eigen::Quaterniond::Identity());
  poses_.assign(model_->links().size(), Eigen::Isometry3d::Identity());
  resetJointPositions();
  rebuildShapes();
}

Status Skeleton::setScale(double scale) {
  if (!std::isfinite(scale) || scale <= 0.0) {
    std::ostringstream msg;
    msg << "scale must be finite and > 0, got " << scale;
    return Status::error(ErrorCode::InvalidArgument, msg.str());
  }
  scale_ = scale;
  rebuildShapes();
  dirty_ = true;
  return Status::success();
}

void Skeleton::rebuildShapes() {
  const auto& links = model_->links();
  shapes_.resize(links.size());
  for (std::size_t l = 0; l < links.size(); ++l) {
    shapes_[l] = links[l].shapes;
    for (ShapeDesc& s : shapes_[l]) {
      s.radius *= scale_;
      s.halfLength *= scale_;
      s.halfExtents *= scale_;
      for (Eigen::Vector3d& v : s.hull) v *= scale_;
      for (Eigen::Vector4d& plane : s.hullPlanes) plane.w() *= scale_;
      s.origin.translation() *= scale_;
    }
  }
}

double Skeleton::restPosition(int joint) const {
  return clampToLimits(joint, 0.0);
}

double Skeleton::clampToLimits(int joint, double q) const {
  assert(joint >= 0 && joint < jointCount() && "joint index out of range");
  const JointDesc& j = model_->joints()[static_cast<std::size_t>(joint)];
  return j.hasLimits ? std::clamp(q, j.lower, j.upper) : q;
}

void Skeleton::resetJointPositions() {
  for (int j = 0; j < jointCount(); ++j) q_[static_cast<std::size_t>(j)] = restPosition(j);
  for (Eigen::Quaterniond& r : rotations_) r = Eigen::Quaterniond::Identity();
  dirty_ = true;
}

Status Skeleton::setJointRotation(const std::string& name, const Eigen::Quaterniond& q) {
  const int j = jointIndex(name);
  if (j < 0)
    return Status::error(ErrorCode::UnknownJoint,
                         "no joint named '" + name + "' in '" + model_->name() + "'");
  return setJointRotation(j, q);
}

Status Skeleton::setJointRotation(int joint, const Eigen::Quaterniond& q) {
  if (joint < 0 || joint >= jointCount()) {
    return Status::error(ErrorCode::UnknownJoint, "joint index " + std::to_string(joint) + " out of range");
  }
  const JointDesc& j = model_->joints()[static_cast<std::size_t>(joint)];
  if (!j.isSpherical()) {
    return Status::error(ErrorCode::NotMovable,
                         "joint '" + j.name + "' is " + toString(j.type) + " and has no rotation to set");
  }
  const double n = q.norm();
  if (!std::isfinite(n) || n < 1e-9) {
    return Status::error(ErrorCode::InvalidArgument,
                         "joint '" + j.name + "': the rotation is not a finite, non-zero quaternion");
  }
  rotations_[static_cast<std::size_t>(joint)] = Eigen::Quaterniond(q.coeffs() / n);
  dirty_ = true;
  return Status::success();
}

Status Skeleton::setJointPosition(const std::string& name, double q) {
  const int j = jointIndex(name);
  if (j < 0)
    return Status::error(ErrorCode::UnknownJoint,
                         "no joint named '" + name + "' in '" + model_->name() + "'");
  return setJointPosition(j, q);
}

Status Skeleton::setJointPosition(int joint, double q) {
  if (joint < 0 || joint >= jointCount()) {
    return Status::error(ErrorCode::UnknownJoint, "joint index " + std::to_string(joint) + " out of range");
  }
  const JointDesc& j = model_->joints()[static_cast<std::size_t>(joint)];
  if (!j.isMovable()) {
    return Status::error(ErrorCode::NotMovable,
                         "joint '" + j.name + "' is " + toString(j.type) + " and has no position to set");
  }
  if (!std::isfinite(q)) {
    return Status::error(ErrorCode::InvalidArgument, "joint '" + j.name + "': position is not finite");
  }
  const double clamped = clampToLimits(joint, q);
  q_[static_cast<std::size_t>(joint)] = clamped;
  dirty_ = true;
  if (clamped != q) {
    std::ostringstream msg;
    msg << "joint '" << j.name << "': " << q << " is outside [" << j.lower << ", " << j.upper
        << "], clamped to " << clamped;
    return Status::error(ErrorCode::OutsideLimits, msg.str());
  }
  return Status::success();
}

Status Skeleton::jointPosition(const std::string& name, double& q) const {
  const int j = jointIndex(name);
  if (j < 0)
    return Status::error(ErrorCode::UnknownJoint,
                         "no joint named '" + name + "' in '" + model_->name() + "'");
  q = q_[static_cast<std::size_t>(j)];
  return Status::success();
}

void Skeleton::setRoot(const Eigen::Vector3d& position, double yaw) {
  Eigen::Isometry3d root = Eigen::Isometry3d::Identity();
  root.translation() = position;
  root.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()).toRotationMatrix();
  setRootTransform(root);
}

void Skeleton::setRootTransform(const Eigen::Isometry3d& root) {
  root_ = root;
  dirty_ = true;
}

void Skeleton::setRootLinkPose(const Eigen::Isometry3d& pose) {
  // linkPose(0) = W * (root rotation * urdfToWorld, root translation), W = sceneToWorld(up).
  const Eigen::Matrix3d w = sceneToWorld(up_);
  const Eigen::Quaterniond r(pose.linear());  // orthonormalised through the quaternion
  Eigen::Isometry3d root = Eigen::Isometry3d::Identity();
  root.linear() = w.transpose() * r.normalized().toRotationMatrix() * urdfToWorld().transpose();
  root.translation() = w.transpose() * pose.translation();
  setRootTransform(root);
}

void Skeleton::updatePoses() const {
  if (!dirty_) return;
  const auto& links = model_->links();
  const auto& joints = model_->joints();
  Eigen::Isometry3d base = root_;
  base.linear() = root_.linear() * urdfToWorld();
  if (up_ != UpAxis::Y) {
    const Eigen::Matrix3d w = sceneToWorld(up_);
    base.linear() = w * base.linear();
    base.translation() = w * base.translation();
  }
  poses_[0] = base;
  for (std::size_t l = 1; l < links.size(); ++l) {
    const JointDesc& j = joints[static_cast<std::size_t>(links[l].parentJoint)];
    Eigen::Isometry3d local = j.origin;
    local.translation() *= scale_;
    const double q = q_[static_cast<std::size_t>(links[l].parentJoint)];
    switch (j.type) {
      case JointType::Revolute:
      case JointType::Continuous:
        local.linear() = local.linear() * Eigen::AngleAxisd(q, j.axis).toRotationMatrix();
        break;
      case JointType::Prismatic:
        local.translation() += local.linear() * (j.axis * (q * scale_));
        break;
      case JointType::Spherical:
        local.linear() = local.linear() * rotations_[static_cast<std::size_t>(links[l].parentJoint)];
        break;
      default:  // fixed; floating and planar joints are held at their origin
        break;
    }
    poses_[l] = poses_[static_cast<std::size_t>(links[l].parentLink)] * local;
  }
  dirty_ = false;
}

const Eigen::Isometry3d& Skeleton::linkPose(int link) const {
  assert(link >= 0 && link < linkCount() && "link index out of range");
  updatePoses();
  return poses_[static_cast<std::size_t>(link)];
}

Status Skeleton::linkPose(const std::string& name, Eigen::Isometry3d& pose) const {
  const int l = model_->findLink(name);
  if (l < 0)
    return Status::error(ErrorCode::UnknownLink, "no link named '" + name + "' in '" + model_->name() + "'");
  pose = linkPose(l);
  return Status::success();
}

void Skeleton::worldShapes(std::vector<WorldShape>& out) const {
  updatePoses();
  out.clear();
  const auto& links = model_->links();
  for (std::size_t l = 0; l < links.size(); ++l) {
    for (const ShapeDesc& s : shapes_[l]) {
      WorldShape w;
      w.link = static_cast<int>(l);
      w.linkName = &links[l].name;
      w.shape = &s;
      w.pose = poses_[l] * s.origin;
      out.push_back(w);
    }
  }
}

std::vector<WorldShape> Skeleton::worldShapes() const {
  std::vector<WorldShape> out;
  worldShapes(out);
  return out;
}

}  // namespace cape::character
