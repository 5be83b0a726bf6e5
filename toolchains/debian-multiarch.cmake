# Shared part of the Debian cross toolchain files: compilers named by triplet, libraries
# from /usr/lib/<triplet> (multiarch), tests run through qemu-user.
set(CMAKE_C_COMPILER ${SKYLOC_TRIPLET}-gcc)
set(CMAKE_CXX_COMPILER ${SKYLOC_TRIPLET}-g++)
set(CMAKE_LIBRARY_ARCHITECTURE ${SKYLOC_TRIPLET})

# qemu-user runs the cross-built tests; -L points it at the target's dynamic loader.
# There is no binfmt_misc on the build machines, so the emulator is always named.
set(CMAKE_CROSSCOMPILING_EMULATOR /usr/bin/qemu-${CMAKE_SYSTEM_PROCESSOR}-static;-L;/usr/${SKYLOC_TRIPLET})
if(CMAKE_SYSTEM_PROCESSOR STREQUAL "arm")
  set(CMAKE_CROSSCOMPILING_EMULATOR /usr/bin/qemu-arm-static;-L;/usr/${SKYLOC_TRIPLET})
endif()

# Never pick up a library of the build machine's architecture.
list(APPEND CMAKE_IGNORE_PATH /usr/lib/x86_64-linux-gnu /lib/x86_64-linux-gnu)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(ENV{PKG_CONFIG_LIBDIR} "/usr/lib/${SKYLOC_TRIPLET}/pkgconfig:/usr/share/pkgconfig")
set(ENV{PKG_CONFIG_PATH} "")
