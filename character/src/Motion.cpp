// Motion clips: checking, binding to a skeleton, frames, and sampling with loops, speed and root motion.
#include "cape/character/Motion.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <unordered_set>

namespace cape::character {

namespace {

constexpr double kPi = 3.14159265358979323846;

bool finite(const Eigen::Vector3d& v) {
  return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z());
}

bool unitish(const Eigen::Quaterniond& q) {
  const double n = q.norm();
  return std::isfinite(n) && std::abs(n - 1.0) <= 1e-3;
}

Status bad(const MotionClip& clip, const std::string& what) {
  return Status::error(ErrorCode::InvalidArgument, "motion clip '" + clip.name + "': " + what);
}

// The (+90 degree about x) turn taking a Y-up tool's axes (x forward, y up, z right) onto the URDF's.
Eigen::Matrix3d yUpToUrdf() {
  return Eigen::AngleAxisd(0.5 * kPi, Eigen::Vector3d::UnitX()).toRotationMatrix();
}

std::string jointsOfKind(const UrdfModel& model, bool spherical) {
  std::string out;
  for (const JointDesc& j : model.joints()) {
    if (spherical ? j.isSpherical() : j.isMovable()) out += (out.empty() ? "" : ", ") + j.name;
  }
  return out.empty() ? std::string("none") : out;
}

double wrapAngle(double a) {
  a = std::fmod(a + kPi, 2.0 * kPi);
  if (a < 0.0) a += 2.0 * kPi;
  return a - kPi;
}

}  // namespace

const char* toString(MotionFrame frame) {
  switch (frame) {
    case MotionFrame::Urdf:
      return "urdf";
    case MotionFrame::World:
      return "world";
    case MotionFrame::YUp:
      return "y-up";
  }
  return "unknown";
}

double headingAboutZ(const Eigen::Quaterniond& q) {
  const Eigen::Vector3d x = q * Eigen::Vector3d::UnitX();
  if (x.x() * x.x() + x.y() * x.y() < 1e-12) {
    // Facing straight up or down: the heading of its y axis instead (turned back by 90 degrees).
    const Eigen::Vector3d y = q * Eigen::Vector3d::UnitY();
    return std::atan2(y.y(), y.x()) - 0.5 * kPi;
  }
  return std::atan2(x.y(), x.x());
}

Status MotionClip::check() const {
  const std::size_t n = times.size();
  if (n == 0) return bad(*this, "no samples");
  if (rootPositions.size() != n || rootRotations.size() != n)
    return bad(*this, "root positions and rotations must number one per sample");
  if (values.size() != n * joints.size()) return bad(*this, "values must number samples x joints");
  if (rotations.size() != n * balls.size()) return bad(*this, "rotations must number samples x balls");
  std::unordered_set<std::string> names;
  for (const std::string& j : joints) {
    if (j.empty()) return bad(*this, "a joint has no name");
    if (!names.insert(j).second) return bad(*this, "joint '" + j + "' is given twice");
  }
  for (const std::string& b : balls) {
    if (b.empty()) return bad(*this, "a joint has no name");
    if (!names.insert(b).second) return bad(*this, "joint '" + b + "' is given twice");
  }
  for (std::size_t s = 0; s < n; ++s) {
    const std::string at = "sample " + std::to_string(s);
    if (!std::isfinite(times[s]) || times[s] < 0.0) return bad(*this, at + ": time not finite or negative");
    if (s > 0 && !(times[s] > times[s - 1])) return bad(*this, at + ": times must increase strictly");
    if (!finite(rootPositions[s])) return bad(*this, at + ": root position not finite");
    if (!unitish(rootRotations[s])) return bad(*this, at + ": root rotation not a unit quaternion");
  }
  for (std::size_t k = 0; k < values.size(); ++k) {
    if (!std::isfinite(values[k]))
      return bad(*this, "sample " + std::to_string(k / joints.size()) + ": joint '" +
                            joints[k % joints.size()] + "' not finite");
  }
  for (std::size_t k = 0; k < rotations.size(); ++k) {
    if (!unitish(rotations[k]))
      return bad(*this, "sample " + std::to_string(k / balls.size()) + ": joint '" + balls[k % balls.size()] +
                            "' not a unit quaternion");
  }
  return Status::success();
}

