#include "cape/scenes/Scene.h"

#include <cmath>

namespace cape {

namespace {
constexpr double kPi = 3.14159265358979323846;

Quat yawRotation(float yaw) {
  return Quat(Eigen::AngleAxisf(yaw, Vec3::UnitY()));
}

// Torso, shoulders, legs of docs/SCENES.md, in the character frame.
const Vec3 kTorsoCentre(0.0f, 1.25f, 0.0f);
const Vec3 kTorsoHalfExtents(0.20f, 0.30f, 0.12f);
const Vec3 kShoulderCentre(0.22f, 1.52f, 0.0f);  // left shoulder is at -X (the character faces -Z)
constexpr float kShoulderRadius = 0.08f;
const Vec3 kHip(0.10f, 0.95f, 0.0f);
constexpr float kLegRadius = 0.07f;
constexpr float kLegHalfHeight = 0.40f - kLegRadius;  // total height 0.80 m including the caps
constexpr float kLegCentreBelowHip = 0.40f;
const Vec3 kPinLine(0.30f, 1.56f, 0.15f);
}  // namespace

WindSettings sceneWind(SceneKind kind) {
  WindSettings w;
  if (kind != SceneKind::Wind) return w;
  w.model = WindSettings::Model::Aerodynamic;
  w.direction = Vec3::UnitX();
  w.speed = 8.0f;
  w.gustAmplitude = 0.5f;
  w.gustFrequency = 0.5f;
  w.turbulenceScale = 2.0f;
  return w;
}

CapeSettings settingsForScene(SceneKind kind, CapeSettings settings) {
  if (settings.wind.model == WindSettings::Model::None) settings.wind = sceneWind(kind);
  return settings;
}

const char* toString(SceneKind kind) {
  switch (kind) {
    case SceneKind::Hang:
      return "hang";
    case SceneKind::Walk:
      return "walk";
    case SceneKind::SprintTurn:
      return "sprint-turn";
    case SceneKind::Wind:
      return "wind";
    case SceneKind::Crowd:
      return "crowd";
  }
  return "?";
}

bool parseSceneKind(const std::string& name, SceneKind& kind) {
  for (SceneKind k :
       {SceneKind::Hang, SceneKind::Walk, SceneKind::SprintTurn, SceneKind::Wind, SceneKind::Crowd}) {
    if (name == toString(k)) {
      kind = k;
      return true;
    }
  }
  return false;
}

const char* toString(PinLayout layout) {
  switch (layout) {
    case PinLayout::Corners:
      return "corners";
    case PinLayout::Collar:
      return "collar";
    case PinLayout::Gathered:
      return "gathered";
  }
  return "?";
}

bool parsePinLayout(const std::string& name, PinLayout& layout) {
  for (PinLayout l : {PinLayout::Corners, PinLayout::Collar, PinLayout::Gathered}) {
    if (name == toString(l)) {
      layout = l;
      return true;
    }
  }
  return false;
}

MotionDesc MotionDesc::forScene(SceneKind kind) {
  MotionDesc m;
  switch (kind) {
    case SceneKind::Hang:
      m.duration = 5.0f;
      break;
    case SceneKind::Wind:
      m.duration = 10.0f;
      break;
    case SceneKind::Walk:
    case SceneKind::Crowd:
      m.speed = 1.4f;
      m.legFrequency = 1.0f;
      m.bobAmplitude = 0.015f;  // 3 cm peak to peak
      m.bobFrequency = 2.0f;    // two bobs per stride
      m.duration = 10.0f;
      break;
    case SceneKind::SprintTurn:
      m.speed = 5.0f;
      m.legFrequency = 2.5f;
      m.bobAmplitude = 0.015f;
      m.bobFrequency = 5.0f;
      m.turns = true;
      m.duration = 10.0f;
      break;
  }
  return m;
}

Pose BodyPose::frame() const {
  Pose p;
  p.position = position + Vec3(0.0f, bob, 0.0f);
  p.rotation = yawRotation(yaw);
  return p;
}

BodyPose motionAt(const MotionDesc& m, double t) {
  BodyPose p;
  p.legAngle = static_cast<float>(m.legAmplitude * std::sin(2.0 * kPi * m.legFrequency * t));
  p.bob = static_cast<float>(m.bobAmplitude * std::sin(2.0 * kPi * m.bobFrequency * t));
  const double v = m.speed;
  // Heading yaw theta: forward = (-sin theta, 0, -cos theta). Integrated exactly, piece by piece.
  double x = 0.0, z = 0.0, yaw = 0.0;
  auto straight = [&](double duration) {
    x += -v * std::sin(yaw) * duration;
    z += -v * std::cos(yaw) * duration;
  };
  auto turn = [&](double duration, double rate) {
    // d/ds of (v / w)(cos(theta0 + w s)) = -v sin(theta0 + w s): the exact arc.
    const double y1 = yaw + rate * duration;
    x += v / rate * (std::cos(y1) - std::cos(yaw));
    z += -v / rate * (std::sin(y1) - std::sin(yaw));
    yaw = y1;
  };
  if (!m.turns) {
    straight(t);
  } else {
    const double period = m.turnPeriod, turning = m.turnDuration, rate = kPi / turning;
    const double whole = std::floor(t / period);
    for (int k = 0; k < static_cast<int>(whole); ++k) {
      straight(period - turning);
      turn(turning, rate);
    }
    const double r = t - whole * period;
    straight(std::min(r, period - turning));
    if (r > period - turning) turn(r - (period - turning), rate);
  }
  p.position = Vec3(static_cast<float>(x), 0.0f, static_cast<float>(z));
  p.yaw = static_cast<float>(std::remainder(yaw, 2.0 * kPi));
  return p;
}

SimpleBody::SimpleBody(const Vec3& offset) : offset_(offset) {
  colliders_.push_back(Collider::box(kTorsoHalfExtents));
  colliders_.back().name = "torso";
  colliders_.push_back(Collider::sphere(kShoulderRadius));
  colliders_.back().name = "left_shoulder";
  colliders_.push_back(Collider::sphere(kShoulderRadius));
  colliders_.back().name = "right_shoulder";
  colliders_.push_back(Collider::capsule(kLegRadius, kLegHalfHeight, 1));
  colliders_.back().name = "left_leg";
  colliders_.push_back(Collider::capsule(kLegRadius, kLegHalfHeight, 1));
  colliders_.back().name = "right_leg";
  colliders_.push_back(Collider::plane(Vec3::UnitY(), 0.0f));
  colliders_.back().name = "ground";
  moveTo(BodyPose(), true);
}

void SimpleBody::moveTo(const BodyPose& pose, bool teleport) {
  BodyPose shifted = pose;
  shifted.position += offset_;
  const Pose frame = shifted.frame();
  auto place = [&](int k, const Pose& local) {
    const Pose world{frame.apply(local.position), frame.rotation * local.rotation};
    if (teleport)
      colliders_[static_cast<std::size_t>(k)].teleportTo(world);
    else
      colliders_[static_cast<std::size_t>(k)].moveTo(world);
  };
  place(kTorso, Pose{kTorsoCentre, Quat::Identity()});
  place(kLeftShoulder,
        Pose{Vec3(-kShoulderCentre.x(), kShoulderCentre.y(), kShoulderCentre.z()), Quat::Identity()});
  place(kRightShoulder, Pose{kShoulderCentre, Quat::Identity()});
  for (int side = 0; side < 2; ++side) {
    const float sign = side == 0 ? -1.0f : 1.0f;  // left (-X) swings +angle, right -angle
    const float angle = side == 0 ? pose.legAngle : -pose.legAngle;
    const Quat swing(Eigen::AngleAxisf(angle, Vec3::UnitX()));
    const Vec3 hip(sign * kHip.x(), kHip.y(), kHip.z());
    place(side == 0 ? kLeftLeg : kRightLeg, Pose{hip + swing * Vec3(0.0f, -kLegCentreBelowHip, 0.0f), swing});
  }
}

Vec3 gatheredPoint(const Vec3& local, const CapeSize& size, const CollarShape& collar) {
  const float half = 0.5f * size.width;
  const float s = (local.x() - half) / half;  // -1 at the left edge, +1 at the right
  // The collar's arc at the top row, fading out linearly over the first 6 cm below it.
  const float along = std::clamp(1.0f + local.y() / 0.06f, 0.0f, 1.0f);
  return Vec3(half + (local.x() - half) * (collar.span / size.width), local.y(),
              local.z() - along * collar.wrap * s * s);
}

Vec3 gatheredLevelPoint(const Vec3& local, const CapeSize& size, const CollarShape& collar) {
  const float half = 0.5f * size.width;
  const float s = (local.x() - half) / half;  // -1 at the left edge, +1 at the right
  // Each column moved up the cape (towards its top) by the collar's wrap at its place: under the hang's
  // turn (capeStartPlacement) that is forward, as the collar's ends go, so every column's top is on the
  // collar and the column follows it straight, at its rest length.
  return Vec3(half + (local.x() - half) * (collar.span / size.width), local.y() + collar.wrap * s * s,
              local.z());
}

Vec3 gatheredStartPoint(SceneKind kind, const Vec3& local, const CapeSize& size, const CollarShape& collar) {
  return kind == SceneKind::Hang ? gatheredLevelPoint(local, size, collar)
                                 : gatheredPoint(local, size, collar);
}

CapeRig makeCapeRig(int n, PinLayout layout, bool bendSprings, const CapeSize& size, int rows,
                    float totalMass, const CollarShape& collar) {
  CapeRig rig;
  const int cols = std::max(n, 2);
  if (layout == PinLayout::Corners) {
    rig.pinnedParticles = {0u, static_cast<std::uint32_t>(cols - 1)};
  } else {
    for (int c = 0; c < cols; ++c) rig.pinnedParticles.push_back(static_cast<std::uint32_t>(c));
  }
  const float half = 0.5f * size.width;  // the canonical 0.6 gives kPinLine.x() exactly
  const Pose start = capeStartPlacement(SceneKind::Walk, size);
  for (std::uint32_t p : rig.pinnedParticles) {
    const float u = static_cast<float>(p) / static_cast<float>(cols - 1);
    if (layout == PinLayout::Gathered) {
      rig.pinLocalPoints.push_back(
          start.apply(gatheredPoint(Vec3(u * size.width, 0.0f, 0.0f), size, collar)));
    } else {
      rig.pinLocalPoints.emplace_back(-half + u * 2.0f * half, kPinLine.y(), kPinLine.z());
    }
  }
  GridDesc g;
  g.columns = n;
  g.rows = rows > 0 ? rows : n;
  g.width = 2.0f * half;
  g.height = size.height;
  // 0.4 kg on the canonical 0.6 m^2; the same mass per area on any other size (exactly 0.4 on the canonical).
  g.totalMass = totalMass > 0.0f ? totalMass : 0.4f * ((g.width * g.height) / (2.0f * kPinLine.x() * 1.0f));
  g.bendSprings = bendSprings;
  g.tetherAnchors = rig.pinnedParticles;
  rig.fabric = Fabric::grid(g).fabric;
  return rig;
}

Pose capeStartPlacement(SceneKind kind, const CapeSize& size) {
  Pose p;
  p.position = Vec3(-0.5f * size.width, kPinLine.y(), kPinLine.z());  // the grid's top-left on the left pin
  if (kind == SceneKind::Hang) {
    // Rotate the grid's -Y (down the cape) onto +Z (away from the back): -90 degrees about X.
    p.rotation = Quat(Eigen::AngleAxisf(-static_cast<float>(kPi / 2), Vec3::UnitX()));
  }
  return p;
}

SimpleScene::SimpleScene(SceneKind kind, int n, PinLayout layout, const CapeSettings& settings,
                         const Vec3& offset)
    : kind_(kind),
      motion_(MotionDesc::forScene(kind)),
      rig_(makeCapeRig(n, layout, settings.bendStiffness > 0.0f)),
      body_(offset),
      cape_(rig_.fabric, settingsForScene(kind, settings),
            Pose{offset + capeStartPlacement(kind).position, capeStartPlacement(kind).rotation}),
      offset_(offset) {
  if (!cape_.ok()) return;
  if (layout == PinLayout::Gathered) {
    // Gathered onto the collar from the start, as cape_walk starts it (BulletScene::startCape): the top row
    // on its pins, not flat at its full width and snapped onto them by the first step.
    const Pose start = capeStartPlacement(kind);
    const Pose placement{offset + start.position, start.rotation};
    const Points& rest = rig_.fabric->restPositions();
    Points& x = cape_.mutableState().positions;
    for (Eigen::Index i = 0; i < rest.rows(); ++i)
      x.row(i) = placement.apply(gatheredStartPoint(kind, rest.row(i).transpose(), CapeSize(), CollarShape()))
                     .transpose();
  }
  body_.moveTo(motionAt(motion_, 0.0), true);
  const Pose frame = [&] {
    BodyPose b = motionAt(motion_, 0.0);
    b.position += offset_;
    return b.frame();
  }();
  for (std::size_t k = 0; k < rig_.pinnedParticles.size(); ++k)
    cape_.pin(rig_.pinnedParticles[k], frame.apply(rig_.pinLocalPoints[k]));
}

void SimpleScene::advanceFrame(float dt) {
  time_ += static_cast<double>(dt);
  BodyPose pose = motionAt(motion_, time_);
  body_.moveTo(pose);
  pose.position += offset_;
  const Pose frame = pose.frame();
  for (std::size_t k = 0; k < rig_.pinnedParticles.size(); ++k)
    cape_.movePin(k, frame.apply(rig_.pinLocalPoints[k]));
  cape_.step(dt, body_.colliders());
}

}  // namespace cape
