// Joint trajectory CSV: a header naming the columns (time, the root's position and quaternion, then joints),
// one row per sample. Read line by line with every field checked; written to 17 significant digits, so that
// reading a written clip gives back its bits.
#include "cape/character/MotionFormats.h"

#include "MotionText.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <string_view>
#include <unordered_map>
#include <vector>

namespace cape::character {

namespace {

using namespace motiontext;

constexpr std::size_t kRootColumns = 8;
constexpr std::array<const char*, kRootColumns> kRootNames = {"time",    "root_x",  "root_y",  "root_z",
                                                              "root_qx", "root_qy", "root_qz", "root_qw"};
// A spherical joint's columns, in the order of Eigen's coeffs() (x, y, z, w).
constexpr std::array<const char*, 4> kBallSuffix = {".qx", ".qy", ".qz", ".qw"};

const char* headerStart() {
  return "time, root_x, root_y, root_z, root_qx, root_qy, root_qz, root_qw";
}

// The lines of a text that hold something: blank lines and '#' comment lines are skipped, a '\r' before the
// '\n' is dropped. `number` is the line's, counted from 1 over every line.
class Lines {
 public:
  explicit Lines(std::string_view text) : text_(text) {
    if (text_.substr(0, 3) == "\xEF\xBB\xBF") text_.remove_prefix(3);  // a UTF-8 byte order mark (Excel)
  }
  bool next(std::string_view& line) {
    while (pos_ < text_.size()) {
      const std::size_t end = text_.find('\n', pos_);
      std::string_view raw =
          text_.substr(pos_, end == std::string_view::npos ? std::string_view::npos : end - pos_);
      pos_ = end == std::string_view::npos ? text_.size() : end + 1;
      ++number_;
      const std::string_view content = trim(raw);
      if (content.empty() || content.front() == '#') continue;
      line = raw;
      return true;
    }
    return false;
  }
  std::size_t number() const { return number_; }

 private:
  std::string_view text_;
  std::size_t pos_ = 0;
  std::size_t number_ = 0;
};

std::size_t fieldCount(std::string_view line) {
  return 1 + static_cast<std::size_t>(std::count(line.begin(), line.end(), ','));
}

// The comma-separated fields of `line`, trimmed.
void splitFields(std::string_view line, std::vector<std::string_view>& out) {
  out.clear();
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = line.find(',', start);
    out.push_back(
        trim(line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start)));
    if (comma == std::string_view::npos) return;
    start = comma + 1;
  }
}

// Which of ".qx" ... ".qw" ends `name` (0..3, Eigen's coeffs() order), or -1.
int ballComponent(std::string_view name) {
  if (name.size() < 3) return -1;
  const std::string_view tail = name.substr(name.size() - 3);
  for (std::size_t c = 0; c < kBallSuffix.size(); ++c) {
    if (tail == kBallSuffix[c]) return static_cast<int>(c);
  }
  return -1;
}

// Where each column after the root's goes: a scalar joint's index, or a ball's index and component.
struct Column {
  bool ball = false;
  std::size_t index = 0;
  int component = 0;  // 0..3: x, y, z, w
};