Eigen::Isometry3d rootPoseToUrdfFrame(const Eigen::Isometry3d& pose, MotionFrame frame,
                                      const Skeleton& skeleton) {
  Eigen::Isometry3d out = pose;
  switch (frame) {
    case MotionFrame::Urdf:
      break;
    case MotionFrame::World: {
      // The Z-up world is the URDF frame; the Y-up world is it turned by urdfToWorld().
      if (skeleton.upAxis() == UpAxis::Y) {
        const Eigen::Matrix3d w = Skeleton::urdfToWorld().transpose();
        out.linear() = w * pose.linear();
        out.translation() = w * pose.translation();
      }
      break;
    }
    case MotionFrame::YUp: {
      const Eigen::Matrix3d turn = yUpToUrdf();
      out.translation() = turn * pose.translation();
      // A model turned onto z at load has its contents turned below the root link: the file's root rotation
      // R becomes turn R turn^-1, so that every link lands where the file's world put it, turned.
      out.linear() = skeleton.model().turnedOntoZ() ? Eigen::Matrix3d(turn * pose.linear() * turn.transpose())
                                                    : Eigen::Matrix3d(turn * pose.linear());
      break;
    }
  }
  return out;
}

Eigen::Isometry3d urdfFrameToWorld(const Eigen::Isometry3d& pose, UpAxis up) {
  if (up == UpAxis::Z) return pose;
  Eigen::Isometry3d out = pose;
  const Eigen::Matrix3d w = Skeleton::urdfToWorld();
  out.linear() = w * pose.linear();
  out.translation() = w * pose.translation();
  return out;
}

