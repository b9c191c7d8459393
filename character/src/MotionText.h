// Small helpers the motion file readers share (private to the character library): strict number parsing,
// trimming, the limits' own check, quaternion normalisation and reading a file under a size limit. Each
// returns its error as a value.
#pragma once

#include "cape/character/MotionFormats.h"
#include "cape/character/Status.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <string_view>
#include <system_error>

namespace cape::character::motiontext {

/// `text` without spaces, tabs, carriage returns and newlines at either end.
inline std::string_view trim(std::string_view text) {
  const std::size_t a = text.find_first_not_of(" \t\r\n");
  if (a == std::string_view::npos) return std::string_view();
  const std::size_t b = text.find_last_not_of(" \t\r\n");
  return text.substr(a, b - a + 1);
}

/// "NAME:LINE: ", the start of a message about one line of a text file (lines count from 1).
inline std::string at(const std::string& name, std::size_t line) {
  return name + ":" + std::to_string(line) + ": ";
}

enum class NumberError : int { Ok, Empty, NotANumber, NotFinite };

/// The whole of `text` (already trimmed) as a double: decimal or scientific, an optional leading '+' or '-';
/// nothing may trail it. "nan" and "inf" parse but give NotFinite, as does a number out of the double's
/// range (1e999). std::from_chars: independent of the C locale (a "," decimal point would break a CSV).
inline NumberError parseDouble(std::string_view text, double& out) {
  if (text.empty()) return NumberError::Empty;
  if (text.front() == '+') {
    text.remove_prefix(1);
    if (text.empty() || text.front() == '-' || text.front() == '+') return NumberError::NotANumber;
  }
  const char* end = text.data() + text.size();
  double value = 0.0;
  const std::from_chars_result r = std::from_chars(text.data(), end, value);
  if (r.ec == std::errc::result_out_of_range && r.ptr == end) return NumberError::NotFinite;
  if (r.ec != std::errc() || r.ptr != end) return NumberError::NotANumber;
  if (!std::isfinite(value)) return NumberError::NotFinite;
  out = value;
  return NumberError::Ok;
}

/// What a NumberError means, for messages: "'abc' is not a number".
inline std::string numberProblem(NumberError error, std::string_view text) {
  switch (error) {
    case NumberError::Ok:
      return "ok";
    case NumberError::Empty:
      return "the field is empty";
    case NumberError::NotANumber:
      return "'" + std::string(text.substr(0, 40)) + (text.size() > 40 ? "...'" : "'") + " is not a number";
    case NumberError::NotFinite:
      return "'" + std::string(text.substr(0, 40)) + (text.size() > 40 ? "...'" : "'") +
             " is not a finite number";
  }
  return "bad number";
}

/// `q` made unit. A quaternion already unit to a few ulps is kept as it is, so that reading a written clip
/// back gives the same bits (renormalising a unit quaternion can move its last bit). The components are
/// first divided by the largest of them, so that 1e200 or 1e-200 components neither overflow nor flush to
/// zero. False (and `q` unchanged) for the zero quaternion, which has no direction.
inline bool normaliseQuaternion(Eigen::Quaterniond& q) {
  const double n2 = q.squaredNorm();
  if (std::abs(n2 - 1.0) <= 8.0 * std::numeric_limits<double>::epsilon()) return true;
  const double big = q.coeffs().cwiseAbs().maxCoeff();
  if (!(big > 0.0) || !std::isfinite(big)) return false;
  Eigen::Quaterniond scaled(q.coeffs() / big);
  scaled.normalize();
  q = scaled;
  return true;
}

/// InvalidArgument when a count of `limits` is 0 (nothing could be read).
inline Status checkLimits(const MotionLimits& limits) {
  const std::pair<std::size_t, const char*> fields[] = {{limits.maxFileBytes, "maxFileBytes"},
                                                        {limits.maxSamples, "maxSamples"},
                                                        {limits.maxJoints, "maxJoints"},
                                                        {limits.maxDepth, "maxDepth"}};
  for (const auto& [value, field] : fields) {
    if (value == 0) {
      return Status::error(ErrorCode::InvalidArgument,
                           std::string("MotionLimits::") + field + " is 0; it must be at least 1");
    }
  }
  return Status::success();
}

/// "NAME: has N bytes; the limit is M (MotionLimits::maxFileBytes)".
inline Status tooManyBytes(const std::string& name, std::size_t bytes, std::size_t limit) {
  return Status::error(ErrorCode::InvalidArgument, name + ": " + std::to_string(bytes) +
                                                       " bytes; the limit is " + std::to_string(limit) +
                                                       " (MotionLimits::maxFileBytes)");
}

/// Reads the file at `path` into `out`. FileNotFound when it is not a readable regular file; InvalidArgument
/// when it holds more than `maxBytes`: the size is checked before reading, and the read stops one byte past
/// the limit (the file may grow meanwhile, or a special file report no size).
inline Status readTextFile(const std::string& path, std::size_t maxBytes, std::string& out) {
  out.clear();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    return Status::error(ErrorCode::FileNotFound,
                         "motion file '" + path + "' does not exist or is not a file");
  }
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (!ec && size > maxBytes) return tooManyBytes(path, static_cast<std::size_t>(size), maxBytes);
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::error(ErrorCode::FileNotFound, "motion file '" + path + "' cannot be opened");
  std::string text;
  char chunk[65536];
  while (in && text.size() <= maxBytes) {
    const std::size_t room = maxBytes - text.size();  // one byte more is read, to see the file is over
    const std::size_t want = room >= sizeof chunk ? sizeof chunk : room + 1;
    in.read(chunk, static_cast<std::streamsize>(want));
    text.append(chunk, static_cast<std::size_t>(in.gcount()));
  }
  if (in.bad()) return Status::error(ErrorCode::FileNotFound, "motion file '" + path + "' cannot be read");
  if (text.size() > maxBytes) {
    return Status::error(ErrorCode::InvalidArgument, path + ": more than " + std::to_string(maxBytes) +
                                                         " bytes; the limit is " + std::to_string(maxBytes) +
                                                         " (MotionLimits::maxFileBytes)");
  }
  out = std::move(text);
  return Status::success();
}

}  // namespace cape::character::motiontext
