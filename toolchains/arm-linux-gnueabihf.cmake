# Cross build for 32-bit ARM Linux with hard float (Raspberry Pi OS 32-bit, armv7)
# with Debian's cross compilers (apt-get install crossbuild-essential-armhf qemu-user-static).
# Debian's armhf baseline is ARMv7-A + VFPv3-D16 + Thumb-2; NEON is not assumed.
# Target libraries come from the armhf sysroot build/sysroot-armhf (./skyloc.sh deps armhf
# makes it with mmdebstrap; -DSKYLOC_SYSROOT=DIR names another).
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR arm)
set(SKYLOC_TRIPLET arm-linux-gnueabihf)
set(SKYLOC_DEBIAN_ARCH armhf)
include(${CMAKE_CURRENT_LIST_DIR}/debian-multiarch.cmake)