Status MotionPlayer::create(const MotionClip& clip, const Skeleton& skeleton,
                            const PlaybackSettings& settings, MotionPlayer& out) {
  Status s = clip.check();
  if (!s.ok()) return s;
  if (!std::isfinite(settings.speed) || settings.speed <= 0.0) {
    std::ostringstream msg;
    msg << "playback speed must be finite and > 0, got " << settings.speed;
    return Status::error(ErrorCode::InvalidArgument, msg.str());
  }
  if (!std::isfinite(settings.startTime)) {
    return Status::error(ErrorCode::InvalidArgument, "playback start time must be finite");
  }
  const UrdfModel& model = skeleton.model();
  MotionPlayer p;
  for (const std::string& name : clip.joints) {
    const int j = model.findJoint(name);
    if (j < 0) {
      return Status::error(ErrorCode::UnknownJoint,
                           "motion clip '" + clip.name + "': no joint named '" + name + "' in '" +
                               model.name() + "' (its movable joints: " + jointsOfKind(model, false) + ")");
    }
    const JointDesc& joint = model.joints()[static_cast<std::size_t>(j)];
    if (!joint.isMovable()) {
      return Status::error(ErrorCode::NotMovable,
                           "motion clip '" + clip.name + "': joint '" + name + "' is " +
                               toString(joint.type) + " and takes no single value (movable joints of '" +
                               model.name() + "': " + jointsOfKind(model, false) + ")");
    }
    p.jointIndex_.push_back(j);
  }
  for (const std::string& name : clip.balls) {
    const int j = model.findJoint(name);
    if (j < 0) {
      return Status::error(ErrorCode::UnknownJoint,
                           "motion clip '" + clip.name + "': no joint named '" + name + "' in '" +
                               model.name() + "' (its spherical joints: " + jointsOfKind(model, true) + ")");
    }
    const JointDesc& joint = model.joints()[static_cast<std::size_t>(j)];
    if (!joint.isSpherical()) {
      return Status::error(ErrorCode::NotMovable, "motion clip '" + clip.name + "': joint '" + name +
                                                      "' is " + toString(joint.type) +
                                                      ", not spherical, and takes no rotation (spherical "
                                                      "joints of '" +
                                                      model.name() + "': " + jointsOfKind(model, true) + ")");
    }
    p.ballIndex_.push_back(j);
  }

  p.model_ = skeleton.modelPtr();
  p.clip_ = clip;
  p.settings_ = settings;
  MotionClip& c = p.clip_;
  const double t0 = c.times.front();
  for (double& t : c.times) t -= t0;
  for (std::size_t k = 0; k < c.times.size(); ++k) {
    Eigen::Isometry3d root = Eigen::Isometry3d::Identity();
    root.linear() = c.rootRotations[k].normalized().toRotationMatrix();
    root.translation() = c.rootPositions[k];
    root = rootPoseToUrdfFrame(root, c.frame, skeleton);
    c.rootPositions[k] = root.translation();
    c.rootRotations[k] = Eigen::Quaterniond(root.linear()).normalized();
  }
  for (Eigen::Quaterniond& q : c.rotations) q.normalize();
  c.frame = MotionFrame::Urdf;
  if (settings.alignHeading) {
    const Eigen::Quaterniond turn(
        Eigen::AngleAxisd(-headingAboutZ(c.rootRotations.front()), Eigen::Vector3d::UnitZ()));
    const Eigen::Vector3d pivot(c.rootPositions.front().x(), c.rootPositions.front().y(), 0.0);
    for (std::size_t k = 0; k < c.times.size(); ++k) {
      c.rootPositions[k] = pivot + turn * (c.rootPositions[k] - pivot);
      c.rootRotations[k] = (turn * c.rootRotations[k]).normalized();
    }
  }

  // The loop's displacement: the first sample's horizontal place and heading onto the last's.
  const Eigen::Vector3d first(c.rootPositions.front().x(), c.rootPositions.front().y(), 0.0);
  const Eigen::Vector3d last(c.rootPositions.back().x(), c.rootPositions.back().y(), 0.0);
  p.loopYaw_ = wrapAngle(headingAboutZ(c.rootRotations.back()) - headingAboutZ(c.rootRotations.front()));
  Eigen::Isometry3d d = Eigen::Isometry3d::Identity();
  d.linear() = Eigen::AngleAxisd(p.loopYaw_, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  d.translation() = (settings.rootMotion ? last : first) - d.linear() * first;
  p.loopStep_ = d;
  p.shift_ = settings.startAtOrigin ? Eigen::Vector3d(-first) : Eigen::Vector3d::Zero();
  out = std::move(p);
  return Status::success();
}

double MotionPlayer::clipTime(double t, long long* loops) const {
  const double c = settings_.startTime + settings_.speed * t;
  const double T = clip_.duration();
  long long k = 0;
  double u = c;
  if (T <= 0.0) {
    u = 0.0;
  } else if (settings_.loop) {
    const double cycles = std::floor(c / T);
    // Far beyond any run (2^53 loops) a loop count is no longer exact: held there.
    const double held = std::clamp(cycles, -9.0e15, 9.0e15);
    k = static_cast<long long>(held);
    u = std::clamp(c - held * T, 0.0, T);
  } else {
    u = std::clamp(c, 0.0, T);
  }
  if (loops) *loops = k;
  return u;
}

void MotionPlayer::sampleAt(double u, MotionPose& out) const {
  const MotionClip& c = clip_;
  const std::size_t n = c.times.size();
  const std::size_t nj = c.joints.size(), nb = c.balls.size();
  out.values.resize(nj);
  out.rotations.resize(nb);
  // The interval [times[a], times[a + 1]] holding u.
  std::size_t a = 0;
  double f = 0.0;
  if (n > 1) {
    const auto it = std::upper_bound(c.times.begin(), c.times.end(), u);
    a = it == c.times.begin() ? 0 : static_cast<std::size_t>(it - c.times.begin()) - 1;
    if (a >= n - 1) {
      a = n - 2;
      f = 1.0;
    } else {
      f = std::clamp((u - c.times[a]) / (c.times[a + 1] - c.times[a]), 0.0, 1.0);
    }
  }
  const std::size_t b = n > 1 ? a + 1 : a;
  // Exactly the keyframe at its time (f = 0 or 1), linear between.
  auto lerp = [f](double x, double y) { return f == 0.0 ? x : f == 1.0 ? y : x + f * (y - x); };
  const Eigen::Vector3d& pa = c.rootPositions[a];
  const Eigen::Vector3d& pb = c.rootPositions[b];
  const Eigen::Vector3d pos(lerp(pa.x(), pb.x()), lerp(pa.y(), pb.y()), lerp(pa.z(), pb.z()));
  const Eigen::Quaterniond rot = f == 0.0   ? c.rootRotations[a]
                                 : f == 1.0 ? c.rootRotations[b]
                                            : c.rootRotations[a].slerp(f, c.rootRotations[b]);
  out.root.setIdentity();
  out.root.linear() = rot.toRotationMatrix();
  out.root.translation() = pos;
  for (std::size_t j = 0; j < nj; ++j) out.values[j] = lerp(c.values[a * nj + j], c.values[b * nj + j]);
  for (std::size_t k = 0; k < nb; ++k) {
    const Eigen::Quaterniond& qa = c.rotations[a * nb + k];
    const Eigen::Quaterniond& qb = c.rotations[b * nb + k];
    out.rotations[k] = f == 0.0 ? qa : f == 1.0 ? qb : qa.slerp(f, qb);
  }
}

void MotionPlayer::sample(double t, MotionPose& out) const {
  long long k = 0;
  const double u = clipTime(t, &k);
  sampleAt(u, out);
  if (!settings_.rootMotion) {
    out.root.translation().x() = clip_.rootPositions.front().x();
    out.root.translation().y() = clip_.rootPositions.front().y();
  }
  if (k != 0) {
    // D^k: D turns by loopYaw about a centre (or, without a turn, moves by its translation), so its k-th
    // power is a turn by k loopYaw about the same centre (or k times the move): exact for any k.
    const Eigen::Vector3d t1 = loopStep_.translation();
    const double kd = static_cast<double>(k);
    Eigen::Isometry3d dk = Eigen::Isometry3d::Identity();
    if (std::abs(loopYaw_) < 1e-12) {
      dk.translation() = kd * t1;
    } else {
      // Centre c with c = R c + t (in the ground plane).
      const Eigen::Matrix2d r = loopStep_.linear().topLeftCorner<2, 2>();
      const Eigen::Vector2d centre = (Eigen::Matrix2d::Identity() - r).inverse() * t1.head<2>();
      const double angle = std::fmod(kd * loopYaw_, 2.0 * kPi);
      const Eigen::Matrix3d rk = Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      dk.linear() = rk;
      const Eigen::Vector3d c3(centre.x(), centre.y(), 0.0);
      dk.translation() = c3 - rk * c3;
    }
    out.root = dk * out.root;
  }
  out.root.translation() += shift_;
}

LoopGap loopGap(const MotionClip& clip) {
  LoopGap gap;
  const std::size_t n = clip.times.size();
  if (n < 2 || clip.values.size() != n * clip.joints.size() ||
      clip.rotations.size() != n * clip.balls.size() || clip.rootRotations.size() != n)
    return gap;
  const auto consider = [&](double value, const std::string& where) {
    if (value > gap.value) gap = {value, where};
  };
  const std::size_t last = n - 1, joints = clip.joints.size(), balls = clip.balls.size();
  for (std::size_t j = 0; j < joints; ++j)
    consider(std::abs(clip.values[last * joints + j] - clip.values[j]), clip.joints[j]);
  for (std::size_t b = 0; b < balls; ++b)
    consider(clip.rotations[last * balls + b].angularDistance(clip.rotations[b]), clip.balls[b]);
  if (clip.frame != MotionFrame::World) {  // a World clip's up axis is the character's: not known here
    const Eigen::Vector3d up =
        clip.frame == MotionFrame::YUp ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitZ();
    const double tilt = (clip.rootRotations[last] * up).dot(clip.rootRotations[0] * up);
    consider(std::acos(std::clamp(tilt, -1.0, 1.0)), "root");
  }
  return gap;
}

}  // namespace cape::character
