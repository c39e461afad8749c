# Cross build for 64-bit ARM Linux (AArch64) with Debian's cross g++; tests run under qemu-user.
#   apt-get install g++-aarch64-linux-gnu qemu-user-static
#   cmake -S . -B build-arm64 -DCMAKE_TOOLCHAIN_FILE=toolchains/aarch64-linux-gnu.cmake
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)

set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)

# Target libraries: the cross toolchain's own folder, then Debian multiarch packages
# (dpkg --add-architecture; apt-get install libfoo-dev:<arch>) under "/", where
# CMAKE_LIBRARY_ARCHITECTURE (from the compiler) selects /usr/lib/aarch64-linux-gnu;
# then SVSLAM_TARGET_ROOT if set: a folder of the target's .debs unpacked with dpkg-deb -x.
set(CMAKE_FIND_ROOT_PATH /usr/aarch64-linux-gnu / ${SVSLAM_TARGET_ROOT})
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES SVSLAM_TARGET_ROOT)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
# Header-only, architecture-independent packages (Eigen's config in /usr/share) come from the
# host; compiled libraries and their configs only from the target's multiarch paths and sysroot.
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE BOTH)

# ctest and gtest_discover_tests run target binaries through this.
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-aarch64-static;-L;/usr/aarch64-linux-gnu)