// Reads the header line: the root's columns, then the joints. Fills the clip's joint and ball names.
Status parseHeader(std::string_view line, std::size_t lineNumber, const std::string& name,
                   const MotionLimits& limits, MotionClip& clip, std::vector<Column>& columns) {
  const std::string where = at(name, lineNumber);
  auto fail = [&](const std::string& why) { return Status::error(ErrorCode::InvalidArgument, where + why); };
  const std::size_t count = fieldCount(line);
  if (count > limits.maxJoints) {
    return fail("the header has " + std::to_string(count) + " columns; the limit is " +
                std::to_string(limits.maxJoints) + " (MotionLimits::maxJoints)");
  }
  std::vector<std::string_view> fields;
  splitFields(line, fields);
  for (std::size_t i = 0; i < kRootColumns; ++i) {
    if (i >= fields.size()) {
      return fail("the header has " + std::to_string(fields.size()) + " columns; it must start with " +
                  headerStart());
    }
    if (fields[i] != kRootNames[i]) {
      return fail("column " + std::to_string(i + 1) + " is '" + std::string(fields[i]) + "' where '" +
                  kRootNames[i] + "' belongs (the header starts " + headerStart() + ")");
    }
  }
  // Every column name once, and every joint once (a scalar "neck" and a ball "neck.qx ..." are one joint
  // named twice). Both maps hold the column (from 1) that named it first.
  std::unordered_map<std::string_view, std::size_t> seenColumns, seenJoints;
  for (std::size_t i = 0; i < fields.size(); ++i) {
    const auto [it, added] = seenColumns.emplace(fields[i], i + 1);
    if (!added && !fields[i].empty()) {
      return fail("column " + std::to_string(i + 1) + " '" + std::string(fields[i]) +
                  "' is the name of column " + std::to_string(it->second) + " too");
    }
  }
  auto addJoint = [&](std::string_view joint, std::size_t column) -> Status {
    const auto [it, added] = seenJoints.emplace(joint, column);
    if (!added) {
      return fail("joint '" + std::string(joint) + "' of column " + std::to_string(column) +
                  " is given twice (also column " + std::to_string(it->second) + ")");
    }
    return Status::success();
  };
  columns.clear();
  for (std::size_t i = kRootColumns; i < fields.size();) {
    const std::string_view field = fields[i];
    const std::string column = "column " + std::to_string(i + 1);
    if (field.empty()) return fail(column + " has no name");
    const int first = ballComponent(field);
    if (first < 0) {
      Status added = addJoint(field, i + 1);
      if (!added.ok()) return added;
      columns.push_back({false, clip.joints.size(), 0});
      clip.joints.emplace_back(field);
      ++i;
      continue;
    }
    // A spherical joint: four adjacent columns BASE.qx, .qy, .qz, .qw, in any order among themselves.
    const std::string_view base = field.substr(0, field.size() - 3);
    if (base.empty()) return fail(column + " '" + std::string(field) + "': the joint name is empty");
    const std::string want = "a spherical joint is four adjacent columns " + std::string(base) + ".qx, " +
                             std::string(base) + ".qy, " + std::string(base) + ".qz and " +
                             std::string(base) + ".qw";
    Status added = addJoint(base, i + 1);
    if (!added.ok()) return added;
    for (std::size_t k = 0; k < 4; ++k) {
      if (i + k >= fields.size()) {
        return fail(column + " '" + std::string(field) + "': the header ends before " + want);
      }
      const std::string_view part = fields[i + k];
      const int c = ballComponent(part);
      if (c < 0 || part.substr(0, part.size() - 3) != base) {
        return fail("column " + std::to_string(i + k + 1) + " is '" + std::string(part) + "': " + want);
      }
      // Each suffix once: a repeated one would be a repeated column name, refused above.
      columns.push_back({true, clip.balls.size(), c});
    }
    clip.balls.emplace_back(base);
    i += 4;
  }
  return Status::success();
}

// "column 3 (root_y)".
std::string columnName(std::size_t i, const std::vector<std::string_view>& header) {
  return "column " + std::to_string(i + 1) + " (" + std::string(header[i]) + ")";
}

void appendNumber(std::string& out, double value) {
  char buffer[40];
  const std::to_chars_result r =
      std::to_chars(buffer, buffer + sizeof buffer, value, std::chars_format::general, 17);
  out.append(buffer, r.ptr);
}

}  // namespace

