// DeepMimic motion files (PyBullet's pybullet_data/data/motions/*.txt): JSON with a "Loop" mode and a list of
// frames, each 44 numbers for PyBullet's DeepMimic humanoid. Parsed with nlohmann_json without exceptions,
// every element's type checked; the frames become a clip in the file's Y-up frame.
#include "cape/character/MotionFormats.h"

#include "MotionText.h"

#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <exception>
#include <string>
#include <vector>

namespace cape::character {

namespace {

using namespace motiontext;
using nlohmann::json;

// A frame: duration (s), root position (3, m), root rotation (w x y z), then the joints of deepMimicJoints()
// in order, a spherical one as a quaternion (w x y z) and a knee or elbow as one angle (rad).
constexpr std::size_t kFrameValues = 44;

// What value i of a frame is, for messages: "neck x", "left_knee angle".
std::string valueLabel(std::size_t i) {
  static const char* const kRoot[8] = {"duration",        "root position x", "root position y",
                                       "root position z", "root rotation w", "root rotation x",
                                       "root rotation y", "root rotation z"};
  if (i < 8) return kRoot[i];
  std::size_t at = 8;
  for (const auto& [joint, spherical] : deepMimicJoints()) {
    const std::size_t width = spherical ? 4 : 1;
    if (i < at + width)
      return joint + (spherical ? std::string(" ") + "wxyz"[i - at] : std::string(" angle"));
    at += width;
  }
  return "value " + std::to_string(i);
}

// Records why the JSON does not parse, with its line and column (nlohmann's non-throwing parse says only
// that it failed): a SAX pass that accepts everything but the error, and throws nothing.
class ParseErrorText : public nlohmann::json_sax<json> {
 public:
  std::string message;
  bool null() override { return true; }
  bool boolean(bool) override { return true; }
  bool number_integer(number_integer_t) override { return true; }
  bool number_unsigned(number_unsigned_t) override { return true; }
  bool number_float(number_float_t, const string_t&) override { return true; }
  bool string(string_t&) override { return true; }
  bool binary(binary_t&) override { return true; }
  bool start_object(std::size_t) override { return true; }
  bool key(string_t&) override { return true; }
  bool end_object() override { return true; }
  bool start_array(std::size_t) override { return true; }
  bool end_array() override { return true; }
  bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception& ex) override {
    message = ex.what();
    // "[json.exception.parse_error.101] parse error at line 1, column 17: ...": the tag means nothing to a
    // person.
    if (!message.empty() && message.front() == '[') {
      const std::size_t close = message.find("] ");
      if (close != std::string::npos) message.erase(0, close + 2);
    }
    return false;
  }
};

MotionClipResult fail(MotionClipResult& result, const std::string& message) {
  result.status = Status::error(ErrorCode::InvalidArgument, message);
  return result;
}

MotionClipResult parseDocument(const json& doc, const DeepMimicOptions& options, const std::string& name) {
  MotionClipResult result;
  const MotionLimits& limits = options.limits;
  if (!doc.is_object()) {
    return fail(result, name + ": the top level is a JSON " + doc.type_name() +
                            ", not an object {\"Loop\": ..., \"Frames\": [...]}");
  }
  MotionClip clip;
  clip.name = name;
  clip.frame = MotionFrame::YUp;
  const auto loop = doc.find("Loop");
  if (loop != doc.end()) {
    const std::string* mode = loop->get_ptr<const std::string*>();
    if (mode && *mode == "wrap") {
      clip.loop = true;
    } else if (mode && *mode == "none") {
      clip.loop = false;
    } else {
      return fail(result, name + ": \"Loop\" is " +
                              (mode ? "\"" + mode->substr(0, 40) + "\""
                                    : std::string("a JSON ") + loop->type_name()) +
                              "; it must be \"wrap\" or \"none\"");
    }
  }
  const auto found = doc.find("Frames");
  if (found == doc.end()) return fail(result, name + ": no \"Frames\" list");
  const json& frames = *found;
  if (!frames.is_array()) {
    return fail(result, name + ": \"Frames\" is a JSON " + frames.type_name() + ", not a list of frames");
  }
  if (frames.empty()) return fail(result, name + ": \"Frames\" is empty");
  if (frames.size() < 2) {
    return fail(result, name +
                            ": \"Frames\" has 1 frame; a clip needs at least 2 (a frame's duration is the "
                            "time to the next)");
  }
  if (frames.size() > limits.maxSamples) {
    return fail(result, name + ": " + std::to_string(frames.size()) + " frames; the limit is " +
                            std::to_string(limits.maxSamples) + " (MotionLimits::maxSamples)");
  }
  if (kFrameValues > limits.maxJoints) {
    return fail(result, name + ": a frame has " + std::to_string(kFrameValues) + " values; the limit is " +
                            std::to_string(limits.maxJoints) + " (MotionLimits::maxJoints)");
  }
  for (const auto& [joint, spherical] : deepMimicJoints())
    (spherical ? clip.balls : clip.joints).push_back(joint);
  const std::size_t count = frames.size();
  clip.times.reserve(count);
  clip.rootPositions.reserve(count);
  clip.rootRotations.reserve(count);
  clip.values.reserve(count * clip.joints.size());
  clip.rotations.reserve(count * clip.balls.size());

  std::array<double, kFrameValues> v{};
  double time = 0.0;  // s, the frame's: the sum of the durations before it
  for (std::size_t k = 0; k < count; ++k) {
    const std::string where = name + ": Frames[" + std::to_string(k) + "]: ";
    const json& frame = frames[k];
    if (!frame.is_array())
      return fail(result, where + "a JSON " + frame.type_name() + ", not a list of numbers");
    if (frame.size() != kFrameValues) {
      return fail(result, where + std::to_string(frame.size()) +
                              " values; a frame of the DeepMimic humanoid has " +
                              std::to_string(kFrameValues) +
                              " (duration, root position 3, root rotation 4, 8 quaternions, 4 angles)");
    }
    for (std::size_t i = 0; i < kFrameValues; ++i) {
      const json& e = frame[i];
      if (!e.is_number()) {
        return fail(result, where + "value " + std::to_string(i) + " (" + valueLabel(i) + ") is a JSON " +
                                e.type_name() + ", not a number");
      }
      v[i] = e.get<double>();
      if (!std::isfinite(v[i])) {
        return fail(result, where + "value " + std::to_string(i) + " (" + valueLabel(i) + ") is not finite");
      }
    }
    clip.times.push_back(time);
    if (k + 1 < count) {  // the last frame's duration leads nowhere and is not read
      if (!(v[0] > 0.0)) {
        return fail(result, where + "the duration " + std::to_string(v[0]) +
                                " s is not positive (it is the time to the next frame)");
      }
      const double next = time + v[0];
      if (!std::isfinite(next) || !(next > time)) {
        return fail(result, where + "the duration " + std::to_string(v[0]) + " s does not move the time " +
                                std::to_string(time) + " s forward in double precision");
      }
      time = next;
    }
    clip.rootPositions.emplace_back(v[1], v[2], v[3]);
    Eigen::Quaterniond root(v[4], v[5], v[6], v[7]);  // the file's (w, x, y, z), as Eigen's constructor
    if (!normaliseQuaternion(root)) return fail(result, where + "the root rotation (values 4 to 7) is zero");
    clip.rootRotations.push_back(root);
    std::size_t i = 8;
    for (const auto& [joint, spherical] : deepMimicJoints()) {
      if (!spherical) {
        clip.values.push_back(v[i++]);
        continue;
      }
      Eigen::Quaterniond q(v[i], v[i + 1], v[i + 2], v[i + 3]);
      if (!normaliseQuaternion(q)) {
        return fail(result, where + "the rotation of " + joint + " (values " + std::to_string(i) + " to " +
                                std::to_string(i + 3) + ") is zero");
      }
      clip.rotations.push_back(q);
      i += 4;
    }
  }
  result.status = clip.check();
  if (!result.status.ok()) return result;
  result.clip = std::move(clip);
  return result;
}

}  // namespace

