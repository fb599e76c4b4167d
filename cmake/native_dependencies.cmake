# The libraries the native library (native/) links, found once for the main build and for the
# fuzzer build (tests/fuzz), which compiles the same sources again with clang's sanitizers.
find_package(Eigen3 3.3 CONFIG REQUIRED)
find_package(glm CONFIG REQUIRED)
find_package(Threads REQUIRED)
# Embree 4 where it is installed, else Embree 3 (Debian 12's, what is tested here); the library's
# sources see which as SD_EMBREE_MAJOR (native/src/bake/embree_scene.h).
find_package(embree 4 CONFIG QUIET)
if(NOT embree_FOUND)
  find_package(embree 3 CONFIG REQUIRED)
endif()
set(SD_EMBREE_MAJOR ${embree_VERSION_MAJOR})
if(NOT DEFINED SD_IMAGE_FILES)   # the fuzzer build's: the main build's option (CMakeLists.txt)
  set(SD_IMAGE_FILES ON)
endif()
if(SD_IMAGE_FILES)   # the wheel's build reads no image files
  # Debian's OpenImageIO CMake target names a non-existent OpenCV include directory; its .pc is clean.
  # Elsewhere (vcpkg: CMakePresets.json, untested here) its CMake package, under the same target name.
  find_package(PkgConfig)
  if(PKG_CONFIG_FOUND)
    pkg_check_modules(OpenImageIO IMPORTED_TARGET OpenImageIO)
  endif()
  if(TARGET PkgConfig::OpenImageIO)
    set(SD_OPENIMAGEIO PkgConfig::OpenImageIO)
  else()
    find_package(OpenImageIO CONFIG REQUIRED)
    set(SD_OPENIMAGEIO OpenImageIO::OpenImageIO)
  endif()
endif()
