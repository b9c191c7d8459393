// Motion clips played on a character, and the user's own motion: keyframes reproduced exactly and
// interpolated between (linear, slerp), loops without a jump, speed, start time, in place, the frames a root
// pose may be given in, spherical joints, errors that list the model's joints, and the kinematic bodies'
// velocities equal to the finite difference of their poses. Clips are made by the tests.
#include "CharacterTestWorld.h"

#include "cape/character/Character.h"
#include "cape/character/Motion.h"

#include <gtest/gtest.h>

#include <cmath>

namespace cape::character {
namespace {

constexpr double kPi = 3.14159265358979323846;

UrdfModelPtr humanoid() {
  const UrdfLoadResult r = UrdfModel::humanoid();
  EXPECT_TRUE(r.ok()) << r.status.message();
  return r.model;
}

Eigen::Quaterniond aboutZ(double a) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()));
}

// A walk-like clip of the shipped humanoid: forward along +x at `speed`, knees on a sine of period T,
// n + 1 samples over one period (the last equal to the first but for the root's advance).
MotionClip walkClip(int n = 30, double period = 1.0, double speed = 1.2, double turnPerLoop = 0.0) {
  MotionClip c;
  c.name = "walk-test";
  c.joints = {"left_knee", "right_knee", "left_hip_pitch"};
  for (int s = 0; s <= n; ++s) {
    const double t = period * s / n;
    const double p = 2.0 * kPi * t / period;
    c.times.push_back(t);
    const double yaw = turnPerLoop * t / period;
    c.rootPositions.emplace_back(speed * t, 0.0, 0.02 * std::sin(2.0 * p));
    c.rootRotations.push_back(aboutZ(yaw));
    c.values.push_back(0.6 + 0.5 * std::sin(p));
    c.values.push_back(0.6 - 0.5 * std::sin(p));
    c.values.push_back(0.4 * std::sin(p));
  }
  return c;
}

PlaybackSettings asWritten() {
  PlaybackSettings s;
  s.startAtOrigin = false;
  s.alignHeading = false;
  return s;
}

Skeleton zUp(const UrdfModelPtr& m) {
  Skeleton s(m);
  s.setUpAxis(UpAxis::Z);  // the world is the URDF frame
  return s;
}

TEST(MotionClip, CheckNamesWhatIsWrong) {
  MotionClip c = walkClip(4);
  EXPECT_TRUE(c.check().ok()) << c.check().message();
  MotionClip bad = c;
  bad.times[2] = bad.times[1];
  EXPECT_NE(bad.check().message().find("increase"), std::string::npos);
  bad = c;
  bad.values[4] = std::nan("");
  EXPECT_NE(bad.check().message().find("right_knee"), std::string::npos) << bad.check().message();
  bad = c;
  bad.rootRotations[0].coeffs() *= 2.0;
  EXPECT_NE(bad.check().message().find("unit quaternion"), std::string::npos);
  bad = c;
  bad.joints[1] = "left_knee";
  EXPECT_NE(bad.check().message().find("twice"), std::string::npos);
  bad = c;
  bad.values.pop_back();
  EXPECT_EQ(bad.check().code(), ErrorCode::InvalidArgument);
  EXPECT_FALSE(MotionClip().check().ok());
}

