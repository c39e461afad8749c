#!/usr/bin/env bash
# Cross-builds the library and the SIMD kernel test for ARM and runs the test under qemu-user,
# so the NEON backend is held to the scalar reference without ARM hardware.
#
#   scripts/cross_test_arm.sh [aarch64] [armhf]     (default: both)
#
# Needs (Debian): apt-get install g++-aarch64-linux-gnu g++-arm-linux-gnueabihf \
#                   qemu-user-static googletest libeigen3-dev
# Build trees go to $SVSLAM_CROSS_BUILD_ROOT (default /tmp/svslam-cross), never the source tree.
set -euo pipefail

src_dir="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_root="${SVSLAM_CROSS_BUILD_ROOT:-/tmp/svslam-cross}"
jobs="${JOBS:-$(nproc)}"
targets=("$@")
[[ ${#targets[@]} -eq 0 ]] && targets=(aarch64 armhf)

failed=()
for t in "${targets[@]}"; do
  case "$t" in
    aarch64) toolchain=aarch64-linux-gnu.cmake; cxx=aarch64-linux-gnu-g++; qemu=qemu-aarch64-static ;;
    armhf) toolchain=armhf-linux-gnueabihf.cmake; cxx=arm-linux-gnueabihf-g++; qemu=qemu-arm-static ;;
    *) echo "unknown target '$t' (aarch64 or armhf)" >&2; exit 2 ;;
  esac
  for tool in "$cxx" "$qemu"; do
    if ! command -v "$tool" > /dev/null; then
      echo "missing $tool; install: apt-get install g++-aarch64-linux-gnu" \
        "g++-arm-linux-gnueabihf qemu-user-static" >&2
      exit 2
    fi
  done
  if [[ ! -f /usr/src/googletest/CMakeLists.txt ]]; then
    echo "missing /usr/src/googletest; install: apt-get install googletest" >&2
    exit 2
  fi

  build="$build_root/$t"
  echo "== $t: configure + build in $build"
  cmake -S "$src_dir" -B "$build" \
    -DCMAKE_TOOLCHAIN_FILE="$src_dir/toolchains/$toolchain" \
    -DSVSLAM_BUILD_TOOLS=OFF -DSVSLAM_BUILD_BENCH=OFF -DSVSLAM_BUILD_TESTS=ON
  cmake --build "$build" -j "$jobs" --target svslam_src simd_stereo_kernels_test
  echo "== $t: SIMD kernel test under $qemu"
  if ! ctest --test-dir "$build" -R '^simd_stereo_kernels_test[.]' --no-tests=error \
    --output-on-failure; then
    failed+=("$t")
  fi
done

if [[ ${#failed[@]} -ne 0 ]]; then
  echo "cross SIMD test failed for: ${failed[*]}" >&2
  exit 1
fi
echo "cross SIMD test passed for: ${targets[*]}"
