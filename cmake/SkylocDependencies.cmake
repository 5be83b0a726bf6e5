# Third-party libraries, all from Debian packages. On a cross build the toolchain file
# points find_* and pkg-config at the target sysroot (build/sysroot-<arch>), so the same
# calls find the ARM libraries. Which drivers a build contains is chosen below and printed
# by configure; the pure algorithms never need more than Eigen.

find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(PkgConfig REQUIRED)
find_package(Threads REQUIRED)

# PNG decoding/encoding for the describe/eval/replay/simulate tools: Debian's stb
# (libstb-dev), used header-only, so the firmware links no image library (a cross build
# finds the headers in its sysroot).
find_path(SKYLOC_STB_INCLUDE stb/stb_image.h REQUIRED)
add_library(skyloc_stb INTERFACE)
target_include_directories(skyloc_stb SYSTEM INTERFACE ${SKYLOC_STB_INCLUDE})
add_library(skyloc::stb ALIAS skyloc_stb)

# toml++ is used header-only (TOML_HEADER_ONLY=1): the firmware links no TOML library.
find_path(SKYLOC_TOMLPP_INCLUDE toml++/toml.h REQUIRED)
add_library(skyloc_tomlpp INTERFACE)
target_include_directories(skyloc_tomlpp SYSTEM INTERFACE ${SKYLOC_TOMLPP_INCLUDE})
target_compile_definitions(skyloc_tomlpp INTERFACE TOML_HEADER_ONLY=1 TOML_EXCEPTIONS=0)
add_library(skyloc::tomlpp ALIAS skyloc_tomlpp)

# SKYLOC_TOOLS and SKYLOC_BUILD_TESTS are ON, OFF or AUTO (CMakeLists.txt); below, AUTO
# becomes what this build contains, ON or OFF, by whether its libraries are found. Any
# other true or false value counts as ON or OFF, as it did when both were plain options.
foreach(part TOOLS BUILD_TESTS)
  if(SKYLOC_${part} STREQUAL "AUTO")
    continue()
  elseif(SKYLOC_${part})
    set(SKYLOC_${part} ON)
  else()
    set(SKYLOC_${part} OFF)
  endif()
endforeach()

# OpenCV (Debian's libopencv-dev) for the lab's tools only: SIFT features and
# k-means for the FAB-MAP baseline. Never linked into dsp/, drivers/ or the ARM firmware.
if(SKYLOC_TOOLS STREQUAL "OFF")
  message(STATUS "skyloc: lab tools (eval, simulate, experiments, FAB-MAP): LEFT OUT (SKYLOC_TOOLS=OFF, "
                 "the default when cross-compiling)")
else()
  find_package(OpenCV 4 QUIET COMPONENTS core imgproc features2d)
  if(OpenCV_FOUND)
    set(SKYLOC_TOOLS ON)
    message(STATUS "skyloc: lab tools (eval, simulate, experiments, FAB-MAP): built, OpenCV ${OpenCV_VERSION}")
  elseif(SKYLOC_TOOLS STREQUAL "AUTO")
    set(SKYLOC_TOOLS OFF)
    message(STATUS "skyloc: lab tools (eval, simulate, experiments, FAB-MAP): LEFT OUT "
                   "(SKYLOC_TOOLS=AUTO and OpenCV 4 was not found: apt-get install libopencv-dev)")
  else()
    message(FATAL_ERROR "skyloc: SKYLOC_TOOLS is ON but OpenCV 4 (core, imgproc, "
                        "features2d) was not found. Install it with 'apt-get install "
                        "libopencv-dev' (./skyloc.sh deps does), or configure with "
                        "-DSKYLOC_TOOLS=OFF to leave the lab's tools out.")
  endif()
endif()

# Drivers. SKYLOC_WITH_<DRIVER> is ON (configure fails when the driver's library is
# missing), OFF (left out on purpose), or AUTO (built when the library is found). The
# cross builds are the product, and their sysroot holds every driver's library
# (toolchains/sysroot-packages.txt), so there the default is ON; a native build defaults
# to AUTO so that a laptop without libcamera-dev still builds. Code asks
# `#if SKYLOC_WITH_<DRIVER>` (always defined, 0 or 1: drivers/CMakeLists.txt).
if(CMAKE_CROSSCOMPILING)
  set(skyloc_driver_default ON)
else()
  set(skyloc_driver_default AUTO)
