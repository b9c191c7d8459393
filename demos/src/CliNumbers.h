// Strict numbers on the command line: every number of every demo option is read here, the whole text or
// nothing. A number is written in decimal: an optional sign, digits with an optional fraction, an optional
// exponent (`20`, `-0.5`, `1e-3`, `+2.5E2`). Spaces, hexadecimal, `inf`, `nan`, trailing characters and
// values that overflow are refused, as is anything outside the option's documented range. Each parser
// returns an empty string when it read the text, else the reason (naming the range), which CLI11 prints
// after the option's name.
#pragma once

#include <CLI/CLI.hpp>
#include <Eigen/Core>

#include <cstdint>
#include <string>

namespace cape::demo {

/// A finite real number in [lo, hi].
std::string parseReal(const std::string& text, double lo, double hi, double& out);

/// A whole number in [lo, hi] (no fraction, no exponent).
std::string parseInteger(const std::string& text, std::int64_t lo, std::int64_t hi, std::int64_t& out);

/// Three comma-separated reals, each with |v| <= bound: `X,Y,Z`.
std::string parseVector3(const std::string& text, double bound, Eigen::Vector3d& out);

/// An image size `WxH`: two whole numbers, each in [lo, hi] and, when `even`, even.
std::string parseImageSize(const std::string& text, int lo, int hi, bool even, int& width, int& height);

/// CLI11 transforms that read an option's text strictly as above and hand CLI11 the value written exactly
/// (a real as a hexadecimal float, so no bit changes on the way), or fail with the reason. The description
/// ("in 0.01..86400") is shown in --help.
CLI::Validator strictReal(double lo, double hi);
CLI::Validator strictInteger(std::int64_t lo, std::int64_t hi);
/// Checks (the text is kept) for `X,Y,Z` and `WxH` options, read again by the functions above.
CLI::Validator strictVector3(double bound);
CLI::Validator strictImageSize(int lo, int hi, bool even);

}  // namespace cape::demo
