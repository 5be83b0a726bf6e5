# Cross build for 64-bit ARM Linux (Raspberry Pi 3/4/5, Jetson, most SBCs) with Debian's
# cross compilers (apt-get install crossbuild-essential-arm64 qemu-user-static).
# Libraries come from Debian multiarch packages (dpkg --add-architecture arm64;
# apt-get install libpng-dev:arm64 libgpiod-dev:arm64 ...), found under /usr/lib/aarch64-linux-gnu.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(SKYLOC_TRIPLET aarch64-linux-gnu)
include(${CMAKE_CURRENT_LIST_DIR}/debian-multiarch.cmake)