MotionClipResult parseMotionCsv(const std::string& text, const CsvMotionOptions& options,
                                const std::string& name) {
  MotionClipResult result;
  result.status = checkLimits(options.limits);
  if (!result.status.ok()) return result;
  const MotionLimits& limits = options.limits;
  if (text.size() > limits.maxFileBytes) {
    result.status = tooManyBytes(name, text.size(), limits.maxFileBytes);
    return result;
  }
  MotionClip clip;
  clip.name = name;
  clip.frame = options.frame;
  clip.loop = options.loop;

  Lines lines(text);
  std::string_view line;
  if (!lines.next(line)) {
    result.status = Status::error(ErrorCode::InvalidArgument,
                                  name + ": no header line (" + headerStart() + ", joints...)");
    return result;
  }
  const std::size_t headerLine = lines.number();
  std::vector<Column> columns;
  result.status = parseHeader(line, headerLine, name, limits, clip, columns);
  if (!result.status.ok()) return result;
  std::vector<std::string_view> header;
  splitFields(line, header);
  const std::size_t width = header.size();

  std::vector<std::string_view> fields;
  std::vector<double> row(width);
  std::size_t previousLine = 0;
  while (lines.next(line)) {
    const std::string where = at(name, lines.number());
    auto fail = [&](const std::string& why) {
      result.status = Status::error(ErrorCode::InvalidArgument, where + why);
      return result;
    };
    if (clip.times.size() >= limits.maxSamples) {
      return fail("more than " + std::to_string(limits.maxSamples) + " samples; the limit is " +
                  std::to_string(limits.maxSamples) + " (MotionLimits::maxSamples)");
    }
    // Counted before splitting, so that a hostile row costs no vector of its fields.
    const std::size_t count = fieldCount(line);
    if (count != width) {
      return fail(std::to_string(count) + " fields; the header (line " + std::to_string(headerLine) +
                  ") has " + std::to_string(width));
    }
    splitFields(line, fields);
    for (std::size_t i = 0; i < width; ++i) {
      const NumberError e = parseDouble(fields[i], row[i]);
      if (e != NumberError::Ok) return fail(columnName(i, header) + ": " + numberProblem(e, fields[i]));
    }
    const double t = row[0];
    if (clip.times.empty() && t < 0.0) {
      return fail("time " + std::string(fields[0]) + " s is negative (a clip starts at 0 or later)");
    }
    if (!clip.times.empty() && !(t > clip.times.back())) {
      return fail("time " + std::string(fields[0]) + " s is not after the time of line " +
                  std::to_string(previousLine) + " (times must increase strictly)");
    }
    Eigen::Quaterniond root(row[7], row[4], row[5], row[6]);  // (w, x, y, z)
    if (!normaliseQuaternion(root)) return fail("the root quaternion (root_qx ... root_qw) is zero");
    clip.times.push_back(t);
    clip.rootPositions.emplace_back(row[1], row[2], row[3]);
    clip.rootRotations.push_back(root);
    const std::size_t valueStart = clip.values.size(), ballStart = clip.rotations.size();
    clip.values.resize(valueStart + clip.joints.size());
    clip.rotations.resize(ballStart + clip.balls.size(), Eigen::Quaterniond(0.0, 0.0, 0.0, 0.0));
    for (std::size_t i = kRootColumns; i < width; ++i) {
      const Column& c = columns[i - kRootColumns];
      if (c.ball) {
        clip.rotations[ballStart + c.index].coeffs()[c.component] = row[i];
      } else {
        clip.values[valueStart + c.index] = row[i];
      }
    }
    for (std::size_t b = 0; b < clip.balls.size(); ++b) {
      if (!normaliseQuaternion(clip.rotations[ballStart + b])) {
        return fail("the quaternion of joint '" + clip.balls[b] + "' is zero");
      }
    }
    previousLine = lines.number();
  }
  if (clip.times.empty()) {
    result.status = Status::error(ErrorCode::InvalidArgument,
                                  at(name, headerLine) + "a header and no sample row after it");
    return result;
  }
  result.status = clip.check();
  if (!result.status.ok()) return result;
  result.clip = std::move(clip);
  return result;
}

