#include "ImageFile.h"

#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace cape::demo {

bool readGrayPng(const std::filesystem::path& file, GrayImage& image, std::string& error) {
  image = GrayImage();
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  // libpng's simplified API: it checks the signature, CRCs and sizes and converts every colour type to
  // gray (luminance, sRGB-decoded from RGB) itself; errors come back in png.message, never as a crash.
  if (!png_image_begin_read_from_file(&png, file.c_str())) {
    error = "cannot read '" + file.string() + "' as a PNG: " + png.message;
    return false;
  }
  if (png.width == 0 || png.height == 0 || png.width > static_cast<png_uint_32>(kMaxWeightMapSide) ||
      png.height > static_cast<png_uint_32>(kMaxWeightMapSide)) {
    error = "'" + file.string() + "' is " + std::to_string(png.width) + " x " + std::to_string(png.height) +
            " pixels: a weight map may have 1 to " + std::to_string(kMaxWeightMapSide) + " on a side";
    png_image_free(&png);
    return false;
  }
  png.format = PNG_FORMAT_GRAY;
  std::vector<std::uint8_t> pixels(PNG_IMAGE_SIZE(png));
  if (!png_image_finish_read(&png, nullptr, pixels.data(), 0, nullptr)) {
    error = "cannot decode '" + file.string() + "': " + png.message;
    png_image_free(&png);
    return false;
  }
  image.width = static_cast<int>(png.width);
  image.height = static_cast<int>(png.height);
  image.pixels.resize(pixels.size());
  for (std::size_t i = 0; i < pixels.size(); ++i) image.pixels[i] = static_cast<float>(pixels[i]) / 255.0f;
  return true;
}

bool writeGrayPng(const std::filesystem::path& file, const GrayImage& image, std::string& error) {
  if (image.width <= 0 || image.height <= 0 ||
      image.pixels.size() != static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height)) {
    error = "writeGrayPng: the image's size does not match its pixels";
    return false;
  }
  std::vector<std::uint8_t> pixels(image.pixels.size());
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    const float v = std::isfinite(image.pixels[i]) ? std::clamp(image.pixels[i], 0.0f, 1.0f) : 0.0f;
    pixels[i] = static_cast<std::uint8_t>(std::lround(255.0f * v));
  }
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  png.width = static_cast<png_uint_32>(image.width);
  png.height = static_cast<png_uint_32>(image.height);
  png.format = PNG_FORMAT_GRAY;
  if (!png_image_write_to_file(&png, file.c_str(), 0, pixels.data(), 0, nullptr)) {
    error = "cannot write '" + file.string() + "': " + png.message;
    return false;
  }
  return true;
}

}  // namespace cape::demo
