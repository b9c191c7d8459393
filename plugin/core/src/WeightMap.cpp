#include "cape/core/WeightMap.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace cape {
namespace {

Status checkRange(float low, float high) {
  if (!std::isfinite(low) || !std::isfinite(high))
    return Status::error("weight map: the range " + std::to_string(low) + " .. " + std::to_string(high) +
                         " is not finite");
  return Status::success();
}

WeightMapResult failure(Status status) {
  WeightMapResult r;
  r.status = std::move(status);
  return r;
}

}  // namespace

WeightMapResult weightMapFromImage(const Fabric& fabric, const GrayImage& image, float low, float high) {
  if (Status st = checkRange(low, high); !st.ok()) return failure(st);
  constexpr int kMaxSide = 16384;
  if (image.width <= 0 || image.height <= 0 || image.width > kMaxSide || image.height > kMaxSide ||
      image.pixels.size() != static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height))
    return failure(Status::error("weight map: an image of " + std::to_string(image.width) + " x " +
                                 std::to_string(image.height) + " pixels with " +
                                 std::to_string(image.pixels.size()) + " values (1 to 16384 a side)"));
  for (std::size_t k = 0; k < image.pixels.size(); ++k)
    if (!(image.pixels[k] >= 0.0f && image.pixels[k] <= 1.0f))
      return failure(Status::error("weight map: pixel " + std::to_string(k) + " is " +
                                   std::to_string(image.pixels[k]) + ", not in 0..1"));
  const std::vector<Eigen::Vector2f>& uvs = fabric.uvs();
  const bool anyUv =
      std::any_of(uvs.begin(), uvs.end(), [&](const Eigen::Vector2f& uv) { return uv != uvs[0]; });
  if (!anyUv) return failure(Status::error("weight map: the fabric has no UVs (all at one point)"));
  for (std::size_t i = 0; i < uvs.size(); ++i)
    if (!uvs[i].allFinite())
      return failure(Status::error("weight map: the UV of particle " + std::to_string(i) + " is not finite"));
  WeightMapResult r;
  r.values.resize(static_cast<Eigen::Index>(uvs.size()));
  const auto at = [&](int x, int y) {
    return image.pixels[static_cast<std::size_t>(y) * static_cast<std::size_t>(image.width) +
                        static_cast<std::size_t>(x)];
  };
  for (std::size_t i = 0; i < uvs.size(); ++i) {
    // Pixel centres at (x + 1/2) / width: the sample point in pixel units, held within the outer centres.
    const float fx = std::clamp(uvs[i].x() * static_cast<float>(image.width) - 0.5f, 0.0f,
                                static_cast<float>(image.width - 1));
    const float fy = std::clamp(uvs[i].y() * static_cast<float>(image.height) - 0.5f, 0.0f,
                                static_cast<float>(image.height - 1));
    const int x0 = std::min(static_cast<int>(fx), image.width - 1),
              y0 = std::min(static_cast<int>(fy), image.height - 1);
    const int x1 = std::min(x0 + 1, image.width - 1), y1 = std::min(y0 + 1, image.height - 1);
    const float tx = fx - static_cast<float>(x0), ty = fy - static_cast<float>(y0);
    const float top = at(x0, y0) + tx * (at(x1, y0) - at(x0, y0));
    const float bottom = at(x0, y1) + tx * (at(x1, y1) - at(x0, y1));
    const float value = top + ty * (bottom - top);
    r.values[static_cast<Eigen::Index>(i)] = low + (high - low) * value;
  }
  return r;
}

WeightMapResult weightMapFromColours(const Fabric& fabric, const std::vector<Vec3>& colours, float low,
                                     float high) {
  if (Status st = checkRange(low, high); !st.ok()) return failure(st);
  if (colours.size() != fabric.particleCount())
    return failure(Status::error("weight map: " + std::to_string(colours.size()) + " colours for " +
                                 std::to_string(fabric.particleCount()) + " particles"));
  WeightMapResult r;
  r.values.resize(static_cast<Eigen::Index>(colours.size()));
  for (std::size_t i = 0; i < colours.size(); ++i) {
    const Vec3& c = colours[i];
    for (int k = 0; k < 3; ++k)
      if (!(c[k] >= 0.0f && c[k] <= 1.0f))
        return failure(
            Status::error("weight map: the colour of vertex " + std::to_string(i) + " is not in 0..1"));
    const float luminance = 0.2126f * c.x() + 0.7152f * c.y() + 0.0722f * c.z();
    r.values[static_cast<Eigen::Index>(i)] = low + (high - low) * luminance;
  }
  return r;
}

}  // namespace cape