const std::vector<std::pair<std::string, bool>>& deepMimicJoints() {
  static const std::vector<std::pair<std::string, bool>> joints = {
      {"chest", true},       {"neck", true},           {"right_hip", true},     {"right_knee", false},
      {"right_ankle", true}, {"right_shoulder", true}, {"right_elbow", false},  {"left_hip", true},
      {"left_knee", false},  {"left_ankle", true},     {"left_shoulder", true}, {"left_elbow", false}};
  return joints;
}

MotionClipResult parseDeepMimic(const std::string& text, const DeepMimicOptions& options,
                                const std::string& name) {
  MotionClipResult result;
  result.status = checkLimits(options.limits);
  if (!result.status.ok()) return result;
  if (text.size() > options.limits.maxFileBytes) {
    result.status = tooManyBytes(name, text.size(), options.limits.maxFileBytes);
    return result;
  }
  // nlohmann_json throws on a type mismatch and std::bad_alloc may come from anywhere: none of it leaves.
  try {
    const json doc = json::parse(text, nullptr, /*allow_exceptions=*/false);
    if (doc.is_discarded()) {
      ParseErrorText why;
      json::sax_parse(text, &why, nlohmann::detail::input_format_t::json, /*strict=*/true);
      return fail(result, name + ": not valid JSON" + (why.message.empty() ? "" : ": " + why.message));
    }
    return parseDocument(doc, options, name);
  } catch (const std::exception& e) {
    return fail(result, name + ": cannot be read: " + e.what());
  } catch (...) {
    return fail(result, name + ": cannot be read");
  }
}

MotionClipResult readDeepMimic(const std::string& path, const DeepMimicOptions& options) {
  MotionClipResult result;
  result.status = checkLimits(options.limits);
  if (!result.status.ok()) return result;
  std::string text;
  result.status = readTextFile(path, options.limits.maxFileBytes, text);
  if (!result.status.ok()) return result;
  return parseDeepMimic(text, options, path);
}

}  // namespace cape::character