// A cycle wraps with no gap but the root's carried-over move and turn; half a cycle wraps with the knees'
// swing; a ball and the root's tilt count too, in the clip's frame.
TEST(MotionClip, LoopGapSaysWhereAClipThatIsNotACycleJumps) {
  EXPECT_LT(loopGap(walkClip(30, 1.0, 1.2, 0.7)).value, 1e-12);  // a turning walk: carried over
  MotionClip half = walkClip(30);
  const int keep = 16;  // t = 0 .. 0.5: the knees at 0.6 at both ends, the hip at 0 too: no gap yet
  half.times.resize(keep), half.rootPositions.resize(keep), half.rootRotations.resize(keep);
  half.values.resize(static_cast<std::size_t>(keep) * half.joints.size());
  EXPECT_LT(loopGap(half).value, 1e-9);
  half.times.pop_back(), half.rootPositions.pop_back(), half.rootRotations.pop_back();
  for (int j = 0; j < 3; ++j) half.values.pop_back();  // t = 0.467: the knees 0.5 sin(0.93 pi) = 0.10 apart
  const LoopGap g = loopGap(half);
  EXPECT_NEAR(g.value, 0.5 * std::sin(2.0 * kPi * 14.0 / 30.0), 1e-12);
  EXPECT_TRUE(g.where == "left_knee" || g.where == "right_knee") << g.where;

  MotionClip ball = walkClip(4);
  ball.balls = {"neck"};
  for (int s = 0; s < 5; ++s)
    ball.rotations.push_back(Eigen::Quaterniond(Eigen::AngleAxisd(0.2 * s, Eigen::Vector3d::UnitX())));
  EXPECT_NEAR(loopGap(ball).value, 0.8, 1e-9);
  EXPECT_EQ(loopGap(ball).where, "neck");
  MotionClip tilt = walkClip(4);
  tilt.rootRotations.back() = Eigen::Quaterniond(Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitY()));
  EXPECT_NEAR(loopGap(tilt).value, 0.5, 1e-9);
  EXPECT_EQ(loopGap(tilt).where, "root");
  tilt.frame = MotionFrame::YUp;  // about y is a heading there
  EXPECT_LT(loopGap(tilt).value, 1e-9);
  EXPECT_EQ(loopGap(MotionClip()).value, 0.0);
}

TEST(MotionPlayer, KeyframesExactlyAtTheirTimesAndInterpolatedBetween) {
  const UrdfModelPtr m = humanoid();
  const Skeleton s = zUp(m);
  MotionClip c = walkClip(10);
  c.times = {0.0, 0.1, 0.25, 0.3, 0.5, 0.6, 0.62, 0.7, 0.8, 0.95, 1.0};  // uneven on purpose
  MotionPlayer p;
  PlaybackSettings ps = asWritten();
  ps.loop = false;
  ASSERT_TRUE(MotionPlayer::create(c, s, ps, p).ok());
  MotionPose pose;
  for (int k = 0; k < c.sampleCount(); ++k) {
    p.sample(c.times[static_cast<std::size_t>(k)], pose);
    EXPECT_EQ(pose.root.translation(), c.rootPositions[static_cast<std::size_t>(k)]) << k;
    for (std::size_t j = 0; j < c.joints.size(); ++j)
      EXPECT_EQ(pose.values[j], c.values[static_cast<std::size_t>(k) * c.joints.size() + j]) << k;
  }
  // Halfway between samples 1 and 2: linear for positions and values, slerp for rotations.
  c.rootRotations[1] = aboutZ(0.2);
  c.rootRotations[2] = aboutZ(0.6);
  ASSERT_TRUE(MotionPlayer::create(c, s, ps, p).ok());
  p.sample(0.175, pose);
  EXPECT_NEAR(pose.root.translation().x(), 0.5 * (c.rootPositions[1].x() + c.rootPositions[2].x()), 1e-12);
  EXPECT_NEAR(pose.values[0], 0.5 * (c.values[3] + c.values[6]), 1e-12);
  EXPECT_NEAR(Eigen::AngleAxisd(pose.root.linear()).angle(), 0.4, 1e-12);
  // Held at the ends without looping.
  p.sample(-3.0, pose);
  EXPECT_EQ(pose.values[0], c.values[0]);
  p.sample(7.0, pose);
  EXPECT_EQ(pose.values[0], c.values[c.values.size() - 3]);
}

