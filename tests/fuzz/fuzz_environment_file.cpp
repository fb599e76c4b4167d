// Environment::load on arbitrary file bytes: the first byte picks the extension (OpenImageIO
// chooses the reader by it, then by the magic bytes), the rest is written to a file of that name.
// Every input must give a map of finite, non-negative pixels whose SH projection is finite, or a
// std::exception with a message: never a crash, hang, leak or undefined behaviour.
#include "fuzz_values.h"
#include "sdlighting/environment.h"
#include "sdlighting/sh_projection.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace {

// The extensions the loader documents (environment.h), in the order of the seeds' first byte.
const char* const kExtensions[] = {".exr", ".hdr", ".png", ".pfm", ".tif", ".jpg"};

std::string scratch_path(int extension) {
  static const std::string base = "/tmp/sd_fuzz_environment_" + std::to_string(::getpid());
  return base + kExtensions[extension];
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* bytes, std::size_t size) {
  if (size < 1) return 0;
  const int extension = bytes[0] % (sizeof kExtensions / sizeof kExtensions[0]);
  const std::string path = scratch_path(extension);
  if (std::FILE* file = std::fopen(path.c_str(), "wb")) {
    std::fwrite(bytes + 1, 1, size - 1, file);
    std::fclose(file);
  } else {
    return 0;
  }
  try {
    const sd::Environment map = sd::Environment::load(path);
    for (float v : map.pixels()) {
      if (!std::isfinite(v) || v < 0.0f) sd::fuzz::contract_broken("a loaded pixel is negative or not finite");
    }
    for (double c : sd::sh(map, 2, 1)) {
      if (!std::isfinite(c)) sd::fuzz::contract_broken("a loaded map's SH coefficient is not finite");
    }
  } catch (const std::exception& error) {
    sd::fuzz::check_message(error);
  }
  std::remove(path.c_str());
  return 0;
}
