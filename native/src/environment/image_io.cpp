// Checking environment images' sizes and pixels: for files (image_file.cpp) and for pixels passed in.
#include "environment/image_io.h"

#include "sdlighting/limits.h"

#include <cmath>
#include <stdexcept>

namespace sd {

const char* const kFaceNames[6] = {"+X", "-X", "+Y", "-Y", "+Z", "-Z"};

void check_image_size(int width, int height, int64_t texels, const std::string& origin) {
  if (width < 1 || height < 1) {
    throw std::invalid_argument(origin + ": the image is empty (" + std::to_string(width) + " x " +
                                std::to_string(height) + " pixels)");
  }
  if (width > kMaxImageSide || height > kMaxImageSide || texels > kMaxTexels) {
    throw std::invalid_argument(origin + ": the image is too large (" + std::to_string(width) + " x " +
                                std::to_string(height) + ")");
  }
}

void check_finite_pixels(const std::vector<float>& rgb, int width, int height, const std::string& origin) {
  for (size_t k = 0; k < rgb.size(); ++k) {
    if (std::isfinite(rgb[k])) continue;
    const size_t pixel = k / 3, channel = k % 3;
    const size_t x = pixel % static_cast<size_t>(width), y = (pixel / width) % static_cast<size_t>(height);
    std::string where = origin + ": pixel (x=" + std::to_string(x) + ", y=" + std::to_string(y) + " from the top";
    const size_t face = pixel / (static_cast<size_t>(width) * height);
    if (face > 0) where += std::string(", face ") + kFaceNames[face % 6];
    throw std::invalid_argument(where + ") channel " + "RGB"[channel] + " is " +
                                (std::isnan(rgb[k]) ? "NaN" : "infinite") + ": environment maps must be finite");
  }
}

}  // namespace sd
