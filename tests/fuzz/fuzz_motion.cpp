// Fuzz target: a motion clip file, as a user hands it to the loaders of MotionFormats.h, then the clip played
// on the shipped humanoid. Input: byte 0 picks the loader and its options, the rest is the file text.
//   bits 0-1:        0 parseMotionCsv, 1 parseDeepMimic, 2 parseBvh onto UrdfModel::humanoid(), 3 onto a
//                    model of the DeepMimic humanoid's ball joints (Y-up, turned), where DeepMimic clips play
//   bits 2-3:        CSV: the root frame (Urdf, World, YUp); BVH: the scale (0 a guess, 0.01, 1, 0.0254)
//   bits 4-5:        BVH: the up axis (Auto, Y, Z; 3 is Auto)
//   bit 6:           BVH: scaleRootToLegs off; every format: playback in place (rootMotion off)
//   bit 7:           the loader's loop flag off (CSV, BVH) and playback without looping
// Small MotionLimits keep a run fast. A loader must return ok or an error with a message. A clip must pass
// check(); a CSV clip must come back bit for bit through writeMotionCsv and parseMotionCsv; and a clip that
// binds to the humanoid (MotionPlayer::create; other joints are an error, fine) must sample to finite
// numbers and unit rotations at any time, before the start, past the end and far away.
#include "FuzzSupport.h"

#include "cape/character/Motion.h"
#include "cape/character/MotionFormats.h"
#include "cape/character/Skeleton.h"
#include "cape/character/Urdf.h"

#include <Eigen/Geometry>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace {

using namespace cape::character;

const UrdfModelPtr& humanoidModel() {
  static const UrdfModelPtr model = [] {
    const UrdfLoadResult loaded = UrdfModel::humanoid();
    if (!loaded.ok()) capefuzz::broken("humanoidModel", "the shipped humanoid: " + loaded.status.message());
    return loaded.model;
  }();
  return model;
}

const Skeleton& humanoidSkeleton() {
  static const Skeleton skeleton(humanoidModel());
  return skeleton;
}

// PyBullet's DeepMimic humanoid's joints (the names and kinds a DeepMimic file drives: ball joints, knees and
// elbows about z), in a small Y-up model loaded turned onto z, so DeepMimic clips play too.
const UrdfModelPtr& ballModel() {
  static const UrdfModelPtr model = [] {
    std::string urdf =
        "<robot name='dm'><link name='base'/><joint name='root' type='fixed'><parent link='base'/>"
        "<child link='root'/></joint><link name='root'/>";
    const auto joint = [&](const std::string& name, const char* type, const char* parent, const char* xyz) {
      urdf += "<joint name='" + name + "' type='" + type + "'><parent link='" + parent + "'/><child link='" +
              name + "'/><origin xyz='" + xyz + "'/>" +
              (std::string(type) == "revolute"
                   ? "<axis xyz='0 0 1'/><limit lower='-3.14' upper='3.14' effort='1' velocity='1'/>"
                   : "") +
              "</joint><link name='" + name + "'><collision><geometry><sphere radius='0.05'/></geometry>" +
              "</collision></link>";
    };
    joint("chest", "spherical", "root", "0 0.24 0");
    joint("neck", "spherical", "chest", "0 0.22 0");
    for (const std::string side : {"right", "left"}) {
      const char* z = side == "right" ? "0 0 0.08" : "0 0 -0.08";
      joint(side + "_hip", "spherical", "root", z);
      joint(side + "_knee", "revolute", (side + "_hip").c_str(), "0 -0.42 0");
      joint(side + "_ankle", "spherical", (side + "_knee").c_str(), "0 -0.41 0");
      joint(side + "_shoulder", "spherical", "chest", z);
      joint(side + "_elbow", "revolute", (side + "_shoulder").c_str(), "0 -0.27 0");
    }
    urdf += "</robot>";
    UrdfLoadOptions options;
    options.modelUp = UrdfLoadOptions::Up::Y;
    const UrdfLoadResult loaded = UrdfModel::fromString(urdf, options);
    if (!loaded.ok()) capefuzz::broken("ballModel", "the ball-jointed model: " + loaded.status.message());
    return loaded.model;
  }();
  return model;
}