endif()
set(skyloc_driver_V4L2_package "linux/videodev2.h (the kernel headers: linux-libc-dev)")
set(skyloc_driver_GPIOD_package "libgpiodcxx>=1.6 (libgpiod-dev)")
set(skyloc_driver_LIBCAMERA_package "libcamera>=0.0.3 (libcamera-dev)")
if(CMAKE_CROSSCOMPILING)
  set(skyloc_driver_where "the ${CMAKE_SYSTEM_PROCESSOR} sysroot ${CMAKE_SYSROOT}")
  set(skyloc_driver_fix "Add its package to toolchains/sysroot-packages.txt (./skyloc.sh "
                        "deps then makes the sysroot again)")
else()
  set(skyloc_driver_where "this machine")
  set(skyloc_driver_fix "Install it (./skyloc.sh deps does)")
endif()
string(JOIN "" skyloc_driver_fix ${skyloc_driver_fix})
string(JOIN "" skyloc_driver_where ${skyloc_driver_where})
include(CheckIncludeFileCXX)
foreach(driver V4L2 GPIOD LIBCAMERA)
  set(SKYLOC_WITH_${driver} ${skyloc_driver_default} CACHE STRING
      "Build the ${driver} driver: ON (fail when its library is missing), OFF, or AUTO")
  set_property(CACHE SKYLOC_WITH_${driver} PROPERTY STRINGS ON OFF AUTO)
  set(mode ${SKYLOC_WITH_${driver}})
  if(NOT mode MATCHES "^(ON|OFF|AUTO)$")
    message(FATAL_ERROR "skyloc: SKYLOC_WITH_${driver}=${mode}: use ON, OFF or AUTO.")
  endif()
  set(found OFF)
  if(NOT mode STREQUAL "OFF")
    if(driver STREQUAL "V4L2")
      check_include_file_cxx(linux/videodev2.h SKYLOC_HAVE_VIDEODEV2)
      set(found ${SKYLOC_HAVE_VIDEODEV2})
    elseif(driver STREQUAL "GPIOD")
      pkg_check_modules(LIBGPIOD IMPORTED_TARGET libgpiodcxx>=1.6)
      set(found ${LIBGPIOD_FOUND})
    else()
      pkg_check_modules(LIBCAMERA IMPORTED_TARGET libcamera>=0.0.3)
      set(found ${LIBCAMERA_FOUND})
    endif()
  endif()
  # From here on SKYLOC_WITH_<DRIVER> is what this build contains: ON or OFF.
  if(found)
    set(SKYLOC_WITH_${driver} ON)
    message(STATUS "skyloc: ${driver} driver: built")
  elseif(mode STREQUAL "OFF")
    set(SKYLOC_WITH_${driver} OFF)
    message(STATUS "skyloc: ${driver} driver: LEFT OUT (SKYLOC_WITH_${driver}=OFF)")
  elseif(mode STREQUAL "ON")
    message(FATAL_ERROR "skyloc: the ${driver} driver is required in this build "
                        "(SKYLOC_WITH_${driver}=ON, the default when cross-compiling), but "
                        "${skyloc_driver_${driver}_package} was not found in "
                        "${skyloc_driver_where}. ${skyloc_driver_fix}, or configure with "
                        "-DSKYLOC_WITH_${driver}=OFF to build without this driver.")
  else()
    set(SKYLOC_WITH_${driver} OFF)
    message(STATUS "skyloc: ${driver} driver: LEFT OUT (SKYLOC_WITH_${driver}=AUTO and "
                   "${skyloc_driver_${driver}_package} was not found in "
                   "${skyloc_driver_where}; -DSKYLOC_WITH_${driver}=ON makes this an error)")
  endif()
endforeach()

# [output] kinds = "dds" (ROS 2 topics): Eclipse Cyclone DDS's C library for the target
# (cyclonedds-dev, from the sysroot when cross-compiling) and its IDL compiler idlc for
# this machine (cyclonedds-tools; it writes C type support from drivers/src/dds/*.idl, the
# same for every architecture). ON, OFF or AUTO like the drivers; code asks
# `#if SKYLOC_WITH_DDS`.
set(SKYLOC_WITH_DDS ${skyloc_driver_default} CACHE STRING
    "Build the DDS output: ON (fail when Cyclone DDS is missing), OFF, or AUTO")
