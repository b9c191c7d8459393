// The motion file formats by name, by extension or first bytes, and one loader for all three.
#include "cape/character/MotionFormats.h"

#include "MotionText.h"

#include <cctype>
#include <filesystem>
#include <fstream>
#include <string_view>

namespace cape::character {

namespace {

std::string lower(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

// The first bytes of a file say its format: a CSV header may follow comment lines, so up to 64 KiB are read.
constexpr std::size_t kSniffBytes = std::size_t(64) << 10;

MotionFormat formatFromContent(std::string_view head) {
  if (head.substr(0, 3) == "\xEF\xBB\xBF") head.remove_prefix(3);  // a UTF-8 byte order mark
  std::size_t pos = 0;
  while (pos < head.size()) {
    const std::size_t end = head.find('\n', pos);
    const std::string_view line = motiontext::trim(
        head.substr(pos, end == std::string_view::npos ? std::string_view::npos : end - pos));
    pos = end == std::string_view::npos ? head.size() : end + 1;
    if (line.empty()) continue;
    if (line.substr(0, 9) == "HIERARCHY") return MotionFormat::Bvh;
    if (line.front() == '{') return MotionFormat::DeepMimic;
    if (line.front() == '#') continue;  // a CSV comment (and nothing BVH or JSON starts with)
    return line.substr(0, 4) == "time" ? MotionFormat::Csv : MotionFormat::Auto;
  }
  return MotionFormat::Auto;
}

}  // namespace

const char* toString(MotionFormat format) {
  switch (format) {
    case MotionFormat::Auto:
      return "auto";
    case MotionFormat::Csv:
      return "csv";
    case MotionFormat::DeepMimic:
      return "deepmimic";
    case MotionFormat::Bvh:
      return "bvh";
  }
  return "unknown";
}

bool parseMotionFormat(const std::string& text, MotionFormat& out) {
  const std::string name = lower(std::string(motiontext::trim(text)));
  for (MotionFormat f : {MotionFormat::Auto, MotionFormat::Csv, MotionFormat::DeepMimic, MotionFormat::Bvh}) {
    if (name == toString(f)) {
      out = f;
      return true;
    }
  }
  return false;
}

MotionFormat detectMotionFormat(const std::string& path) {
  const std::string ext = lower(std::filesystem::path(path).extension().string());
  if (ext == ".csv") return MotionFormat::Csv;
  if (ext == ".bvh") return MotionFormat::Bvh;
  if (ext == ".json") return MotionFormat::DeepMimic;
  // PyBullet ships DeepMimic as .txt, but a .txt may be anything: its first bytes decide, DeepMimic if
  // they say nothing.
  const bool text = ext == ".txt";
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return text ? MotionFormat::DeepMimic : MotionFormat::Auto;
  std::ifstream in(path, std::ios::binary);
  if (!in) return text ? MotionFormat::DeepMimic : MotionFormat::Auto;
  std::string head(kSniffBytes, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));
  const MotionFormat found = formatFromContent(head);
  return text && found == MotionFormat::Auto ? MotionFormat::DeepMimic : found;
}

MotionClipResult loadMotion(const std::string& path, const UrdfModelPtr& model,
                            const MotionLoadOptions& options, const JointMapping* mapping,
                            double characterScale) {
  MotionFormat format = options.format;
  if (format == MotionFormat::Auto) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) {
      MotionClipResult result;
      result.status = Status::error(ErrorCode::FileNotFound,
                                    "motion file '" + path + "' does not exist or is not a file");
      return result;
    }
    format = detectMotionFormat(path);
  }
  switch (format) {
    case MotionFormat::Csv:
      return readMotionCsv(path, options.csv);
    case MotionFormat::DeepMimic:
      return readDeepMimic(path, options.deepMimic);
    case MotionFormat::Bvh:
      if (!model) {
        MotionClipResult result;
        result.status = Status::error(ErrorCode::InvalidArgument,
                                      path + ": a BVH is retargeted onto a URDF model, and none was given");
        return result;
      }
      return readBvh(path, model, options.bvh, mapping, characterScale);
    case MotionFormat::Auto:
      break;
  }
  MotionClipResult result;
  result.status = Status::error(ErrorCode::InvalidArgument, "cannot tell the format of " + path +
                                                                "; give --motion-format csv|deepmimic|bvh");
  return result;
}

}  // namespace cape::character