const Skeleton& ballSkeleton() {
  static const Skeleton skeleton(ballModel());
  return skeleton;
}

MotionLimits smallLimits() {
  MotionLimits limits;
  limits.maxFileBytes = std::size_t(1) << 20;
  limits.maxSamples = 4000;
  limits.maxJoints = 200;
  limits.maxDepth = 64;
  return limits;
}

bool sameBits(double a, double b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

bool sameBits(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return sameBits(a.x(), b.x()) && sameBits(a.y(), b.y()) && sameBits(a.z(), b.z()) && sameBits(a.w(), b.w());
}

// writeMotionCsv then parseMotionCsv gives the clip back, bit for bit (MotionFormats.h: 17 digits).
void checkCsvRoundTrip(const MotionClip& clip, const CsvMotionOptions& options) {
  const std::string text = writeMotionCsv(clip);
  const MotionClipResult again = parseMotionCsv(text, options, clip.name);
  CAPE_FUZZ_CHECK(again.ok(), "the written CSV does not read back: " + again.status.message());
  const MotionClip& b = again.clip;
  CAPE_FUZZ_CHECK(b.times.size() == clip.times.size(), "the written CSV reads back another sample count");
  CAPE_FUZZ_CHECK(b.joints == clip.joints && b.balls == clip.balls,
                  "the written CSV reads back other joints");
  CAPE_FUZZ_CHECK(b.values.size() == clip.values.size() && b.rotations.size() == clip.rotations.size(),
                  "the written CSV reads back other array sizes");
  for (std::size_t s = 0; s < clip.times.size(); ++s) {
    const std::string at = "sample " + std::to_string(s);
    CAPE_FUZZ_CHECK(sameBits(b.times[s], clip.times[s]), at + ": the time changed through the CSV");
    for (int k = 0; k < 3; ++k)
      CAPE_FUZZ_CHECK(sameBits(b.rootPositions[s][k], clip.rootPositions[s][k]),
                      at + ": the root position changed through the CSV");
    CAPE_FUZZ_CHECK(sameBits(b.rootRotations[s], clip.rootRotations[s]),
                    at + ": the root rotation changed through the CSV");
  }
  for (std::size_t k = 0; k < clip.values.size(); ++k)
    CAPE_FUZZ_CHECK(sameBits(b.values[k], clip.values[k]), "a joint value changed through the CSV");
  for (std::size_t k = 0; k < clip.rotations.size(); ++k)
    CAPE_FUZZ_CHECK(sameBits(b.rotations[k], clip.rotations[k]), "a ball rotation changed through the CSV");
}

bool finite(const Eigen::Quaterniond& q) {
  return std::isfinite(q.x()) && std::isfinite(q.y()) && std::isfinite(q.z()) && std::isfinite(q.w());
}

void checkPose(const MotionPose& pose, const MotionPlayer& player, double t) {
  const std::string at = "t = " + std::to_string(t);
  const Eigen::Matrix4d& m = pose.root.matrix();
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c)
      CAPE_FUZZ_CHECK(std::isfinite(m(r, c)), at + ": a root pose entry not finite");
  const Eigen::Matrix3d r = pose.root.linear();
  CAPE_FUZZ_CHECK((r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() <= 1e-6,
                  at + ": the root rotation is not a rotation");
  CAPE_FUZZ_CHECK(pose.values.size() == player.jointIndices().size(),
                  at + ": joint values of the wrong count");
  CAPE_FUZZ_CHECK(pose.rotations.size() == player.ballIndices().size(),
                  at + ": rotations of the wrong count");
  for (double v : pose.values) CAPE_FUZZ_CHECK(std::isfinite(v), at + ": a joint value not finite");
  for (const Eigen::Quaterniond& q : pose.rotations) {
    CAPE_FUZZ_CHECK(finite(q), at + ": a ball rotation not finite");
    CAPE_FUZZ_CHECK(std::abs(q.norm() - 1.0) <= 1e-6, at + ": a ball rotation not unit");
  }
  long long loops = 0;
  const double c = player.clipTime(t, &loops);
  CAPE_FUZZ_CHECK(std::isfinite(c) && c >= 0.0 && c <= player.duration(), at + ": clip time out of range");
}

void play(const MotionClip& clip, const Skeleton& skeleton, bool loop, bool rootMotion) {
  PlaybackSettings settings;
  settings.loop = loop;
  settings.rootMotion = rootMotion;
  MotionPlayer player;
  const Status bound = MotionPlayer::create(clip, skeleton, settings, player);
  if (!bound.ok()) {
    CAPE_FUZZ_CHECK(!bound.message().empty(), "MotionPlayer::create: an error without a message");
    return;
  }
  const double T = player.duration();
  MotionPose pose;
  for (double t : {0.0, 0.5 * T, T, T + 0.25, -3.7, 7.3 * T + 0.01, 1e4, -1e4, 1e7}) {
    player.sample(t, pose);
    checkPose(pose, player, t);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  capefuzz::ByteReader in(data, size);
  const std::uint8_t selector = in.u8();
  const std::string text = in.rest();
  const int format = (selector & 3) < 2 ? selector & 3 : 2;
  const bool loop = (selector & 0x80) == 0;
  const bool rootMotion = (selector & 0x40) == 0;
  MotionClipResult loaded;
  CsvMotionOptions csv;
  if (format == 0) {
    static const MotionFrame kFrames[] = {MotionFrame::Urdf, MotionFrame::World, MotionFrame::YUp,
                                          MotionFrame::Urdf};
    csv.frame = kFrames[(selector >> 2) & 3];
    csv.loop = loop;
    csv.limits = smallLimits();
    loaded = parseMotionCsv(text, csv, "fuzz.csv");
  } else if (format == 1) {
    DeepMimicOptions options;
    options.limits = smallLimits();
    loaded = parseDeepMimic(text, options, "fuzz.txt");
  } else {
    static const double kScales[] = {0.0, 0.01, 1.0, 0.0254};
    static const BvhUp kUps[] = {BvhUp::Auto, BvhUp::Y, BvhUp::Z, BvhUp::Auto};
    BvhOptions options;
    options.scale = kScales[(selector >> 2) & 3];
    options.up = kUps[(selector >> 4) & 3];
    options.scaleRootToLegs = rootMotion;
    options.loop = loop;
    options.limits = smallLimits();
    loaded = parseBvh(text, (selector & 3) == 3 ? ballModel() : humanoidModel(), options, nullptr, 1.0,
                      "fuzz.bvh");
  }
  if (!loaded.ok()) {
    CAPE_FUZZ_CHECK(!loaded.status.message().empty(), "a loader error without a message");
    return 0;
  }
  const Status checked = loaded.clip.check();
  CAPE_FUZZ_CHECK(checked.ok(), "a loaded clip fails check(): " + checked.message());
  if (format == 0) checkCsvRoundTrip(loaded.clip, csv);
  // DeepMimic clips and BVH retargeted onto it (format 3) play on the ball-jointed model, the rest on the
  // humanoid; anything also on the other (its joints are unknown there: a clean error).
  const bool balls = format == 1 || (selector & 3) == 3;
  play(loaded.clip, balls ? ballSkeleton() : humanoidSkeleton(), loop, rootMotion);
  play(loaded.clip, balls ? humanoidSkeleton() : ballSkeleton(), loop, rootMotion);
  return 0;
}
