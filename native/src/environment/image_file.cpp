// Environment maps from image files, read with OpenImageIO: the one part of the library that needs
// an image library. Built as its own library (sdlighting_image_files), so that the add-on's module,
// which gets Blender's pixels (environment_from_pixels), links none (issue 31).
#include "environment/image_io.h"
#include "sdlighting/environment.h"
#include "sdlighting/limits.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <filesystem>
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
// it blocks until a writer comes), a device such as /dev/zero (endless data) or a socket. The status
// is looked up without opening the file, so nothing here can block or read.
void check_regular_file(const std::string& path, const std::string& origin) {
  namespace fs = std::filesystem;
  std::error_code error;
  const fs::file_status status = fs::status(path, error);
  if (error) throw std::runtime_error("cannot open " + origin + ": " + error.message());
  if (fs::is_directory(status)) throw std::runtime_error("cannot open " + origin + ": it is a directory, not an image file");
  if (!fs::is_regular_file(status)) {
    const char* kind = fs::is_fifo(status)                                        ? "a FIFO (named pipe)"
                       : fs::is_character_file(status) || fs::is_block_file(status) ? "a device file"
                       : fs::is_socket(status)                                    ? "a socket"
                                                                                  : "not a regular file";
    throw std::runtime_error("cannot open " + origin + ": it is " + kind +
                             ", not an image file (refused without reading: it could block or never end)");
  }
  if (fs::file_size(path, error) == 0 && !error) {
    throw std::runtime_error("cannot open " + origin + ": the file is empty (0 bytes)");
  }
}

}  // namespace

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

Environment Environment::load(const std::string& path) {
  LoadedImage image = read_image_file(path);
  return from_texels(EnvironmentLayout::Equirect, image.width, image.height, std::move(image.rgb),
                     "environment map '" + path + "'");
}

Environment Environment::load_cube(const std::array<std::string, 6>& faces) {
  std::vector<float> rgb;
  int size = 0;
  for (int f = 0; f < 6; ++f) {
    const LoadedImage image = read_image_file(faces[f]);
    const std::string origin = std::string("cube face ") + kFaceNames[f] + " '" + faces[f] + "'";
    if (image.width != image.height) {
      throw std::invalid_argument(origin + " is not square (" + std::to_string(image.width) + " x " +
                                  std::to_string(image.height) + ")");
    }
    if (f == 0) {
      size = image.width;
      rgb.reserve(static_cast<size_t>(size) * size * 18);
    } else if (image.width != size) {
      throw std::invalid_argument(origin + " is " + std::to_string(image.width) + " pixels wide, face +X is " +
                                  std::to_string(size) + ": all faces must have one size");
    }
    rgb.insert(rgb.end(), image.rgb.begin(), image.rgb.end());
  }
  return from_texels(EnvironmentLayout::Cube, size, size, std::move(rgb), "cube map '" + faces[0] + "', ...");
}

}  // namespace sd
