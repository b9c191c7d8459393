/// \file
/// Weight maps: one value per particle (a MotionConstraints array, or any per-particle setting) painted by an
/// artist as a grayscale image over the fabric's UVs, or as the vertex colours of the mesh the fabric was
/// made from, mapped from 0..1 onto a range of the setting's units.
#pragma once

#include "cape/core/Export.h"
#include "cape/core/Fabric.h"
#include "cape/core/Types.h"

#include <Eigen/Core>

#include <vector>

namespace cape {

/// A grayscale image in memory, from whatever loader the application has: width x height values in 0..1,
/// row after row from the top.
struct GrayImage {
  int width = 0;              ///< Pixels across.
  int height = 0;             ///< Pixels down.
  std::vector<float> pixels;  ///< width * height values in 0..1, the top row first.
};

/// A weight map, or why there is none.
struct WeightMapResult {
  Eigen::VectorXf values;             ///< One value per particle; empty on error.
  Status status = Status::success();  ///< Why there are no values.
  /// True when the map was made.
  explicit operator bool() const { return status.ok(); }
};

/// Per particle, low + (high - low) times the image at the particle's UV: bilinear between pixel centres,
/// held at the edges beyond the outer centres and beyond 0..1. UV (0, 0) is the image's top-left corner and
/// (1, 1) its bottom-right (glTF's convention, and the grid fabric's: v = 0 along the top row, the pinned
/// one). An error when the image's size does not match its pixels (or is 0 or over 16384 a side), a pixel
/// is not in 0..1, low or high is not finite, or the fabric's UVs are all one point (a fabric made without
/// UVs).
CAPE_CORE_API WeightMapResult weightMapFromImage(const Fabric& fabric, const GrayImage& image, float low,
                                                 float high);

/// Per particle, low + (high - low) times the luminance of its vertex's colour (Rec. 709: 0.2126 r +
/// 0.7152 g + 0.0722 b), from one RGB colour in 0..1 per vertex of the mesh the fabric was made from
/// (Fabric::fromMesh keeps the mesh's vertices as the particles, in order). An error on another count than
/// the particles, a component outside 0..1, or low or high not finite.
CAPE_CORE_API WeightMapResult weightMapFromColours(const Fabric& fabric, const std::vector<Vec3>& colours,
                                                   float low, float high);

}  // namespace cape