TEST(MotionPlayer, ALoopHasNoJumpInPositionOrVelocity) {
  const UrdfModelPtr m = humanoid();
  const Skeleton s = zUp(m);
  for (double turn : {0.0, 0.5}) {
    const MotionClip c = walkClip(60, 1.0, 1.2, turn);
    MotionPlayer p;
    ASSERT_TRUE(MotionPlayer::create(c, s, PlaybackSettings(), p).ok());
    const double dt = 1.0 / 60.0;
    MotionPose a, b, d;
    double worstJump = 0.0, worstAccel = 0.0;
    for (int f = 1; f < 60 * 5; ++f) {
      p.sample((f - 1) * dt, a);
      p.sample(f * dt, b);
      p.sample((f + 1) * dt, d);
      const Eigen::Vector3d v0 = (b.root.translation() - a.root.translation()) / dt;
      const Eigen::Vector3d v1 = (d.root.translation() - b.root.translation()) / dt;
      worstJump = std::max(worstJump, (b.root.translation() - a.root.translation()).norm());
      worstAccel = std::max(worstAccel, (v1 - v0).norm());
      EXPECT_LT(std::abs(b.values[0] - a.values[0]), 0.06) << "frame " << f;
    }
    // One frame's motion at 1.2 m/s (plus the bob) is ~2.2 cm; the velocity changes only by the bob's and
    // the turn's curvature, nothing like a jump.
    EXPECT_LT(worstJump, 1.2 * dt * 1.2) << "turn " << turn;
    EXPECT_LT(worstAccel, 0.6) << "turn " << turn;
    // Five loops on, the root has advanced five strides (in a straight line without a turn).
    p.sample(5.0, a);
    if (turn == 0.0) {
      EXPECT_NEAR(a.root.translation().x(), 6.0, 1e-9);
    }
  }
}

TEST(MotionPlayer, TurningLoopsComposeExactly) {
  const UrdfModelPtr m = humanoid();
  const Skeleton s = zUp(m);
  const MotionClip c = walkClip(20, 1.0, 1.0, 0.7);
  MotionPlayer p;
  ASSERT_TRUE(MotionPlayer::create(c, s, asWritten(), p).ok());
  MotionPose first, later;
  p.sample(0.3, first);
  // The loop's displacement D, applied k times by hand.
  Eigen::Isometry3d d = Eigen::Isometry3d::Identity();
  d.linear() = aboutZ(0.7).toRotationMatrix();
  d.translation() = Eigen::Vector3d(c.rootPositions.back().x(), c.rootPositions.back().y(), 0.0);
  Eigen::Isometry3d dk = Eigen::Isometry3d::Identity();
  for (int k = 1; k <= 7; ++k) {
    dk = dk * d;
    p.sample(0.3 + k, later);
    EXPECT_LT(((dk * first.root).translation() - later.root.translation()).norm(), 1e-9) << k;
    EXPECT_TRUE((dk * first.root).linear().isApprox(later.root.linear(), 1e-9)) << k;
  }
}

TEST(MotionPlayer, SpeedStartInPlaceAndTheOrigin) {
  const UrdfModelPtr m = humanoid();
  const Skeleton s = zUp(m);
  MotionClip c = walkClip(30);
  for (Eigen::Vector3d& r : c.rootPositions) r += Eigen::Vector3d(5.0, -3.0, 0.0);
  MotionPlayer normal, fast, late, still, origin;
  PlaybackSettings ps = asWritten();
  ASSERT_TRUE(MotionPlayer::create(c, s, ps, normal).ok());
  ps.speed = 2.0;
  ASSERT_TRUE(MotionPlayer::create(c, s, ps, fast).ok());
  ps.speed = 1.0;
  ps.startTime = 0.25;
  ASSERT_TRUE(MotionPlayer::create(c, s, ps, late).ok());
  ps.startTime = 0.0;
  ps.rootMotion = false;
  ASSERT_TRUE(MotionPlayer::create(c, s, ps, still).ok());
  ASSERT_TRUE(MotionPlayer::create(c, s, PlaybackSettings(), origin).ok());
  MotionPose a, b;
  normal.sample(0.5, a);
  fast.sample(0.25, b);
  EXPECT_EQ(a.values, b.values);
  EXPECT_EQ(a.root.translation(), b.root.translation());
  normal.sample(0.75, a);
  late.sample(0.5, b);
  EXPECT_EQ(a.values, b.values);
  for (double t : {0.2, 0.9, 3.4}) {
    still.sample(t, b);
    EXPECT_EQ(b.root.translation().x(), 5.0);
    EXPECT_EQ(b.root.translation().y(), -3.0);
  }
  origin.sample(0.0, b);
  EXPECT_NEAR(b.root.translation().head<2>().norm(), 0.0, 1e-12);
  // Bad settings.
  ps = PlaybackSettings();
  ps.speed = 0.0;
  EXPECT_EQ(MotionPlayer::create(c, s, ps, still).code(), ErrorCode::InvalidArgument);
  ps.speed = 1.0;
  ps.startTime = std::nan("");
  EXPECT_EQ(MotionPlayer::create(c, s, ps, still).code(), ErrorCode::InvalidArgument);
}