MotionClipResult readMotionCsv(const std::string& path, const CsvMotionOptions& options) {
  MotionClipResult result;
  result.status = checkLimits(options.limits);
  if (!result.status.ok()) return result;
  std::string text;
  result.status = readTextFile(path, options.limits.maxFileBytes, text);
  if (!result.status.ok()) return result;
  return parseMotionCsv(text, options, path);
}

Status writeMotionCsv(const MotionClip& clip, std::string& out) {
  const Status checked = clip.check();
  if (!checked.ok()) return checked;
  const auto refuse = [&](const std::string& name, const char* why) {
    return Status::error(ErrorCode::InvalidArgument, "motion clip '" + clip.name + "': joint '" + name +
                                                         "' cannot be a CSV column: " + why);
  };
  const auto writable = [&](const std::string& name, bool scalar) -> Status {
    if (name.empty()) return refuse(name, "an empty name");
    if (name.find_first_of(",\r\n") != std::string::npos)
      return refuse(name, "a comma or a line break in it");
    if (name.front() == '#') return refuse(name, "it starts with '#' (a comment)");
    if (std::isspace(static_cast<unsigned char>(name.front())) ||
        std::isspace(static_cast<unsigned char>(name.back())))
      return refuse(name, "spaces at an end (they are trimmed on reading)");
    for (const char* root : kRootNames)
      if (name == root) return refuse(name, "the name of a root column");
    if (scalar && name.size() > 3)
      for (const char* suffix : kBallSuffix)
        if (name.compare(name.size() - 3, 3, suffix) == 0)
          return refuse(name, "read back as a ball's column");
    return Status::success();
  };
  for (const std::string& j : clip.joints) {
    const Status s = writable(j, true);
    if (!s.ok()) return s;
  }
  for (const std::string& b : clip.balls) {
    const Status s = writable(b, false);
    if (!s.ok()) return s;
  }
  out = writeMotionCsv(clip);
  return Status::success();
}

std::string writeMotionCsv(const MotionClip& clip) {
  // Only the samples every array holds are written (a clip that fails check() is written as far as its
  // arrays agree; it is not read back as it was).
  std::size_t samples = std::min({clip.times.size(), clip.rootPositions.size(), clip.rootRotations.size()});
  if (!clip.joints.empty()) samples = std::min(samples, clip.values.size() / clip.joints.size());
  if (!clip.balls.empty()) samples = std::min(samples, clip.rotations.size() / clip.balls.size());

  std::string name = clip.name;
  for (char& c : name) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  std::string out = "# motion clip '" + name + "', " + std::to_string(samples) +
                    " samples; the root is in the " + toString(clip.frame) +
                    " frame (read it with CsvMotionOptions::frame set so)\n";
  for (std::size_t i = 0; i < kRootColumns; ++i) out += std::string(i ? "," : "") + kRootNames[i];
  for (const std::string& j : clip.joints) out += "," + j;
  for (const std::string& b : clip.balls) {
    for (const char* suffix : kBallSuffix) out += "," + b + suffix;
  }
  out += '\n';
  for (std::size_t s = 0; s < samples; ++s) {
    appendNumber(out, clip.times[s]);
    for (int k = 0; k < 3; ++k) {
      out += ',';
      appendNumber(out, clip.rootPositions[s][k]);
    }
    for (int k = 0; k < 4; ++k) {  // x, y, z, w
      out += ',';
      appendNumber(out, clip.rootRotations[s].coeffs()[k]);
    }
    for (std::size_t j = 0; j < clip.joints.size(); ++j) {
      out += ',';
      appendNumber(out, clip.values[s * clip.joints.size() + j]);
    }
    for (std::size_t b = 0; b < clip.balls.size(); ++b) {
      const Eigen::Quaterniond& q = clip.rotations[s * clip.balls.size() + b];
      for (int k = 0; k < 4; ++k) {
        out += ',';
        appendNumber(out, q.coeffs()[k]);
      }
    }
    out += '\n';
  }
  return out;
}

}  // namespace cape::character
