# Shared part of the Debian cross toolchain files: compilers named by triplet, every target
# header and library from the target sysroot, tests run through qemu-user against the
# sysroot's libraries.
#
# The sysroot (build/sysroot-<debian-arch>/) is a minimal Debian root of the target
# architecture that ./skyloc.sh makes with mmdebstrap from toolchains/sysroot-packages.txt
# (docs/ARCHITECTURE.md, "Cross builds and their libraries"). The cross compiler brings
# its own libc, libstdc++ and kernel headers; nothing is searched in the build machine's
# /usr/include or /usr/lib.
set(CMAKE_C_COMPILER ${SKYLOC_TRIPLET}-gcc)
set(CMAKE_CXX_COMPILER ${SKYLOC_TRIPLET}-g++)
set(CMAKE_LIBRARY_ARCHITECTURE ${SKYLOC_TRIPLET})

if(NOT SKYLOC_SYSROOT)
  get_filename_component(SKYLOC_SYSROOT
                         "${CMAKE_CURRENT_LIST_DIR}/../build/sysroot-${SKYLOC_DEBIAN_ARCH}" ABSOLUTE)
endif()
if(NOT EXISTS "${SKYLOC_SYSROOT}/skyloc-sysroot/stamp")
  message(FATAL_ERROR "skyloc: no ${SKYLOC_DEBIAN_ARCH} target sysroot at ${SKYLOC_SYSROOT}. "
                      "Make it with './skyloc.sh deps ${CMAKE_SYSTEM_PROCESSOR}' (mmdebstrap, "
                      "toolchains/sysroot-packages.txt), or name another one with "
                      "-DSKYLOC_SYSROOT=DIR.")
endif()
set(SKYLOC_SYSROOT "${SKYLOC_SYSROOT}" CACHE PATH "Target sysroot (./skyloc.sh makes it)")
# try_compile projects read this file again: hand them the same sysroot.
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES SKYLOC_SYSROOT)
set(CMAKE_SYSROOT "${SKYLOC_SYSROOT}")

# find_* look only inside the sysroot; programs (pkg-config, clang-format) are the build
# machine's.
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
# pkg-config reads only the sysroot's .pc files and prefixes their paths with it.
set(ENV{PKG_CONFIG_SYSROOT_DIR} "${SKYLOC_SYSROOT}")
set(ENV{PKG_CONFIG_LIBDIR}
    "${SKYLOC_SYSROOT}/usr/lib/${SKYLOC_TRIPLET}/pkgconfig:${SKYLOC_SYSROOT}/usr/share/pkgconfig:${SKYLOC_SYSROOT}/usr/lib/pkgconfig")
set(ENV{PKG_CONFIG_PATH} "")

# qemu-user runs the cross-built tests; -L makes it load the target's dynamic loader and
# libraries (libcamera's, libgpiod's, libc) from the sysroot. There is no binfmt_misc on
# the build machines, so the emulator is always named.
# aarch64 runs on a Cortex-A53, the core of the Raspberry Pi 3 and Zero 2 our users fly,
# rather than qemu's default "max" (every optional feature, SVE and pointer authentication
# among them, none of which the A53 has): the tests then run on the users' core, and 7 %
# faster (a quarter of the dsp tests: 27.3 s against 25.5 s, 2026-11-28). armhf keeps the
# default: cortex-a7 and cortex-a15 were no faster there.
if(CMAKE_SYSTEM_PROCESSOR STREQUAL "arm")
  set(CMAKE_CROSSCOMPILING_EMULATOR /usr/bin/qemu-arm-static;-L;${SKYLOC_SYSROOT})
else()
  set(CMAKE_CROSSCOMPILING_EMULATOR
      /usr/bin/qemu-${CMAKE_SYSTEM_PROCESSOR}-static;-cpu;cortex-a53;-L;${SKYLOC_SYSROOT})
endif()