TEST(MotionPlayer, UnknownJointsAreErrorsListingTheModelsJoints) {
  const UrdfModelPtr m = humanoid();
  const Skeleton s = zUp(m);
  MotionClip c = walkClip(4);
  c.joints[1] = "knee_of_nobody";
  MotionPlayer p;
  const Status st = MotionPlayer::create(c, s, PlaybackSettings(), p);
  EXPECT_EQ(st.code(), ErrorCode::UnknownJoint);
  EXPECT_NE(st.message().find("knee_of_nobody"), std::string::npos);
  EXPECT_NE(st.message().find("left_elbow"), std::string::npos) << st.message();
  c.joints[1] = "pelvis_joint";  // fixed
  EXPECT_EQ(MotionPlayer::create(c, s, PlaybackSettings(), p).code(), ErrorCode::NotMovable);
  c = walkClip(4);
  c.balls = {"neck"};  // not spherical
  c.rotations.assign(c.times.size(), Eigen::Quaterniond::Identity());
  EXPECT_EQ(MotionPlayer::create(c, s, PlaybackSettings(), p).code(), ErrorCode::NotMovable);
}

// A small Y-up model (x forward, y up, as PyBullet's DeepMimic humanoid): a root, a spherical joint 1 m up
// to a chest, and a revolute elbow-like joint about z.
const char* kYUpModel = R"(<robot name="yup">
  <link name="base"><collision><geometry><sphere radius="0.1"/></geometry></collision></link>
  <link name="chest"><collision><origin xyz="0 0.3 0"/><geometry><sphere radius="0.2"/></geometry></collision></link>
  <link name="hand"><collision><geometry><sphere radius="0.05"/></geometry></collision></link>
  <joint name="chest" type="spherical"><parent link="base"/><child link="chest"/><origin xyz="0 1 0"/></joint>
  <joint name="elbow" type="revolute"><parent link="chest"/><child link="hand"/><origin xyz="0.5 0 0"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
</robot>)";

TEST(MotionFrames, SphericalJointsAndAYUpRootLandWhereTheFilesWorldSays) {
  // The file's world: root at p with rotation R, the chest turned by q, the elbow by e. Where the hand goes
  // there, turned onto z (+90 degrees about x), is where it must go in the URDF frame, whether or not the
  // loader turned the model.
  const Eigen::Vector3d p(0.3, 0.9, -0.2);
  const Eigen::Quaterniond R(Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.2, 1.0, 0.1).normalized()));
  const Eigen::Quaterniond q(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1.0, 0.3, -0.5).normalized()));
  const double e = 0.9;
  const Eigen::Vector3d handInFile = p + R * (Eigen::Vector3d(0, 1, 0) + q * (Eigen::Vector3d(0.5, 0, 0)));
  const Eigen::Vector3d expected = Eigen::AngleAxisd(0.5 * kPi, Eigen::Vector3d::UnitX()) * handInFile;
  (void)e;
  for (UrdfLoadOptions::Up up : {UrdfLoadOptions::Up::Y, UrdfLoadOptions::Up::Z}) {
    UrdfLoadOptions o;
    o.modelUp = up;
    const UrdfLoadResult r = UrdfModel::fromString(kYUpModel, o);
    ASSERT_TRUE(r.ok()) << r.status.message();
    EXPECT_EQ(r.model->turnedOntoZ(), up == UrdfLoadOptions::Up::Y);
    EXPECT_EQ(r.model->joints()[static_cast<std::size_t>(r.model->findJoint("chest"))].type,
              JointType::Spherical);
    MotionClip c;
    c.name = "yup";
    c.frame = MotionFrame::YUp;
    c.times = {0.0, 1.0};
    c.rootPositions = {p, p};
    c.rootRotations = {R, R};
    c.balls = {"chest"};
    c.rotations = {q, q};
    c.joints = {"elbow"};
    c.values = {e, e};
    Skeleton s = zUp(r.model);
    MotionPlayer player;
    ASSERT_TRUE(MotionPlayer::create(c, s, asWritten(), player).ok());
    MotionPose pose;
    player.sample(0.5, pose);
    s.setRootLinkPose(pose.root);
    ASSERT_TRUE(s.setJointRotation("chest", pose.rotations[0]).ok());
    ASSERT_TRUE(s.setJointPosition("elbow", pose.values[0]).ok());
    const Eigen::Vector3d hand = s.linkPose(r.model->findLink("hand")).translation();
    EXPECT_LT((hand - expected).norm(), 1e-12) << "model up " << static_cast<int>(up);
  }
}

