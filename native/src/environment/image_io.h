// Checking environment images' sizes and pixels, and reading image files (read_image_file: image_file.cpp,
// the library sdlighting_image_files). Private to the environment files.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace sd {

/// Guards against absurd allocations (and int overflow of texel indices in the bindings).
constexpr int kMaxImageSide = 65536;
constexpr int64_t kMaxTexels = int64_t(1) << 28;

/// Cube faces in their order: +X, −X, +Y, −Y, +Z, −Z.
extern const char* const kFaceNames[6];

/// Throws std::invalid_argument naming `origin` for an empty image or one beyond the guards.
void check_image_size(int width, int height, int64_t texels, const std::string& origin);

/// Throws std::invalid_argument for a NaN or infinite value, naming `origin`, the pixel (x, y from
/// the top, and the face for a six-face block of width × height faces) and the channel.
void check_finite_pixels(const std::vector<float>& rgb, int width, int height, const std::string& origin);

/// Linear RGB floats of an image file, rows top-first.
struct LoadedImage {
  int width = 0, height = 0;
  std::vector<float> rgb;
};

/// Reads subimage 0 of a file with OpenImageIO as environment.h's Environment::load() describes:
/// float data as linear, integer data decoded from sRGB unless the file names a linear space,
/// grey copied to RGB, alpha ignored. Throws std::runtime_error when the file cannot be opened or
/// read or is not a non-empty regular file (checked with stat first: a FIFO or /dev/zero is
/// refused without reading), std::invalid_argument for an empty image or non-finite values.
LoadedImage read_image_file(const std::string& path);

}  // namespace sd
