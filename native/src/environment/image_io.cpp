// Reading environment images through OpenImageIO and checking their pixels.
#include "environment/image_io.h"

#include "sdlighting/limits.h"

#include <OpenImageIO/imageio.h>

#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace sd {
namespace {

// The exact sRGB decoding curve (IEC 61966-2-1), as Blender decodes byte images.
double srgb_to_linear(double c) { return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4); }

bool names_linear_space(std::string name) {
  std::transform(name.begin(), name.end(), name.begin(), [](unsigned char ch) { return std::tolower(ch); });
  return name.find("linear") != std::string::npos;
}

// Refuses what is not a non-empty regular file before OpenImageIO opens it: a directory, a FIFO (opening
// it blocks until a writer comes), a device such as /dev/zero (endless data) or a socket. stat() looks
// without opening, so nothing here can block or read.
void check_regular_file(const std::string& path, const std::string& origin) {
  struct stat info {};
  if (::stat(path.c_str(), &info) != 0) {
    throw std::runtime_error("cannot open " + origin + ": " + std::strerror(errno));
  }
  if (S_ISDIR(info.st_mode)) throw std::runtime_error("cannot open " + origin + ": it is a directory, not an image file");
  if (!S_ISREG(info.st_mode)) {
    const char* kind = S_ISFIFO(info.st_mode)                                 ? "a FIFO (named pipe)"
                       : S_ISCHR(info.st_mode) || S_ISBLK(info.st_mode)       ? "a device file"
                       : S_ISSOCK(info.st_mode)                               ? "a socket"
                                                                              : "not a regular file";
    throw std::runtime_error("cannot open " + origin + ": it is " + kind +
                             ", not an image file (refused without reading: it could block or never end)");
  }
  if (info.st_size == 0) throw std::runtime_error("cannot open " + origin + ": the file is empty (0 bytes)");
}

}  // namespace

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

LoadedImage read_image_file(const std::string& path) {
  const std::string origin = "environment map '" + path + "'";
  check_regular_file(path, origin);
  // Alpha is ignored: ask for the stored (unassociated) colour, never colour × alpha.
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  auto in = OIIO::ImageInput::open(path, &config);
  if (!in) {
    std::string message = OIIO::geterror();
    if (message.empty()) message = "unknown OpenImageIO error";
    throw std::runtime_error("cannot open " + origin + ": " + message);
  }
  const OIIO::ImageSpec spec = in->spec();
  const int64_t texels = static_cast<int64_t>(spec.width) * spec.height;
  check_image_size(spec.width, spec.height, texels, origin);
  if (spec.depth > 1) throw std::invalid_argument(origin + ": volume images are not environment maps");
  const int channels = spec.nchannels;
  if (channels < 1) throw std::invalid_argument(origin + ": the image has no channels");
  // What OpenImageIO decodes into, and the RGB copy.
  check_allocation(origin + ": decoding " + std::to_string(spec.width) + " x " + std::to_string(spec.height) + " x " +
                       std::to_string(channels) + " pixels",
                   4.0 * static_cast<double>(texels) * (channels + 3));
  std::vector<float> data(static_cast<size_t>(texels) * channels);
  // A truncated TIFF reads "successfully" with its error only recorded: has_error() catches it.
  if (!in->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, data.data()) || in->has_error()) {
    std::string message = in->geterror();
    if (message.empty()) message = OIIO::geterror();
    if (message.empty()) message = "unknown OpenImageIO error";
    throw std::runtime_error("cannot read " + origin + ": " + message);
  }
  in->close();

  const bool decode_srgb = !spec.format.is_floating_point() &&
                           !names_linear_space(spec.get_string_attribute("oiio:ColorSpace"));
  LoadedImage image;
  image.width = spec.width;
  image.height = spec.height;
  image.rgb.resize(static_cast<size_t>(texels) * 3);
  const bool grey = channels < 3;  // grey, or grey + alpha
  for (int64_t p = 0; p < texels; ++p) {
    const float* src = data.data() + p * channels;
    for (int c = 0; c < 3; ++c) {
      float v = src[grey ? 0 : c];
      if (decode_srgb && std::isfinite(v)) v = static_cast<float>(srgb_to_linear(v));
      image.rgb[3 * p + c] = v;
    }
  }
  check_finite_pixels(image.rgb, image.width, image.height, origin);
  return image;
}


}  // namespace sd