TEST(MotionFrames, WorldUrdfAndBothUpAxesAgree) {
  const UrdfModelPtr m = humanoid();
  Eigen::Isometry3d root = Eigen::Isometry3d::Identity();
  root.linear() = aboutZ(0.8).toRotationMatrix();
  root.translation() = Eigen::Vector3d(1.0, -2.0, 0.05);
  Skeleton z(m), y(m);
  z.setUpAxis(UpAxis::Z);
  z.setRootLinkPose(urdfFrameToWorld(root, UpAxis::Z));
  y.setRootLinkPose(urdfFrameToWorld(root, UpAxis::Y));
  for (int l = 0; l < z.linkCount(); ++l) {
    EXPECT_LT((Skeleton::urdfToWorld() * z.linkPose(l).translation() - y.linkPose(l).translation()).norm(),
              1e-12);
  }
  EXPECT_LT((z.linkPose(0).matrix() - root.matrix()).norm(), 1e-12);
  // A World pose in a Y-up world is the URDF pose turned by urdfToWorld.
  const Eigen::Isometry3d back =
      rootPoseToUrdfFrame(urdfFrameToWorld(root, UpAxis::Y), MotionFrame::World, y);
  EXPECT_LT((back.matrix() - root.matrix()).norm(), 1e-12);
}

TEST(CharacterMotion, SetMotionMovesTheBodiesWithTheVelocitiesOfTheirPoses) {
  const UrdfModelPtr m = humanoid();
  for (UpAxis up : {UpAxis::Y, UpAxis::Z}) {
    capetest::World w;
    CharacterSettings cs;
    cs.up = up;
    CharacterResult made = Character::create(m, w.world, Gait::forScene(SceneKind::Hang), cs);
    ASSERT_TRUE(made.ok()) << made.status.message();
    Character& c = *made.character;
    Eigen::Isometry3d root = Eigen::Isometry3d::Identity();
    ASSERT_TRUE(c.setMotion(0.0, root, {{"left_knee", 0.2}}, {}, MotionFrame::Urdf).ok());
    const int shin = m->findLink("left_shin");
    ASSERT_GE(shin, 0);
    btRigidBody* body = c.bodies().bodyForLink(shin);
    ASSERT_NE(body, nullptr);
    const btTransform before = body->getWorldTransform();
    double right = 0.0;
    ASSERT_TRUE(c.skeleton().jointPosition("right_knee", right).ok());
    const double dt = 1.0 / 60.0;
    root.translation() = Eigen::Vector3d(0.03, 0.01, 0.002);
    root.linear() = aboutZ(0.05).toRotationMatrix();
    ASSERT_TRUE(
        c.setMotion(dt, root, {{"left_knee", 0.35}, {"left_hip_pitch", 0.1}}, {}, MotionFrame::Urdf).ok());
    const btTransform after = body->getWorldTransform();
    btVector3 v, wv;
    btTransformUtil::calculateVelocity(before, after, btScalar(dt), v, wv);
    EXPECT_LT((body->getLinearVelocity() - v).length(), 1e-4);
    EXPECT_LT((body->getAngularVelocity() - wv).length(), 1e-4);
    EXPECT_GT(v.length(), 0.5);  // it did move
    double kept = 0.0;
    ASSERT_TRUE(c.skeleton().jointPosition("right_knee", kept).ok());
    EXPECT_EQ(kept, right);  // a joint not given keeps its value
    // The root link is where it was put (in the world of the up axis).
    const Eigen::Isometry3d want = urdfFrameToWorld(root, up);
    EXPECT_LT((c.skeleton().linkPose(0).matrix() - want.matrix()).norm(), 1e-12);
  }
}

