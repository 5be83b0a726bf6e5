# Third-party libraries, all from Debian packages. On a cross build the toolchain file
# points find_* at Debian's multiarch directories (/usr/lib/<triplet>), so the same
# calls find the ARM libraries. A driver whose library is missing is left out, and
# configure says so; the pure algorithms never need more than Eigen.

find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(PkgConfig REQUIRED)
find_package(Threads REQUIRED)

# PNG decoding/encoding for the describe/eval/replay/simulate tools: Debian's stb
# (libstb-dev), used header-only so every architecture shares one set of headers; a
# multiarch libpng-dev:arm64 is often not co-installable with the host's during mirror
# syncs (seen on these machines), which would break the ARM build for an image codec.
find_path(SKYLOC_STB_INCLUDE stb/stb_image.h REQUIRED)
add_library(skyloc_stb INTERFACE)
target_include_directories(skyloc_stb SYSTEM INTERFACE ${SKYLOC_STB_INCLUDE})
add_library(skyloc::stb ALIAS skyloc_stb)

# toml++ is used header-only (TOML_HEADER_ONLY=1), so one set of headers serves every
# architecture and the ARM build needs no libtomlplusplus:arm64.
find_path(SKYLOC_TOMLPP_INCLUDE toml++/toml.h REQUIRED)
add_library(skyloc_tomlpp INTERFACE)
target_include_directories(skyloc_tomlpp SYSTEM INTERFACE ${SKYLOC_TOMLPP_INCLUDE})
target_compile_definitions(skyloc_tomlpp INTERFACE TOML_HEADER_ONLY=1 TOML_EXCEPTIONS=0)
add_library(skyloc::tomlpp ALIAS skyloc_tomlpp)

# OpenCV (Debian's libopencv-dev) for the host-only evaluation tools only: SIFT features and
# k-means for the FAB-MAP baseline. Never linked into dsp/, drivers/ or the ARM firmware.
if(SKYLOC_HOST_EVAL)
  find_package(OpenCV 4 QUIET COMPONENTS core imgproc features2d)
  if(NOT OpenCV_FOUND)
    message(FATAL_ERROR "skyloc: SKYLOC_HOST_EVAL is ON but OpenCV 4 (core, imgproc, "
                        "features2d) was not found. Install it with 'apt-get install "
                        "libopencv-dev' (./skyloc.sh deps does), or configure with "
                        "-DSKYLOC_HOST_EVAL=OFF to leave the evaluation tools out.")
  endif()
  message(STATUS "skyloc: host evaluation tools (FAB-MAP): built, OpenCV ${OpenCV_VERSION}")
else()
  message(STATUS "skyloc: host evaluation tools (FAB-MAP): LEFT OUT (SKYLOC_HOST_EVAL=OFF, "
                 "the default when cross-compiling)")
endif()

# Optional drivers: each is built only when its library is installed for the target.
pkg_check_modules(LIBGPIOD IMPORTED_TARGET libgpiodcxx>=1.6)
pkg_check_modules(LIBCAMERA IMPORTED_TARGET libcamera>=0.0.3)
include(CheckIncludeFileCXX)
check_include_file_cxx(linux/videodev2.h SKYLOC_HAVE_VIDEODEV2)

set(SKYLOC_WITH_V4L2 ${SKYLOC_HAVE_VIDEODEV2})
set(SKYLOC_WITH_GPIOD ${LIBGPIOD_FOUND})
set(SKYLOC_WITH_LIBCAMERA ${LIBCAMERA_FOUND})
foreach(driver V4L2 GPIOD LIBCAMERA)
  if(SKYLOC_WITH_${driver})
    message(STATUS "skyloc: ${driver} driver: built")
  else()
    message(STATUS "skyloc: ${driver} driver: LEFT OUT (its development package is not "
                   "installed for ${CMAKE_SYSTEM_PROCESSOR}; see docs/ARCHITECTURE.md, "
                   "'Cross builds')")
  endif()
endforeach()

if(SKYLOC_BUILD_TESTS)
  # GoogleTest is always built from Debian's source package (/usr/src/googletest), so host,
  # sanitizer and cross builds link a GoogleTest compiled with their own compiler and flags.
  set(INSTALL_GTEST OFF CACHE BOOL "" FORCE)
  set(BUILD_GMOCK ON CACHE BOOL "" FORCE)
  if(NOT EXISTS /usr/src/googletest/CMakeLists.txt)
    message(FATAL_ERROR "skyloc: /usr/src/googletest is missing. Install it with: "
                        "apt-get install googletest")
  endif()
  add_subdirectory(/usr/src/googletest ${CMAKE_BINARY_DIR}/_deps/googletest EXCLUDE_FROM_ALL)
  foreach(t gtest gtest_main gmock gmock_main)
    if(TARGET ${t})
      target_link_libraries(${t} PUBLIC skyloc::sanitize)
    endif()
  endforeach()
  include(GoogleTest)
endif()

if(SKYLOC_BUILD_BENCHMARKS)
  find_package(benchmark QUIET)
  if(NOT benchmark_FOUND)
    message(STATUS "skyloc: Google Benchmark not found for ${CMAKE_SYSTEM_PROCESSOR}: "
                   "benchmarks are not built")
    set(SKYLOC_BUILD_BENCHMARKS OFF)
  endif()
endif()