set_property(CACHE SKYLOC_WITH_DDS PROPERTY STRINGS ON OFF AUTO)
if(NOT SKYLOC_WITH_DDS MATCHES "^(ON|OFF|AUTO)$")
  message(FATAL_ERROR "skyloc: SKYLOC_WITH_DDS=${SKYLOC_WITH_DDS}: use ON, OFF or AUTO.")
endif()
set(skyloc_dds_mode ${SKYLOC_WITH_DDS})
set(skyloc_dds_missing "")
if(NOT skyloc_dds_mode STREQUAL "OFF")
  pkg_check_modules(CYCLONEDDS IMPORTED_TARGET CycloneDDS>=0.10)
  # idlc runs on this machine, also in a cross build: never from the sysroot.
  find_program(SKYLOC_IDLC idlc NO_CMAKE_FIND_ROOT_PATH)
  if(NOT CYCLONEDDS_FOUND)
    set(skyloc_dds_missing "CycloneDDS>=0.10 (cyclonedds-dev) in ${skyloc_driver_where}")
  elseif(NOT SKYLOC_IDLC)
    set(skyloc_dds_missing "idlc (cyclonedds-tools) on this machine")
  endif()
endif()
if(skyloc_dds_mode STREQUAL "OFF")
  set(SKYLOC_WITH_DDS OFF)
  message(STATUS "skyloc: DDS output (ROS 2 topics): LEFT OUT (SKYLOC_WITH_DDS=OFF)")
elseif(skyloc_dds_missing STREQUAL "")
  set(SKYLOC_WITH_DDS ON)
  message(STATUS "skyloc: DDS output (ROS 2 topics): built, Cyclone DDS ${CYCLONEDDS_VERSION}, "
                 "${SKYLOC_IDLC}")
elseif(skyloc_dds_mode STREQUAL "ON")
  message(FATAL_ERROR "skyloc: the DDS output is required in this build (SKYLOC_WITH_DDS=ON, "
                      "the default when cross-compiling), but ${skyloc_dds_missing} was not "
                      "found. ${skyloc_driver_fix} (cyclonedds-tools goes on the build machine: "
                      "apt-get install cyclonedds-tools), or configure with "
                      "-DSKYLOC_WITH_DDS=OFF to build without it.")
else()
  set(SKYLOC_WITH_DDS OFF)
  message(STATUS "skyloc: DDS output (ROS 2 topics): LEFT OUT (SKYLOC_WITH_DDS=AUTO and "
                 "${skyloc_dds_missing} was not found; -DSKYLOC_WITH_DDS=ON makes this an "
                 "error)")
endif()

# GoogleTest and GoogleMock as Debian builds them (libgtest-dev, libgmock-dev; for the ARM
# builds from their sysroot): the same version and compiler as the source package, and the
# five build kinds of ./skyloc.sh test no longer compile it each (about 26 s of CPU a build,
# measured). The sanitizer builds link it uninstrumented: the sanitizers check the code under
# test, and GoogleTest's templates (the assertions) are compiled into the tests with their
# flags anyway; TSan still sees the framework's locks through its pthread interceptors.
if(NOT SKYLOC_BUILD_TESTS STREQUAL "OFF")
  find_package(GTest 1.12 CONFIG QUIET)
  if(NOT GTest_FOUND OR NOT TARGET GTest::gmock)
    if(CMAKE_CROSSCOMPILING)
      set(skyloc_gtest_fix "the sysroot lists libgtest-dev and libgmock-dev "
                           "(toolchains/sysroot-packages.txt; ./skyloc.sh makes it again)")
    else()
      set(skyloc_gtest_fix "apt-get install libgtest-dev libgmock-dev")
    endif()
    if(SKYLOC_BUILD_TESTS STREQUAL "AUTO")
      message(STATUS "skyloc: tests: LEFT OUT (SKYLOC_BUILD_TESTS=AUTO and GoogleTest/GoogleMock "
                     "were not found: ${skyloc_gtest_fix})")
      set(SKYLOC_BUILD_TESTS OFF)
    else()
      message(FATAL_ERROR "skyloc: GoogleTest and GoogleMock (CMake package GTest >= 1.12) were "
                          "not found: ${skyloc_gtest_fix}; or configure with "
                          "-DSKYLOC_BUILD_TESTS=OFF")
    endif()
  endif()
endif()
if(SKYLOC_BUILD_TESTS STREQUAL "OFF")
  set(SKYLOC_BUILD_TESTS OFF)
else()
  set(SKYLOC_BUILD_TESTS ON)
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
