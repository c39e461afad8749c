# Cross build for 32-bit ARM Linux, hard float, with NEON (armv7-a) using Debian's cross g++;
# tests run under qemu-user.
#   apt-get install g++-arm-linux-gnueabihf qemu-user-static
#   cmake -S . -B build-armhf -DCMAKE_TOOLCHAIN_FILE=toolchains/armhf-linux-gnueabihf.cmake
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR armv7)

set(CMAKE_C_COMPILER arm-linux-gnueabihf-gcc)
set(CMAKE_CXX_COMPILER arm-linux-gnueabihf-g++)
set(CMAKE_C_FLAGS_INIT "-mfpu=neon -mfloat-abi=hard")
set(CMAKE_CXX_FLAGS_INIT "-mfpu=neon -mfloat-abi=hard")

# Target libraries: the cross toolchain's own folder, then Debian multiarch packages
# (dpkg --add-architecture; apt-get install libfoo-dev:<arch>) under "/", where
# CMAKE_LIBRARY_ARCHITECTURE (from the compiler) selects /usr/lib/arm-linux-gnueabihf;
# then SVSLAM_TARGET_ROOT if set: a folder of the target's .debs unpacked with dpkg-deb -x.
set(CMAKE_FIND_ROOT_PATH /usr/arm-linux-gnueabihf / ${SVSLAM_TARGET_ROOT})
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES SVSLAM_TARGET_ROOT)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
# Header-only, architecture-independent packages (Eigen's config in /usr/share) come from the
# host; compiled libraries and their configs only from the target's multiarch paths and sysroot.
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE BOTH)

set(CMAKE_CROSSCOMPILING_EMULATOR qemu-arm-static;-L;/usr/arm-linux-gnueabihf)
