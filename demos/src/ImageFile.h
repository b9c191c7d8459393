// Grayscale images from PNG files through libpng, for the weight maps of cape/core/WeightMap.h (the core
// takes pixels, not files): any PNG (gray, gray + alpha, RGB, RGBA, palette; 8 or 16 bits) read as its
// luminance in 0..1, the top row first.
#pragma once

#include "cape/core/WeightMap.h"

#include <filesystem>
#include <string>

namespace cape::demo {

/// The largest side a weight-map image may have, pixels (WeightMap.h's bound).
constexpr int kMaxWeightMapSide = 16384;

/// Reads `file` into `image` (values in 0..1, 1 white). False with a reason (the file is missing, not a
/// PNG, truncated or corrupt, or larger than kMaxWeightMapSide on a side); `image` is then left empty.
bool readGrayPng(const std::filesystem::path& file, GrayImage& image, std::string& error);

/// Writes `image` as an 8-bit grayscale PNG (values clamped to 0..1). False with a reason on failure.
bool writeGrayPng(const std::filesystem::path& file, const GrayImage& image, std::string& error);

}  // namespace cape::demo
