# Cross build for 64-bit ARM Linux (Raspberry Pi 3/4/5, Jetson, most SBCs) with Debian's
# cross compilers (apt-get install crossbuild-essential-arm64 qemu-user-static).
# Target libraries come from the arm64 sysroot build/sysroot-arm64 (./skyloc.sh deps
# aarch64 makes it with mmdebstrap; -DSKYLOC_SYSROOT=DIR names another).
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(SKYLOC_TRIPLET aarch64-linux-gnu)
set(SKYLOC_DEBIAN_ARCH arm64)
include(${CMAKE_CURRENT_LIST_DIR}/debian-multiarch.cmake)
