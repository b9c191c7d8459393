#include "CliNumbers.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <system_error>

namespace cape::demo {

namespace {

std::string show(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", v);
  return text;
}

/// The text as quoted in a message, cut short when long.
std::string quoted(const std::string& text) {
  return "'" + (text.size() > 40 ? text.substr(0, 40) + "..." : text) + "'";
}

bool isDigit(char c) {
  return c >= '0' && c <= '9';
}

/// Length of the run of digits at text[at...].
std::size_t digitsAt(const std::string& text, std::size_t at) {
  std::size_t n = 0;
  while (at + n < text.size() && isDigit(text[at + n])) ++n;
  return n;
}

/// The decimal grammar of the header: [+-] (D+ [. D*] | . D+) ([eE] [+-] D+).
bool isDecimalReal(const std::string& t) {
  std::size_t i = 0;
  if (i < t.size() && (t[i] == '+' || t[i] == '-')) ++i;
  const std::size_t whole = digitsAt(t, i);
  i += whole;
  std::size_t fraction = 0;
  if (i < t.size() && t[i] == '.') {
    ++i;
    fraction = digitsAt(t, i);
    i += fraction;
  }
  if (whole == 0 && fraction == 0) return false;
  if (i < t.size() && (t[i] == 'e' || t[i] == 'E')) {
    ++i;
    if (i < t.size() && (t[i] == '+' || t[i] == '-')) ++i;
    const std::size_t exponent = digitsAt(t, i);
    if (exponent == 0) return false;
    i += exponent;
  }
  return i == t.size();
}

bool isDecimalInteger(const std::string& t) {
  const std::size_t sign = !t.empty() && (t[0] == '+' || t[0] == '-') ? 1 : 0;
  const std::size_t digits = digitsAt(t, sign);
  return digits > 0 && sign + digits == t.size();
}

/// from_chars reads no leading '+'.
const char* afterPlus(const std::string& t) {
  return t.data() + (!t.empty() && t[0] == '+' ? 1 : 0);
}

}  // namespace

std::string parseReal(const std::string& text, double lo, double hi, double& out) {
  const std::string range = "a number from " + show(lo) + " to " + show(hi);
  if (!isDecimalReal(text)) return quoted(text) + " is not a decimal number; give " + range;
  double value = 0.0;
  const char* end = text.data() + text.size();
  const std::from_chars_result r = std::from_chars(afterPlus(text), end, value);
  if (r.ec == std::errc::result_out_of_range || !std::isfinite(value) || value < lo || value > hi)
    return quoted(text) + " is out of range; give " + range;
  if (r.ec != std::errc() || r.ptr != end) return quoted(text) + " is not a decimal number; give " + range;
  out = value;
  return {};
}

std::string parseInteger(const std::string& text, std::int64_t lo, std::int64_t hi, std::int64_t& out) {
  const std::string range = "a whole number from " + std::to_string(lo) + " to " + std::to_string(hi);
  if (!isDecimalInteger(text)) return quoted(text) + " is not a whole number; give " + range;
  std::int64_t value = 0;
  const char* end = text.data() + text.size();
  const std::from_chars_result r = std::from_chars(afterPlus(text), end, value);
  if (r.ec == std::errc::result_out_of_range || value < lo || value > hi)
    return quoted(text) + " is out of range; give " + range;
  if (r.ec != std::errc() || r.ptr != end) return quoted(text) + " is not a whole number; give " + range;
  out = value;
  return {};
}

std::string parseVector3(const std::string& text, double bound, Eigen::Vector3d& out) {
  const std::string form = "give X,Y,Z: three numbers from " + show(-bound) + " to " + show(bound);
  Eigen::Vector3d v;
  std::size_t start = 0;
  for (int k = 0; k < 3; ++k) {
    const std::size_t comma = text.find(',', start);
    if ((k < 2) != (comma != std::string::npos)) return quoted(text) + " is not X,Y,Z; " + form;
    const std::string item = text.substr(start, k < 2 ? comma - start : std::string::npos);
    if (!parseReal(item, -bound, bound, v[k]).empty())
      return quoted(text) + ": " + "XYZ"[k] + " " + quoted(item) + " is not a number in range; " + form;
    start = comma + 1;
  }
  out = v;
  return {};
}

std::string parseImageSize(const std::string& text, int lo, int hi, bool even, int& width, int& height) {
  const std::string form = "give WxH, two " + std::string(even ? "even " : "") + "whole numbers from " +
                           std::to_string(lo) + " to " + std::to_string(hi) + " (e.g. 640x360)";
  const std::size_t x = text.find('x');
  if (x == std::string::npos) return quoted(text) + " is not WxH; " + form;
  std::int64_t w = 0, h = 0;
  if (!parseInteger(text.substr(0, x), lo, hi, w).empty() ||
      !parseInteger(text.substr(x + 1), lo, hi, h).empty())
    return quoted(text) + " is not a size in range; " + form;
  if (even && (w % 2 != 0 || h % 2 != 0))
    return quoted(text) + " has an odd side (the video needs even); " + form;
  width = static_cast<int>(w);
  height = static_cast<int>(h);
  return {};
}

CLI::Validator strictReal(double lo, double hi) {
  return CLI::Validator(
      [lo, hi](std::string& text) {
        double value = 0.0;
        std::string error = parseReal(text, lo, hi, value);
        if (error.empty()) {
          char exact[64];
          std::snprintf(exact, sizeof exact, "%a", value);
          text = exact;
        }
        return error;
      },
      "in " + show(lo) + ".." + show(hi));
}

CLI::Validator strictInteger(std::int64_t lo, std::int64_t hi) {
  return CLI::Validator(
      [lo, hi](std::string& text) {
        std::int64_t value = 0;
        std::string error = parseInteger(text, lo, hi, value);
        if (error.empty()) text = std::to_string(value);
        return error;
      },
      "in " + std::to_string(lo) + ".." + std::to_string(hi));
}

CLI::Validator strictVector3(double bound) {
  return CLI::Validator(
      [bound](std::string& text) {
        Eigen::Vector3d unused;
        return parseVector3(text, bound, unused);
      },
      "X,Y,Z, each in " + show(-bound) + ".." + show(bound));
}

CLI::Validator strictImageSize(int lo, int hi, bool even) {
  return CLI::Validator(
      [lo, hi, even](std::string& text) {
        int w = 0, h = 0;
        return parseImageSize(text, lo, hi, even, w, h);
      },
      "WxH, each " + std::string(even ? "even, " : "") + "in " + std::to_string(lo) + ".." +
          std::to_string(hi));
}

}  // namespace cape::demo
