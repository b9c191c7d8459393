// The joint trajectory CSV and DeepMimic readers against files the tests write: a written clip read back to
// the bit, header variants (spaces, CRLF, comments, a byte order mark), every malformed case with its line or
// frame in the message, a DeepMimic file whose every value lands in its slot, the Loop modes, hostile JSON,
// the limits; and the formats told by name, extension and content, and loadMotion's dispatch.
#include "cape/character/MotionFormats.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace cape::character {
namespace {

namespace fs = std::filesystem;

bool has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

bool sameBits(double a, double b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

// A folder of its own under the system's temporary folder, removed with everything in it at the end.
class TempDir {
 public:
  TempDir() {
    const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("cape_motion_" + std::to_string(::getpid()) + "_" + info->test_suite_name() + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string write(const std::string& file, const std::string& text) const {
    const fs::path p = dir_ / file;
    std::ofstream(p, std::ios::binary) << text;
    return p.string();
  }
  std::string path(const std::string& file) const { return (dir_ / file).string(); }

 private:
  fs::path dir_;
};

const char* kHeader = "time,root_x,root_y,root_z,root_qx,root_qy,root_qz,root_qw";

// --- CSV ------------------------------------------------------------------------------------------------

// A clip whose numbers need all 17 digits (thirds, pi, tiny and huge values, -0), two scalar joints and two
// balls of unit quaternions made by Eigen (not unit to the last bit).
MotionClip awkwardClip() {
  MotionClip c;
  c.name = "awkward";
  c.frame = MotionFrame::World;
  c.joints = {"left_knee", "waist"};
  c.balls = {"neck", "right_shoulder"};
  for (int s = 0; s < 6; ++s) {
    const double t = s / 3.0 + 1e-17 * s;
    c.times.push_back(t);
    c.rootPositions.emplace_back(std::sqrt(2.0) * s, -0.0, 1e-300 * (s + 1));
    c.rootRotations.push_back(Eigen::Quaterniond(1.0, 0.1 * s, -0.3, 1.0 / 7.0).normalized());
    c.values.push_back(3.14159265358979323846 * s / 7.0);
    c.values.push_back(-1e200 / (s + 3.0));
    c.rotations.push_back(Eigen::Quaterniond(0.2, 1.0 / 3.0, s, -0.7).normalized());
    c.rotations.push_back(
        Eigen::Quaterniond(Eigen::AngleAxisd(0.1 * s + 0.05, Eigen::Vector3d(1, 2, 3).normalized())));
  }
  return c;
}

void expectSameBits(const MotionClip& a, const MotionClip& b) {
  ASSERT_EQ(a.times.size(), b.times.size());
  ASSERT_EQ(a.joints, b.joints);
  ASSERT_EQ(a.balls, b.balls);
  ASSERT_EQ(a.values.size(), b.values.size());
  ASSERT_EQ(a.rotations.size(), b.rotations.size());
  for (std::size_t s = 0; s < a.times.size(); ++s) {
    EXPECT_TRUE(sameBits(a.times[s], b.times[s])) << "time " << s;
    for (int k = 0; k < 3; ++k) EXPECT_TRUE(sameBits(a.rootPositions[s][k], b.rootPositions[s][k])) << s;
    for (int k = 0; k < 4; ++k)
      EXPECT_TRUE(sameBits(a.rootRotations[s].coeffs()[k], b.rootRotations[s].coeffs()[k])) << s;
  }
  for (std::size_t i = 0; i < a.values.size(); ++i) EXPECT_TRUE(sameBits(a.values[i], b.values[i])) << i;
  for (std::size_t i = 0; i < a.rotations.size(); ++i) {
    for (int k = 0; k < 4; ++k)
      EXPECT_TRUE(sameBits(a.rotations[i].coeffs()[k], b.rotations[i].coeffs()[k])) << i;
  }
}

TEST(MotionCsv, AWrittenClipReadsBackBitForBit) {
  const MotionClip clip = awkwardClip();
  ASSERT_TRUE(clip.check().ok()) << clip.check().message();
  const std::string text = writeMotionCsv(clip);
  CsvMotionOptions options;
  options.frame = MotionFrame::World;
  const MotionClipResult back = parseMotionCsv(text, options, "awkward.csv");
  ASSERT_TRUE(back.ok()) << back.status.message();
  EXPECT_TRUE(back.clip.check().ok());
  expectSameBits(clip, back.clip);
  EXPECT_EQ(back.clip.frame, MotionFrame::World);
  EXPECT_TRUE(std::signbit(back.clip.rootPositions[0].y()));  // -0 stays -0
  // Written again, the text is the same: the reader keeps a unit quaternion's bits.
  MotionClip again = back.clip;
  again.name = clip.name;
  EXPECT_EQ(writeMotionCsv(again), text);
}

// The checked writer refuses what would not read back as it was, naming the joint; else it writes the same.
TEST(MotionCsv, TheCheckedWriterRefusesNamesTheFormatCannotHold) {
  const MotionClip good = awkwardClip();
  std::string out = "untouched";
  ASSERT_TRUE(writeMotionCsv(good, out).ok());
  EXPECT_EQ(out, writeMotionCsv(good));
  for (const std::string& bad :
       {std::string("a,b"), std::string("line\nbreak"), std::string("#hash"), std::string(" padded"),
        std::string(""), std::string("root_x"), std::string("time"), std::string("knee.qw")}) {
    MotionClip c = good;
    c.joints[0] = bad;
    out = "untouched";
    const Status s = writeMotionCsv(c, out);
    EXPECT_EQ(s.code(), ErrorCode::InvalidArgument) << bad;
    EXPECT_TRUE(has(s.message(), "cannot be a CSV column") || bad.empty()) << s.message();
    EXPECT_EQ(out, "untouched") << bad;
  }
  MotionClip ball = good;
  ball.balls[0] = "neck,1";
  EXPECT_FALSE(writeMotionCsv(ball, out).ok());
  MotionClip broken = good;
  broken.times[1] = broken.times[0];
  EXPECT_FALSE(writeMotionCsv(broken, out).ok());
}

TEST(MotionCsv, AWrittenFileReadsBackBitForBit) {
  TempDir dir;
  const MotionClip clip = awkwardClip();
  const std::string path = dir.write("clip.csv", writeMotionCsv(clip));
  CsvMotionOptions options;
  options.frame = MotionFrame::YUp;
  options.loop = false;
  const MotionClipResult back = readMotionCsv(path, options);
  ASSERT_TRUE(back.ok()) << back.status.message();
  expectSameBits(clip, back.clip);
  EXPECT_EQ(back.clip.name, path);
  EXPECT_EQ(back.clip.frame, MotionFrame::YUp);
  EXPECT_FALSE(back.clip.loop);
}

TEST(MotionCsv, HeaderAndRowsMayHaveSpacesCrlfCommentsAndBlankLines) {
  const std::string text =
      "\xEF\xBB\xBF# a walk, written by hand\r\n"
      "\r\n"
      "   \t\r\n"
      " time , root_x,root_y , root_z,root_qx,root_qy,root_qz,root_qw , knee ,neck.qw, "
      "neck.qz,neck.qx,neck.qy\r\n"
      "# the first sample\r\n"
      " 0 , 1 , 2 , 3 , 0 , 0 , 0 , 1 , 0.5 , 1 , 0 , 0 , 0 \r\n"
      "\r\n"
      "0.5,+1.5,2e0,-3,0,0,0,2,-0.25,0,0.6,0,0.8\r\n";
  const MotionClipResult r = parseMotionCsv(text);
  ASSERT_TRUE(r.ok()) << r.status.message();
  const MotionClip& c = r.clip;
  EXPECT_TRUE(c.check().ok()) << c.check().message();
  EXPECT_EQ(c.name, "csv");
  EXPECT_EQ(c.frame, MotionFrame::Urdf);
  EXPECT_TRUE(c.loop);
  ASSERT_EQ(c.sampleCount(), 2);
  EXPECT_EQ(c.times, (std::vector<double>{0.0, 0.5}));
  EXPECT_EQ(c.rootPositions[1], Eigen::Vector3d(1.5, 2.0, -3.0));
  EXPECT_EQ(c.rootRotations[1].coeffs(), Eigen::Vector4d(0, 0, 0, 1));  // (0, 0, 0, 2) normalised
  EXPECT_EQ(c.joints, std::vector<std::string>{"knee"});
  EXPECT_EQ(c.values, (std::vector<double>{0.5, -0.25}));
  EXPECT_EQ(c.balls, std::vector<std::string>{"neck"});
  // neck.qw, neck.qz, neck.qx, neck.qy = 0, 0.6, 0, 0.8: x 0, y 0.8, z 0.6, w 0.
  const Eigen::Quaterniond& q = c.rotations[1];
  EXPECT_EQ(q.x(), 0.0);
  EXPECT_NEAR(q.y(), 0.8, 1e-15);
  EXPECT_NEAR(q.z(), 0.6, 1e-15);
  EXPECT_EQ(q.w(), 0.0);
  EXPECT_EQ(c.rotations[0].coeffs(), Eigen::Vector4d(0, 0, 0, 1));
}

TEST(MotionCsv, QuaternionsAreNormalisedOnReading) {
  const std::string text = std::string(kHeader) + ",b.qx,b.qy,b.qz,b.qw\n0,0,0,0,0,0,3,4,1e-200,0,0,0\n" +
                           "1,0,0,0,1e200,1e200,1e200,1e200,0,0,-7,0\n";
  const MotionClipResult r = parseMotionCsv(text);
  ASSERT_TRUE(r.ok()) << r.status.message();
  EXPECT_NEAR(r.clip.rootRotations[0].z(), 0.6, 1e-15);
  EXPECT_NEAR(r.clip.rootRotations[0].w(), 0.8, 1e-15);
  EXPECT_NEAR(r.clip.rootRotations[1].w(), 0.5, 1e-15);                  // huge components, no overflow
  EXPECT_EQ(r.clip.rotations[0].coeffs(), Eigen::Vector4d(1, 0, 0, 0));  // tiny, no underflow
  EXPECT_EQ(r.clip.rotations[1].coeffs(), Eigen::Vector4d(0, 0, -1, 0));
  EXPECT_TRUE(r.clip.check().ok());
}

TEST(MotionCsv, AClipOfOneSampleAndNoJointsIsRead) {
  const MotionClipResult r = parseMotionCsv(std::string(kHeader) + "\n0.25,0,0,1,0,0,0,1\n");
  ASSERT_TRUE(r.ok()) << r.status.message();
  EXPECT_EQ(r.clip.sampleCount(), 1);
  EXPECT_TRUE(r.clip.joints.empty());
  EXPECT_TRUE(r.clip.balls.empty());
}

struct BadCsv {
  const char* what;
  std::string text;
  std::string message;  // a part of the expected message
};

TEST(MotionCsv, EveryMalformedFileGivesItsLineAndProblem) {
  const std::string h = kHeader;
  const std::string row0 = "0,0,0,0,0,0,0,1", row1 = "1,0,0,0,0,0,0,1";
  const std::vector<BadCsv> cases = {
      {"empty", "", "test.csv: no header line"},
      {"only comments", "# nothing\n\n", "no header line"},
      {"header only", h + "\n", "test.csv:1: a header and no sample row"},
      {"misnamed root column", "time,root_x,root_y,root_z,root_qw,root_qy,root_qz,root_qx\n" + row0,
       "test.csv:1: column 5 is 'root_qw' where 'root_qx' belongs"},
      {"missing root columns", "time,root_x,root_y\n0,0,0\n", "test.csv:1: the header has 3 columns"},
      {"no time", "t,root_x,root_y,root_z,root_qx,root_qy,root_qz,root_qw\n" + row0, ":1: column 1 is 't'"},
      {"too few fields", h + "\n" + row0 + "\n1,0,0\n", "test.csv:3: 3 fields; the header (line 1) has 8"},
      {"too many fields", h + "\n" + row0 + ",5\n", "test.csv:2: 9 fields"},
      {"not a number", h + "\n" + row0 + "\n1,0,abc,0,0,0,0,1\n",
       "test.csv:3: column 3 (root_y): 'abc' is not a number"},
      {"trailing text", h + "\n0,0,0,0,0,0,0,1x\n", ":2: column 8 (root_qw): '1x' is not a number"},
      {"two signs", h + "\n0,+-1,0,0,0,0,0,1\n", ":2: column 2 (root_x): '+-1' is not a number"},
      {"empty field", h + "\n0,0,,0,0,0,0,1\n", ":2: column 3 (root_y): the field is empty"},
      {"NaN", h + "\n0,nan,0,0,0,0,0,1\n", ":2: column 2 (root_x): 'nan' is not a finite number"},
      {"infinity", h + "\n0,0,0,-inf,0,0,0,1\n", ":2: column 4 (root_z): '-inf' is not a finite number"},
      {"overflow", h + "\n0,0,0,1e999,0,0,0,1\n", ":2: column 4 (root_z): '1e999' is not a finite number"},
      {"equal times", h + "\n" + row0 + "\n" + row0 + "\n",
       "test.csv:3: time 0 s is not after the time of line 2"},
      {"decreasing times", h + "\n" + row1 + "\n# c\n" + row0 + "\n", "test.csv:4: time 0 s is not after"},
      {"negative time", h + "\n-1,0,0,0,0,0,0,1\n", ":2: time -1 s is negative"},
      {"zero root quaternion", h + "\n" + row0 + "\n1,0,0,0,0,0,0,0\n", "test.csv:3: the root quaternion"},
      {"zero ball quaternion", h + ",b.qx,b.qy,b.qz,b.qw\n" + row0 + ",0,0,0,1\n" + row1 + ",0,0,0,-0\n",
       "test.csv:3: the quaternion of joint 'b' is zero"},
      {"column twice", h + ",knee,hip,knee\n" + row0 + ",1,2,3\n",
       "test.csv:1: column 11 'knee' is the name of column 9 too"},
      {"root column twice", h + ",root_x\n" + row0 + ",1\n", ":1: column 9 'root_x' is the name of column 2"},
      {"joint as scalar and ball", h + ",b,b.qx,b.qy,b.qz,b.qw\n" + row0 + ",0,0,0,0,1\n",
       ":1: joint 'b' of column 10 is given twice (also column 9)"},
      {"empty joint name", h + ",.qx,.qy,.qz,.qw\n" + row0 + ",0,0,0,1\n",
       ":1: column 9 '.qx': the joint name is empty"},
      {"empty column name", h + ",knee,,hip\n" + row0 + ",1,2,3\n", ":1: column 10 has no name"},
      {"ball of three columns", h + ",b.qx,b.qy,b.qz\n" + row0 + ",0,0,0\n",
       ":1: column 9 'b.qx': the header ends before a spherical joint is four adjacent columns"},
      {"ball split", h + ",b.qx,knee,b.qy,b.qz,b.qw\n" + row0 + ",0,0,0,0,1\n",
       ":1: column 10 is 'knee': a spherical joint is four adjacent columns b.qx, b.qy, b.qz and b.qw"},
      {"ball mixed with another", h + ",b.qx,b.qy,c.qz,b.qw,b.qz\n" + row0 + ",0,0,0,1,0\n",
       ":1: column 11 is 'c.qz'"},
  };
  for (const BadCsv& c : cases) {
    const MotionClipResult r = parseMotionCsv(c.text, {}, "test.csv");
    EXPECT_FALSE(r.ok()) << c.what;
    EXPECT_EQ(r.status.code(), ErrorCode::InvalidArgument) << c.what;
    EXPECT_TRUE(has(r.status.message(), c.message)) << c.what << ": " << r.status.message();
    EXPECT_TRUE(r.clip.times.empty()) << c.what;
  }
}

TEST(MotionCsv, LineNumbersCountCommentsBlankLinesAndCrlf) {
  const std::string text = std::string("# one\r\n\r\n") + kHeader + "\r\n# four\r\n0,0,0,0,0,0,0,1\r\n\r\n" +
                           "1,0,0,0,0,0,x,1\r\n";
  const MotionClipResult r = parseMotionCsv(text, {}, "walk.csv");
  EXPECT_EQ(r.status.code(), ErrorCode::InvalidArgument);
  EXPECT_TRUE(has(r.status.message(), "walk.csv:7: column 7 (root_qz): 'x' is not a number"))
      << r.status.message();
}

TEST(MotionCsv, LimitsRefuseTooManySamplesColumnsAndBytes) {
  const std::string text =
      std::string(kHeader) + ",a,b\n0,0,0,0,0,0,0,1,0,0\n1,0,0,0,0,0,0,1,0,0\n" + "2,0,0,0,0,0,0,1,0,0\n";
  CsvMotionOptions options;
  options.limits.maxSamples = 2;
  MotionClipResult r = parseMotionCsv(text, options, "big.csv");
  EXPECT_EQ(r.status.code(), ErrorCode::InvalidArgument);
  EXPECT_TRUE(
      has(r.status.message(), "big.csv:4: more than 2 samples; the limit is 2 (MotionLimits::maxSamples)"))
      << r.status.message();
  options.limits.maxSamples = 3;
  EXPECT_TRUE(parseMotionCsv(text, options).ok());

  options.limits.maxJoints = 9;
  r = parseMotionCsv(text, options, "wide.csv");
  EXPECT_TRUE(has(r.status.message(),
                  "wide.csv:1: the header has 10 columns; the limit is 9 (MotionLimits::maxJoints)"))
      << r.status.message();
  options.limits.maxJoints = 10;
  EXPECT_TRUE(parseMotionCsv(text, options).ok());

  options.limits.maxFileBytes = text.size() - 1;
  r = parseMotionCsv(text, options, "long.csv");
  EXPECT_EQ(r.status.code(), ErrorCode::InvalidArgument);
  EXPECT_TRUE(has(r.status.message(), "MotionLimits::maxFileBytes")) << r.status.message();
  TempDir dir;
  const std::string path = dir.write("long.csv", text);
  r = readMotionCsv(path, options);
  EXPECT_EQ(r.status.code(), ErrorCode::InvalidArgument);
  EXPECT_TRUE(has(r.status.message(), path + ": " + std::to_string(text.size()) + " bytes; the limit is"))
      << r.status.message();
  options.limits.maxFileBytes = text.size();
  EXPECT_TRUE(readMotionCsv(path, options).ok());

  options.limits.maxSamples = 0;
  r = parseMotionCsv(text, options);
  EXPECT_EQ(r.status.code(), ErrorCode::InvalidArgument);
  EXPECT_TRUE(has(r.status.message(), "MotionLimits::maxSamples is 0")) << r.status.message();
}

TEST(MotionCsv, AMissingFileIsFileNotFound) {
  TempDir dir;
  const MotionClipResult r = readMotionCsv(dir.path("nothing.csv"));
  EXPECT_EQ(r.status.code(), ErrorCode::FileNotFound);
  EXPECT_TRUE(has(r.status.message(), "nothing.csv")) << r.status.message();
  EXPECT_EQ(readMotionCsv(dir.path("")).status.code(), ErrorCode::FileNotFound);  // a folder
}

// --- DeepMimic ----------------------------------------------------------------------------------------

// Frame k: duration 1/30 s, then value i = i + 100 k (quaternions normalised on reading).
std::vector<double> numberedFrame(int k) {
  std::vector<double> v(44);
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = static_cast<double>(i) + 100.0 * k;
  v[0] = 1.0 / 30.0;
  return v;
}

std::string frameJson(const std::vector<double>& v) {
  std::string out = "[";
  for (std::size_t i = 0; i < v.size(); ++i) {
    char buffer[40];
    std::snprintf(buffer, sizeof buffer, "%.17g", v[i]);
    out += (i ? ", " : "") + std::string(buffer);
  }
  return out + "]";
}

std::string deepMimicJson(const std::vector<std::vector<double>>& frames,
                          const std::string& loop = "\"wrap\"") {
  std::string out = "{\n";
  if (!loop.empty()) out += "\"Loop\": " + loop + ",\n";
  out += "\"Frames\":\n[\n";
  for (std::size_t k = 0; k < frames.size(); ++k) out += (k ? ",\n" : "") + frameJson(frames[k]);
  return out + "\n]\n}\n";
}

std::vector<std::vector<double>> threeFrames() {
  return {numberedFrame(0), numberedFrame(1), numberedFrame(2)};
}

// (w, x, y, z) from entries i..i+3 of frame k, normalised.
Eigen::Quaterniond expectedRotation(int k, int i) {
  const double b = 100.0 * k;
  return Eigen::Quaterniond(i + b, i + 1 + b, i + 2 + b, i + 3 + b).normalized();
}

void expectRotation(const Eigen::Quaterniond& q, const Eigen::Quaterniond& want, const std::string& what) {
  EXPECT_NEAR(q.w(), want.w(), 1e-15) << what;
  EXPECT_NEAR(q.x(), want.x(), 1e-15) << what;
  EXPECT_NEAR(q.y(), want.y(), 1e-15) << what;
  EXPECT_NEAR(q.z(), want.z(), 1e-15) << what;
}

TEST(DeepMimic, EveryValueOfAFrameLandsInItsSlot) {
  const MotionClipResult r = parseDeepMimic(deepMimicJson(threeFrames()), {}, "walk.txt");
  ASSERT_TRUE(r.ok()) << r.status.message();
  const MotionClip& c = r.clip;
  EXPECT_TRUE(c.check().ok()) << c.check().message();
  EXPECT_EQ(c.name, "walk.txt");
  EXPECT_EQ(c.frame, MotionFrame::YUp);
  EXPECT_TRUE(c.loop);
  ASSERT_EQ(c.sampleCount(), 3);
  const double d = 1.0 / 30.0;
  EXPECT_EQ(c.times, (std::vector<double>{0.0, d, d + d}));
  EXPECT_EQ(c.joints, (std::vector<std::string>{"right_knee", "right_elbow", "left_knee", "left_elbow"}));
  EXPECT_EQ(c.balls, (std::vector<std::string>{"chest", "neck", "right_hip", "right_ankle", "right_shoulder",
                                               "left_hip", "left_ankle", "left_shoulder"}));
  for (int k = 0; k < 3; ++k) {
    const double b = 100.0 * k;
    const std::size_t s = static_cast<std::size_t>(k);
    EXPECT_EQ(c.rootPositions[s], Eigen::Vector3d(1 + b, 2 + b, 3 + b));
    expectRotation(c.rootRotations[s], expectedRotation(k, 4), "root");
    // The knees and elbows: entries 20, 29, 34 and 43.
    EXPECT_EQ(c.values[4 * s + 0], 20 + b);  // right_knee
    EXPECT_EQ(c.values[4 * s + 1], 29 + b);  // right_elbow
    EXPECT_EQ(c.values[4 * s + 2], 34 + b);  // left_knee
    EXPECT_EQ(c.values[4 * s + 3], 43 + b);  // left_elbow
    const int starts[8] = {8, 12, 16, 21, 25, 30, 35, 39};
    for (std::size_t j = 0; j < 8; ++j)
      expectRotation(c.rotations[8 * s + j], expectedRotation(k, starts[j]), c.balls[j]);
  }
  // The neck is (w, x, y, z) = entries 12..15.
  EXPECT_NEAR(c.rotations[1].w(), 12.0 / std::sqrt(12.0 * 12 + 13 * 13 + 14 * 14 + 15 * 15), 1e-15);
  EXPECT_NEAR(c.rotations[1].z(), 15.0 / std::sqrt(12.0 * 12 + 13 * 13 + 14 * 14 + 15 * 15), 1e-15);
}

TEST(DeepMimic, JointsAreTheHumanoidsTwelveInFileOrder) {
  const auto& j = deepMimicJoints();
  ASSERT_EQ(j.size(), 12u);
  std::size_t values = 8;
  for (const auto& [name, spherical] : j) values += spherical ? 4 : 1;
  EXPECT_EQ(values, 44u);
  EXPECT_EQ(j[1], (std::pair<std::string, bool>("neck", true)));
  EXPECT_EQ(j[8], (std::pair<std::string, bool>("left_knee", false)));
}

TEST(DeepMimic, ARealPyBulletFrameReads) {
  // The first frame of PyBullet's humanoid3d_walk.txt layout: duration, root, then w-first quaternions.
  const std::string text = R"({"Loop": "wrap", "Frames": [
    [0.0625, 0.0, 0.886733, 0.0, 0.999412, 0.029215, -0.000525, -0.017963, 0.999985, 0.000432, 0.000572,
     0.0055, 0.9897717, 0.00166, -0.011165, -0.140564, 0.998945, -0.02445, -0.0008386, -0.0388686, -0.014186,
     0.988643, 0.010702, -0.104681, 0.035223, 0.989539, -0.003003, -0.124234, 0.07328, 0.240463, 1, 0, 0, 0,
     -0.5, 1, 0, 0, 0, 1, 0, 0, 0, 0.3],
    [0, 0.1, 0.886733, 0.0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0,
     0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0]]})";
  const MotionClipResult r = parseDeepMimic(text);
  ASSERT_TRUE(r.ok()) << r.status.message();
  EXPECT_EQ(r.clip.name, "deepmimic");
  EXPECT_EQ(r.clip.times, (std::vector<double>{0.0, 0.0625}));  // the last frame's duration 0 is not read
  EXPECT_NEAR(r.clip.rootPositions[0].y(), 0.886733, 1e-15);
  EXPECT_NEAR(r.clip.rootRotations[0].w(), 0.999412, 1e-3);
  EXPECT_NEAR(r.clip.values[0], -0.014186, 1e-15);  // right_knee
  EXPECT_NEAR(r.clip.values[1], 0.240463, 1e-15);   // right_elbow
  EXPECT_EQ(r.clip.values[2], -0.5);                // left_knee
  EXPECT_EQ(r.clip.values[3], 0.3);                 // left_elbow
  EXPECT_TRUE(r.clip.check().ok());
}

TEST(DeepMimic, LoopIsWrapNoneOrAbsent) {
  MotionClipResult r = parseDeepMimic(deepMimicJson(threeFrames(), "\"none\""));
  ASSERT_TRUE(r.ok()) << r.status.message();
  EXPECT_FALSE(r.clip.loop);
  r = parseDeepMimic(deepMimicJson(threeFrames(), "\"wrap\""));
  ASSERT_TRUE(r.ok());
  EXPECT_TRUE(r.clip.loop);
  r = parseDeepMimic(deepMimicJson(threeFrames(), ""));
  ASSERT_TRUE(r.ok());
  EXPECT_TRUE(r.clip.loop);
  for (const char* bad : {"\"once\"", "\"Wrap\"", "1", "true", "null", "[\"wrap\"]"}) {
    r = parseDeepMimic(deepMimicJson(threeFrames(), bad), {}, "m.txt");
    EXPECT_EQ(r.status.code(), ErrorCode::InvalidArgument) << bad;
    EXPECT_TRUE(has(r.status.message(), "m.txt: \"Loop\" is ")) << r.status.message();
    EXPECT_TRUE(has(r.status.message(), "it must be \"wrap\" or \"none\"")) << r.status.message();
  }
}

struct BadJson {
  const char* what;
  std::string text;
  std::string message;
};

TEST(DeepMimic, EveryMalformedFileGivesItsFrameAndProblem) {
  const std::string good = deepMimicJson(threeFrames());
  auto withFrame = [](int k, std::vector<double> v) {
    std::vector<std::vector<double>> f = threeFrames();
    f[static_cast<std::size_t>(k)] = std::move(v);
    return deepMimicJson(f);
  };
  auto replaceValue = [](int k, int i, const std::string& json) {
    // Frame k's entry i as raw JSON text.
    std::vector<std::vector<double>> f = threeFrames();
    std::string out = "{\"Loop\": \"wrap\", \"Frames\": [";
    for (std::size_t fk = 0; fk < f.size(); ++fk) {
      std::string frame = "[";
      for (std::size_t j = 0; j < 44; ++j) {
        frame += (j ? "," : "");
        frame += (static_cast<int>(fk) == k && static_cast<int>(j) == i) ? json : std::to_string(f[fk][j]);
      }
      out += (fk ? "," : "") + frame + "]";
    }
    return out + "]}";
  };
  std::vector<double> short43 = numberedFrame(1);
  short43.pop_back();
  std::vector<double> long45 = numberedFrame(1);
  long45.push_back(1.0);
  std::vector<double> zeroDuration = numberedFrame(0);
  zeroDuration[0] = 0.0;
  std::vector<double> negativeDuration = numberedFrame(1);
  negativeDuration[0] = -0.1;
  std::vector<double> zeroNeck = numberedFrame(1);
  zeroNeck[12] = zeroNeck[13] = zeroNeck[14] = zeroNeck[15] = 0.0;
  std::vector<double> zeroRoot = numberedFrame(2);
  zeroRoot[4] = zeroRoot[5] = zeroRoot[6] = zeroRoot[7] = 0.0;
  const std::vector<BadJson> cases = {
      {"empty", "", "m.txt: not valid JSON"},
      {"truncated", good.substr(0, good.size() / 2), "m.txt: not valid JSON: "},
      {"trailing comma", "{\"Frames\": [1,]}", "not valid JSON"},
      {"trailing text", good + "x", "not valid JSON"},
      {"NaN literal", replaceValue(1, 3, "NaN"), "not valid JSON"},
      {"overflow", replaceValue(1, 3, "1e999"), "m.txt: "},
      {"not an object", "[1, 2]", "m.txt: the top level is a JSON array, not an object"},
      {"no Frames", "{\"Loop\": \"wrap\"}", "m.txt: no \"Frames\" list"},
      {"Frames not a list", "{\"Frames\": {}}", "m.txt: \"Frames\" is a JSON object, not a list of frames"},
      {"Frames empty", "{\"Frames\": []}", "m.txt: \"Frames\" is empty"},
      {"one frame", "{\"Frames\": [" + frameJson(numberedFrame(0)) + "]}", "\"Frames\" has 1 frame"},
      {"frame not a list", "{\"Frames\": [" + frameJson(numberedFrame(0)) + ", 3]}",
       "m.txt: Frames[1]: a JSON number, not a list of numbers"},
      {"43 values", withFrame(1, short43),
       "m.txt: Frames[1]: 43 values; a frame of the DeepMimic humanoid has 44"},
      {"45 values", withFrame(2, long45), "m.txt: Frames[2]: 45 values"},
      {"a string", replaceValue(2, 5, "\"0.5\""),
       "m.txt: Frames[2]: value 5 (root rotation x) is a JSON string, not a number"},
      {"null", replaceValue(0, 34, "null"),
       "m.txt: Frames[0]: value 34 (left_knee angle) is a JSON null, not a number"},
      {"a bool", replaceValue(1, 14, "true"), "Frames[1]: value 14 (neck y) is a JSON boolean"},
      {"a list", replaceValue(1, 43, "[1]"), "Frames[1]: value 43 (left_elbow angle) is a JSON array"},
      {"zero duration", withFrame(0, zeroDuration),
       "m.txt: Frames[0]: the duration 0.000000 s is not positive"},
      {"negative duration", withFrame(1, negativeDuration),
       "m.txt: Frames[1]: the duration -0.100000 s is not positive"},
      {"zero neck", withFrame(1, zeroNeck),
       "m.txt: Frames[1]: the rotation of neck (values 12 to 15) is zero"},
      {"zero root", withFrame(2, zeroRoot), "m.txt: Frames[2]: the root rotation (values 4 to 7) is zero"},
      {"durations that do not move time",
       "{\"Frames\": [" + frameJson(numberedFrame(0)) + "," + frameJson([] {
         auto v = numberedFrame(1);
         v[0] = 1e300;
         return v;
       }()) +
           "," + frameJson([] {
             auto v = numberedFrame(2);
             v[0] = 1e-300;
             return v;
           }()) +
           "," + frameJson(numberedFrame(2)) + "]}",
       "m.txt: Frames[2]: the duration"},
  };
  for (const BadJson& c : cases) {
    MotionClipResult r;
    EXPECT_NO_THROW(r = parseDeepMimic(c.text, {}, "m.txt")) << c.what;
    EXPECT_FALSE(r.ok()) << c.what;
    EXPECT_EQ(r.status.code(), ErrorCode::InvalidArgument) << c.what;
    EXPECT_TRUE(has(r.status.message(), c.message)) << c.what << ": " << r.status.message();
  }
  // nlohmann's message says where the JSON breaks.
  const MotionClipResult r = parseDeepMimic(good.substr(0, good.size() / 2), {}, "m.txt");
  EXPECT_TRUE(has(r.status.message(), "line ")) << r.status.message();
}

TEST(DeepMimic, TheLastFramesDurationIsNotRead) {
  std::vector<std::vector<double>> f = threeFrames();
  f[2][0] = -5.0;
  const MotionClipResult r = parseDeepMimic(deepMimicJson(f));
  ASSERT_TRUE(r.ok()) << r.status.message();
  EXPECT_EQ(r.clip.sampleCount(), 3);
}

TEST(DeepMimic, DeepNestingIsAnErrorNotACrash) {
  const std::size_t depth = 100000;
  const std::string nested = std::string(depth, '[') + std::string(depth, ']');
  MotionClipResult r = parseDeepMimic(nested, {}, "deep.txt");
  EXPECT_EQ(r.status.code(), ErrorCode::InvalidArgument);
  r = parseDeepMimic("{\"Frames\": [" + nested + ", " + nested + "]}", {}, "deep.txt");
  EXPECT_EQ(r.status.code(), ErrorCode::InvalidArgument);
  EXPECT_TRUE(has(r.status.message(), "deep.txt: Frames[0]: 1 values")) << r.status.message();
  r = parseDeepMimic(std::string(depth, '['), {}, "deep.txt");
  EXPECT_TRUE(has(r.status.message(), "not valid JSON")) << r.status.message();
}

TEST(DeepMimic, LimitsRefuseTooManyFramesValuesAndBytes) {
  const std::string text = deepMimicJson(threeFrames());
  DeepMimicOptions options;
  options.limits.maxSamples = 2;
  MotionClipResult r = parseDeepMimic(text, options, "m.txt");
  EXPECT_TRUE(has(r.status.message(), "m.txt: 3 frames; the limit is 2 (MotionLimits::maxSamples)"))
      << r.status.message();
  options.limits.maxSamples = 3;
  options.limits.maxJoints = 43;
  r = parseDeepMimic(text, options, "m.txt");
  EXPECT_TRUE(has(r.status.message(), "a frame has 44 values; the limit is 43 (MotionLimits::maxJoints)"))
      << r.status.message();
  options.limits.maxJoints = 44;
  EXPECT_TRUE(parseDeepMimic(text, options).ok());
  options.limits.maxFileBytes = text.size() - 1;
  TempDir dir;
  const std::string path = dir.write("m.txt", text);
  r = readDeepMimic(path, options);
  EXPECT_EQ(r.status.code(), ErrorCode::InvalidArgument);
  EXPECT_TRUE(has(r.status.message(), "MotionLimits::maxFileBytes")) << r.status.message();
  EXPECT_FALSE(parseDeepMimic(text, options).ok());
  options.limits.maxFileBytes = text.size();
  r = readDeepMimic(path, options);
  ASSERT_TRUE(r.ok()) << r.status.message();
  EXPECT_EQ(r.clip.name, path);
  // By default 64 MiB (the document is built whole: about four times the text in memory), said before any
  // of it is parsed.
  EXPECT_EQ(DeepMimicOptions().limits.maxFileBytes, std::size_t(64) << 20);
  EXPECT_EQ(DeepMimicOptions().limits.maxSamples, MotionLimits().maxSamples);
  const std::string big = "{\"Frames\": [" + std::string((std::size_t(64) << 20) - 12, ' ') + "]}";
  r = parseDeepMimic(big);
  EXPECT_TRUE(has(r.status.message(), "MotionLimits::maxFileBytes")) << r.status.message();
}

TEST(DeepMimic, AMissingFileIsFileNotFound) {
  TempDir dir;
  const MotionClipResult r = readDeepMimic(dir.path("none.txt"));
  EXPECT_EQ(r.status.code(), ErrorCode::FileNotFound);
  EXPECT_TRUE(has(r.status.message(), "none.txt")) << r.status.message();
}

// --- Formats ---------------------------------------------------------------------------------------------

TEST(MotionFormat, NamesReadBackAndAnythingElseIsRefused) {
  for (MotionFormat f : {MotionFormat::Auto, MotionFormat::Csv, MotionFormat::DeepMimic, MotionFormat::Bvh}) {
    MotionFormat out = MotionFormat::Auto;
    EXPECT_TRUE(parseMotionFormat(toString(f), out)) << toString(f);
    EXPECT_EQ(out, f);
  }
  EXPECT_STREQ(toString(MotionFormat::DeepMimic), "deepmimic");
  MotionFormat out = MotionFormat::Csv;
  EXPECT_TRUE(parseMotionFormat("BVH", out));
  EXPECT_EQ(out, MotionFormat::Bvh);
  out = MotionFormat::Csv;
  EXPECT_FALSE(parseMotionFormat("json", out));
  EXPECT_FALSE(parseMotionFormat("", out));
  EXPECT_EQ(out, MotionFormat::Csv);  // untouched
}

TEST(MotionFormat, TheExtensionDecidesFirst) {
  TempDir dir;
  EXPECT_EQ(detectMotionFormat(dir.path("walk.CSV")), MotionFormat::Csv);  // need not exist
  EXPECT_EQ(detectMotionFormat(dir.path("walk.bvh")), MotionFormat::Bvh);
  EXPECT_EQ(detectMotionFormat(dir.path("walk.Json")), MotionFormat::DeepMimic);
  EXPECT_EQ(detectMotionFormat(dir.path("humanoid3d_walk.txt")), MotionFormat::DeepMimic);
  // Over what the file holds.
  EXPECT_EQ(detectMotionFormat(dir.write("mocap.csv", "HIERARCHY\n")), MotionFormat::Csv);
  EXPECT_EQ(detectMotionFormat(dir.path("walk.motion")), MotionFormat::Auto);  // missing, no extension known
}

// A .txt is PyBullet's DeepMimic by name, but its content decides when it says something.
TEST(MotionFormat, ATxtFileIsReadByItsFirstBytes) {
  TempDir dir;
  EXPECT_EQ(detectMotionFormat(dir.write("a.txt", "{\"Loop\": \"wrap\"}")), MotionFormat::DeepMimic);
  EXPECT_EQ(detectMotionFormat(dir.write("b.txt", "HIERARCHY\nROOT Hips\n")), MotionFormat::Bvh);
  EXPECT_EQ(detectMotionFormat(dir.write("c.txt", "time, root_x\n")), MotionFormat::Csv);
  EXPECT_EQ(detectMotionFormat(dir.write("d.txt", "something else")), MotionFormat::DeepMimic);
}

TEST(MotionFormat, WithoutAKnownExtensionTheFirstBytesDecide) {
  TempDir dir;
  EXPECT_EQ(detectMotionFormat(dir.write("a", "HIERARCHY\nROOT Hips\n")), MotionFormat::Bvh);
  EXPECT_EQ(detectMotionFormat(dir.write("b.mocap", "\r\n  HIERARCHY\r\n")), MotionFormat::Bvh);
  EXPECT_EQ(detectMotionFormat(dir.write("c", "\n\t{\"Loop\": \"wrap\"}")), MotionFormat::DeepMimic);
  EXPECT_EQ(detectMotionFormat(dir.write("d", "# my walk\n\n# more\n time, root_x\n")), MotionFormat::Csv);
  EXPECT_EQ(detectMotionFormat(dir.write("e", "\xEF\xBB\xBFtime,root_x\n")), MotionFormat::Csv);
  EXPECT_EQ(detectMotionFormat(dir.write("f", "# comment\nroot_x,time\n")), MotionFormat::Auto);
  EXPECT_EQ(detectMotionFormat(dir.write("g", "")), MotionFormat::Auto);
  EXPECT_EQ(detectMotionFormat(dir.write("h", "  \n\n")), MotionFormat::Auto);
  EXPECT_EQ(detectMotionFormat(dir.path("missing")), MotionFormat::Auto);
  EXPECT_EQ(detectMotionFormat(dir.path("")), MotionFormat::Auto);  // a folder
}

TEST(MotionFormat, LoadMotionDispatchesByFormat) {
  TempDir dir;
  const std::string csv = std::string(kHeader) + ",knee\n0,0,0,0,0,0,0,1,0.5\n1,1,0,0,0,0,0,1,0.25\n";
  const std::string json = deepMimicJson(threeFrames(), "\"none\"");

  MotionLoadOptions options;
  options.csv.frame = MotionFrame::World;
  MotionClipResult r = loadMotion(dir.write("walk.csv", csv), nullptr, options);
  ASSERT_TRUE(r.ok()) << r.status.message();
  EXPECT_EQ(r.clip.joints, std::vector<std::string>{"knee"});
  EXPECT_EQ(r.clip.frame, MotionFrame::World);  // the CSV options were used

  r = loadMotion(dir.write("walk.txt", json), nullptr);
  ASSERT_TRUE(r.ok()) << r.status.message();
  EXPECT_EQ(r.clip.frame, MotionFrame::YUp);
  EXPECT_FALSE(r.clip.loop);

  r = loadMotion(dir.write("walk-data", csv), nullptr);  // by content
  ASSERT_TRUE(r.ok()) << r.status.message();
  EXPECT_EQ(r.clip.sampleCount(), 2);
  r = loadMotion(dir.write("dm-data", json), nullptr);
  ASSERT_TRUE(r.ok()) << r.status.message();
  EXPECT_EQ(r.clip.sampleCount(), 3);

  options.format = MotionFormat::Csv;  // given: the .txt extension does not count
  r = loadMotion(dir.write("csv.txt", csv), nullptr, options);
  ASSERT_TRUE(r.ok()) << r.status.message();
  EXPECT_EQ(r.clip.sampleCount(), 2);
  options.format = MotionFormat::DeepMimic;
  r = loadMotion(dir.path("csv.txt"), nullptr, options);
  EXPECT_EQ(r.status.code(), ErrorCode::InvalidArgument);
  EXPECT_TRUE(has(r.status.message(), "not valid JSON")) << r.status.message();

  const std::string unknown = dir.write("notes", "hello\n");
  r = loadMotion(unknown, nullptr);
  EXPECT_EQ(r.status.code(), ErrorCode::InvalidArgument);
  EXPECT_TRUE(has(r.status.message(),
                  "cannot tell the format of " + unknown + "; give --motion-format csv|deepmimic|bvh"))
      << r.status.message();

  r = loadMotion(dir.path("missing"), nullptr);
  EXPECT_EQ(r.status.code(), ErrorCode::FileNotFound);
  r = loadMotion(dir.path("missing.csv"), nullptr);
  EXPECT_EQ(r.status.code(), ErrorCode::FileNotFound);

  r = loadMotion(dir.write("walk.bvh", "HIERARCHY\n"), nullptr);
  EXPECT_EQ(r.status.code(), ErrorCode::InvalidArgument);
  EXPECT_TRUE(has(r.status.message(), "a BVH is retargeted onto a URDF model, and none was given"))
      << r.status.message();
  const UrdfLoadResult model = UrdfModel::humanoid();
  ASSERT_TRUE(model.ok());
  r = loadMotion(dir.path("missing.bvh"), model.model);  // reaches the BVH reader, which finds no file
  EXPECT_FALSE(r.ok());
}

}  // namespace
}  // namespace cape::character
