// Writes the seed inputs of fuzz_environment_file into the directory given: a small image in each
// format the loader reads (float and 8-bit, RGB and grey), prefixed by the byte that selects its
// extension in the fuzz target.
#include <OpenImageIO/imageio.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace {

// A seed: the byte that selects the extension (fuzz_environment_file's kExtensions), then the file.
void write_seed(const std::filesystem::path& path, int selector, const std::vector<char>& bytes) {
  std::ofstream seed(path, std::ios::binary);
  seed.put(static_cast<char>(selector));
  seed.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_seeds DIRECTORY\n");
    return 2;
  }
  const std::filesystem::path directory = argv[1];
  std::filesystem::create_directories(directory);
  struct Seed {
    const char* extension;  // in the order of fuzz_environment_file's kExtensions
    int selector;
    OIIO::TypeDesc format;
    int channels;
  };
  const Seed seeds[] = {{".exr", 0, OIIO::TypeDesc::HALF, 3},  {".exr", 0, OIIO::TypeDesc::FLOAT, 4},
                        {".hdr", 1, OIIO::TypeDesc::FLOAT, 3}, {".png", 2, OIIO::TypeDesc::UINT8, 3},
                        {".png", 2, OIIO::TypeDesc::UINT16, 1}, {".tif", 4, OIIO::TypeDesc::FLOAT, 3}, {".tif", 4, OIIO::TypeDesc::UINT8, 2},
                        {".jpg", 5, OIIO::TypeDesc::UINT8, 3}};
  const int width = 8, height = 4;
  int index = 0;
  for (const Seed& seed : seeds) {
    std::vector<float> pixels(width * height * seed.channels);
    for (std::size_t k = 0; k < pixels.size(); ++k) pixels[k] = 0.05f * static_cast<float>(k % 17);
    const std::string image = (directory / ("image" + std::string(seed.extension))).string();
    auto out = OIIO::ImageOutput::create(image);
    if (!out || !out->open(image, OIIO::ImageSpec(width, height, seed.channels, seed.format)) ||
        !out->write_image(OIIO::TypeDesc::FLOAT, pixels.data()) || !out->close()) {
      std::fprintf(stderr, "fuzz_seeds: cannot write %s: %s\n", image.c_str(),
                   out ? out->geterror().c_str() : OIIO::geterror().c_str());
      return 1;
    }
    out.reset();
    std::ifstream in(image, std::ios::binary);
    const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    in.close();
    std::filesystem::remove(image);
    write_seed(directory / ("seed_" + std::to_string(index++)), seed.selector, bytes);
  }
  // OpenImageIO reads PFM but has no writer for it: its three header lines (bands, size, a
  // negative scale for little-endian floats, rows bottom-up) and the floats.
  std::string pfm = "PF\n" + std::to_string(width) + " " + std::to_string(height) + "\n-1.0\n";
  for (int k = 0; k < width * height * 3; ++k) {
    const float value = 0.05f * static_cast<float>(k % 17);
    pfm.append(reinterpret_cast<const char*>(&value), sizeof value);
  }
  write_seed(directory / ("seed_" + std::to_string(index)), 3, std::vector<char>(pfm.begin(), pfm.end()));
  return 0;
}