TEST(CharacterMotion, ErrorsListTheJointsAndChangeNothing) {
  const UrdfModelPtr m = humanoid();
  capetest::World w;
  CharacterResult made = Character::create(m, w.world, Gait::forScene(SceneKind::Hang));
  ASSERT_TRUE(made.ok());
  Character& c = *made.character;
  const Eigen::Isometry3d before = c.skeleton().linkPose(0);
  double knee = 0.0;
  ASSERT_TRUE(c.skeleton().jointPosition("left_knee", knee).ok());
  Eigen::Isometry3d moved = Eigen::Isometry3d::Identity();
  moved.translation().x() = 1.0;
  Status s = c.setMotion(0.1, moved, {{"left_knee", 1.0}, {"tail", 0.3}});
  EXPECT_EQ(s.code(), ErrorCode::UnknownJoint);
  EXPECT_NE(s.message().find("tail"), std::string::npos);
  EXPECT_NE(s.message().find("right_hip_pitch"), std::string::npos) << s.message();
  EXPECT_EQ(c.setMotion(0.1, moved, {{"pelvis_joint", 1.0}}).code(), ErrorCode::NotMovable);
  EXPECT_EQ(c.setMotion(0.1, moved, {{"left_knee", 1.0}, {"left_knee", 0.5}}).code(),
            ErrorCode::InvalidArgument);
  EXPECT_EQ(c.setMotion(0.1, moved, {{"left_knee", std::nan("")}}).code(), ErrorCode::InvalidArgument);
  EXPECT_EQ(c.setMotion(0.1, moved, {}, {{"left_knee", Eigen::Quaterniond::Identity()}}).code(),
            ErrorCode::NotMovable);
  Eigen::Isometry3d broken = moved;
  broken.translation().y() = std::numeric_limits<double>::infinity();
  EXPECT_EQ(c.setMotion(0.1, broken).code(), ErrorCode::InvalidArgument);
  EXPECT_EQ(c.setMotion(std::nan(""), moved).code(), ErrorCode::InvalidArgument);
  double after = 0.0;
  ASSERT_TRUE(c.skeleton().jointPosition("left_knee", after).ok());
  EXPECT_EQ(after, knee);
  EXPECT_TRUE(c.skeleton().linkPose(0).isApprox(before));
  EXPECT_EQ(c.time(), 0.0);
  // Values outside the limits are clamped (the knee bends 0 to 2.3 rad).
  ASSERT_TRUE(c.setMotion(0.1, moved, {{"left_knee", 9.0}}).ok());
  ASSERT_TRUE(c.skeleton().jointPosition("left_knee", after).ok());
  EXPECT_EQ(after, 2.3);
}

TEST(CharacterMotion, PlayingAClipEqualsSettingItsPoses) {
  const UrdfModelPtr m = humanoid();
  capetest::World w1, w2;
  CharacterResult a = Character::create(m, w1.world, Gait::forScene(SceneKind::Hang));
  CharacterResult b = Character::create(m, w2.world, Gait::forScene(SceneKind::Hang));
  ASSERT_TRUE(a.ok() && b.ok());
  const MotionClip clip = walkClip(30);
  MotionPlayer p;
  ASSERT_TRUE(MotionPlayer::create(clip, a.character->skeleton(), PlaybackSettings(), p).ok());
  MotionPose pose;
  for (int f = 0; f <= 90; ++f) {
    const double t = f / 60.0;
    ASSERT_TRUE(a.character->play(p, t).ok());
    p.sample(t, pose);
    JointPose joints;
    for (std::size_t j = 0; j < clip.joints.size(); ++j) joints.emplace_back(clip.joints[j], pose.values[j]);
    ASSERT_TRUE(b.character->setMotion(t, pose.root, joints, {}, MotionFrame::Urdf).ok());
  }
  for (int l = 0; l < a.character->skeleton().linkCount(); ++l)
    EXPECT_EQ(a.character->skeleton().linkPose(l).matrix(), b.character->skeleton().linkPose(l).matrix());
  // A player bound to another model is refused.
  const UrdfLoadResult other = UrdfModel::humanoid();
  capetest::World w3;
  CharacterResult c = Character::create(other.model, w3.world, Gait::forScene(SceneKind::Hang));
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(c.character->play(p, 0.1).code(), ErrorCode::InvalidArgument);
}

}  // namespace
}  // namespace cape::character
